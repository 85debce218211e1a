"""Network units vs real rodent cells, with the same analyses on the same layout.

A thin entry point over :func:`hippo_probe.paper.rodent.make` (which ``hippo-probe
figures`` calls; its docstring says what is compared). The network's recording is cached
in the repository's ``recordings/paper-<size>/``, as the figure scripts' are.

    python analyses/network_vs_rodent.py [--size tiny|full|paper] [--out figures/]

Writes ``network_vs_rodent.png/.pdf`` (one figure), ``network_vs_rodent.md`` (one table)
and ``network_vs_rodent.json``.
"""

import argparse
from pathlib import Path

from hippo_probe.paper import rodent
from hippo_probe.paper.config import CONFIGS, first_run, with_cache

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", choices=sorted(CONFIGS), default="full")
    ap.add_argument("--out", default=str(ROOT / "figures"))
    ap.add_argument("--session", default=str(ROOT / rodent.SESSION),
                    help="the mouse's NWB session")
    a = ap.parse_args()
    # the networks of the figures' first run (the darkness world's, once shipped)
    rodent.make(first_run(with_cache(CONFIGS[a.size], ROOT / "recordings")), Path(a.out),
                session=a.session)


if __name__ == "__main__":
    main()
