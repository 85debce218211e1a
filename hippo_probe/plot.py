"""Plots of analysis results, and the ``.hp`` xarray accessor so results plot themselves.

>>> maps = hp.ratemaps(rec)          # doctest: +SKIP
>>> fig = maps.hp.plot()             # doctest: +SKIP

Every helper returns the matplotlib Figure and labels its axes from the result's
``units`` and ``long_name`` attrs. matplotlib is imported on first use only, so importing
the analyses stays light.
"""

from __future__ import annotations

import numpy as np
import xarray as xr


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _label(da, default=""):
    """'long_name (units)' of a DataArray or coordinate."""
    attrs = getattr(da, "attrs", {})
    name = attrs.get("long_name", getattr(da, "name", None) or default)
    units = attrs.get("units")
    return f"{name} ({units})" if units not in (None, "", "1") else str(name)


def _grid(n, max_cols):
    cols = min(n, max_cols)
    return cols, int(np.ceil(n / cols))


def _outline(maps, group_dim, label):
    """Arena outline (V, 2) of the environment of maps already reduced to one group, or
    None when it is unknown or ambiguous (several arenas pooled)."""
    verts = maps.attrs.get("arena_vertices")
    envs = maps.attrs.get("arena_environment")
    if verts is None or envs is None:
        return None
    verts, envs = np.asarray(verts), np.asarray(envs)
    if group_dim == "environment":
        env = label
    elif "environment" in maps.coords and maps["environment"].ndim == 0:
        env = maps["environment"].item()  # e.g. the environment of a trial's map
    elif len(envs) == 1:
        env = envs[0]
    else:
        return None
    hit = np.flatnonzero(envs == env)
    return verts[hit[0]] if hit.size else None


def ratemap_grid(maps, *, units=None, group=None, max_cols=8, cmap="viridis", panel=1.6,
                 scale="unit"):
    """A grid of rate maps, one panel per unit, with the arena outline when known.

    Parameters
    ----------
    maps : xarray.DataArray
        Output of :func:`hippo_probe.ratemaps` (unit, [group], y, x).
    units : sequence, optional
        Unit ids to show (default: all, at most 64).
    group : label, optional
        Which environment/trial to show when the maps have a group dim (default: the first).
    scale : {"unit", "shared"}
        Colour scale per panel (each map from its minimum to its maximum, written in the
        title) or one scale for all panels, with a colour bar.
    """
    plt = _plt()
    group_dim = next((d for d in maps.dims if d not in ("unit", "y", "x")), None)
    label = None
    if group_dim is not None:
        label = maps[group_dim].values[0] if group is None else group
        maps = maps.sel({group_dim: label})
    if units is not None:
        maps = maps.sel(unit=list(units))
    maps = maps.isel(unit=slice(0, 64))
    cols, rows = _grid(maps.sizes["unit"], max_cols)
    fig, axes = plt.subplots(rows, cols, figsize=(panel * cols, panel * rows + 0.4),
                             squeeze=False)
    outline = _outline(maps, group_dim, label)
    x, y = maps["x"].values, maps["y"].values
    half = (x[1] - x[0]) / 2 if len(x) > 1 else 0.5
    ext = (x[0] - half, x[-1] + half, y[0] - half, y[-1] + half)
    colours = plt.get_cmap(cmap).with_extremes(bad="white")  # unvisited bins
    pad = 0.04 * max(ext[1] - ext[0], ext[3] - ext[2])
    shared = dict(vmin=float(maps.min()), vmax=float(maps.max())) if scale == "shared" \
        else {}
    for ax, u in zip(axes.flat, maps["unit"].values):
        m = maps.sel(unit=u)
        im = ax.imshow(m.values, origin="lower", extent=ext, cmap=colours,
                       interpolation="nearest", **shared)
        if outline is not None:
            closed = np.vstack([outline, outline[:1]])
            ax.plot(closed[:, 0], closed[:, 1], color="0.2", lw=0.8)
        ax.set_xlim(ext[0] - pad, ext[1] + pad)
        ax.set_ylim(ext[2] - pad, ext[3] + pad)
        for spine in ax.spines.values():
            spine.set_visible(False)
        if np.isfinite(m.values).any():
            ax.set_title(f"{u}  {np.nanmin(m.values):.2g}..{np.nanmax(m.values):.2g}",
                         fontsize=7)
        else:
            ax.set_title(f"{u}  (no data)", fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[maps.sizes["unit"]:]:
        ax.axis("off")
    title = _label(maps, "rate")
    if group_dim is not None:
        title += f" — {group_dim} {label}"
    fig.suptitle(title, fontsize=9)
    corner = axes[-1, 0] if (rows - 1) * cols < maps.sizes["unit"] else axes[0, 0]
    corner.set_xlabel(_label(maps["x"]), fontsize=7)
    corner.set_ylabel(_label(maps["y"]), fontsize=7)
    if scale == "shared":
        fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.6, label=_label(maps))
    return fig


