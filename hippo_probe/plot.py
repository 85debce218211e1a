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
    """Arena outline (V, 2) of a map's environment, or None."""
    verts = maps.attrs.get("arena_vertices")
    envs = maps.attrs.get("arena_environment")
    if verts is None or envs is None:
        return None
    verts, envs = np.asarray(verts), np.asarray(envs)
    if group_dim == "environment":
        env = label
    elif "environment" in maps.coords and group_dim is not None and \
            maps["environment"].dims == (group_dim,):
        env = maps["environment"].sel({group_dim: label}).item()
    elif len(envs) == 1:
        env = envs[0]
    else:
        return None
    hit = np.flatnonzero(envs == env)
    return verts[hit[0]] if hit.size else None


def ratemap_grid(maps, *, units=None, group=None, max_cols=8, cmap="viridis", panel=1.6):
    """A grid of rate maps, one panel per unit, with the arena outline when known.

    Parameters
    ----------
    maps : xarray.DataArray
        Output of :func:`hippo_probe.ratemaps` (unit, [group], y, x).
    units : sequence, optional
        Unit ids to show (default: all, at most 64).
    group : label, optional
        Which environment/trial to show when the maps have a group dim (default: the first).
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
    for ax, u in zip(axes.flat, maps["unit"].values):
        m = maps.sel(unit=u)
        im = ax.imshow(m.values, origin="lower", extent=ext, cmap=cmap, interpolation="nearest")
        if outline is not None:
            closed = np.vstack([outline, outline[:1]])
            ax.plot(closed[:, 0], closed[:, 1], color="w", lw=0.8)
        peak = np.nanmax(m.values) if np.isfinite(m.values).any() else np.nan
        ax.set_title(f"{u}  max {peak:.2g}", fontsize=7)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[maps.sizes["unit"]:]:
        ax.axis("off")
    title = _label(maps, "rate")
    if group_dim is not None:
        title += f" — {group_dim} {label}"
    fig.suptitle(title, fontsize=9)
    axes[-1, 0].set_xlabel(_label(maps["x"]), fontsize=7)
    axes[-1, 0].set_ylabel(_label(maps["y"]), fontsize=7)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.6, label=_label(maps))
    return fig


@xr.register_dataarray_accessor("hp")
class _DataArrayAccessor:
    """``result.hp.plot()``: the right plot for a hippo_probe result."""

    def __init__(self, obj):
        self._obj = obj

    def plot(self, **kwargs):
        kind = self._obj.attrs.get("analysis")
        if kind == "ratemaps":
            return ratemap_grid(self._obj, **kwargs)
        raise ValueError(f"no hippo_probe plot for a DataArray with attrs['analysis'] = "
                         f"{kind!r}; expected 'ratemaps'")
