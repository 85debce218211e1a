"""Skaggs spatial information, exact, with an optional shuffle correction."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_dims
from . import _common
from .._docs import fill_doc
from .config import INFORMATION
from .ratemaps import _maps_dataarray, _ratemap_parts


def skaggs_information(maps, occupancy, axes):
    """Skaggs information (bits per unit of activity) and mean rate of each map.

    .. math:: I = \\sum_i p_i \\frac{\\lambda_i}{\\bar\\lambda}
              \\log_2 \\frac{\\lambda_i}{\\bar\\lambda},\\qquad
              \\bar\\lambda = \\sum_i p_i \\lambda_i,\\qquad p_i = N_i / \\sum_j N_j

    over the bins with a finite rate; every bin counts, including those below the mean
    (their terms are negative), and :math:`0 \\log 0 = 0`. ``maps`` must be non-negative.
    """
    maps = np.asarray(maps, float)
    occ = np.where(np.isfinite(maps), np.broadcast_to(occupancy, maps.shape), 0.0)
    total = occ.sum(axis=axes, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        p = occ / total
        lam = np.where(occ > 0, maps, 0.0)
        mean = (p * lam).sum(axis=axes, keepdims=True)
        ratio = lam / mean
        terms = np.where(ratio > 0, p * ratio * np.log2(np.where(ratio > 0, ratio, 1.0)), 0.0)
        info = terms.sum(axis=axes)
    mean = np.squeeze(mean, axis=axes)
    info = np.where((mean > 0) & np.isfinite(mean), info, np.nan)
    return info, mean


def _nan_reason(mean, total_occ):
    if not np.isfinite(total_occ) or total_occ <= 0:
        return "no bin with a rate (unvisited, or below `min_occupancy`)"
    if not np.isfinite(mean):
        return "activity holds NaN or inf"
    if mean <= 0:
        return "mean activity is 0 (after the non-negative shift): information undefined"
    return ""


@fill_doc
def spatial_information(rec_or_maps, *, n_shuffles=None, seed=None, bin_size=None,
                        sigma=None, min_occupancy=None, min_speed=None, by=None,
                        extent=None):
    """Skaggs spatial information of every unit, exact.

    .. math:: I = \\sum_i p_i \\frac{\\lambda_i}{\\bar\\lambda}
              \\log_2 \\frac{\\lambda_i}{\\bar\\lambda} \\quad
              \\text{(bits per unit of activity; bits/spike for spikes)},
              \\qquad \\dot I = \\bar\\lambda\\, I \\quad \\text{(bits/s)}

    with :math:`p_i` the occupancy probability of bin :math:`i`, :math:`\\lambda_i` the
    rate map and :math:`\\bar\\lambda = \\sum_i p_i\\lambda_i`. No bin is clipped (some
    implementations drop bins below the mean, which overstates I). Skaggs information is
    not offset-invariant: signed activity (the LSTM's h) is first made a non-negative rate
    per unit, ``activity - min`` over the recording (stated in ``attrs['rate_offset']``).

    The finite-sample bias (information of a spatially uniform unit is > 0 on a finite
    recording) is estimated with ``n_shuffles`` circular time shifts of the activity
    against the trajectory; ``information_corrected = information - mean(shuffled)``.
    Without shuffles (the default) only the raw estimate is returned: on spike counts,
    compare units by ``information_corrected`` (``n_shuffles=100``, say): a spatially
    flat 1 Hz Poisson unit over 10 minutes of 20 ms bins scores 0.70 bits/spike raw,
    -0.003 corrected.

    Parameters
    ----------
    rec_or_maps : xarray.Dataset or xarray.DataArray
        A recording (maps are made here, unsmoothed by default) or the output of
        :func:`ratemaps` (which keeps occupancy and ``activity_min``).
    n_shuffles : int, optional
        Number of circular time-shift shuffles (default 0; needs a recording; refused
        with ``by``: the shifts would mix the groups' activity into each group's null;
        shuffle a group alone by selecting its trials, :func:`~hippo_probe.select_trials`).
    %(seed)s
    %(bin_size)s
    %(sigma_unsmoothed)s
    %(min_occupancy)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``information`` (unit, [group]) in bits per unit of activity (bits/spike for
        spikes), ``information_rate`` in bits/s (spikes and rates in Hz; NaN for other
        activity, which has no rate), ``mean_rate``; with shuffles also
        ``shuffle_mean``, ``shuffle_std``, ``information_corrected`` and ``p_value``.

    References
    ----------
    Skaggs, McNaughton, Gothard & Markus (1993), An information-theoretic approach to
    deciphering the hippocampal code, NIPS 5, 1030-1037.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(4000) * 0.1
    >>> xy = np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> rate = np.c_[(xy[:, 0] > 0.5).astype(float), np.ones(len(t))]
    >>> rec = from_arrays(t, xy, activity=rate, activity_kind="rate")
    >>> info = spatial_information(rec, bin_size=0.25)
    >>> bool(info.information[0] > 1.0), float(info.information[1])
    (True, 0.0)
    """
    n_shuffles = INFORMATION.n_shuffles if n_shuffles is None else n_shuffles
    if isinstance(rec_or_maps, xr.DataArray):
        _common.refuse_map_options(n_shuffles, seed=seed, bin_size=bin_size, sigma=sigma,
                                   min_occupancy=min_occupancy, min_speed=min_speed,
                                   by=by, extent=extent)
        maps = rec_or_maps
        if "occupancy" not in maps.coords or "activity_min" not in maps.coords:
            raise ValueError("`rec_or_maps` must be a recording or the output of "
                             "ratemaps() (with coords 'occupancy' and 'activity_min'); "
                             f"got a DataArray with coords {list(maps.coords)}")
        rec, stack = None, None
        attrs_from = maps.attrs
    else:
        rec = _common.check_recording(rec_or_maps, ["activity", "position"],
                                      why="spatial information")
        shifts = _common.shifts_for(rec, n_shuffles, seed, by)
        parts = _ratemap_parts(
            rec, bin_size=bin_size, sigma=INFORMATION.sigma if sigma is None else sigma,
            min_occupancy=min_occupancy, min_speed=min_speed, by=by, extent=extent,
            shifts=shifts)
        stack = parts["maps"]
        maps = _maps_dataarray(rec, parts, stack[0], by=by, min_speed=min_speed)
        attrs_from = maps.attrs

    kind_rec = rec if rec is not None else xr.Dataset(attrs=attrs_from)
    check_dims("rec_or_maps", maps, ("unit", "y", "x"))
    floor = maps.min([d for d in maps.dims if d != "unit"], skipna=True).values
    offset, why_offset = _common.nonnegative_offset(kind_rec, maps["activity_min"].values,
                                                    floor)
    lead = tuple(d for d in maps.dims if d not in ("y", "x"))
    maps = maps.transpose(*lead, "y", "x")
    axes = (-2, -1)
    offset = offset.reshape((-1,) + (1,) * (maps.ndim - 1))
    occ = maps["occupancy"].transpose(*[d for d in maps.dims if d in maps["occupancy"].dims])
    occ = np.broadcast_to(occ.values, maps.shape[1:])
    info, mean = skaggs_information(maps.values - offset, occ, axes)

    is_hz = maps.attrs.get("units") == "Hz"
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    unit_info = "bits/spike" if is_hz else "bits per unit of activity"
    out = xr.Dataset(coords=coords)
    out["information"] = (lead, info, {"units": unit_info, "long_name": "spatial information"})
    # bits/s needs a rate of events (spikes in Hz): a signal in other units has none
    rate_attrs = {"units": "bits/s", "long_name": "spatial information rate"}
    if not is_hz:
        rate_attrs["note"] = (f"NaN: bits/s is information x mean firing rate (Hz); this "
                              f"activity is in {maps.attrs.get('units', '1')!r}, not a rate")
    out["information_rate"] = (lead, info * mean if is_hz else np.full_like(info, np.nan),
                               rate_attrs)
    out["mean_rate"] = (lead, mean, {"units": maps.attrs.get("units", "1"),
                                     "long_name": "mean rate (after the non-negative shift)"})
    if stack is not None and len(stack) > 1:
        scale = _common.rate_scale(rec)[0]
        shuffled_maps = stack[1:] if by is not None else stack[1:, :, 0]
        shuffled, _ = skaggs_information(shuffled_maps * scale - offset, occ, axes)
        s_mean, s_std = np.nanmean(shuffled, axis=0), np.nanstd(shuffled, axis=0)
        exceed = (shuffled >= info[None]).sum(axis=0)
        out["shuffle_mean"] = (lead, s_mean, {"units": unit_info,
                                              "long_name": "mean information of shuffles"})
        out["shuffle_std"] = (lead, s_std, {"units": unit_info,
                                            "long_name": "s.d. of information of shuffles"})
        out["information_corrected"] = (lead, info - s_mean, {
            "units": unit_info, "long_name": "shuffle-corrected spatial information"})
        out["p_value"] = (lead, (1 + exceed) / len(stack), {
            "units": "1", "long_name": "fraction of shuffles at least as informative"})
    # the occupancy of the bins with a rate: those below `min_occupancy` are NaN maps
    total_occ = np.where(np.isfinite(maps.values), occ, 0.0).sum(axis=axes)
    reasons = [_nan_reason(m, o) for m, o in zip(mean.ravel(), total_occ.ravel())]
    attrs = {k: v for k, v in attrs_from.items()
             if k not in ("analysis", "units", "long_name", "arena_vertices",
                          "arena_environment")}
    attrs.update(_common.provenance("spatial_information", n_shuffles=n_shuffles,
                                    seed=_common.shuffle_seed(seed), rate_offset=why_offset,
                                    definition="Skaggs et al. 1993, no clipping"))
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["information"]),
                                   reasons, "spatial information")
    return out
