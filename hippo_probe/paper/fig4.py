"""Figure 4: the networks' units recorded like cells.

A-B rate maps of example units measured twice in one arena (two disjoint sets of trials)
and once in another — A specialized network (familiar arenas), B generalized network
(novel arenas) — with place-field stability across all units; C head-direction tuning of
20 units; D cumulative population-vector similarity within vs across environments, with
the label-shuffled control; E distribution of spatial selectivity and, inset,
selectivity vs projection strength onto the arena classifier.

The builder of ``hippo-probe figures --only fig4`` and of the script
``paper_figures/fig4.py``; contract in :mod:`hippo_probe.paper`.
"""

import warnings

import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp

from . import config as C

N_EXAMPLES = 4
BIN = 0.05          # m: 5 cm bins in the 0.33 m arenas
SIGMA = 1.0         # bins
HD_UNITS_SHOWN = 10  # the most tuned units' polar plots, in two rows of five


def _three_maps(rec):
    """Maps of every unit in arena A (first half of its trials), A (second half), B."""
    env = rec.trial_environment.values
    ids = rec.trial_id.values
    arenas = np.unique(env)
    a, b = arenas[0], arenas[1]
    in_a = ids[env == a]
    half = len(in_a) // 2
    sets = [in_a[:half], in_a[half:], ids[env == b]]
    v = rec.arena_vertices.sel(environment_id=[a, b]).values.reshape(-1, 2)
    ext = (v[:, 0].min(), v[:, 0].max(), v[:, 1].min(), v[:, 1].max())   # one grid for all
    maps = [hp.ratemaps(hp.select_trials(rec, trials=s), bin_size=BIN, sigma=SIGMA,
                        extent=ext) for s in sets]
    return maps, (a, b)


def _corr(m1, m2, min_bins=5):
    """Per-unit Pearson correlation of two rate maps over the bins both visited."""
    from hippo_probe.analysis.place_field_stability import pearson_masked
    x, y = m1.values.reshape(len(m1.unit), -1), m2.values.reshape(len(m2.unit), -1)
    return pearson_masked(x, y, min_bins)[0]


def _maps_panel(sub, rec, title, numbers, key):
    maps, (a, b) = _three_maps(rec)
    same = _corr(maps[0], maps[1])
    across = _corr(maps[0], maps[2])
    with warnings.catch_warnings():
        # the two arenas pooled on purpose: the examples are the units whose activity
        # position explains best over both
        warnings.filterwarnings("ignore", "the recording spans", hp.AnalysisWarning)
        sel = hp.spatial_selectivity(rec, bin_size=BIN).selectivity
    sel = sel.max(dim=[d for d in sel.dims if d != "unit"]) if sel.ndim > 1 else sel
    examples = np.argsort(-np.nan_to_num(sel.values))[:N_EXAMPLES]
    gs = sub.add_gridspec(N_EXAMPLES, 4, width_ratios=[1, 1, 1, 2.2], wspace=0.05,
                          hspace=0.1)
    fig = sub
    verts = rec.arena_vertices
    for row, u in enumerate(examples):
        # one colour scale per unit across its three maps, so A-vs-B differences show
        imgs = [m.isel(unit=u) for m in maps]
        lo = min(float(i.min()) for i in imgs)
        hi = max(float(i.max()) for i in imgs)
        for col, (img, env) in enumerate(zip(imgs, (a, a, b))):
            ax = fig.add_subplot(gs[row, col])
            mesh = ax.pcolormesh(img.x, img.y, (img - lo) / (hi - lo or 1.0),
                                 shading="nearest", cmap="viridis", vmin=0, vmax=1)
            v = verts.sel(environment_id=env).values
            ax.plot(*np.vstack([v, v[:1]]).T, color="k", lw=0.8)
            ax.set_aspect("equal")
            ax.set_xticks([])
            ax.set_yticks([])
            if row == 0:
                ax.set_title(["arena A, trial set 1", "arena A, trial set 2", "arena B"][col],
                             fontsize=7)
            if col == 0:
                ax.set_ylabel(f"unit {int(rec.unit[u])}", fontsize=7)
    fig.colorbar(mesh, ax=list(fig.axes), shrink=0.5, pad=0.02,
                 label="activity, scaled per unit (0 = min, 1 = max)").ax.tick_params(
                     labelsize=6)
    ax = fig.add_subplot(gs[:, 3])
    hp.plot.cumulative({"A vs A": same, "A vs B": across}, medians=True, ax=ax,
                       styles={"A vs A": {"color": "k"}, "A vs B": {"color": "tab:red"}},
                       xlabel="rate-map correlation (Pearson)",
                       ylabel="cumulative fraction of units",
                       title="stability across all units")
    ax.tick_params(labelsize=7)
    ax.xaxis.label.set_fontsize(8)
    ax.yaxis.label.set_fontsize(8)
    ax.legend(frameon=False, fontsize=8)
    sub.suptitle(f"{title} (the {N_EXAMPLES} most spatially selective units)", fontsize=10,
                 x=0.02, ha="left")
    numbers[key] = {"stability_same_arena_median": float(np.nanmedian(same)),
                    "correlation_across_arenas_median": float(np.nanmedian(across)),
                    "example_units": rec.unit.values[examples]}


