"""Figure 2: localization in a familiar arena (mean radius 1 m), start unknown.

Euclidean, radial and angular error vs time in trial of the localization network, the
oracular particle filter, single hypothesis and path integration, on the test split.

The builder of ``hippo-probe figures --only fig2`` and of the script
``paper_figures/fig2.py``; contract in :mod:`hippo_probe.paper`.
"""

import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp

from . import config as C

ESTIMATES = ["estimate", "estimate_pf", "estimate_sh", "estimate_pi"]


def make(cfg, out):
    """Draw the figure into ``out``; returns the numbers written to its JSON."""
    cfg = C.cached_under(cfg, out)
    rec = C.recording("localization", cfg)
    err = hp.localization_error(rec, estimate=ESTIMATES)
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), constrained_layout=True)
    t = err.trial_time.values
    numbers = {"trial_time_s": t, "n_trials": int(rec.sizes["trial_id"])}
    hp.plot.error_curves(err, colors=C.COLORS, labels=C.LABELS, degrees=True, axes=axes)
    for kind in ("euclidean", "radial", "angular"):
        scale = np.degrees(1) if kind == "angular" else 1.0
        for name in ESTIMATES:
            numbers.setdefault(kind, {})[C.LABELS[name]] = \
                err[kind].sel(estimate=name).values * scale
    # one legend for the three panels, below them: every corner of a panel holds a curve
    axes[0].get_legend().remove()
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center",
               ncols=len(ESTIMATES), frameon=False, fontsize=9)
    fig.suptitle("Fig. 2 — localization in a familiar arena (mean radius 1 m, start "
                 "unknown), "
                 f"{numbers['n_trials']} test trials, mean ± s.e.m.")
    numbers["summary"] = {
        C.LABELS[n]: C.at_times(t, err.euclidean.sel(estimate=n).values) for n in ESTIMATES}
    late = t > 100
    numbers["summary"]["network / PF error, t > 100 s"] = float(
        err.euclidean.sel(estimate="estimate").values[late].mean()
        / err.euclidean.sel(estimate="estimate_pf").values[late].mean())
    C.save(fig, "fig2", numbers, cfg, out)
    return numbers

