"""Localization error of networks beside the oracular particle filter, on the same trials.

The oracular particle filter (the library's defaults, as in the figures) runs once on
``--trials`` test trials of the generalized task; every network named (a shipped name,
``name@seed``, or a ``.pt`` file / run folder) is recorded on the same trials. For each:
the mean error at 50 / 100 / 200 s and Fig. 3A's ratio, network / PF error averaged over
t > 100 s (``hippo_probe.paper.fig3``'s definition).

    python analyses/localization_vs_pf.py generalized runs/generalized_s0_continued \\
        [--trials 1000] [--out analyses/data/continued_training/localization.json]
"""

import argparse
import json
from pathlib import Path

import numpy as np

import hippo_probe as hp
from hippo_probe._atomic import write_text
from hippo_probe.paper.config import baseline_estimates
from hippo_probe.tasks import make_trials, task_config

TIMES_S = (50, 100, 200)


def load(name: str):
    """A network by shipped name (``name`` or ``name@seed``) or path."""
    if Path(name).exists():
        return hp.load_pretrained(Path(name))
    base, _, seed = name.partition("@")
    return hp.load_pretrained(base, int(seed) if seed else None)


def pf_estimate(batch):
    """The oracular particle filter's estimate in the arena frame, as the figures run it."""
    return baseline_estimates(batch, ("pf",), None)["estimate_pf"]


def errors(net, batch, pf) -> dict:
    """Mean error at ``TIMES_S`` and the network / PF ratio over t > 100 s."""
    rec = hp.record(net, batch, baselines={"estimate_pf": pf})
    err = hp.localization_error(rec, ["estimate", "estimate_pf"]).euclidean
    t = err.trial_time.values
    late = t > 100
    out = {f"error_{s}s_m": float(err.sel(estimate="estimate")[np.argmin(abs(t - s))])
           for s in TIMES_S}
    out.update({f"pf_error_{s}s_m": float(err.sel(estimate="estimate_pf")[np.argmin(abs(t - s))])
                for s in TIMES_S})
    out["ratio_to_pf_t_gt_100s"] = float(err.sel(estimate="estimate")[late].mean()
                                         / err.sel(estimate="estimate_pf")[late].mean())
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("networks", nargs="+", help="shipped names (name@seed) or .pt files")
    ap.add_argument("--trials", type=int, default=1000, help="generalized test trials")
    ap.add_argument("--out", type=Path,
                    default=Path("analyses/data/continued_training/localization.json"))
    args = ap.parse_args()
    nets = {name: load(name) for name in args.networks}
    worlds = {net.world for net in nets.values()}
    if len(worlds) != 1:
        raise SystemExit(f"the networks are of several worlds ({sorted(worlds)}); name "
                         f"networks of one world")
    # the figures' trials: seed 0 of the test split, the world's task configuration
    batch = make_trials("generalized", args.trials, "test", 0,
                        config=task_config("generalized", worlds.pop()))
    pf = pf_estimate(batch)
    rows = {name: errors(net, batch, pf) for name, net in nets.items()}
    for name, row in rows.items():
        print(f"{name}: " + ", ".join(f"{k} {v:.4f}" for k, v in row.items()))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_text(args.out, json.dumps({"trials": args.trials, "results": rows}, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
