"""Where one run of the paper figures spends its time, figure by figure.

Makes every figure of one run (a world and a training seed) in this process on one
thread, under :mod:`cProfile`, and prints per figure the seconds of each stage: the
reference filters (the oracular particle filter and PF-SLAM, made by a world's first run
and read by its others), the networks' recordings (forward passes) and their saving, each
analysis, and the figure's drawing and saving. A stage's seconds are cumulative: a stage
called inside another counts in both (an analysis that makes rate maps, PF-SLAM inside
the particle filter's total), so the rows do not add up to the figure's.
Each figure's profile is kept as ``<out>/<run>-<figure>.prof`` for ``snakeviz`` or
:mod:`pstats`.

The first figure of a run to need a recording makes it; a world's first run makes its
reference filters unless ``--cache`` already holds them (run a world's seed 0 first, with
the same ``--cache``, to profile a later seed as ``hippo-probe main`` runs it).

    python benchmarks/profile_figures.py [--world darkness] [--seed 0] [--size paper]
        [--cache /tmp/profile_figures] [--out /tmp/profile_figures]
"""

import argparse
import cProfile
import os
import pstats
import time
from pathlib import Path

os.environ.setdefault("MPLBACKEND", "Agg")

#: Stages: (label, file suffix, function name); the first matching each.
STAGES = (
    ("particle filter (reference)", "baselines/particle_filter.py", "run_filter"),
    ("PF-SLAM (part of the above)", "baselines/pf_slam.py", "pf_slam"),
    ("recording: forward pass", "model/record.py", "record"),
    ("recording: save to zarr", "recording/store.py", "save_recording"),
    ("figure: draw and save", "paper/config.py", "save"),
)


def stage_seconds(stats: pstats.Stats) -> dict:
    """Cumulative seconds per stage, and per public analysis (``hippo_probe/analysis``)."""
    out = {}
    for (file, _, name), (_, _, _, cumulative, _) in stats.stats.items():
        for label, suffix, function in STAGES:
            if file.endswith(suffix) and name == function:
                out[label] = out.get(label, 0.0) + cumulative
        module = Path(file).stem
        if f"hippo_probe{os.sep}analysis" in file and name == module:
            out[f"analysis: {name}"] = out.get(f"analysis: {name}", 0.0) + cumulative
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", default="darkness")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--size", default="paper", choices=("tiny", "full", "paper"))
    ap.add_argument("--cache", default="/tmp/profile_figures",
                    help="cached recordings and reference filters (reused by later runs)")
    ap.add_argument("--out", default="/tmp/profile_figures",
                    help="the figures and the profiles")
    ap.add_argument("--min-seconds", type=float, default=1.0,
                    help="stages shorter than this are left out of the table")
    a = ap.parse_args()

    from hippo_probe._threads import limit_threads
    limit_threads(1)                        # as each of the main job's runs
    from hippo_probe import paper
    from hippo_probe.paper import config as C

    cfg = C.for_run(C.with_cache(C.CONFIGS[a.size], a.cache), a.world, a.seed)
    out = Path(a.out)
    print(f"| {cfg.run} ({a.size}) | stage | seconds | share |\n|---|---|---|---|")
    for name in paper.FIGURES:
        t0 = time.perf_counter()
        profile = cProfile.Profile()
        profile.enable()
        paper.builder(name).make(cfg, out / cfg.run)
        profile.disable()
        total = time.perf_counter() - t0
        path = out / f"{cfg.run}-{name}.prof"
        profile.dump_stats(path)
        stages = stage_seconds(pstats.Stats(str(path)))
        print(f"| {name} | total | {total:.0f} | 100% |")
        for label, seconds in sorted(stages.items(), key=lambda kv: -kv[1]):
            if seconds >= a.min_seconds:
                print(f"| | {label} | {seconds:.0f} | {seconds / total:.0%} |", flush=True)


if __name__ == "__main__":
    main()
