"""Speed score (Kropff et al. 2015): correlation of activity with running speed."""

from __future__ import annotations

import itertools

import numpy as np
import xarray as xr
from scipy import ndimage

from .._validators import check_number, check_option
from . import _common
from ._common import shifts_for
from .._docs import fill_doc
from ._shuffles import add_significance, check_percentile
from .config import CELL_CLASS, RATEMAP, SPEED


def smooth_in_trials(values, trial, sigma_samples, truncate=None):
    """Gaussian smoothing along axis 0, within each run of equal ``trial`` labels.

    Normalized convolution inside each trial (smoothed values over smoothed ones), so a
    trial's first and last samples are not pulled towards zero and samples of another
    trial never mix in; NaN samples are left out the same way.
    """
    values = np.asarray(values, float)
    if sigma_samples <= 0 or len(values) == 0:
        return values
    truncate = RATEMAP.truncate if truncate is None else truncate
    trial = np.asarray(trial).ravel()
    out = np.empty_like(values)
    edges = np.flatnonzero(np.r_[True, trial[1:] != trial[:-1], True])
    for a, b in itertools.pairwise(edges):
        seg = values[a:b]
        ok = np.isfinite(seg)
        num = ndimage.gaussian_filter1d(np.where(ok, seg, 0.0), sigma_samples, axis=0,
                                        mode="constant", truncate=truncate)
        den = ndimage.gaussian_filter1d(ok.astype(float), sigma_samples, axis=0,
                                        mode="constant", truncate=truncate)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[a:b] = np.where(den > 1e-12, num / den, np.nan)
    return out


def _smooth_block(block, trial_block, sigma_samples):
    return smooth_in_trials(block, trial_block[:, 0], sigma_samples)


def _partial(block, t0, speed, valid, shifts, rows):
    """Sums over the samples ``t0 .. t0 + m`` of one activity block, for every shift.

    Shift ``k`` pairs activity at ``t`` with speed at ``t - shifts[k]`` (circularly).
    """
    block = np.asarray(block, float)
    m = block.shape[0]
    n = len(speed)
    sums = {k: 0.0 for k in ("n", "sa", "saa", "sas", "ss", "sss")}
    for a in range(0, m, rows):
        blk = block[a:a + rows]
        t = t0 + a + np.arange(len(blk))
        src = (t[:, None] - shifts[None, :]) % n
        msk = valid[src].astype(float)               # (m, K)
        s = np.where(valid[src], speed[src], 0.0)    # masked speed
        sums["n"] = sums["n"] + msk.sum(0)
        sums["ss"] = sums["ss"] + s.sum(0)
        sums["sss"] = sums["sss"] + (s * s).sum(0)
        sums["sa"] = sums["sa"] + blk.T @ msk       # (U, K)
        sums["saa"] = sums["saa"] + (blk * blk).T @ msk
        sums["sas"] = sums["sas"] + blk.T @ s
    return sums


def _add(parts):
    out = dict(parts[0])
    for p in parts[1:]:
        for k, v in p.items():
            out[k] = out[k] + v
    return out


def speed_sums(act, speed, valid, shifts, trial, sigma_samples, rows):
    """Sums of :func:`_partial` over the whole recording, eager or lazy (dask)."""
    if not hasattr(act, "dask"):
        sm = smooth_in_trials(np.asarray(act, float), trial, sigma_samples)
        return _partial(sm, 0, speed, valid, shifts, rows)
    import dask
    import dask.array as da

    if sigma_samples > 0:
        depth = int(np.ceil(RATEMAP.truncate * sigma_samples)) + 1
        labels = da.from_array(np.asarray(trial).reshape(-1, 1), chunks=(act.chunks[0], 1))
        act = da.map_overlap(_smooth_block, act.astype(float), labels,
                             depth=[{0: depth, 1: 0}, {0: depth, 1: 0}],
                             boundary="none", sigma_samples=sigma_samples,
                             dtype=float, align_arrays=False)
    blocks = act.to_delayed()
    starts = np.concatenate([[0], np.cumsum(act.chunks[0])[:-1]])
    part = dask.delayed(_partial, pure=True)
    sp, va, sh = (dask.delayed(x, pure=True) for x in (speed, valid, shifts))
    columns = [dask.delayed(_add)([part(blocks[i, j], int(starts[i]), sp, va, sh, rows)
                                   for i in range(blocks.shape[0])])
               for j in range(blocks.shape[1])]
    results = dask.compute(*columns)
    out = dict(results[0])
    for k in ("sa", "saa", "sas"):
        out[k] = np.concatenate([r[k] for r in results], axis=0)
    return out


