"""Plots of analysis results, and the ``.hp`` xarray accessor so results plot themselves.

>>> maps = hp.ratemaps(rec)          # doctest: +SKIP
>>> fig = maps.hp.plot()             # doctest: +SKIP

Every helper returns the matplotlib Figure and labels its axes from the result's
``units`` and ``long_name`` attrs. Single-axes plots take ``ax=``, grids take ``fig=`` (a
Figure or SubFigure to draw the grid in) or ``axes=`` (one Axes per panel), so a plot can
go into a figure of one's own; they then return that figure:

>>> fig, (a, b) = plt.subplots(1, 2)                      # doctest: +SKIP
>>> hp.spatial_information(rec).hp.plot(ax=a)             # doctest: +SKIP

matplotlib is imported on first use only, so importing the analyses stays light.
"""

from __future__ import annotations

import functools

import warnings

import numpy as np
import xarray as xr

#: Fraction of a map's peak below which a negative minimum is shown as 0 (its colour and
#: its title): smoothing noise around silent bins, not signed activity.
NEGLIGIBLE_MINIMUM = 0.01


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
    cols = max(1, min(n, max_cols))
    return cols, max(1, int(np.ceil(n / cols)))


def _figure(figsize):
    # constrained layout keeps titles, colour bars and labels apart without tight_layout,
    # which would also move a user's own axes
    return _plt().figure(figsize=figsize, layout="constrained")


def _one_axes(ax, figsize):
    """The given Axes and its figure, or a new figure holding one Axes."""
    if ax is None:
        fig = _figure(figsize)
        return fig, fig.add_subplot()
    from matplotlib.axes import Axes

    if not isinstance(ax, Axes):
        raise TypeError(f"`ax` must be a matplotlib Axes; got {type(ax).__name__}")
    return ax.figure, ax


def _panels(n, *, max_cols, panel, fig=None, axes=None, polar=False, what="unit"):
    """Axes for ``n`` panels: the given ``axes``, a grid drawn in ``fig`` (a Figure or a
    SubFigure), or a new figure; returns the figure and the flat list of axes."""
    from matplotlib.axes import Axes
    from matplotlib.figure import FigureBase

    if fig is not None and axes is not None:
        raise ValueError("pass `fig` (a grid is drawn in it) or `axes` (one per panel), "
                         "not both")
    kw = {"projection": "polar"} if polar else {}
    if axes is not None:
        flat = list(np.ravel(np.asarray(axes, dtype=object)))
        if not all(isinstance(a, Axes) for a in flat):
            raise TypeError("`axes` must be a matplotlib Axes or an array of them; got "
                            f"{type(axes).__name__}")
        if len(flat) < n:
            raise ValueError(f"`axes` holds {len(flat)} axes; the plot needs {n} "
                             f"(one per {what}); pass `units=` to show fewer")
        if polar and any(a.name != "polar" for a in flat[:n]):
            raise ValueError("`axes` must be polar axes (subplot_kw={'projection': "
                             "'polar'}); got " + ", ".join(sorted({a.name for a in flat})))
        return flat[0].figure, flat
    cols, rows = _grid(n, max_cols)
    if fig is None:
        fig = _figure((max(panel * cols, 3.0) + 0.8, panel * rows + 0.6))
    elif not isinstance(fig, FigureBase):
        raise TypeError(f"`fig` must be a matplotlib Figure or SubFigure; got "
                        f"{type(fig).__name__}")
    grid = fig.subplots(rows, cols, squeeze=False, subplot_kw=kw)
    return fig, list(grid.flat)


def _bottom_left(axes):
    """The panel at the bottom left of a set of axes (the one to carry axis labels)."""
    def key(ax):
        box = ax.get_position()
        return round(box.x0, 3), round(box.y0, 3)

    return min(axes, key=key)


def _num(value):
    """A number short enough for a panel title: 31, 3.1, 0.82, 0.0034."""
    if not np.isfinite(value):
        return "nan"
    a = abs(value)
    text = f"{value:.0f}" if a >= 10 else f"{value:.1f}" if a >= 1 else f"{value:.2g}"
    return text.replace("-", "\N{MINUS SIGN}")


def _units_text(da):
    units = da.attrs.get("units")
    return "" if units in (None, "", "1") else f" {units}"


def _unit_name(da, u):
    """'unit 12' and, when the result carries a per-unit ``region``, ' · CA1'."""
    text = f"unit {u}"
    if "region" in da.coords and da["region"].dims == ("unit",):
        text += f" \N{MIDDLE DOT} {da['region'].sel(unit=u).item()}"
    return text


