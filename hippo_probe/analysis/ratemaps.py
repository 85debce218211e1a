"""Rate maps: occupancy-normalised mean activity per spatial bin."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import ndimage

from .._validators import check_allocation, check_number, check_real, check_shape
from . import _common
from ._binning import BinSums, bin_sums, compact, grid_bins
from .._docs import fill_doc
from .config import RATEMAP


@dataclass(frozen=True)
class Grid:
    """Square spatial bins covering ``extent = (x_min, x_max, y_min, y_max)``."""

    extent: tuple
    bin_size: float
    nx: int
    ny: int

    @property
    def x_edges(self):
        return self.extent[0] + self.bin_size * np.arange(self.nx + 1)

    @property
    def y_edges(self):
        return self.extent[2] + self.bin_size * np.arange(self.ny + 1)

    @property
    def x(self):
        return self.x_edges[:-1] + self.bin_size / 2

    @property
    def y(self):
        return self.y_edges[:-1] + self.bin_size / 2


def _positions(rec):
    """``(x, y)`` of every sample as two contiguous float64 arrays."""
    pos = rec["position"]
    if "space" not in pos.dims or pos.sizes["space"] < 2:
        raise ValueError(f"`rec.position` must have dims ('time', 'space') with space = "
                         f"['x', 'y']; got dims {pos.dims}")
    if "space" in pos.coords and {"x", "y"} <= set(map(str, pos["space"].values)):
        pos = pos.sel(space=["x", "y"])
    pos = _common.values(pos.transpose("space", "time"))
    return (np.ascontiguousarray(pos[0], dtype=np.float64),
            np.ascontiguousarray(pos[1], dtype=np.float64))


def _arena_vertices(rec):
    """(environment ids, vertices (E, V, 2)) of the environments in ``rec``, or None."""
    if "arena_vertices" not in rec:
        return None
    verts = rec["arena_vertices"]
    ids = _common.values(verts["environment_id"]) if "environment_id" in verts.coords \
        else np.arange(verts.shape[0])
    if "environment" in rec.coords or "environment" in rec:
        present = np.isin(ids, np.unique(_common.values(rec["environment"])))
        if present.any():
            ids, verts = ids[present], verts.isel(environment_id=np.flatnonzero(present))
    return ids, _common.values(verts.transpose(..., "space")).astype(float)


def _warn_outliers_set_extent(x, y, lo, hi):
    """Warn when a few samples at the ends of an axis set most of the extent (config
    ``RATEMAP.outlier_fraction`` and ``outlier_stretch``)."""
    q = RATEMAP.outlier_fraction
    for axis, values, a, b in (("x", x, lo[0], hi[0]), ("y", y, lo[1], hi[1])):
        core_lo, core_hi = np.nanquantile(values, [q, 1 - q])
        span = max(core_hi - core_lo, 1e-12)
        if (b - a) > RATEMAP.outlier_stretch * span:
            margin = 0.25 * span            # count the far samples, not the core's tails
            n_out = int(((values < core_lo - margin) | (values > core_hi + margin)).sum())
            _common.warn(
                f"{n_out} of {int(np.isfinite(values).sum())} samples stretch the {axis} "
                f"extent to [{a:.3g}, {b:.3g}] m while the rest lie in [{core_lo:.3g}, "
                f"{core_hi:.3g}] m: the bins are coarser than intended. Pass `extent=` "
                f"(or clean the tracking)")


def spatial_grid(rec, bin_size=None, extent=None, *, n_bins=None, xy=None) -> Grid:
    """The bins of a recording's rate maps.

    ``extent`` defaults to the bounding box of the recording's arenas
    (``arena_vertices``) when known, else of its finite positions (``xy``, if already
    read, saves reading them again).
    """
    if extent is None:
        arenas = _arena_vertices(rec)
        if arenas is not None and np.isfinite(arenas[1]).any():
            v = arenas[1].reshape(-1, 2)
            extent = (np.nanmin(v[:, 0]), np.nanmax(v[:, 0]),
                      np.nanmin(v[:, 1]), np.nanmax(v[:, 1]))
        else:
            x, y = _positions(rec) if xy is None else xy
            lo = np.array([np.fmin.reduce(x), np.fmin.reduce(y)])  # fmin skips NaN
            hi = np.array([np.fmax.reduce(x), np.fmax.reduce(y)])
            if not np.isfinite(np.r_[lo, hi]).all():
                raise ValueError("`rec.position` has no finite sample: cannot place bins "
                                 "(all positions are NaN)")
            for axis, a, b in (("x", lo[0], hi[0]), ("y", lo[1], hi[1])):
                if a == b:
                    raise ValueError(
                        f"`rec.position`'s {axis} is constant ({a:.6g} m) over every finite "
                        f"sample: there is no extent to place bins on (a stuck tracker, "
                        f"or a single sample?); pass `extent=` to map it anyway")
            _warn_outliers_set_extent(x, y, lo, hi)
            pad = RATEMAP.extent_margin * np.maximum(hi - lo, 1e-12)
            extent = (lo[0] - pad[0], hi[0] + pad[0], lo[1] - pad[1], hi[1] + pad[1])
    extent = tuple(float(e) for e in check_shape(
        "extent", check_real("extent", extent).astype(float), (4,)))
    width, height = extent[1] - extent[0], extent[3] - extent[2]
    if not (np.isfinite(extent).all() and width > 0 and height > 0):
        raise ValueError("`extent` must be finite (x_min, x_max, y_min, y_max) with "
                         f"x_min < x_max and y_min < y_max; got {extent}")
    defaulted = bin_size is None
    if defaulted:
        bin_size = max(width, height) / (n_bins or RATEMAP.n_bins)
    bin_size = check_number("bin_size", bin_size, low=0)
    if bin_size >= min(width, height):
        if defaulted:       # the extent is what is wrong, not an argument never given
            raise ValueError(
                f"the extent ({width:.3g} x {height:.3g} m) is so elongated that its "
                f"default bins ({bin_size:.3g} m, the longer side / "
                f"{n_bins or RATEMAP.n_bins}) do not fit its shorter side: pass `extent=` "
                f"(a few stray positions may have stretched it) or a `bin_size`")
        raise ValueError(f"`bin_size` must be > 0 and smaller than the arena "
                         f"({width:.3g} x {height:.3g} m); got {bin_size}")
    nx = int(np.ceil(width / bin_size - 1e-9))
    ny = int(np.ceil(height / bin_size - 1e-9))
    return Grid(extent, bin_size, nx, ny)


def position_bins(rec, grid: Grid, *, min_speed=None, xy=None):
    """Flat bin ``iy * nx + ix`` of every sample; -1 where it is not counted.

    Returns ``(bins, counts)`` with ``counts`` the number of samples dropped for each
    reason (position NaN, outside the extent, too slow).
    """
    x, y = _positions(rec) if xy is None else xy
    bins, n_nan, n_out = grid_bins(x, y, grid.extent[0], grid.extent[2], grid.bin_size,
                                   grid.nx, grid.ny)
    if n_nan == len(x):
        raise ValueError("`rec.position` has no finite sample: cannot compute a spatial "
                         "map (all positions are NaN)")
    dropped = {"position_nan": int(n_nan), "outside_extent": int(n_out)}
    if min_speed is not None:
        check_number("min_speed", min_speed, low=0, low_inclusive=True)
        speed = _common.speed(rec)
        unknown = np.isnan(speed)     # one-sample trials, or beside a NaN position
        with np.errstate(invalid="ignore"):
            slow = speed < min_speed
        dropped["below_min_speed"] = int((slow & (bins >= 0)).sum())
        dropped["speed_unknown"] = int((unknown & (bins >= 0)).sum())
        bins[slow | unknown] = -1
    return bins, dropped


def smooth_normalized(sums, counts, sigma, n_axes=2, truncate=None, mode="constant"):
    """Normalized convolution over the last ``n_axes`` axes: smooth sums and occupancy,
    then divide.

    .. math:: \\hat\\lambda = \\frac{G_\\sigma * S}{G_\\sigma * N}

    Bins outside the data (zero occupancy) contribute nothing, so edges and holes are not
    pulled towards zero (Knutsson & Westin 1993). ``counts`` broadcasts against ``sums``;
    ``mode="wrap"`` smooths circular variables (head direction).
    """
    truncate = RATEMAP.truncate if truncate is None else truncate
    if sigma == 0:
        with np.errstate(invalid="ignore", divide="ignore"):
            return sums / counts

    def smooth(a):
        sig = [0.0] * (a.ndim - n_axes) + [sigma] * n_axes
        return ndimage.gaussian_filter(np.asarray(a, float), sig, mode=mode,
                                       truncate=truncate)

    with np.errstate(invalid="ignore", divide="ignore"):
        return smooth(sums) / smooth(counts)


def tuning_sums(rec, bins, groups, n_groups, n_bins, shifts=(0,), want_sq=False):
    """Sums per (group, bin) for each shift, as a :class:`BinSums` on the full grid.

    ``sums`` is (K, U, G, n_bins), ``counts`` (G, n_bins), ``sumsq`` (U, G, n_bins) or
    None. Only the visited (group, bin) pairs are accumulated, then scattered onto the
    grid, so accumulators stay small even for many groups.
    """
    small, occupied = compact(bins, groups, n_bins, n_groups)
    res = bin_sums(_common.activity(rec).data, small, len(occupied), shifts,
                   want_min=_common.tracks_minimum(rec), want_sq=want_sq)
    n_shifts, _, n_units = res.sums.shape

    def grid(a):  # (..., n_occupied, U) -> (..., U, G, n_bins)
        full = np.zeros(a.shape[:-2] + (n_groups * n_bins, n_units))
        full[..., occupied, :] = a
        full = full.reshape(a.shape[:-2] + (n_groups, n_bins, n_units))
        return np.moveaxis(full, -1, -3)

    counts = np.zeros(n_groups * n_bins, np.int64)
    counts[occupied] = res.counts[0]
    return BinSums(sums=grid(res.sums), counts=counts.reshape(n_groups, n_bins),
                   amin=res.amin, sumsq=None if res.sumsq is None else grid(res.sumsq))


def warn_nonfinite(rec, res, what):
    """Warn (naming units) when activity holds NaN or inf: their sums are not finite."""
    bad = ~np.isfinite(res.sums[0]).reshape(res.sums.shape[1], -1).all(axis=1)
    if bad.any():
        units = _common.values(rec["unit"])[bad] if "unit" in rec.coords else np.flatnonzero(bad)
        _common.warn(f"`rec.activity` holds NaN or inf for units {list(units[:5])}"
                      f"{' ...' if bad.sum() > 5 else ''}: their {what} are NaN in the "
                      "bins where such samples fall")


def _nothing_to_map(dropped, n, min_speed, extent) -> str:
    """The error when no sample is left to map, naming the argument (or the data) that
    dropped most of them."""
    cause = max(dropped, key=dropped.get)
    k = dropped[cause]
    if cause == "below_min_speed":
        first = f"`min_speed` = {min_speed!r} m/s leaves no sample to map: {k} of {n} are slower"
    elif cause == "speed_unknown":
        first = (f"`min_speed` = {min_speed!r} m/s leaves no sample to map: the speed of {k} "
                 f"of {n} is unknown (trials of one sample, or NaN positions beside them); "
                 f"pass min_speed=None")
    elif cause == "outside_extent":
        where = f"`extent` = {extent!r}" if extent is not None else "the bins' extent"
        first = f"{where} leaves no sample to map: {k} of {n} positions lie outside it"
    else:
        first = f"`rec.position` leaves no sample to map: {k} of {n} are NaN"
    return f"{first} (samples dropped: {dropped})"


def _ratemap_parts(rec, *, bin_size, sigma, min_occupancy, min_speed, by, extent,
                   shifts=(0,), n_bins=None, want_sq=False, groups=None, batch=False):
    """Everything a rate map (and its shuffles) is made of.

    ``batch``: ``shifts`` are one batch of the shuffles (:class:`~._shuffles.MapStack`),
    not all of them: a batch too large for memory is the bins' doing, not the shuffles'.

    ``groups = (codes, labels, dim)`` replaces the grouping given by ``by``.
    """
    rec = _common.check_recording(rec, ["activity", "position"], why="rate maps")
    sigma = check_number("sigma", RATEMAP.sigma if sigma is None else sigma, low=0,
                         low_inclusive=True)
    min_occupancy = check_number(
        "min_occupancy", RATEMAP.min_occupancy if min_occupancy is None else min_occupancy,
        low=0, low_inclusive=True)
    xy = _positions(rec)
    grid = spatial_grid(rec, bin_size, extent, n_bins=n_bins, xy=xy)
    bins, dropped = position_bins(rec, grid, min_speed=min_speed, xy=xy)
    codes, labels, dim = _common.group_codes(rec, by) if groups is None else groups
    if by is None and groups is None:
        _common.warn_pooled_environments(rec, "rate maps")
    n_groups = 1 if labels is None else len(labels)
    n_valid = int((bins >= 0).sum())
    if n_valid == 0:
        raise ValueError(_nothing_to_map(dropped, len(bins), min_speed, extent))
    n_cells = grid.nx * grid.ny * n_groups
    one = (rec.sizes["unit"], n_groups, grid.ny, grid.nx)
    if batch:
        check_allocation("bin_size", (len(shifts),) + one)
    else:
        check_allocation("bin_size", one, shuffles=len(shifts))
    if n_valid < RATEMAP.few_samples_ratio * n_cells:
        _common.warn(f"only {n_valid} valid samples for {n_cells} bins: most bins are "
                      "unvisited and NaN; use a larger `bin_size`")
    res = tuning_sums(rec, bins, codes, n_groups, grid.nx * grid.ny, shifts, want_sq)
    warn_nonfinite(rec, res, "rate maps")
    dt = _common.sample_dt(rec)
    shape = (grid.ny, grid.nx)
    sums = res.sums.reshape(res.sums.shape[:3] + shape)
    counts = res.counts.reshape((n_groups,) + shape)
    maps = smooth_normalized(sums, counts, sigma)
    unvisited = (counts == 0) | (counts * dt < min_occupancy)
    maps[..., unvisited] = np.nan
    if unvisited.all():
        _common.warn(f"every bin is NaN: no bin reaches `min_occupancy` = "
                     f"{min_occupancy} s (the most visited: {counts.max() * dt:.3g} s)")
    return dict(maps=maps, counts=counts, res=res, sums=sums, grid=grid, dropped=dropped,
                labels=labels, dim=dim, codes=codes, n_valid=n_valid, dt=dt,
                sigma=sigma, min_occupancy=min_occupancy)


def _maps_dataarray(rec, parts, maps, *, by, min_speed):
    """Label rate-map arrays (U, G, ny, nx) as the public DataArray."""
    grid, dim, labels, dt = parts["grid"], parts["dim"], parts["labels"], parts["dt"]
    scale, units, long_name = _common.rate_scale(rec)
    unit_coords = {name: c for name, c in rec["activity"].coords.items()
                   if c.dims == ("unit",)}
    coords = dict(unit_coords)
    coords["y"] = ("y", grid.y, {"units": "m", "long_name": "y position"})
    coords["x"] = ("x", grid.x, {"units": "m", "long_name": "x position"})
    occ_dims = ("y", "x")
    occ = parts["counts"] * dt
    if dim is None:
        data, occ = maps[:, 0], occ[0]
        dims = ("unit", "y", "x")
    else:
        data = maps
        dims = ("unit", dim, "y", "x")
        occ_dims = (dim, "y", "x")
        coords[dim] = (dim, labels, rec[dim].attrs)
        if dim == "trial" and "environment" in rec:
            env = _common.values(rec["environment"])
            first = np.unique(parts["codes"], return_index=True)[1]
            coords["environment"] = (dim, env[first], rec["environment"].attrs)
    coords["occupancy"] = (occ_dims, occ, {"units": "s", "long_name": "occupancy"})
    min_attrs = {"units": units, "long_name": "minimum over the recording"}
    if not _common.tracks_minimum(rec):
        min_attrs["note"] = (f"NaN: not tracked, activity_kind "
                             f"{rec.attrs.get('activity_kind')!r} is non-negative")
    coords["activity_min"] = ("unit", parts["res"].amin * scale, min_attrs)
    attrs = _common.provenance(
        "ratemaps", rec, bin_size=grid.bin_size, sigma=parts["sigma"],
        sigma_units="bins", min_occupancy=parts["min_occupancy"], min_speed=min_speed,
        by=by, extent=list(grid.extent), n_samples=parts["n_valid"],
        samples_dropped=str(parts["dropped"]),
        smoothing=("normalized convolution: Gaussian-smoothed activity sums over "
                   "Gaussian-smoothed occupancy" if parts["sigma"] else "none"),
        unvisited="NaN (occupancy 0 or below min_occupancy)",
        units=units, long_name=long_name)
    arenas = _arena_vertices(rec)
    if arenas is not None:
        attrs["arena_environment"] = arenas[0]
        attrs["arena_vertices"] = arenas[1]
    return xr.DataArray(data * scale, dims=dims, coords=coords, attrs=attrs,
                        name="ratemap")


@fill_doc
def ratemaps(rec, *, bin_size=None, sigma=None, min_occupancy=None, min_speed=None,
             by=None, extent=None):
    """Occupancy-normalised mean activity of every unit in every spatial bin.

    .. math:: \\lambda_{u,i} = \\frac{\\sum_{t: x_t \\in i} a_{u,t}}{N_i}

    with :math:`N_i` the number of samples in bin :math:`i` (occupancy time
    :math:`N_i\\,dt`). With smoothing, the activity sums and the occupancy are each
    convolved with a Gaussian and then divided (normalized convolution), so unvisited
    bins do not drag the map towards zero. Unvisited bins are NaN. Spike counts are
    reported in Hz (divided by ``dt``); other activity keeps its units.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording (schema v1) with ``activity`` and ``position``; may be dask-backed
        (the samples are streamed chunk by chunk, never loaded whole).
    %(bin_size)s
    %(sigma_maps)s
    %(min_occupancy)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.DataArray
        Dims (unit, [environment | trial], y, x); coords ``occupancy`` (seconds per bin)
        and ``activity_min`` (each unit's minimum over the recording, used to make signed
        activity non-negative); attrs give every parameter and the arena outlines.

    References
    ----------
    Skaggs, McNaughton, Gothard & Markus (1993), An information-theoretic approach to
    deciphering the hippocampal code, NIPS 5. Knutsson & Westin (1993), Normalized and
    differential convolution, CVPR.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(2000) * 0.1
    >>> xy = 0.5 * np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> field = np.exp(-((xy - 0.2) ** 2).sum(1, keepdims=True) / 0.02)
    >>> rec = from_arrays(t, xy, activity=field, activity_kind="rate")
    >>> maps = ratemaps(rec, bin_size=0.1, sigma=0)
    >>> maps.dims
    ('unit', 'y', 'x')
    """
    parts = _ratemap_parts(rec, bin_size=bin_size, sigma=sigma, min_occupancy=min_occupancy,
                           min_speed=min_speed, by=by, extent=extent)
    return _maps_dataarray(rec, parts, parts["maps"][0], by=by, min_speed=min_speed)
