"""The ablation figure: what the compass takes away, claim by claim.

For each quantitative claim of the study (:func:`hippo_probe.paper.results.rows`), its
headline numbers in the darkness world (the study's: the sensed heading drifts) beside
the compass world (a drift-free heading sense), one point per training seed, a bar at
their mean, and the study's value where it gives one.

Unlike the figure builders, it reads the runs' figure data rather than recordings:
``make(figures_dir, out) -> path of the PNG``, after every run's figures are made.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.pyplot as plt
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
import numpy as np

from .._atomic import save_figure, write_text
from . import config as C
from .results import read_runs, rows

#: Colour of each world's points.
WORLD_COLORS = {"darkness": "k", "compass": "tab:orange"}


def make(figures_dir, out, runs=None) -> Path:
    """Draw ``<out>/ablation.png/.pdf`` and ``ablation.json`` from the runs under
    ``figures_dir`` (``<world>-seed<k>/fig*.json``; only the folders ``runs`` if given);
    returns the PNG's path."""
    runs = read_runs(figures_dir, runs)
    claims = list(rows({}))
    per_world = {w: [list(rows(figs)) for figs in by_seed.values()]
                 for w, by_seed in runs.items()}
    n = len(claims)
    cols = 4
    fig, axes = plt.subplots(-(-n // cols), cols, figsize=(4.2 * cols, 3.3 * -(-n // cols)),
                             constrained_layout=True, squeeze=False)
    numbers = {}
    for i, (claim, ax) in enumerate(zip(claims, axes.ravel())):
        labels = list(claim.headline)
        width = 0.8 / max(len(runs), 1)
        for k, (world, seeds) in enumerate(per_world.items()):
            for j, label in enumerate(labels):
                values = [r[i].headline.get(label) for r in seeds]
                values = np.array([v for v in values if v is not None], float)
                x = j + (k - (len(runs) - 1) / 2) * width
                numbers.setdefault(claim.claim, {}).setdefault(world, {})[label] = \
                    values.tolist()
                if not len(values):       # e.g. no scaling range: say so, not a gap
                    if seeds:
                        ax.annotate("n/a", (x, 0), xytext=(0, 3), textcoords="offset points",
                                    ha="center", va="bottom", rotation=90, fontsize=7,
                                    color=WORLD_COLORS.get(world, "gray"))
                    continue
                ax.bar(x, values.mean(), width * 0.9, color=WORLD_COLORS.get(world, "gray"),
                       alpha=0.25)
                ax.plot(np.full(len(values), x), values, "o", ms=4,
                        color=WORLD_COLORS.get(world, "gray"))
        for j, label in enumerate(labels):
            if label in claim.study:
                ax.hlines(claim.study[label], j - 0.45, j + 0.45, colors="tab:blue",
                          linestyles="--")
        ax.set_xticks(range(len(labels)), labels, rotation=20, ha="right", fontsize=7)
        ax.axhline(0, color="gray", lw=0.5)
        ax.set_title(claim.title or claim.claim, fontsize=9)
        ax.set_ylabel(claim.ylabel, fontsize=8)
    for ax in axes.ravel()[n:]:
        ax.set_axis_off()
    # one legend, off the data: in the grid's empty corner (or below the panels)
    handles = [Patch(color=WORLD_COLORS.get(w, "gray"), alpha=0.4,
                     label=f"{w} world: mean over seeds (bar), each seed (dot)")
               for w in runs]
    handles.append(Line2D([], [], color="tab:blue", ls="--", label="the study's value"))
    if n < axes.size:
        axes.ravel()[-1].legend(handles=handles, loc="center", frameon=False, fontsize=9)
    else:
        fig.legend(handles=handles, loc="outside lower center", ncols=len(handles),
                   frameon=False)
    fig.suptitle("What the compass takes away: each claim's numbers in the darkness world "
                 "(the study's) and the compass world, one point per training seed")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    png = save_figure(fig, out / "ablation.png", dpi=130)
    save_figure(fig, out / "ablation.pdf")
    plt.close(fig)
    write_text(out / "ablation.json", json.dumps(C.jsonable(
        {"figure": "ablation", "runs": {w: list(s) for w, s in runs.items()},
         "headlines": numbers}), indent=1), what="figure data")
    print(f"  wrote {out / 'ablation'}.png/.pdf/.json")
    return png