def _pick_group(da, keep, group):
    """``da`` reduced to one entry of its first dim outside ``keep`` (``group``, default
    the first), and the (dim, label) chosen; other extra dims take their first entry."""
    extra = [d for d in da.dims if d not in keep]
    if not extra:
        return da, None, None
    dim = extra[0]
    label = da[dim].values[0] if group is None else group
    da = da.sel({dim: label})
    rest = [d for d in da.dims if d not in keep]
    return (da.isel({d: 0 for d in rest}) if rest else da), dim, label


def _field_labels(fields, maps, label):
    """The ``field_label`` (unit, y, x) of a place_fields result for the units and group
    of ``maps``; refused if it was made on other bins."""
    if not isinstance(fields, xr.Dataset) or "field_label" not in fields:
        raise ValueError(f"`fields` must be the output of hippo_probe.place_fields (with "
                         f"`field_label`); got {type(fields).__name__}")
    labels, _, _ = _pick_group(fields["field_label"], ("unit", "y", "x"), label)
    labels = labels.transpose("unit", "y", "x")
    if labels.shape[1:] != maps.shape[1:] or not np.allclose(labels["x"], maps["x"]) \
            or not np.allclose(labels["y"], maps["y"]):
        raise ValueError(f"`fields` were detected on other bins ({labels.shape[2]} x "
                         f"{labels.shape[1]}) than these maps ({maps.shape[2]} x "
                         f"{maps.shape[1]}): make them with hp.place_fields(maps)")
    return labels.sel(unit=maps["unit"].values)


def _group_caption(da, dim, label) -> str:
    """The title's note of the group ``label`` of ``da``'s ``dim`` that
    :func:`_pick_group` chose, and how many there are (a grid shows one environment or
    trial of several)."""
    if dim is None:
        return ""
    labels = list(da[dim].values)
    caption = f" \N{EM DASH} {dim} {label}"
    if len(labels) > 1 and label in labels:
        caption += f" ({labels.index(label) + 1} of {len(labels)}; `group=` shows another)"
    return caption


def _units(da, units, limit):
    if units is not None:
        da = da.sel(unit=list(units))
    return da.isel(unit=slice(0, limit))


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


def _draw_maps(axes, maps, *, cmap, norms, outline, titles, regions=None):
    """One image per unit of ``maps`` (unit, y, x) into ``axes``, with each unit's
    ``regions`` (y, x; > 0 inside, e.g. its place fields) outlined; unused axes are
    hidden."""
    from matplotlib.ticker import MaxNLocator

    plt = _plt()
    ydim, xdim = maps.dims[-2:]
    x, y = maps[xdim].values, maps[ydim].values
    half = (x[1] - x[0]) / 2 if len(x) > 1 else 0.5
    ext = (x[0] - half, x[-1] + half, y[0] - half, y[-1] + half)
    colours = plt.get_cmap(cmap).with_extremes(bad="white")  # unvisited bins
    pad = 0.04 * max(ext[1] - ext[0], ext[3] - ext[2])
    n = maps.sizes["unit"]
    for ax, u, norm, title in zip(axes, maps["unit"].values, norms, titles):
        ax.imshow(maps.sel(unit=u).values, origin="lower", extent=ext, cmap=colours,
                  interpolation="nearest", norm=norm)
        if outline is not None:
            closed = np.vstack([outline, outline[:1]])
            ax.plot(closed[:, 0], closed[:, 1], color="0.2", lw=0.8)
        if regions is not None and (regions.sel(unit=u).values > 0).any():
            inside = (regions.sel(unit=u).values > 0).astype(float)
            ax.contour(x, y, inside, levels=[0.5], colors="white", linewidths=0.9)
        ax.set_xlim(ext[0] - pad, ext[1] + pad)
        ax.set_ylim(ext[2] - pad, ext[3] + pad)
        ax.set_aspect("equal")
        for spine in ax.spines.values():
            spine.set_visible(False)
        ax.set_title(title, fontsize=7, linespacing=1.1)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in axes[n:]:
        ax.axis("off")
    corner = _bottom_left(axes[:n])
    corner.set_xlabel(_label(maps[xdim]), fontsize=7, labelpad=1)
    corner.set_ylabel(_label(maps[ydim]), fontsize=7, labelpad=1)
    # ticks on one panel only: the scale of the arena without crowding the grid
    corner.xaxis.set_major_locator(MaxNLocator(3))
    corner.yaxis.set_major_locator(MaxNLocator(3))
    corner.tick_params(labelsize=6, length=2, pad=1)
    return colours


def _colorbar(fig, axes, mappable, label, ticks=None, ticklabels=None):
    cbar = fig.colorbar(mappable, ax=axes, shrink=0.8, aspect=25, pad=0.02, ticks=ticks)
    if ticklabels is not None:
        cbar.set_ticklabels(ticklabels)
    cbar.set_label(label, fontsize=7)
    cbar.ax.tick_params(labelsize=6)
    return cbar


