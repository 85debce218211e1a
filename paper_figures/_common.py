"""Command line of the paper-figure scripts of this folder.

The figures themselves are built by the package (:mod:`hippo_probe.paper`: one module
per figure with ``make(config, out)``, its configurations and caching helpers in
:mod:`hippo_probe.paper.config`, re-exported here for older scripts). Run as scripts, the
figures cache their recordings in the repository's ``recordings/paper-<size>/`` (ignored
by git), as ``hippo-probe figures --cache recordings`` does.
"""

import argparse
from pathlib import Path

# the old home of these names
from hippo_probe.paper.config import *
from hippo_probe.paper.config import CONFIGS, WORLDS, for_run, shipped_runs, with_cache

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "recordings"


def parse_args(description: str):
    """``--size``, ``--world``, ``--seed`` and ``--out`` of a figure script ->
    (configuration, output folder of the run: ``OUT/<world>-seed<k>``, where
    ``paper_figures/results.py`` reads it)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--size", choices=sorted(CONFIGS), default="full",
                    help="data size (default full: minutes on 2 cores)")
    first = (shipped_runs() or [(WORLDS[0], 0)])[0]
    ap.add_argument("--world", choices=WORLDS, default=first[0],
                    help="world of the networks and their trials (default: the first "
                         "world with shipped networks, the darkness world once shipped)")
    ap.add_argument("--seed", type=int, default=0, help="training seed of the networks")
    ap.add_argument("--out", default=str(ROOT / "figures"), help="output folder")
    a = ap.parse_args()
    cfg = for_run(with_cache(CONFIGS[a.size], CACHE), a.world, a.seed)
    return cfg, Path(a.out) / cfg.run
