"""When does a variant's localization fall behind the study's network? Validation curves.

The map-ingredient variants and their reference (``generalized_faithful``: the study's
network trained the variants' 20,000 steps) side by side, every shipped seed of each: the
validation error the trainer measured every 250 steps on the generalized task's
1,000-trial validation split of the darkness world, read from the shipped training logs
(:func:`hippo_probe.pretrained.summary.training_log`; nothing is recomputed). The table
gives each network's error at a few steps (the mean over its seeds, their range in
brackets).

    python analyses/variant_learning_curves.py [--steps 4000 8000 12000 20000]
        [--out analyses/data/map_ingredients]

Writes ``<out>/learning_curves.png`` and ``<out>/learning_curves.md``.
"""

import argparse
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from hippo_probe._atomic import save_figure, write_text
from hippo_probe.pretrained import shipped_seeds
from hippo_probe.pretrained.summary import spread_text, training_log

ROOT = Path(__file__).resolve().parents[1]
#: The networks compared, with their line colours; the reference first.
NETWORKS = {"generalized_faithful": "black", "generalized_nonneg": "tab:orange",
            "generalized_dale": "tab:red", "generalized_placecells": "tab:blue"}


def curves(name):
    """Per shipped seed of ``name``: (steps, validation error in m)."""
    out = {}
    for seed in shipped_seeds(name):
        val = training_log(name, seed)["validation"]
        out[seed] = (np.array([v["step"] for v in val]),
                     np.array([v["mean_error_m"] for v in val]))
    return out


def error_at(curve, step):
    """The validation error at ``step`` (NaN where the run has no validation there)."""
    steps, errors = curve
    hit = np.flatnonzero(steps == step)
    return float(errors[hit[0]]) if hit.size else float("nan")


def table(all_curves, steps):
    """Markdown: each network's error at ``steps``, mean (min–max) over its seeds."""
    lines = ["| network | seeds | " + " | ".join(f"{s:,} steps" for s in steps) + " |",
             "|---" * (len(steps) + 2) + "|"]
    for name, by_seed in all_curves.items():
        cells = [spread_text([v for v in (error_at(c, step) for c in by_seed.values())
                              if np.isfinite(v)], 3) for step in steps]
        lines.append(f"| `{name}` | {len(by_seed)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, nargs="+", default=[4000, 8000, 12000, 20000],
                    help="steps at which the table gives each network's error")
    ap.add_argument("--out", default=str(ROOT / "analyses" / "data" / "map_ingredients"))
    a = ap.parse_args()
    all_curves = {name: curves(name) for name in NETWORKS}
    validated = {int(k) for by_seed in all_curves.values() for steps, _ in by_seed.values()
                 for k in steps}
    missing = sorted(set(a.steps) - validated)
    if missing:
        ap.error(f"--steps {missing} are not steps at which the logs hold a validation "
                 f"(every 250 steps, 0 to 20,000)")
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    for name, by_seed in all_curves.items():
        for k, (seed, (steps, errors)) in enumerate(by_seed.items()):
            ax.plot(steps, errors, color=NETWORKS[name], lw=1.2 if seed == 0 else 0.7,
                    alpha=1.0 if seed == 0 else 0.6,
                    label=f"{name} ({len(by_seed)} seed{'s' * (len(by_seed) > 1)})"
                    if k == 0 else None)
    # the first validations (0.25-0.43 m at step 0) lie above the plot: the range shown
    # is the one where the networks part
    ax.set(xlabel="optimizer step", ylabel="validation error (m)", ylim=(0.08, 0.22),
           title="generalized task, darkness world: validation error while training "
                 "(1,000 trials; the first steps' errors are above the top)")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=8, frameon=False)
    out = Path(a.out)
    save_figure(fig, out / "learning_curves.png", dpi=120)
    plt.close(fig)
    text = table(all_curves, a.steps)
    write_text(out / "learning_curves.md", text, what="--out")
    print(text, end="")


if __name__ == "__main__":
    main()