def make(cfg, out):
    """Draw the figure into ``out``; returns the numbers written to its JSON."""
    cfg = C.cached_under(cfg, out)
    numbers = {}
    spec_maps = C.recording("specialized_maps", cfg)
    gen_maps = C.recording("generalized_maps", cfg)
    many = C.recording("specialized_many", cfg)

    fig = plt.figure(figsize=(15, 13), layout="constrained")
    rows = fig.subfigures(3, 1, height_ratios=[1, 1, 0.85])
    top = rows[0].subfigures(1, 2, width_ratios=[1.6, 1])
    mid = rows[1].subfigures(1, 2, width_ratios=[1.6, 1])
    bottom = rows[2].subfigures(1, 2, width_ratios=[1, 1.6])
    _maps_panel(top[0], spec_maps, "A  specialized network: rate maps of example units",
                numbers, "A")
    _maps_panel(mid[0], gen_maps, "B  generalized network in novel arenas", numbers, "B")

    hd = hp.head_direction_tuning(many, n_bins=60)
    mvl = hd.mean_vector_length.values.ravel()
    # two rows: polar plots large enough to read a weak tuning's shape
    show = np.argsort(-np.nan_to_num(mvl))[:HD_UNITS_SHOWN]
    hp.plot.hd_polar(hd, units=many.unit.values[show], max_cols=5, fig=top[1])
    # after hd_polar, whose own title this replaces
    top[1].suptitle(f"C1  head-direction tuning of the {len(show)} most tuned units "
                    "(specialized "
                    "network, 60 bins;\nradius from 0 = the unit's minimum, 0° = +x, "
                    "counter-clockwise)", fontsize=10)
    numbers["C_mean_vector_length"] = {
        "median_all_units": float(np.nanmedian(mvl)),
        "max": float(np.nanmax(mvl)), "shown_units": many.unit.values[show],
        "fraction_R_gt_0.3": float(np.mean(mvl > 0.3)),
        "fraction_significant_p_lt_0.01": float(np.mean(hd.p_value.values < 0.01)),
        "n_shuffles": int(hd.attrs["n_shuffles"])}

    ax = mid[1].add_subplot(1, 1, 1)
    ax.hist(mvl, bins=30, color="gray")
    ax.set_xlabel("mean vector length R (from the tuning curve)")
    ax.set_ylabel("units")
    ax.set_title("C2  R of all units (specialized network)\n"
                 f"{np.mean(hd.p_value.values < 0.01):.0%} significant: p < 0.01 against "
                 f"{hd.attrs['n_shuffles']} time-shift shuffles", fontsize=9)

    ax = bottom[0].add_subplot(1, 1, 1)
    colours = {"same": "tab:blue", "different": "tab:orange"}
    groups, styles = {}, {}
    for centred, style in ((False, ":"), (True, "-")):
        sim = hp.remapping_similarity(many, center_units=centred)
        s = sim.similarity.values
        kind = "units centred" if centred else "raw, not centred"
        for name, mask in (("same", sim.same_environment.values),
                           ("different", ~sim.same_environment.values)):
            label = f"{name} arena ({kind})"
            groups[label] = s[mask]
            styles[label] = {"color": colours[name], "ls": style}
        if centred:     # the control: labels permuted, all pairs of the centred measure
            label = "same arena, labels shuffled (centred)"
            groups[label] = s[sim.same_environment_permuted.values]
            styles[label] = {"color": "gray", "ls": "--"}
        key = "D_similarity_units_centred" if centred else "D_similarity"
        numbers[key] = {c: float(sim["mean"].sel(comparison=c))
                        for c in sim.comparison.values}
    hp.plot.cumulative(groups, styles=styles, ax=ax,
                       xlabel="population-vector correlation between trials",
                       ylabel="cumulative fraction of trial pairs")
    ax.set_title("D remapping (specialized network); centred: each unit's mean removed",
                 fontsize=9)
    # the top left is empty: the different-arena curves reach it only right of x = 0.3
    ax.legend(frameon=False, fontsize=6.5, loc="upper left")

    ctx = hp.context_cells(many)
    ax, scatter = bottom[1].subplots(1, 2)
    sel = ctx.spatial_selectivity.values
    ax.hist(sel[np.isfinite(sel)], bins=30, color="tab:blue")
    ax.set_xlabel("spatial selectivity (variance explained by position)")
    ax.set_ylabel("units")
    ax.set_title("E1  spatial selectivity (specialized network)", fontsize=9)
    rho = ctx.attrs.get("rank_correlation")
    p = ctx.attrs.get("rank_correlation_p")
    scatter.scatter(ctx.projection_strength, sel, s=6, color="k")
    scatter.set_xlabel("projection strength onto the arena classifier")
    scatter.set_ylabel("spatial selectivity")
    scatter.set_title(f"E2  selectivity vs projection: Spearman ρ = {rho:.2f}\n"
                      f"(p = {p:.2g}, n = {np.isfinite(sel).sum()} units)", fontsize=9)
    numbers["E"] = {"selectivity_median": float(np.nanmedian(sel)),
                    "rank_correlation": rho,
                    "rank_correlation_p": ctx.attrs.get("rank_correlation_p")}
    fig.suptitle("Fig. 4 — hidden units recorded like cells")
    C.save(fig, "fig4", numbers, cfg, out)
    return numbers

