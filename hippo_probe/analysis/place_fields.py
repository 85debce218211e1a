"""Place fields: contiguous regions of a rate map above a fraction of its range."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import ndimage

from .._validators import check_dims, check_number, check_option
from . import _common
from ._common import refuse_map_options
from .._docs import fill_doc
from ._shuffles import flat_maps
from .config import PLACE_FIELD
from .ratemaps import ratemaps


@dataclass
class Fields:
    """Fields detected on a stack of maps (N, ny, nx).

    Attributes
    ----------
    labels : ndarray (N, ny, nx) int
        0 outside fields; fields of each map numbered 1, 2, ... by decreasing peak.
    count : ndarray (N,) int
    map_index, number : ndarray (F,) int
        Map and number (1-based) of each field, ordered by map then number.
    size : ndarray (F,) int
        Bins of each field.
    peak, mean : ndarray (F,)
        Peak and mean rate of each field (the map's units).
    peak_index : ndarray (F, 2)
        (row, column) of each field's peak.
    centroid_index : ndarray (F, 2)
        (row, column) of each field's centre of mass, weighted by the rate above the map's
        minimum (fractional bins).
    level : ndarray (N,)
        Each map's detection level, ``min + threshold (peak - min)``.
    """

    labels: np.ndarray
    count: np.ndarray
    map_index: np.ndarray
    number: np.ndarray
    size: np.ndarray
    peak: np.ndarray
    mean: np.ndarray
    peak_index: np.ndarray
    centroid_index: np.ndarray
    level: np.ndarray


def detect_fields(maps, *, threshold, min_bins, min_peak=-np.inf, connectivity=1,
                  describe=True) -> Fields:
    """Fields of every map of a stack: contiguous bins above a level, large enough.

    .. math:: F = \\text{connected components of }
              \\{i : \\lambda_i > \\lambda_{min} + \\theta(\\lambda_{max} - \\lambda_{min})\\},
              \\quad |F| \\ge n_{min},\\ \\max_F \\lambda \\ge \\lambda_{peak}

    over the visited (finite) bins, with connectivity from
    ``scipy.ndimage.generate_binary_structure(2, connectivity)``. All maps are labelled in
    one call (a 3-D structure that connects bins of the same map only).

    Parameters
    ----------
    maps : ndarray (N, ny, nx)
        Rate maps, NaN where unvisited.
    threshold : float
        Fraction of each map's range above its minimum, in [0, 1).
    min_bins : int
        Smallest field, in bins.
    min_peak : float
        Smallest field peak, in the maps' units (default: none).
    connectivity : {1, 2}
        4- or 8-connectivity.
    describe : bool
        Measure each field's peak, mean and centre (else only labels, counts and sizes,
        fields numbered in label order: the border score needs no more).

    Returns
    -------
    Fields
    """
    maps = np.asarray(maps, float)
    n_maps = maps.shape[0]
    finite = np.isfinite(maps)
    with np.errstate(invalid="ignore"):
        any_finite = finite.reshape(n_maps, -1).any(axis=1)
        lo = np.where(any_finite, np.nanmin(np.where(finite, maps, np.inf), axis=(1, 2)),
                      np.nan)
        hi = np.where(any_finite, np.nanmax(np.where(finite, maps, -np.inf), axis=(1, 2)),
                      np.nan)
        level = lo + threshold * (hi - lo)
        above = finite & (maps > level[:, None, None]) & (hi > lo)[:, None, None]
    structure = np.zeros((3, 3, 3), bool)
    structure[1] = ndimage.generate_binary_structure(2, connectivity)
    labels, n = ndimage.label(above, structure=structure)
    index = np.arange(1, n + 1)
    if not describe:
        return _lean_fields(labels, n, min_bins, level)
    filled = np.where(finite, maps, 0.0)
    weight = np.where(above, maps - lo[:, None, None], 0.0)
    if n:
        size = np.bincount(labels.ravel(), minlength=n + 1)[1:]
        peak = np.asarray(ndimage.maximum(filled, labels, index), float)
        total = np.asarray(ndimage.sum_labels(filled, labels, index), float)
        peak_pos = np.asarray(ndimage.maximum_position(filled, labels, index), int)
        w = np.asarray(ndimage.sum_labels(weight, labels, index), float)
        rows = np.broadcast_to(np.arange(maps.shape[1])[None, :, None], maps.shape)
        cols = np.broadcast_to(np.arange(maps.shape[2])[None, None, :], maps.shape)
        cy = np.asarray(ndimage.sum_labels(weight * rows, labels, index), float)
        cx = np.asarray(ndimage.sum_labels(weight * cols, labels, index), float)
        with np.errstate(invalid="ignore", divide="ignore"):
            centroid = np.c_[cy / w, cx / w]
        map_index = peak_pos[:, 0]
    else:
        size = peak = total = w = np.zeros(0)
        peak_pos = np.zeros((0, 3), int)
        centroid = np.zeros((0, 2))
        map_index = np.zeros(0, int)
    keep = (size >= min_bins) & (peak >= min_peak)
    # renumber each map's kept fields 1, 2, ... by decreasing peak
    order = np.lexsort((-peak[keep], map_index[keep]))
    kept = np.flatnonzero(keep)[order]
    k_map = map_index[kept]
    number, relabel = _renumber(kept, k_map, n)
    new_labels = relabel[labels]
    count = np.bincount(k_map, minlength=n_maps).astype(np.int64)
    return Fields(labels=new_labels, count=count, map_index=k_map, number=number,
                  size=size[kept].astype(np.int64), peak=peak[kept],
                  mean=(total[kept] / np.maximum(size[kept], 1)),
                  peak_index=peak_pos[kept, 1:], centroid_index=centroid[kept],
                  level=level)


def _renumber(kept, k_map, n):
    """Fields kept (indices into the n labels, grouped by map ``k_map``) numbered 1, 2, ...
    within each map, and the old-label -> new-number table (0 = dropped)."""
    first = np.r_[True, k_map[1:] != k_map[:-1]] if len(kept) else np.zeros(0, bool)
    start = np.maximum.accumulate(np.where(first, np.arange(len(kept)), 0)) \
        if len(kept) else np.zeros(0, int)
    number = np.arange(len(kept)) - start + 1
    relabel = np.zeros(n + 1, np.int64)
    relabel[kept + 1] = number
    return number, relabel


def _lean_fields(labels, n, min_bins, level):
    """:class:`Fields` with labels, counts and sizes only (fields in label order)."""
    n_maps = labels.shape[0]
    size = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    objects = ndimage.find_objects(labels, max_label=n)
    map_index = np.array([sl[0].start for sl in objects], dtype=np.int64) if n \
        else np.zeros(0, np.int64)
    kept = np.flatnonzero(size >= min_bins)
    k_map = map_index[kept]
    number, relabel = _renumber(kept, k_map, n)
    empty = np.full(len(kept), np.nan)
    return Fields(labels=relabel[labels], count=np.bincount(k_map, minlength=n_maps),
                  map_index=k_map, number=number, size=size[kept].astype(np.int64),
                  peak=empty, mean=empty, peak_index=np.zeros((len(kept), 2), int),
                  centroid_index=np.full((len(kept), 2), np.nan), level=level)


def check_maps(name, maps):
    """``maps`` must be the output of :func:`ratemaps` (dims unit, [group], y, x)."""
    if not isinstance(maps, xr.DataArray):
        raise TypeError(f"`{name}` must be a recording (xarray.Dataset) or the output of "
                        f"ratemaps() (xarray.DataArray); got {type(maps).__name__}")
    if not {"y", "x"} <= set(maps.dims):      # e.g. a recording's activity
        raise ValueError(f"`{name}` must be a recording (xarray.Dataset) or the output of "
                         f"ratemaps() (dims unit, [group], y, x); got a DataArray with dims "
                         f"{maps.dims}")
    check_dims(name, maps, ("unit", "y", "x"))
    if maps.ndim > 4:
        raise ValueError(f"`{name}` must have dims (unit, [group], y, x); got {maps.dims}")
    lead = ("unit",) + tuple(d for d in maps.dims if d not in ("unit", "y", "x"))
    return maps.transpose(*lead, "y", "x"), lead


def bin_coords(maps):
    """Bin centres (x, y) and bin size of labelled maps."""
    x, y = maps["x"].values, maps["y"].values
    size = maps.attrs.get("bin_size")
    if size is None:
        size = float(np.median(np.diff(x))) if len(x) > 1 else float(np.median(np.diff(y)))
    return x, y, float(size)


def _interp(axis_values, index):
    """Coordinate at a fractional bin index (the bins are evenly spaced)."""
    step = axis_values[1] - axis_values[0] if len(axis_values) > 1 else 0.0
    return axis_values[0] + np.asarray(index, float) * step


@fill_doc
def place_fields(rec_or_maps, *, threshold=None, min_bins=None, min_peak=None,
                 connectivity=None, bin_size=None, sigma=None, min_speed=None, by=None,
                 extent=None):
    """Place fields of every unit: their count, size, peak and centre.

    .. math:: F = \\text{connected components of }
              \\{i : \\lambda_i > \\lambda_{min} + \\theta\\,(\\lambda_{max} -
              \\lambda_{min})\\},\\qquad |F| \\ge n_{min}

    A field is a contiguous set (4-connected by default; ``scipy.ndimage.label``) of
    visited bins of the (smoothed) rate map above a fraction ``threshold`` of the map's
    range above its minimum, with at least ``min_bins`` bins and a peak of at least
    ``min_peak``. For spike maps, whose minimum is about 0, the level is the usual fraction
    of the peak rate; taking the range makes the rule offset-invariant, so the LSTM's signed
    h needs no shift. Fields are numbered by decreasing peak. A field's centre is its
    centre of mass, each bin weighted by its rate above the map's minimum.

    Parameters
    ----------
    rec_or_maps : xarray.Dataset or xarray.DataArray
        A recording (maps are made here with :func:`hippo_probe.ratemaps`, smoothed by one
        bin by default) or the output of :func:`ratemaps`.
    threshold : float, optional
        Fraction of the range (default 0.2).
    min_bins : int, optional
        Smallest field in bins (default 9).
    min_peak : float, optional
        Smallest field peak in the maps' units (default None: none).
    connectivity : {1, 2}, optional
        4- (1, default) or 8-connectivity (2).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``n_fields`` (unit, [group]); per field (dim ``field``, NaN beyond a unit's count):
        ``field_size`` (bins), ``field_area`` (m^2), ``field_peak`` and ``field_mean``
        (the maps' units), ``field_centroid`` and ``field_peak_position`` (``space`` = x,
        y, in m); ``field_label`` (unit, [group], y, x): 0 outside fields, else the field's
        number; ``level`` (the detection level of each map).

    References
    ----------
    O'Keefe & Dostrovsky (1971), Brain Res. 34:171-175. Muller, Kubie & Ranck (1987),
    Spatial firing patterns of hippocampal complex-spike cells in a fixed environment,
    J. Neurosci. 7:1935-1950. The 9-bin minimum is that of the BNT and opexebo
    (``firing_field_min_bins``).

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> rng = np.random.default_rng(0)
    >>> xy = rng.uniform(-0.5, 0.5, (20000, 2))
    >>> centres = np.array([[-0.25, -0.25], [0.25, 0.2]])
    >>> rate = np.exp(-((xy[:, None] - centres) ** 2).sum(-1) / (2 * 0.06**2)).sum(1)
    >>> rec = from_arrays(np.arange(20000) * 0.1, xy, activity=rate[:, None],
    ...                   activity_kind="rate")
    >>> fields = place_fields(rec, bin_size=0.05)
    >>> int(fields.n_fields[0])
    2

    The fields outlined on their maps (``ratemap_grid``'s ``fields=``):

    >>> from hippo_probe import ratemaps
    >>> maps = ratemaps(rec, bin_size=0.05)
    >>> fig = maps.hp.plot(fields=place_fields(maps))
    """
    threshold = check_number("threshold", PLACE_FIELD.threshold if threshold is None
                             else threshold, low=0, high=1, low_inclusive=True,
                             high_inclusive=False)
    min_bins = check_number("min_bins", PLACE_FIELD.min_bins if min_bins is None
                            else min_bins, low=1, low_inclusive=True, integer=True)
    min_peak = PLACE_FIELD.min_peak if min_peak is None else min_peak
    if min_peak is not None:
        min_peak = check_number("min_peak", min_peak)
    connectivity = check_option("connectivity", PLACE_FIELD.connectivity if connectivity
                                is None else connectivity, (1, 2))
    if isinstance(rec_or_maps, xr.Dataset):
        maps = ratemaps(rec_or_maps, bin_size=bin_size, sigma=sigma, min_speed=min_speed,
                        by=by, extent=extent)
    else:
        refuse_map_options(bin_size=bin_size, sigma=sigma, min_speed=min_speed, by=by,
                           extent=extent)
        maps = rec_or_maps
    maps, lead = check_maps("rec_or_maps", maps)
    flat, shape = flat_maps(maps.values)
    f = detect_fields(flat, threshold=threshold, min_bins=min_bins,
                      min_peak=-np.inf if min_peak is None else min_peak,
                      connectivity=connectivity)
    return fields_dataset(maps, lead, shape, f, analysis="place_fields",
                          params=dict(threshold=threshold, min_bins=min_bins,
                                      min_peak=min_peak, connectivity=connectivity))


def fields_dataset(maps, lead, shape, f: Fields, *, analysis, params):
    """Label detected fields as a Dataset (see :func:`place_fields`)."""
    x, y, size = bin_coords(maps)
    n_max = int(f.count.max()) if f.count.size and f.count.max() > 0 else 0
    n_maps = f.count.size

    def per_field(values, fill=np.nan, trailing=()):
        out = np.full((n_maps, n_max) + trailing, fill, float)
        if len(f.map_index):
            out[f.map_index, f.number - 1] = values
        return out.reshape(shape + (n_max,) + trailing)

    centroid = np.c_[_interp(x, f.centroid_index[:, 1]), _interp(y, f.centroid_index[:, 0])]
    peak_xy = np.c_[x[f.peak_index[:, 1]], y[f.peak_index[:, 0]]] if len(f.size) \
        else np.zeros((0, 2))
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    coords["field"] = ("field", np.arange(1, n_max + 1), {"units": "1",
                                                         "long_name": "field number"})
    coords["space"] = ["x", "y"]
    coords["y"] = maps["y"]
    coords["x"] = maps["x"]
    units = maps.attrs.get("units", "1")
    out = xr.Dataset(coords=coords)
    out["n_fields"] = (lead, f.count.reshape(shape), {"units": "1",
                                                      "long_name": "number of fields"})
    fl = lead + ("field",)
    out["field_size"] = (fl, per_field(f.size), {"units": "bins", "long_name": "field size"})
    out["field_area"] = (fl, per_field(f.size * size**2), {"units": "m^2",
                                                           "long_name": "field area"})
    out["field_peak"] = (fl, per_field(f.peak), {"units": units, "long_name": "field peak"})
    out["field_mean"] = (fl, per_field(f.mean), {"units": units,
                                                 "long_name": "mean rate in the field"})
    out["field_centroid"] = (fl + ("space",), per_field(centroid, trailing=(2,)), {
        "units": "m", "long_name": "field centre of mass"})
    out["field_peak_position"] = (fl + ("space",), per_field(peak_xy, trailing=(2,)), {
        "units": "m", "long_name": "position of the field's peak"})
    out["field_label"] = (lead + ("y", "x"), f.labels.reshape(shape + f.labels.shape[1:]), {
        "units": "1", "long_name": "field number (0 = none)"})
    out["level"] = (lead, f.level.reshape(shape), {"units": units,
                                                   "long_name": "detection level"})
    attrs = {k: v for k, v in maps.attrs.items()
             if k not in ("analysis", "units", "long_name", "arena_vertices",
                          "arena_environment")}
    attrs.update(_common.provenance(
        analysis, **params, map_sigma=maps.attrs.get("sigma", "unknown"),
        definition="connected components of visited bins above min + threshold x "
                   "(peak - min) of each map, at least min_bins bins"))
    reasons = ["no visited bin" if not np.isfinite(lv) else "" for lv in f.level]
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["n_fields"]), reasons,
                                   "field detection level")
    return out
