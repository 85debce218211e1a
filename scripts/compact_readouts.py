"""Rewrite full readout files as readout files holding their classifier alone.

A readout retrained on a frozen network used to be shipped with a copy of that
network's parameters. This rewrites each ``<folder>/<name>_readout[_seed<k>].pt`` whose
network, ``<folder>/<name>[_seed<k>].pt``, has exactly those parameters, as a readout
file naming that network (``hippo_probe.model.load.READOUT_OF``); every number it gives
is unchanged. A file already in that form, or whose network differs, is left alone.

    python scripts/compact_readouts.py hippo_probe/pretrained
"""

import argparse
from pathlib import Path

from hippo_probe.model.checkpoint import load, save_atomic
from hippo_probe.model.load import READOUT_OF, as_readout


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    folder = Path(ap.parse_args().folder)
    for path in sorted(folder.glob("*_readout*.pt")):
        network = load(path)
        base_name = path.name.replace("_readout", "", 1)
        if READOUT_OF in network or not (folder / base_name).is_file():
            print(f"{path.name}: left as it is")
            continue
        try:
            compact = as_readout(network, load(folder / base_name), folder / base_name)
        except ValueError as err:
            print(f"{path.name}: left as it is ({err})")
            continue
        save_atomic(compact, path)
        print(f"{path.name}: the classifier alone, reading {base_name}")


if __name__ == "__main__":
    main()
