"""Head-direction x place conjunctive tuning: the factorial (position x direction) model."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from .._validators import check_allocation, check_number, check_option
from . import _common
from ._common import AnalysisWarning
from ._common import shifts_for
from ._shuffles import add_significance, check_percentile
from .config import CELL_CLASS, CONJUNCTIVE, HEAD_DIRECTION
from .head_direction_tuning import (direction_bins, mean_vector, narrow_reason,
                                    unvisited_arc)
from .ratemaps import _positions, position_bins, spatial_grid, tuning_sums
from .spatial_information import skaggs_information
from .._docs import fill_doc


def _ratio(num, den):
    """``num / den`` where ``den > 0``, else 0."""
    return np.divide(num, den, out=np.zeros(np.broadcast(num, den).shape), where=den > 0)


def factorize(sums, counts, n_iterations, tolerance):
    """Maximum-likelihood factorial model of joint (direction x position) tuning.

    .. math:: \\hat S_{d,x} = f_x\\, g_d\\, N_{d,x};\\qquad
              f_x = \\frac{\\sum_d S_{d,x}}{\\sum_d g_d N_{d,x}},\\quad
              g_d = \\frac{\\sum_x S_{d,x}}{\\sum_x f_x N_{d,x}}

    iterated from :math:`g = 1` (Burgess et al. 2005): the position factor ``f`` is the
    rate map corrected for how directions were sampled in each place, and the direction
    factor ``g`` the tuning curve corrected for where each direction was sampled.
    ``g`` is scaled to an occupancy-weighted mean of 1, so ``f`` carries the rate.

    Parameters
    ----------
    sums : ndarray (..., D, X)
        Non-negative activity summed over the samples of each (direction, position) bin.
    counts : ndarray (D, X)
        Samples per bin.

    Returns
    -------
    f : ndarray (..., X), NaN at unvisited positions
    g : ndarray (..., D), NaN at unsampled directions
    n_iter : int
    """
    sums = np.asarray(sums, float)
    counts = np.asarray(counts, float)
    lead = sums.shape[:-2]
    s_x = sums.sum(axis=-2)
    s_d = sums.sum(axis=-1)
    occ_x = counts.sum(0) > 0
    occ_d = counts.sum(1) > 0
    w_d = counts.sum(1) / counts.sum()
    g = np.ones(lead + (counts.shape[0],))
    f = np.zeros(lead + (counts.shape[1],))
    n_iter = 0
    with np.errstate(invalid="ignore", divide="ignore"):
        for n_iter in range(1, n_iterations + 1):
            # a bin whose expected count is 0 (visited only in directions, or at places,
            # where the unit is silent) has factor 0, not 0/0: a NaN there would spread
            # through the next product and reset the whole model every other iteration
            f_new = _ratio(s_x, g @ counts) * occ_x
            g_new = _ratio(s_d, f_new @ counts.T) * occ_d
            scale = (g_new * w_d).sum(-1, keepdims=True)
            g_new = np.where(scale > 0, g_new / scale, 1.0)
            f_new = f_new * np.where(scale > 0, scale, 1.0)
            # relative change of each map on its own scale: a weak unit converges too
            peak = np.maximum(np.abs(f_new).max(-1), 1e-300)
            change = (np.abs(f_new - f).max(-1) / peak).max() if f_new.size else 0.0
            f, g = f_new, g_new
            if change < tolerance:
                break
        else:
            _common.warn(f"the position x direction model did not converge in "
                          f"{n_iterations} iterations (relative change {change:.2g} > "
                          f"{tolerance:g})")
    f = np.where(occ_x, f, np.nan)
    g = np.where(occ_d, g, np.nan)
    return f, g, n_iter


def _hd_lengths(rec, bins_60, shifts, scale):
    """Mean vector length (K, U) of the 60-bin, unsmoothed head-direction curves of every
    shift, exactly as :func:`head_direction_tuning` computes the observed one."""
    n_bins = HEAD_DIRECTION.n_bins
    res = tuning_sums(rec, bins_60, np.zeros(len(bins_60), np.int64), 1, n_bins, shifts)
    with np.errstate(invalid="ignore", divide="ignore"):
        curves = res.sums[:, :, 0] / res.counts[0] * scale     # (K, U, D)
    curves[..., res.counts[0] == 0] = np.nan
    floor = np.where(np.isfinite(curves[0]), curves[0], np.inf).min(axis=1)
    offset, why = _common.nonnegative_offset(rec, res.amin * scale, floor)
    theta = -np.pi + (np.arange(n_bins) + 0.5) * 2 * np.pi / n_bins
    length, phase = mean_vector(curves - offset[None, :, None], theta)
    arc = float(unvisited_arc(res.counts[0]))
    if arc > HEAD_DIRECTION.max_unvisited_arc:        # as head_direction_tuning
        length[:], phase[:] = np.nan, np.nan
    return length, phase, why, arc


def conjunctive_arrays(rec, *, n_shuffles, seed, n_bins, n_dir, min_speed, extent):
    """Observed (row 0) and shuffled HD lengths, direction-factor lengths and
    position-factor information (K + 1, U), with the observed factors."""
    xy = _positions(rec)
    shifts = shifts_for(rec, n_shuffles, seed)
    grid = spatial_grid(rec, None, extent, n_bins=n_bins, xy=xy)
    n_x = grid.nx * grid.ny
    # the joint sums of a batch of shifts, (shifts, units, directions, places): refused
    # before allocating, naming the larger of the two bin counts
    check_allocation("n_bins" if n_x >= n_dir else "n_directions",
                     (min(len(shifts), CONJUNCTIVE.batch), rec.sizes["unit"], n_dir, n_x))
    pos, dropped = position_bins(rec, grid, min_speed=min_speed, xy=xy)
    hd = _common.values(rec["head_direction"])
    d_bins = direction_bins(hd, n_dir)
    valid = (pos >= 0) & (d_bins >= 0)
    if not valid.any():
        raise ValueError("no sample with both a position and a head direction: "
                         "`rec.position` or `rec.head_direction` is all NaN")
    pos = np.where(valid, pos, -1)
    bins_60 = direction_bins(hd, HEAD_DIRECTION.n_bins)   # as head_direction_tuning
    if min_speed is not None:
        with np.errstate(invalid="ignore"):
            bins_60[~(_common.speed(rec) >= min_speed)] = -1
    scale = _common.rate_scale(rec)[0]

    hd_len, hd_phase, why, hd_arc = _hd_lengths(rec, bins_60, shifts, scale)
    # the direction factor over too short an arc is as long as the raw curve would be
    d_arc = float(unvisited_arc(np.bincount(d_bins[valid], minlength=n_dir)))
    length_parts, info_parts, phase0 = [], [], None
    theta = -np.pi + (np.arange(n_dir) + 0.5) * 2 * np.pi / n_dir
    f0 = g0 = None
    offset = None
    for start in range(0, len(shifts), CONJUNCTIVE.batch):
        batch = shifts[start:start + CONJUNCTIVE.batch]
        with warnings.catch_warnings():
            if start:
                warnings.simplefilter("ignore", AnalysisWarning)
            res = tuning_sums(rec, pos, np.where(valid, d_bins, 0), n_dir, n_x, batch)
        counts = res.counts.astype(float)                       # (D, X)
        if offset is None:
            # the same per-unit shift as the HD curves (the recording's minimum)
            with np.errstate(invalid="ignore", divide="ignore"):
                marg = res.sums[0].sum(axis=1) / counts.sum(0) * scale   # (U, X)
            floor = np.where(np.isfinite(marg), marg, np.inf).min(axis=1)
            offset, _ = _common.nonnegative_offset(rec, res.amin * scale, floor)
        sums = res.sums * scale - offset[None, :, None, None] * counts[None, None]
        sums = np.maximum(sums, 0.0)       # round-off below 0 after the shift
        f, g, _ = factorize(sums, counts, CONJUNCTIVE.n_iterations, CONJUNCTIVE.tolerance)
        length, phase = mean_vector(g, theta)
        if d_arc > HEAD_DIRECTION.max_unvisited_arc:
            length[:], phase[:] = np.nan, np.nan
        info, _ = skaggs_information(f, counts.sum(0), axes=(-1,))
        if start == 0:
            f0, g0, phase0 = f[0], g[0], phase[0]
        length_parts.append(length)
        info_parts.append(info)
    length = np.concatenate(length_parts)
    info = np.concatenate(info_parts)

    return dict(hd_len=hd_len, hd_phase=hd_phase, length=length, info=info, f0=f0, g0=g0,
                phase0=phase0, theta=theta, grid=grid, dropped=dropped, why=why,
                hd_arc=hd_arc, d_arc=d_arc)


@fill_doc
def conjunctive_tuning(rec, *, n_shuffles=None, seed=None, percentile=None, threshold=None,
                       n_bins=None, n_directions=None, min_speed=None, extent=None):
    """Head-direction x place tuning: head-direction tuning, and the factorial model that
    separates position from direction.

    Two views of a unit's dependence on direction and place:

    - the head-direction tuning curve (60 bins of 6 degrees, unsmoothed) and its mean
      vector length R, as :func:`head_direction_tuning` (the usual HD-cell criterion);
    - the factorial (position x direction) model of Burgess et al. (2005), fitted by
      maximum likelihood to the joint tuning (16 x 16 places x 12 directions by default):

      .. math:: \\lambda(x, \\theta) = f(x)\\, g(\\theta)

      Its direction factor ``g`` is the tuning to direction with the place tuning
      explained away (a place cell visited in each place mostly along one direction has a
      tuned raw HD curve but a flat ``g``), and its position factor ``f`` the rate map with
      the direction tuning explained away. ``pxd_direction_length`` is the mean vector
      length of ``g``; ``pxd_position_information`` the Skaggs information of ``f``
      (bits per unit of activity; :func:`spatial_information`). A conjunctive
      (position x direction) cell is significant on both.

    Activity is made a non-negative rate first (signed activity: minus the unit's minimum
    over the recording), as R, information and the model need. Significance: circular
    time shifts of the activity against the behaviour; thresholds are the shuffles'
    ``percentile`` (default 99th). Both lengths are NaN where the head direction left more
    than half the circle unvisited, as in :func:`head_direction_tuning`.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity``, ``position`` and ``head_direction``; may be
        dask-backed.
    %(n_shuffles)s
    %(seed)s
    percentile : float, optional
        Default 99.
    threshold : {'unit', 'pooled'}, optional
    n_bins : int, optional
        Spatial bins along the extent's longer side for the model (default 16).
    n_directions : int, optional
        Direction bins of the model (default 12).
    %(min_speed)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``hd_mean_vector_length``, ``hd_preferred_direction`` (unit);
        ``pxd_direction_length``, ``pxd_preferred_direction``,
        ``pxd_position_information`` (unit); ``direction_factor`` (unit, pxd_direction),
        ``position_factor`` (unit, y, x); with shuffles a ``_threshold``, ``_p_value``,
        ``_shuffle_mean`` and ``_shuffle_std`` for each of ``hd_mean_vector_length``,
        ``pxd_direction_length`` and ``pxd_position_information``, and ``conjunctive``
        (both factors above their thresholds).

    References
    ----------
    Burgess, Cacucci, Lever & O'Keefe (2005), Characterizing multiple independent
    behavioral correlates of cell firing in freely moving animals, Hippocampus
    15:149-153. Cacucci, Lever, Wills, Burgess & O'Keefe (2004), Theta-modulated
    place-by-direction cells in the hippocampal formation of the rat, J. Neurosci.
    24:8265-8277. Sargolini et al. (2006), Science 312:758-762.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> rng = np.random.default_rng(0)
    >>> xy = rng.uniform(-0.5, 0.5, (30000, 2)); hd = rng.uniform(-np.pi, np.pi, 30000)
    >>> place = np.exp(-((xy - 0.2) ** 2).sum(1) / 0.02)
    >>> rate = np.c_[place, place * np.exp(2 * (np.cos(hd) - 1))]
    >>> rec = from_arrays(np.arange(30000) * 0.1, xy, activity=rate, head_direction=hd,
    ...                   activity_kind="rate")
    >>> res = conjunctive_tuning(rec, n_shuffles=0)
    >>> [round(float(v), 1) for v in res.pxd_direction_length]
    [0.0, 0.7]
    """
    rec = _common.check_recording(rec, ["activity", "position", "head_direction"],
                            why="conjunctive tuning")
    n_shuffles = CELL_CLASS.n_shuffles if n_shuffles is None else n_shuffles
    percentile = check_percentile("percentile", CELL_CLASS.conjunctive_percentile
                                  if percentile is None else percentile)
    threshold = check_option("threshold", CELL_CLASS.threshold if threshold is None
                             else threshold, ("unit", "pooled"))
    n_bins = check_number("n_bins", CONJUNCTIVE.n_bins if n_bins is None else n_bins,
                          low=2, low_inclusive=True, integer=True)
    n_dir = check_number("n_directions", CONJUNCTIVE.n_directions if n_directions is None
                         else n_directions, low=2, low_inclusive=True, integer=True)
    arr = conjunctive_arrays(rec, n_shuffles=n_shuffles, seed=seed, n_bins=n_bins,
                             n_dir=n_dir, min_speed=min_speed, extent=extent)
    hd_len, hd_phase, length, info = arr["hd_len"], arr["hd_phase"], arr["length"], arr["info"]
    f0, g0, phase0, theta, grid = arr["f0"], arr["g0"], arr["phase0"], arr["theta"], arr["grid"]
    dropped, why = arr["dropped"], arr["why"]

    coords = {name: c for name, c in rec["activity"].coords.items() if c.dims == ("unit",)}
    coords["pxd_direction"] = ("pxd_direction", theta,
                               {"units": "rad", "long_name": "head direction"})
    coords["y"] = ("y", grid.y, {"units": "m", "long_name": "y position"})
    coords["x"] = ("x", grid.x, {"units": "m", "long_name": "x position"})
    out = xr.Dataset(coords=coords)
    units = _common.rate_scale(rec)[1]
    out["hd_mean_vector_length"] = ("unit", hd_len[0], {
        "units": "1", "long_name": "mean vector length (60-bin HD curve)"})
    out["hd_preferred_direction"] = ("unit", hd_phase[0], {
        "units": "rad", "long_name": "preferred direction (HD curve)"})
    out["pxd_direction_length"] = ("unit", length[0], {
        "units": "1", "long_name": "mean vector length of the direction factor"})
    out["pxd_preferred_direction"] = ("unit", phase0, {
        "units": "rad", "long_name": "preferred direction of the direction factor"})
    info_units = "bits/spike" if units == "Hz" else "bits per unit of activity"
    out["pxd_position_information"] = ("unit", info[0], {
        "units": info_units, "long_name": "Skaggs information of the position factor"})
    out["direction_factor"] = (("unit", "pxd_direction"), g0, {
        "units": "1", "long_name": "direction factor (occupancy-weighted mean 1)"})
    out["position_factor"] = (("unit", "y", "x"), f0.reshape(-1, grid.ny, grid.nx), {
        "units": units, "long_name": "position factor (rate, after the non-negative shift)"})
    if n_shuffles:
        add_significance(out, "hd_mean_vector_length", ("unit",), hd_len[0], hd_len[1:],
                         percentile, threshold, "1", "mean vector length")
        d = add_significance(out, "pxd_direction_length", ("unit",), length[0], length[1:],
                             percentile, threshold, "1", "direction-factor length")
        p = add_significance(out, "pxd_position_information", ("unit",), info[0], info[1:],
                             percentile, threshold, info_units, "position-factor information")
        with np.errstate(invalid="ignore"):
            both = (length[0] > d["threshold"]) & (info[0] > p["threshold"])
        out["conjunctive"] = ("unit", both, {
            "units": "1", "long_name": "both factors above their thresholds"})
    attrs = _common.provenance(
        "conjunctive_tuning", rec, n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed),
        percentile=percentile,
        threshold=threshold, n_bins=n_bins, n_directions=n_dir, hd_bins=HEAD_DIRECTION.n_bins,
        bin_size=grid.bin_size, extent=list(grid.extent), min_speed=min_speed,
        samples_dropped=str(dropped), rate_offset=why,
        definition="lambda(x, theta) = f(x) g(theta), maximum likelihood (Burgess et al. "
                   "2005); HD curve as head_direction_tuning (60 bins, unsmoothed)")
    limit = HEAD_DIRECTION.max_unvisited_arc
    hd_why = narrow_reason(arr["hd_arc"]) if arr["hd_arc"] > limit else "curve sums to 0"
    d_why = (narrow_reason(arr["d_arc"]) if arr["d_arc"] > limit
             else "activity is constant (after the non-negative shift)")
    reasons = ["; ".join(([f"R: {hd_why}"] if not np.isfinite(r) else [])
                         + ([f"direction factor: {d_why}"] if not np.isfinite(v) else []))
               for r, v in zip(hd_len[0], length[0])]
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["pxd_direction_length"]),
                                   reasons, "head-direction or direction-factor length")
    return out
