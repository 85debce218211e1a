"""The L1 activity cost of the non-negative variants, chosen by a short sweep.

Each run folder named is one weight of ``scripts/sweep_activity_l1.sh`` (the same task,
seed and step budget, the stopping rule off). For each finished run: its best validation
error, and its units' activity on ``--trials`` generalized test trials (mean ``h``,
fraction of units silent, Treves-Rolls lifetime and population sparseness, as
``hp.map_scorecard`` measures them). The weight kept is the largest whose best validation
error is within ``--tolerance`` (10%) of the unpenalised run's (weight 0): the rule is
fixed here, before the runs.

    python analyses/activity_l1_sweep.py runs/sweep_nonneg_l1_* [--trials 64]
        [--out analyses/data/activity_l1_sweep]

Writes ``<out>/sweep.json``, ``sweep.md`` and ``sweep.png`` (error and sparseness against
the weight).
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp
from hippo_probe._atomic import save_figure, write_text
from hippo_probe.analysis.map_scorecard import treves_rolls
from hippo_probe.tasks import make_trials

SILENT = 1e-3        # a unit whose activity never exceeds this on the trials is silent


def activity_summary(run: Path, n_trials: int) -> dict:
    """Mean activity, silent units and sparseness of the run's network on test trials."""
    net = hp.load_pretrained(run / "network.pt")
    batch = make_trials("generalized", n_trials, "test", 0, world=net.world)
    h = hp.record(net, batch).activity.values               # (time, unit), >= 0
    active = h.max(0) > SILENT
    return {"mean_activity": float(h.mean()),
            "fraction_silent": float(1 - active.mean()),
            "lifetime_sparseness": float(np.median(treves_rolls(h[:, active], 0))),
            "population_sparseness": float(np.nanmean(treves_rolls(h, 1)))}


def summarise(run: Path, n_trials: int) -> dict:
    log = json.loads((run / "log.json").read_text())
    validation = log["validation"]
    best = min(validation, key=lambda v: v["mean_error_m"])
    return {"run": run.name, "weight": log["config"]["activity_l1"],
            "steps": validation[-1]["step"],
            "best_validation_error_m": best["mean_error_m"], "best_step": best["step"],
            "test_error_100s_m": log["test"]["error_100s_m"],
            **activity_summary(run, n_trials)}


def choose(rows, tolerance):
    """The largest weight whose best validation error is within ``tolerance`` of weight
    0's (None without a weight-0 run)."""
    base = [r for r in rows if r["weight"] == 0]
    if not base:
        return None
    limit = (1 + tolerance) * base[0]["best_validation_error_m"]
    return max(r["weight"] for r in rows if r["best_validation_error_m"] <= limit)


def table(rows, chosen, tolerance) -> str:
    header = ("| L1 weight | best validation error (m) | vs weight 0 | test error after "
              "100 s (m) | mean h | silent units | lifetime sparseness | population "
              "sparseness |")
    lines = [header, "|---|---|---|---|---|---|---|---|"]
    base = next((r["best_validation_error_m"] for r in rows if r["weight"] == 0), np.nan)
    for r in rows:
        lines.append(f"| {r['weight']:g}{' (kept)' if r['weight'] == chosen else ''} | "
                     f"{r['best_validation_error_m']:.4f} | "
                     f"{r['best_validation_error_m'] / base - 1:+.1%} | "
                     f"{r['test_error_100s_m']:.4f} | {r['mean_activity']:.4f} | "
                     f"{r['fraction_silent']:.2f} | {r['lifetime_sparseness']:.3f} | "
                     f"{r['population_sparseness']:.3f} |")
    steps = sorted({r["steps"] for r in rows})
    lines += ["", (f"{', '.join(map(str, steps))} steps per run; the weight kept is the "
                   f"largest within {tolerance:.0%} of weight 0's best validation error.")]
    return "\n".join(lines) + "\n"


def plot(rows, chosen):
    w = np.array([r["weight"] for r in rows], float)
    x = np.where(w > 0, w, w[w > 0].min() / 10 if (w > 0).any() else 1e-3)
    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 3.2), layout="constrained")
    a.plot(x, [r["best_validation_error_m"] for r in rows], "o-k")
    a.set(xscale="log", xlabel="L1 weight (0 drawn at the left)",
          ylabel="best validation error (m)")
    if chosen is not None:
        a.axvline(x[w == chosen][0], color="tab:green", ls=":", label="kept")
        a.legend(frameon=False)
    for key, style in (("lifetime_sparseness", "o-"), ("population_sparseness", "s-"),
                       ("fraction_silent", "^-")):
        b.plot(x, [r[key] for r in rows], style, label=key.replace("_", " "))
    b.set(xscale="log", xlabel="L1 weight", ylim=(0, 1))
    b.legend(frameon=False, fontsize=8)
    fig.suptitle("nonneg variant (a departure from the study): L1 activity cost")
    return fig


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="run folders of the sweep")
    ap.add_argument("--trials", type=int, default=64, help="test trials for the activity")
    ap.add_argument("--tolerance", type=float, default=0.10,
                    help="largest loss of validation error accepted, as a fraction")
    ap.add_argument("--out", type=Path, default=Path("analyses/data/activity_l1_sweep"))
    args = ap.parse_args()
    finished = [r for r in args.runs if (r / "log.json").exists()
                and "test" in json.loads((r / "log.json").read_text())]
    for r in sorted(set(args.runs) - set(finished)):
        print(f"(not finished, left out: {r})")
    if not finished:
        raise SystemExit("no finished run among those named")
    rows = sorted((summarise(r, args.trials) for r in finished), key=lambda r: r["weight"])
    chosen = choose(rows, args.tolerance)
    args.out.mkdir(parents=True, exist_ok=True)
    write_text(args.out / "sweep.json", json.dumps({"rows": rows, "kept": chosen,
                                                    "tolerance": args.tolerance}, indent=1))
    text = table(rows, chosen, args.tolerance)
    write_text(args.out / "sweep.md", text)
    save_figure(plot(rows, chosen), args.out / "sweep.png", dpi=120)
    print(text)


if __name__ == "__main__":
    main()