def ratemap_grid(maps, *, units=None, group=None, max_cols=8, cmap="viridis", panel=1.6,
                 scale="unit", fields=None, fig=None, axes=None):
    """A grid of rate maps, one panel per unit, with the arena outline and a colour bar.

    Each panel is titled with its unit, the unit's ``region`` when the result has one,
    and its peak with units ("unit 12 · CA1 / peak 3.1 Hz").

    Parameters
    ----------
    maps : xarray.DataArray
        Output of :func:`hippo_probe.ratemaps` (unit, [group], y, x).
    units : sequence, optional
        Unit ids to show (default: all, at most 64).
    group : label, optional
        Which environment/trial to show when the maps have a group dim (default: the first).
    scale : {"unit", "shared"}
        ``"unit"``: each panel from 0 (or its minimum, when negative) to its own peak,
        written in its title, the colour bar reading 0..peak; ``"shared"``: one scale
        for all panels, the colour bar in the maps' units.
    fields : xarray.Dataset, optional
        Output of :func:`hippo_probe.place_fields` on these maps: each unit's fields are
        outlined (white) and counted in its title.
    fig : matplotlib Figure or SubFigure, optional
        Draw the grid in this figure (e.g. one of ``plt.figure().subfigures(1, 2)``).
    axes : array of matplotlib Axes, optional
        Draw one map into each of these axes (at least one per unit shown).

    Returns
    -------
    matplotlib.figure.Figure
        The figure drawn into (``fig``, the figure of ``axes``, or a new one).
    """
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    from ._validators import check_option

    check_option("scale", scale, ("unit", "shared"))
    picked, group_dim, label = _pick_group(maps, ("unit", "y", "x"), group)
    caption = _group_caption(maps, group_dim, label)   # of every group, before picking
    maps = picked
    maps = _units(maps, units, 64).transpose("unit", "y", "x")
    regions = None if fields is None else _field_labels(fields, maps, label)
    fig, axes = _panels(maps.sizes["unit"], max_cols=max_cols, panel=panel, fig=fig,
                        axes=axes)
    values = maps.values
    finite = np.isfinite(values).reshape(len(values), -1).any(1)
    with warnings.catch_warnings():  # all-NaN maps (a unit never seen) are titled below
        warnings.simplefilter("ignore", RuntimeWarning)
        peaks, lows = np.nanmax(values, axis=(1, 2)), np.nanmin(values, axis=(1, 2))
    # a minimum this close to 0 (noise around a silent bin) is drawn and read as 0
    lows = np.where(lows < -NEGLIGIBLE_MINIMUM * np.abs(peaks), lows, np.maximum(lows, 0))
    signed = bool(np.nanmin(lows, initial=0.0) < 0) if finite.any() else False
    units_txt = _units_text(maps)
    titles, norms = [], []
    if scale == "shared" and finite.any():
        shared = Normalize(float(np.nanmin(lows)) if signed else 0.0, float(np.nanmax(peaks)))
    for u, ok, peak, low in zip(maps["unit"].values, finite, peaks, lows):
        head = _unit_name(maps, u)
        if not ok:
            titles.append(f"{head}\n(no data)")
            norms.append(Normalize(0, 1))
            continue
        line = f"peak {_num(peak)}{units_txt}"
        if low < 0:
            line += f", min {_num(low)}"
        if regions is not None:
            numbers = regions.sel(unit=u).values
            n_fields = len(np.unique(numbers[numbers > 0]))
            line += f", {n_fields} field{'s' if n_fields != 1 else ''}"
        titles.append(f"{head}\n{line}")
        lo = min(float(low), 0.0)
        norms.append(shared if scale == "shared" else
                     Normalize(lo, float(peak) if peak > lo else lo + 1.0))
    colours = _draw_maps(axes, maps, cmap=cmap, norms=norms,
                         outline=_outline(maps, group_dim, label),
                         titles=titles, regions=regions)
    used = axes[:maps.sizes["unit"]]
    if scale == "shared" and finite.any():
        _colorbar(fig, used, ScalarMappable(shared, colours), _label(maps))
    else:
        floor = "min" if signed else "0"
        # one bar for panels of different scales: it reads from 0 (or each panel's
        # minimum) to each panel's peak, written in the panel's title
        _colorbar(fig, used, ScalarMappable(Normalize(0, 1), colours), _label(maps),
                  ticks=[0, 1], ticklabels=[floor, "peak"])
    fig.suptitle(_label(maps, "rate") + caption, fontsize=9)
    return fig