def correlation(sums):
    """Pearson r (U, K), slope and intercept of the linear fit, from the sums."""
    n, sa, saa, sas, ss, sss = (np.asarray(sums[k], float) for k in
                                ("n", "sa", "saa", "sas", "ss", "sss"))
    with np.errstate(invalid="ignore", divide="ignore"):
        cov = n * sas - sa * ss
        var_a = n * saa - sa * sa
        var_s = n * sss - ss * ss
        r = cov / np.sqrt(var_a * var_s)
        slope = cov / var_s
        intercept = (sa - slope * ss) / n
    tiny = 1e-12 * np.maximum(n * saa, 1e-300)
    r = np.where(var_a > tiny, r, np.nan)
    return np.clip(r, -1, 1), slope, intercept


def speed_arrays(rec, *, n_shuffles, seed, sigma, min_speed, max_speed):
    """Speed scores (U, K + 1) of the observed (column 0) and shifted speeds, the linear
    fit (U, K + 1) each, the raw sums and the samples in the speed range."""
    dt = _common.sample_dt(rec)
    trial = _common.values(rec["trial"]) if "trial" in rec.variables else \
        np.zeros(rec.sizes["time"], np.int64)
    sigma_samples = sigma / dt
    speed = smooth_in_trials(_common.speed(rec), trial, sigma_samples)
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(speed) & (speed >= min_speed) & (speed <= max_speed)
    if not valid.any():
        raise ValueError(f"no sample with a speed in [{min_speed}, {max_speed}] m/s "
                         "(`min_speed`, `max_speed`): cannot compute speed scores")
    shifts = shifts_for(rec, n_shuffles, seed)
    act = _common.activity(rec).data
    sums = speed_sums(act, np.where(valid, speed, 0.0), valid, shifts, trial,
                      sigma_samples, SPEED.block)
    r, slope, intercept = correlation(sums)
    return r, slope, intercept, sums, valid


