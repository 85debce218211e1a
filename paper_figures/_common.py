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
from hippo_probe.paper.config import CONFIGS, with_cache

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / "recordings"


def parse_args(description: str):
    """``--size`` and ``--out`` of a figure script -> (configuration, output folder)."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("--size", choices=sorted(CONFIGS), default="full",
                    help="data size (default full: minutes on 2 cores)")
    ap.add_argument("--out", default=str(ROOT / "figures"), help="output folder")
    a = ap.parse_args()
    return with_cache(CONFIGS[a.size], CACHE), Path(a.out)