def autocorrelation_grid(acorr, *, units=None, group=None, max_cols=8, cmap="RdBu_r",
                         panel=1.6, fig=None, axes=None):
    """A grid of spatial autocorrelograms, one panel per unit, on one -1..1 colour bar.

    Parameters
    ----------
    acorr : xarray.DataArray
        Output of :func:`hippo_probe.spatial_autocorrelation` (unit, [group], lag_y, lag_x).
    units, group, max_cols, panel, fig, axes
        As for :func:`ratemap_grid`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    picked, group_dim, label = _pick_group(acorr, ("unit", "lag_y", "lag_x"), group)
    caption = _group_caption(acorr, group_dim, label)   # of every group, before picking
    acorr = picked
    acorr = _units(acorr, units, 64).transpose("unit", "lag_y", "lag_x")
    seen = np.isfinite(acorr.values).any(0)
    if seen.any():  # crop to the lags defined somewhere (an odd-shaped arena leaves few)
        rows, cols = np.flatnonzero(seen.any(1)), np.flatnonzero(seen.any(0))
        acorr = acorr.isel(lag_y=slice(rows[0], rows[-1] + 1),
                           lag_x=slice(cols[0], cols[-1] + 1))
    fig, axes = _panels(acorr.sizes["unit"], max_cols=max_cols, panel=panel, fig=fig,
                        axes=axes)
    norm = Normalize(-1.0, 1.0)
    n = acorr.sizes["unit"]
    colours = _draw_maps(axes, acorr, cmap=cmap, norms=[norm] * n, outline=None,
                         titles=[_unit_name(acorr, u) for u in acorr["unit"].values])
    _colorbar(fig, axes[:n], ScalarMappable(norm, colours), _label(acorr),
              ticks=[-1, 0, 1])
    fig.suptitle(f"spatial {acorr.attrs.get('long_name', 'autocorrelation')}" + caption,
                 fontsize=9)
    return fig


def hd_polar(tuning, *, units=None, group=None, max_cols=6, panel=1.8, fig=None,
             axes=None):
    """Polar plots of head-direction tuning curves, one per unit.

    Each panel is titled with its unit, the unit's ``region`` when the result has one,
    the mean vector length R and the preferred direction in degrees (0-360,
    counter-clockwise from +x, the convention of the polar axes, whose ticks are in
    degrees too). Given the whole result of :func:`~hippo_probe.head_direction_tuning`,
    a curve with a non-zero ``rate_offset`` (signed activity such as LSTM h: the unit's
    minimum, which R was computed without) is drawn minus that offset, radius from 0, so a
    weakly tuned unit is a nearly round curve, as its small R says; a bare
    ``tuning_curve`` is drawn as it is.

    Parameters
    ----------
    tuning : xarray.Dataset or DataArray
        Output of :func:`hippo_probe.head_direction_tuning` (or its ``tuning_curve``).
    units : sequence, optional
        Unit ids to show (default: all, at most 48).
    group : label, optional
        Which environment/trial to show when the tuning has a group dim (default: the
        first).
    fig : matplotlib Figure or SubFigure, optional
        Draw the grid of polar axes in this figure.
    axes : array of polar matplotlib Axes, optional
        Draw one curve into each (``subplot_kw={"projection": "polar"}``).

    Returns
    -------
    matplotlib.figure.Figure
    """
    stats = tuning if isinstance(tuning, xr.Dataset) and "mean_vector_length" in tuning \
        else None
    curves = tuning["tuning_curve"] if isinstance(tuning, xr.Dataset) else tuning
    picked, group_dim, label = _pick_group(curves, ("unit", "direction"), group)
    caption = _group_caption(curves, group_dim, label)   # of every group, before picking
    curves = picked
    curves = _units(curves, units, 48).transpose("unit", "direction")
    offset = None
    if stats is not None:
        if "rate_offset" in tuning and (tuning["rate_offset"] != 0).any():
            offset = tuning["rate_offset"]
        stats = stats[["mean_vector_length", "preferred_direction"]]
        stats, _, _ = _pick_group(stats, ("unit",), label if group_dim else None)
    n = curves.sizes["unit"]
    fig, axes = _panels(n, max_cols=max_cols, panel=panel, fig=fig, axes=axes, polar=True)
    theta = curves["direction"].values
    closed = np.r_[theta, theta[:1]]
    units_txt = _units_text(curves)
    regions = list(dict.fromkeys(curves["region"].values)) \
        if "region" in curves.coords and curves["region"].dims == ("unit",) else []
    for ax, u in zip(axes, curves["unit"].values):
        r = curves.sel(unit=u).values
        if offset is not None:
            r = r - offset.sel(unit=u).item()
        colour = f"C{regions.index(curves['region'].sel(unit=u).item()) % 10}" \
            if regions else "C0"
        ax.plot(closed, np.r_[r, r[:1]], lw=1, color=colour)
        title = _unit_name(curves, u)
        if stats is not None:
            length = stats["mean_vector_length"].sel(unit=u).item()
            pref = np.degrees(stats["preferred_direction"].sel(unit=u).item()) % 360
            title += f"\nR = {length:.2f}, pref {pref:.0f}\N{DEGREE SIGN}"
        ax.set_title(title, fontsize=7, linespacing=1.1, pad=9)
        ax.set_xticks(np.radians([0, 90, 180, 270]),
                      [f"{d}\N{DEGREE SIGN}" for d in (0, 90, 180, 270)])
        ax.tick_params(axis="x", labelsize=6, pad=-1)
        if np.isfinite(r).any() and np.nanmin(r) >= 0 and np.nanmax(r) > 0:
            # r from 0, so the curve's shape is not distorted; the outer ring is the peak
            peak = float(np.nanmax(r))
            ax.set_ylim(0, peak)
            ax.set_yticks([peak / 2, peak], ["", f"{_num(peak)}{units_txt}"])
        ax.tick_params(axis="y", labelsize=6)
        ax.set_rlabel_position(45)
        ax.grid(lw=0.4)
    for ax in axes[n:]:
        ax.axis("off")
    title = (f"{_label(curves)} vs {curves['direction'].attrs.get('long_name', 'direction')}"
             f" (\N{DEGREE SIGN})") + caption
    if stats is not None:
        title += "\nR: mean vector length; pref: preferred direction"
    if offset is not None:
        title += "; radius: activity above the unit's minimum"
    fig.suptitle(title, fontsize=8)
    return fig


def cumulative(values, *, xlabel="", ylabel="cumulative fraction", title="", styles=None,
               medians=False, ax=None):
    """Empirical cumulative distributions, one line per entry of ``values``.

    Parameters
    ----------
    values : dict of label -> array, or a DataArray (one line)
        NaNs are left out (and counted in the legend).
    xlabel, ylabel, title : str
    styles : dict of label -> dict, optional
        Line properties of some entries (e.g. ``{"A vs B": {"color": "tab:red",
        "ls": "--"}}``).
    medians : bool
        Mark each distribution's median (a dotted line of its colour; the value in the
        legend).
    ax : matplotlib Axes, optional
        Draw into this axes (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
    """
    if isinstance(values, xr.DataArray):
        xlabel = xlabel or _label(values)
        values = {values.name or "values": values.values}
    styles = styles or {}
    fig, ax = _one_axes(ax, (4, 3))
    for label, v in values.items():
        v = np.asarray(v, float).ravel()
        ok = np.sort(v[np.isfinite(v)])
        if not ok.size:
            continue
        y = np.arange(1, ok.size + 1) / ok.size
        dropped = v.size - ok.size
        text = f"{label} (n={ok.size}" + (f", {dropped} NaN" if dropped else "")
        if medians:
            text += f", median {np.median(ok):.2f}"
        line, = ax.step(ok, y, where="post", label=text + ")", **styles.get(label, {}))
        if medians:
            ax.axvline(np.median(ok), color=line.get_color(), ls=":", lw=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_ylim(0, 1.02)
    if title:
        ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7, frameon=False)
    return fig


def remapping_cdf(sim, *, ax=None):
    """Cumulative distributions of trial-pair similarity: same vs different environment,
    and the label-permuted control (dashed). Returns the figure."""
    s = sim["similarity"]
    same, perm = sim["same_environment"].values, sim["same_environment_permuted"].values
    groups = {"same environment": s.values[same], "different environment": s.values[~same],
              "same (labels permuted)": s.values[perm],
              "different (labels permuted)": s.values[~perm]}
    styles = {"same environment": {"color": "C0"}, "different environment": {"color": "C1"},
              "same (labels permuted)": {"color": "C0", "ls": "--"},
              "different (labels permuted)": {"color": "C1", "ls": "--"}}
    return cumulative(groups, xlabel=_label(s), title="remapping", styles=styles, ax=ax)


#: Legend labels of the position estimates a recording may hold (``record``'s
#: ``estimate`` and the baselines'): what :func:`error_curves` writes by default.
ESTIMATE_LABELS = {"estimate": "network", "estimate_pf": "particle filter (oracle)",
                   "estimate_sh": "single hypothesis", "estimate_pi": "path integration",
                   "estimate_nb": "naive Bayes", "estimate_pfslam": "PF-SLAM"}


def error_curves(err, *, variables=("euclidean", "radial", "angular"), colors=None,
                 labels=None, degrees=False, fig=None, axes=None):
    """Localization error vs time in trial (mean +- s.e.m. over trials), one panel per
    kind of error, one line per estimate.

    Parameters
    ----------
    err : xarray.Dataset
        Output of :func:`hippo_probe.localization_error`.
    variables : sequence of str
        Kinds of error, one panel each.
    colors, labels : dict, optional
        Colour and legend label of each estimate, by its name (e.g. ``"estimate_pf"``);
        default matplotlib's cycle and :data:`ESTIMATE_LABELS` (else the names).
    degrees : bool
        Angular error in degrees instead of radians.
    fig, axes
        As for :func:`ratemap_grid`.

    Returns
    -------
    matplotlib.figure.Figure
    """
    variables = [v for v in variables if v in err]
    fig, axes = _panels(len(variables), max_cols=len(variables), panel=2.8, fig=fig,
                        axes=axes, what="kind of error")
    colors, labels = colors or {}, {**ESTIMATE_LABELS, **(labels or {})}
    t = err["trial_time"].values
    for ax, name in zip(axes, variables):
        da = err[name]
        scale = np.degrees(1.0) if degrees and da.attrs.get("units") == "rad" else 1.0
        if "estimate" in da.dims:
            lines = da.transpose("estimate", "trial_time")
        else:
            names = err.attrs.get("estimate", ["estimate"])
            lines = da.expand_dims(estimate=[names[0] if isinstance(names, list) else names])
        sem = err.get(f"{name}_sem")
        for i, estimate in enumerate(lines["estimate"].values):
            y = lines.values[i] * scale
            colour = colors.get(str(estimate), f"C{i % 10}")
            ax.plot(t, y, lw=1.4, color=colour, label=labels.get(str(estimate), str(estimate)))
            if sem is not None:
                e = (sem.values[i] if "estimate" in sem.dims else sem.values) * scale
                ax.fill_between(t, y - e, y + e, color=colour, alpha=0.15, lw=0)
        ax.set_xlabel(_label(err["trial_time"]))
        ax.set_ylabel(f"{da.attrs.get('long_name', name)} (deg)" if scale != 1.0
                      else _label(da))
        ax.set_xlim(t[0] if t[0] > t[-1] * 0.05 else 0, t[-1])
        ax.set_ylim(bottom=0)
    axes[0].legend(fontsize=7, frameon=False)
    return fig


def accuracy_curve(acc, *, ax=None):
    """Classification accuracy vs time in trial, with chance level. Returns the figure."""
    fig, ax = _one_axes(ax, (4, 3))
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
    return fig


def correlation_sum(res, *, fig=None, axes=None):
    """log C(r) vs log r with the scaling range and its slope D, and the local slopes.
    ``fig`` / ``axes`` (two) as for :func:`ratemap_grid`; returns the figure."""
    fig, axes = _panels(2, max_cols=2, panel=3.0, fig=fig, axes=axes, what="panel")
    a, b = axes[:2]
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
    else:
        a.set_title("D = NaN", fontsize=9)
    fig.suptitle("\n".join(["correlation dimension (Grassberger-Procaccia)",
                             *_nan_reasons(res)]), fontsize=8)
    a.set_xlabel(_label(res["log_r"]))
    a.set_ylabel(_label(res["log_c"]))
    b.set_xlabel(_label(res["log_r"]))
    b.set_ylabel(_label(res["local_slope"]))
    return fig


def scatter(x, y, *, title="", ax=None):
    """Scatter of two per-unit measures, labelled from their attrs. Returns the figure."""
    fig, ax = _one_axes(ax, (3.6, 3.2))
    ax.plot(x.values, y.values, "o", ms=3, alpha=0.7)
    ax.set_xlabel(_label(x))
    ax.set_ylabel(_label(y))
    if title:
        ax.set_title(title, fontsize=9)
    return fig


def bars(da, *, title="", ax=None):
    """Bar chart of a 1-D result, one bar per entry of its dim. Returns the figure."""
    fig, ax = _one_axes(ax, (3.2, 2.8))
    labels = [str(v) for v in da[da.dims[0]].values]
    ax.bar(labels, np.nan_to_num(da.values, nan=0.0))
    for k, value in enumerate(da.values):
        if not np.isfinite(value):          # a refused estimate: said, not left blank
            ax.annotate("NaN", (k, 0), ha="center", va="bottom", fontsize=8, color="0.4")
    ax.set_xlabel(da.dims[0])
    ax.set_ylabel(_label(da))
    reasons = _nan_reasons(da, width=48)
    if not np.isfinite(da.values).any():
        ax.set_ylim(0, 1)
    if title or reasons:
        ax.set_title("\n".join([title, *reasons]).strip(), fontsize=9 if not reasons else 7)
    return fig


def _nan_reasons(result, width=90) -> list[str]:
    """A result's NaN reasons (``attrs["nan_reasons"]``), one line of at most ``width``
    characters each (the whole reasons are in the attrs)."""
    import textwrap

    reasons = result.attrs.get("nan_reasons") or {}
    if isinstance(reasons, str):
        reasons = {"": reasons}
    return [textwrap.shorten(f"{k}: NaN, {r}" if k else f"NaN: {r}", width)
            for k, r in list(reasons.items())[:3]]


def class_fractions(cells, *, ax=None):
    """Fraction of units in each cell class (one bar per class, in the precedence order
    of :func:`hippo_probe.classify_cells`, then unclassified), side by side per
    ``region`` when the result has one; each bar is labelled with its count.

    Parameters
    ----------
    cells : xarray.Dataset
        Output of :func:`hippo_probe.classify_cells`.
    ax : matplotlib Axes, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    labels = cells["cell_class"].values.astype(str)
    order = [c for c in cells["cell_class"].attrs.get("precedence", []) if c in labels]
    order += sorted(set(labels) - set(order) - {"unclassified"})
    order += ["unclassified"] if "unclassified" in labels else []
    if "region" in cells.coords and cells["region"].dims == ("unit",):
        region = cells["region"].values.astype(str)
        groups = {g: region == g for g in dict.fromkeys(region)}
    else:
        groups = {"all units": np.ones(labels.size, bool)}
    fig, ax = _one_axes(ax, (max(3.2, 0.55 * len(order) * max(1, len(groups)) + 1.2), 3.0))
    width = 0.8 / len(groups)
    pos = np.arange(len(order))
    for k, (name, member) in enumerate(groups.items()):
        counts = np.array([(labels[member] == c).sum() for c in order])
        total = max(int(member.sum()), 1)
        rects = ax.bar(pos + (k - (len(groups) - 1) / 2) * width, counts / total, width,
                       label=f"{name} (n={int(member.sum())})")
        ax.bar_label(rects, labels=[str(c) if c else "" for c in counts], fontsize=6,
                     padding=1)
    ax.set_xticks(pos, [c.replace("_", " ") for c in order], rotation=30, ha="right",
                  fontsize=7)
    ax.set_ylabel("fraction of units")
    ax.set_ylim(0, 1.1)
    ax.set_title(f"cell classes ({labels.size} units)", fontsize=9)
    if len(groups) > 1 or "region" in cells.coords:
        ax.legend(fontsize=7, frameon=False, loc="upper left")
    return fig


def recording_overview(rec, *, trial=None, n_units=64, fig=None):
    """A recording at a glance: the path of one trial in its arena, and the activity of
    its first ``n_units`` units over that trial (a raster of the activity, one row a
    unit).

    Parameters
    ----------
    rec : xarray.Dataset
        A recording (schema v1).
    trial : int, optional
        The trial shown (default: the first).
    n_units : int
        Units shown (default 64).
    fig : matplotlib.figure.Figure, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    trials = np.asarray(rec["trial_id"].values) if "trial_id" in rec.coords else \
        np.unique(rec["trial"].values)
    trial = trials[0] if trial is None else trial
    one = rec.isel(time=np.flatnonzero(np.asarray(rec["trial"].values) == trial))
    fig = fig or plt.figure(figsize=(9.0, 3.4))
    ax_path, ax_act = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 2.2]})
    xy = np.asarray(one["position"].transpose("time", "space").values, float)
    if "arena_vertices" in rec and "environment" in one.coords:
        env = np.asarray(one["environment"].values)[0]
        verts = np.asarray(rec["arena_vertices"].sel(environment_id=env).values, float)
        ax_path.fill(verts[:, 0], verts[:, 1], color="0.92", ec="0.4", lw=1)
    ax_path.plot(xy[:, 0], xy[:, 1], lw=0.7, color="tab:blue")
    ax_path.set_aspect("equal")
    ax_path.set_xlabel("x (m)")
    ax_path.set_ylabel("y (m)")
    ax_path.set_title(f"trial {trial}: path", fontsize=9)
    act = one["activity"].transpose("unit", "time").isel(unit=slice(0, n_units))
    tt = np.asarray(one["trial_time"].values, float)
    image = ax_act.imshow(np.asarray(act.values, float), aspect="auto", origin="lower",
                          cmap="viridis", interpolation="nearest",
                          extent=(tt[0], tt[-1], -0.5, act.sizes["unit"] - 0.5))
    ax_act.set_xlabel("time in trial (s)")
    ax_act.set_ylabel("unit (index)")
    units = rec["activity"].attrs.get("units", "")
    fig.colorbar(image, ax=ax_act, label=f"{rec['activity'].attrs.get('long_name', 'activity')}"
                 + (f" ({units})" if units and units != "1" else ""))
    ax_act.set_title(f"activity of the first {act.sizes['unit']} units", fontsize=9)
    fig.tight_layout()
    return fig


def drawn_once_in_jupyter(fig):
    """Return ``fig``, made to be drawn once when a Jupyter cell returns it.

    A Figure that ends a cell is drawn twice under matplotlib's inline backend: as the
    cell's value, and by the backend, which draws every open figure when the cell ends.
    There, whichever draws ``fig`` first also hands it back from pyplot, so the other
    finds nothing left to draw; a later ``fig`` alone in a cell draws it again, as for
    any Figure. Under any other backend (scripts, terminal IPython, Qt or widget windows)
    nothing is changed.
    """
    import matplotlib

    if "inline" in matplotlib.get_backend():
        fig._ipython_display_ = functools.partial(_display_once, fig)
    return fig


def _display_once(fig):
    """``fig._ipython_display_``: close ``fig`` in pyplot, then display it as usual."""
    import matplotlib.pyplot as plt
    from IPython.display import display

    plt.close(fig)                     # drawn now: the inline flush will not again
    hook = fig.__dict__.pop("_ipython_display_", None)
    try:
        display(fig)
    finally:
        if hook is not None:
            fig._ipython_display_ = hook


def plot_result(result, **kwargs):
    """The natural plot of any hippo_probe result (dispatch on ``attrs['analysis']``), or
    of a recording itself (:func:`recording_overview`).

    Keyword arguments go to the specific helper: ``ax=`` for single-axes plots,
    ``fig=`` / ``axes=`` for grids; every helper returns the figure it drew into, drawn
    once when it ends a Jupyter cell (:func:`drawn_once_in_jupyter`).
    """
    return drawn_once_in_jupyter(_plot_result(result, **kwargs))


def _plot_result(result, **kwargs):
    kind = result.attrs.get("analysis")
    if kind is None and "schema_version" in result.attrs and "activity" in result:
        return recording_overview(result, **kwargs)
    if kind == "ratemaps":
        return ratemap_grid(result, **kwargs)
    if kind == "spatial_autocorrelation":
        return autocorrelation_grid(result, **kwargs)
    if kind == "head_direction_tuning":
        return hd_polar(result, **kwargs)
    if kind == "classify_cells":
        return class_fractions(result, **kwargs)
    if kind == "remapping_similarity":
        return remapping_cdf(result, **kwargs)
    if kind == "localization_error":
        return error_curves(result, **kwargs)
    if kind in ("classification_accuracy", "decode_environment"):
        return accuracy_curve(result, **kwargs)
    if kind == "intrinsic_dimension":
        return bars(result["dimension"].assign_attrs(
            nan_reasons=result.attrs.get("nan_reasons", {})), title="intrinsic dimension",
            **kwargs)
    if kind == "correlation_dimension":
        return correlation_sum(result, **kwargs)
    if kind == "context_cells":
        rho = result.attrs.get("rank_correlation", np.nan)
        return scatter(result["spatial_selectivity"], result["projection_strength"],
                       title=f"Spearman rho = {rho:.2f}", **kwargs)
    if kind == "decode_covariance":
        return bars(result["r2"], title=f"decoding {result.attrs.get('target', '')}",
                    **kwargs)
    if kind in PER_UNIT:
        return cumulative(_per_group(result[PER_UNIT[kind]]), xlabel=_label(
            result[PER_UNIT[kind]]), title=kind.replace("_", " "), **kwargs)
    if kind == "map_scorecard":
        raise ValueError("a map_scorecard is a table of numbers with nothing to draw: "
                         "print it, or plot the rate maps it was made from")
    raise ValueError(f"no hippo_probe plot for a result with attrs['analysis'] = {kind!r}; "
                     f"expected the output of a hippo_probe analysis (a recording, or one "
                     f"of: {', '.join(PLOTTED)})")


def _per_group(da):
    """A per-unit measure as one distribution per environment or trial when it has that
    dim (``by=``), rather than every group's units pooled into one."""
    extra = [d for d in da.dims if d != "unit"]
    if not extra:
        return da
    dim = extra[0]
    return {f"{dim} {label}": da.sel({dim: label}).values for label in da[dim].values}


#: Per-unit results drawn as the cumulative distribution of one measure over the units.
PER_UNIT = {"spatial_information": "information", "spatial_selectivity": "selectivity",
            "place_field_stability": "stability", "place_fields": "n_fields",
            "grid_score": "grid_score", "border_score": "border_score",
            "speed_score": "speed_score", "conjunctive_tuning": "pxd_direction_length"}
#: Every analysis whose result ``.hp.plot()`` draws.
PLOTTED = ("ratemaps", "spatial_autocorrelation", "head_direction_tuning", "classify_cells",
           "remapping_similarity", "localization_error", "classification_accuracy",
           "decode_environment", "correlation_dimension", "intrinsic_dimension",
           "context_cells", "decode_covariance", *PER_UNIT)