@fill_doc
def speed_score(rec, *, n_shuffles=None, seed=None, percentile=None, threshold=None,
                sigma=None, min_speed=None, max_speed=None):
    """Speed score of every unit: the correlation of its activity with running speed.

    .. math:: s = \\mathrm{corr}_t\\left(a_t, v_t\\right),\\qquad
              a_t = (G_\\sigma * a)_t,\\ v_t = (G_\\sigma * v)_t

    Pearson correlation over the samples whose (smoothed) speed lies in
    [``min_speed``, ``max_speed``] (default 2-50 cm/s), after both activity and speed are
    smoothed in time, within trials, by a Gaussian of ``sigma`` s (default 0.25 s). Speed
    is ``rec.speed``, else derived from ``position`` within trials. The linear fit
    ``a = intercept + slope * v`` over the same samples is given too.

    Significance: the same correlation with the speed shifted circularly in time by
    ``n_shuffles`` random shifts (each at least 20 s); the threshold is their 99th
    percentile (Kropff et al. 2015). Computed in one pass over the samples (all shifts
    together, blocks of samples times shifted speeds), eager or lazy (dask).

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and ``position`` (or ``speed``); may be dask-backed.
    %(n_shuffles)s
    %(seed)s
    percentile : float, optional
        Default 99.
    threshold : {'unit', 'pooled'}, optional
    sigma : float, optional
        Smoothing s.d. in seconds (default 0.25; 0 = none).
    min_speed, max_speed : float, optional
        Speed range in m/s (default 0.02, 0.5).

    Returns
    -------
    xarray.Dataset
        ``speed_score`` (unit), ``speed_slope`` (activity units per m/s),
        ``speed_intercept``, coord ``n_samples``; with shuffles ``speed_score_threshold``,
        ``speed_score_p_value``, ``speed_score_shuffle_mean``, ``speed_score_shuffle_std``.

    References
    ----------
    Kropff, Carmichael, Moser & Moser (2015), Speed cells in the medial entorhinal cortex,
    Nature 523:419-424.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(20000) * 0.1
    >>> xy = np.c_[np.cumsum(0.02 * np.sin(t / 9)), np.zeros(20000)]
    >>> rate = np.abs(np.sin(t / 9))[:, None] * 5          # follows the speed
    >>> rec = from_arrays(t, xy, activity=rate, activity_kind="rate")
    >>> bool(speed_score(rec, n_shuffles=0).speed_score[0] > 0.9)
    True
    """
    rec = _common.check_recording(rec, ["activity"], why="speed score")
    if "speed" not in rec:
        rec = _common.check_recording(rec, ["position"], why="speed score (no `speed` variable)")
    n_shuffles = CELL_CLASS.n_shuffles if n_shuffles is None else n_shuffles
    percentile = check_percentile("percentile", CELL_CLASS.speed_percentile
                                  if percentile is None else percentile)
    threshold = check_option("threshold", CELL_CLASS.threshold if threshold is None
                             else threshold, ("unit", "pooled"))
    sigma = check_number("sigma", SPEED.sigma if sigma is None else sigma, low=0,
                         low_inclusive=True)
    min_speed = check_number("min_speed", SPEED.min_speed if min_speed is None
                             else min_speed, low=0, low_inclusive=True)
    if max_speed is None and min_speed >= SPEED.max_speed:
        raise ValueError(f"`min_speed` must be < the default max_speed {SPEED.max_speed} "
                         f"m/s; got {min_speed} (pass a larger max_speed too)")
    max_speed = check_number("max_speed", SPEED.max_speed if max_speed is None
                             else max_speed, low=min_speed)
    r, slope, intercept, sums, valid = speed_arrays(
        rec, n_shuffles=n_shuffles, seed=seed, sigma=sigma, min_speed=min_speed,
        max_speed=max_speed)
    coords = {name: c for name, c in rec["activity"].coords.items() if c.dims == ("unit",)}
    coords["n_samples"] = ((), int(valid.sum()), {"units": "1",
                                                 "long_name": "samples in the speed range"})
    out = xr.Dataset(coords=coords)
    # spike counts per sample as Hz (Kropff et al. report Hz per cm/s); others as they are
    scale, units, _ = _common.rate_scale(rec)
    out["speed_score"] = ("unit", r[:, 0], {"units": "1", "long_name": "speed score"})
    out["speed_slope"] = ("unit", slope[:, 0] * scale, {
        "units": f"{units} per m/s", "long_name": "slope of activity on speed"})
    out["speed_intercept"] = ("unit", intercept[:, 0] * scale, {
        "units": units, "long_name": "activity at zero speed (linear fit)"})
    if n_shuffles:
        add_significance(out, "speed_score", ("unit",), r[:, 0], r[:, 1:].T, percentile,
                         threshold, "1", "speed score")
    attrs = _common.provenance(
        "speed_score", rec, n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed),
        percentile=percentile,
        threshold=threshold, sigma=sigma, sigma_units="s", min_speed=min_speed,
        max_speed=max_speed,
        speed_source="rec.speed" if "speed" in rec else "derived from position",
        definition="Pearson correlation of smoothed activity and smoothed speed over "
                   "samples in the speed range (Kropff et al. 2015)")
    finite = np.isfinite(np.asarray(sums["saa"])[:, 0])
    reasons = ["" if np.isfinite(v) else "activity holds NaN or inf" if not ok else
               "activity is constant over the samples in the speed range"
               for v, ok in zip(r[:, 0], finite)]
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["speed_score"]), reasons,
                                   "speed score")
    return out
