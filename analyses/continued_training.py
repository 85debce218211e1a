"""A network trained on from a shipped one: validation error and arena code against step.

Reads the shipped network's training log and the continued run's (``--run``: its
``log.json``, or its ``checkpoint.pt`` while it trains) and draws, against the total step
(the shipped run's steps, then the continuation's), the validation error and the arena
code: for a generalized network, the arena probe fitted on the run's snapshots
(``analyses/arena_readout.py --networks <shipped .pt> <run>/snapshots/step_*.pt --sizes
2000 --taus inf --kinds h leaky --out <probe>``); for a specialized network, its own
classifier's validation accuracy averaged over the trial.

    python analyses/continued_training.py [--base generalized] \\
        [--run runs/generalized_s0_continued] [--probe analyses/data/arena_probe_steps] \\
        [--out analyses/data/continued_training]
    python analyses/continued_training.py --base specialized \\
        --run runs/specialized_s0_continued --out analyses/data/continued_training_specialized

Writes ``<out>/continued_training.png`` and ``continued_training.json``.
"""

import argparse
import json
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from hippo_probe._atomic import save_figure, write_text
from hippo_probe.model import checkpoint
from hippo_probe.pretrained import resolve_network_file

LATE_S = 200.0          # the probe's accuracy is read at this time in the trial


def validation(log, key: str = "mean_error_m") -> list[tuple[int, float]]:
    return [(v["step"], v[key]) for v in log["validation"]]


def run_log(run: Path) -> dict:
    if (run / "log.json").exists():
        return json.loads((run / "log.json").read_text())
    return checkpoint.load(run / "checkpoint.pt")["log"]


def probe_by_step(probe: Path, run_name: str, base_name: str) -> dict:
    """{continuation step: {kind: test accuracy at LATE_S}} from the probe's JSON files:
    the run's snapshots (``<run>_step_NNNNNN``) and the shipped network (step 0)."""
    out = {}
    for path in sorted(probe.glob("*.json")):
        res = json.loads(path.read_text())
        if "kinds" not in res:
            continue
        name = res["network"]
        match = re.match(rf"{re.escape(run_name)}_step_(\d+)", name)
        if match is None and not re.fullmatch(rf"(.+_)?{re.escape(base_name)}", name):
            continue
        step = int(match.group(1)) if match else 0
        if step in out:
            raise SystemExit(f"two probe results for step {step} in {probe}: keep one")
        acc = {}
        for kind, curve in res["kinds"].items():
            row = curve["rows"][-1]
            times = curve["times"]
            acc[kind] = row["test_accuracy"][min(range(len(times)),
                                                 key=lambda i: abs(times[i] - LATE_S))]
        out[step] = acc
    return dict(sorted(out.items()))


def plot_both_runs(ax, base, cont, offset):
    """A validation curve of the shipped run, then of its continuation after ``offset``."""
    ax.plot(*zip(*base), color="0.5", lw=1, label="shipped run")
    ax.plot([offset + s for s, _ in cont], [v for _, v in cont], color="k", lw=1,
            label="trained on (fresh schedule)")
    ax.axvline(offset, color="tab:blue", ls=":", lw=1)


def plot(base, cont, offset, probe, label, accuracy=None):
    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6), layout="constrained")
    plot_both_runs(a, base, cont, offset)
    a.set(xlabel="training step", ylabel="validation error (m)", yscale="log",
          title=f"{label}: validation error")
    a.legend(frameon=False)
    if accuracy is not None:
        # a specialized network: its own classifier, validation trials, mean over the trial
        plot_both_runs(b, *accuracy, offset)
        b.set(xlabel="training step", ylabel="validation arena accuracy (mean over trial)",
              title="arena classification (chance 0.01)")
        b.legend(frameon=False, fontsize=8)
        return fig
    steps = [offset + s for s in probe]
    for kind, style in (("h", "o-k"), ("leaky_inf", "s-")):
        values = [acc.get(kind) for acc in probe.values()]
        if any(v is not None for v in values):
            b.plot(steps, values, style, label={"h": "units h at 200 s (the study's)",
                                                "leaky_inf": "running mean of h "
                                                             "(variant)"}[kind])
    b.axvline(offset, color="tab:blue", ls=":", lw=1)
    b.set(xlabel="training step", ylabel="arena probe accuracy (2,000 trials)",
          ylim=(0, None), title="arena probe (chance 0.01)")
    b.legend(frameon=False, fontsize=8)
    return fig


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--base", default="generalized", help="the shipped network trained on")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--run", type=Path, default=Path("runs/generalized_s0_continued"))
    ap.add_argument("--probe", type=Path, default=Path("analyses/data/arena_probe_steps"))
    ap.add_argument("--out", type=Path, default=Path("analyses/data/continued_training"))
    a = ap.parse_args()
    shipped = resolve_network_file(a.base, a.seed)
    base_log = json.loads(shipped.with_suffix(".log.json").read_text())
    log = run_log(a.run)
    base, cont = validation(base_log), validation(log)
    offset = log["base_network"].get("steps_done") or base[-1][0]
    classifies = "mean_accuracy" in log["validation"][0]
    accuracy = ((validation(base_log, "mean_accuracy"), validation(log, "mean_accuracy"))
                if classifies else None)
    probe = {} if classifies else probe_by_step(a.probe, a.run.name, shipped.stem)
    a.out.mkdir(parents=True, exist_ok=True)
    fig = plot(base, cont, offset, probe, f"{a.base} seed {a.seed}", accuracy)
    save_figure(fig, a.out / "continued_training.png", dpi=120)
    summary = {"base": a.base, "seed": a.seed, "base_steps": offset,
               "continued_steps": cont[-1][0], "stopped": log.get("stopped"),
               "validation_error_at_restart_m": dict(cont).get(0),
               "best_validation_error_m": min(e for _, e in cont),
               "best_step": min(cont, key=lambda v: v[1])[0],
               "test": log.get("test"), "test_before": base_log.get("test")}
    if classifies:
        cont_acc = accuracy[1]
        summary.update(validation_accuracy_at_restart=dict(cont_acc).get(0),
                       best_validation_accuracy=max(v for _, v in cont_acc),
                       best_accuracy_step=max(cont_acc, key=lambda v: v[1])[0])
    else:
        summary["probe_accuracy_at_200s"] = {str(offset + s): v for s, v in probe.items()}
    write_text(a.out / "continued_training.json", json.dumps(summary, indent=1))
    print(json.dumps({k: v for k, v in summary.items() if not k.startswith("test")},
                     indent=1))


if __name__ == "__main__":
    main()