def hd_polar(tuning, *, units=None, max_cols=6, panel=1.8):
    """Polar plots of head-direction tuning curves, one per unit, titled with R and the
    preferred direction.

    Parameters
    ----------
    tuning : xarray.Dataset or DataArray
        Output of :func:`hippo_probe.head_direction_tuning` (or its ``tuning_curve``).
    units : sequence, optional
        Unit ids to show (default: all, at most 48).
    """
    plt = _plt()
    curves = tuning["tuning_curve"] if isinstance(tuning, xr.Dataset) else tuning
    extra = [d for d in curves.dims if d not in ("unit", "direction")]
    if extra:
        curves = curves.isel({d: 0 for d in extra})
    if units is not None:
        curves = curves.sel(unit=list(units))
    curves = curves.isel(unit=slice(0, 48))
    cols, rows = _grid(curves.sizes["unit"], max_cols)
    fig, axes = plt.subplots(rows, cols, figsize=(panel * cols, panel * rows + 0.4),
                             subplot_kw={"projection": "polar"}, squeeze=False)
    theta = curves["direction"].values
    closed = np.r_[theta, theta[:1]]
    for ax, u in zip(axes.flat, curves["unit"].values):
        r = curves.sel(unit=u).values
        ax.plot(closed, np.r_[r, r[:1]], lw=1)
        title = f"{u}"
        if isinstance(tuning, xr.Dataset) and "mean_vector_length" in tuning:
            sel = {d: tuning[d].values[0] for d in extra}
            length = tuning["mean_vector_length"].sel(unit=u, **sel).item()
            pref = tuning["preferred_direction"].sel(unit=u, **sel).item()
            title += f"  R={length:.2f} {np.degrees(pref):.0f}\N{DEGREE SIGN}"
        ax.set_title(title, fontsize=7)
        ax.set_xticks(np.radians([0, 90, 180, 270]))
        ax.tick_params(labelsize=6)
    for ax in list(axes.flat)[curves.sizes["unit"]:]:
        ax.axis("off")
    fig.suptitle(f"{_label(curves)} vs {_label(curves['direction'])}", fontsize=9)
    fig.tight_layout()
    return fig


def cumulative(values, *, xlabel="", title="", ax=None):
    """Empirical cumulative distributions, one line per entry of ``values``.

    Parameters
    ----------
    values : dict of label -> array, or a DataArray (one line)
        NaNs are left out (and counted in the legend).
    """
    plt = _plt()
    if isinstance(values, xr.DataArray):
        xlabel = xlabel or _label(values)
        values = {values.name or "values": values.values}
    fig = ax.figure if ax is not None else plt.subplots(figsize=(4, 3))[0]
    ax = ax or fig.axes[0]
    for label, v in values.items():
        v = np.asarray(v, float).ravel()
        ok = np.sort(v[np.isfinite(v)])
        if not ok.size:
            continue
        y = np.arange(1, ok.size + 1) / ok.size
        dropped = v.size - ok.size
        ax.step(ok, y, where="post", label=f"{label} (n={ok.size}"
                + (f", {dropped} NaN)" if dropped else ")"))
    ax.set_xlabel(xlabel)
    ax.set_ylabel("cumulative fraction")
    ax.set_ylim(0, 1.02)
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig


def remapping_cdf(sim):
    """Cumulative distributions of trial-pair similarity: same vs different environment,
    and the label-permuted control."""
    s = sim["similarity"]
    same, perm = sim["same_environment"].values, sim["same_environment_permuted"].values
    groups = {"same environment": s.values[same], "different environment": s.values[~same],
              "same (labels permuted)": s.values[perm],
              "different (labels permuted)": s.values[~perm]}
    fig = cumulative(groups, xlabel=_label(s), title="remapping")
    for line in fig.axes[0].get_lines()[2:]:
        line.set_linestyle("--")
    fig.axes[0].legend(fontsize=7, frameon=False)
    return fig


def error_curves(err, *, variables=("euclidean", "radial", "angular")):
    """Localization error vs time in trial (mean +- s.e.m. over trials), one panel per
    kind of error, one line per estimate."""
    plt = _plt()
    variables = [v for v in variables if v in err]
    fig, axes = plt.subplots(1, len(variables), figsize=(3.4 * len(variables), 2.8),
                             squeeze=False)
    t = err["trial_time"].values
    for ax, name in zip(axes[0], variables):
        da = err[name]
        if "estimate" in da.dims:
            lines = da.transpose("estimate", "trial_time")
        else:
            names = err.attrs.get("estimate", ["estimate"])
            lines = da.expand_dims(estimate=[names[0] if isinstance(names, list) else names])
        sem = err.get(f"{name}_sem")
        for i, label in enumerate(lines["estimate"].values):
            y = lines.values[i]
            ax.plot(t, y, lw=1, label=str(label))
            if sem is not None:
                e = sem.values[i] if "estimate" in sem.dims else sem.values
                ax.fill_between(t, y - e, y + e, alpha=0.25, lw=0)
        ax.set_xlabel(_label(err["trial_time"]))
        ax.set_ylabel(_label(da))
    if "estimate" in err.dims:
        axes[0, 0].legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig


def accuracy_curve(acc):
    """Classification accuracy vs time in trial, with chance level."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(4, 3))
    t = acc["trial_time"].values
    ax.plot(t, acc["accuracy"].values, label="accuracy")
    if "accuracy_sem" in acc:
        y, e = acc["accuracy"].values, acc["accuracy_sem"].values
        ax.fill_between(t, y - e, y + e, alpha=0.25, lw=0)
    if "true_class_probability" in acc:
        ax.plot(t, acc["true_class_probability"].values, lw=1,
                label=acc["true_class_probability"].attrs.get("long_name", ""))
    if "chance" in acc.attrs:
        ax.axhline(acc.attrs["chance"], color="0.5", ls=":", label="chance")
    ax.set_xlabel(_label(acc["trial_time"]))
    ax.set_ylabel(_label(acc["accuracy"]))
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=7, frameon=False)
    fig.tight_layout()
    return fig


def correlation_sum(res):
    """log C(r) vs log r with the scaling range and its slope D, and the local slopes."""
    plt = _plt()
    fig, (a, b) = plt.subplots(1, 2, figsize=(7, 3))
    x = res["log_r"].values
    a.plot(x, res["log_c"].values, ".", ms=2)
    b.plot(x, res["local_slope"].values, lw=1)
    d = res.attrs.get("dimension", np.nan)
    if np.isfinite(d):
        lo, hi = np.log10(res.attrs["r_min"]), np.log10(res.attrs["r_max"])
        for ax in (a, b):
            ax.axvspan(lo, hi, color="C1", alpha=0.2, lw=0)
        b.axhline(d, color="C1", ls="--")
        a.set_title(f"D = {d:.2f}", fontsize=9)
    a.set_xlabel(_label(res["log_r"]))
    a.set_ylabel(_label(res["log_c"]))
    b.set_xlabel(_label(res["log_r"]))
    b.set_ylabel(_label(res["local_slope"]))
    fig.tight_layout()
    return fig


def scatter(x, y, *, title=""):
    """Scatter of two per-unit measures, labelled from their attrs."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(3.6, 3.2))
    ax.plot(x.values, y.values, "o", ms=3, alpha=0.7)
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    if title:
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def _bars(da, title=""):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(3.2, 2.8))
    labels = [str(v) for v in da[da.dims[0]].values]
    ax.bar(labels, da.values)
    ax.set_xlabel(da.dims[0])
    ax.set_ylabel(_label(da))
    if title:
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_result(result, **kwargs):
    """The natural plot of any hippo_probe result (dispatch on ``attrs['analysis']``)."""
    kind = result.attrs.get("analysis")
    if kind == "ratemaps":
        return ratemap_grid(result, **kwargs)
    if kind == "head_direction_tuning":
        return hd_polar(result, **kwargs)
    if kind == "remapping_similarity":
        return remapping_cdf(result)
    if kind == "localization_error":
        return error_curves(result, **kwargs)
    if kind == "classification_accuracy":
        return accuracy_curve(result)
    if kind == "correlation_dimension":
        return correlation_sum(result)
    if kind == "context_cells":
        rho = result.attrs.get("rank_correlation", np.nan)
        return scatter(result["spatial_selectivity"], result["projection_strength"],
                       title=f"Spearman rho = {rho:.2f}")
    if kind == "decode_covariance":
        return _bars(result["r2"], title=f"decoding {result.attrs.get('target', '')}")
    per_unit = {"spatial_information": "information", "spatial_selectivity": "selectivity",
                "place_field_stability": "stability"}
    if kind in per_unit:
        return cumulative(result[per_unit[kind]], title=kind.replace("_", " "))
    raise ValueError(f"no hippo_probe plot for a result with attrs['analysis'] = {kind!r}; "
                     "expected the output of a hippo_probe analysis")


@xr.register_dataarray_accessor("hp")
@xr.register_dataset_accessor("hp")
class HippoProbeAccessor:
    """``result.hp.plot()``: the natural plot of a hippo_probe result, as a Figure."""

    def __init__(self, obj):
        self._obj = obj

    def plot(self, **kwargs):
        """Plot the result; keyword arguments go to the specific plot helper."""
        return plot_result(self._obj, **kwargs)
