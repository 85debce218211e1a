"""Head-direction tuning: curves, mean vector length, preferred direction, significance."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from .._angles import wrap_angle
from .._validators import check_allocation, check_number
from . import _common
from .._docs import fill_doc
from .config import HEAD_DIRECTION
from .ratemaps import smooth_normalized, tuning_sums, warn_nonfinite


#: Fewest direction bins: 45 degree bins shorten R by 2.6% (sin(w/2)/(w/2)); two bins
#: cannot place a preferred direction at all.
MIN_DIRECTION_BINS = 8
#: The untuned (flat-curve) mean vector length above which the coverage is warned about:
#: about 8% of the circle unvisited.
FLAT_LENGTH_WARNING = 0.05


def direction_bins(hd, n_bins):
    """Bin of each head direction (radians, any range) in ``n_bins`` bins of [-pi, pi);
    -1 where NaN."""
    hd = np.asarray(hd, float)
    finite = np.isfinite(hd)
    bins = np.full(hd.shape, -1, np.int64)
    k = np.floor((wrap_angle(hd[finite]) + np.pi) / (2 * np.pi) * n_bins)
    bins[finite] = np.minimum(k.astype(np.int64), n_bins - 1)
    return bins


def mean_vector(curves, theta):
    """Mean resultant vector of tuning curves along the last axis.

    .. math:: R\\,e^{i\\phi} = \\frac{\\sum_k r_k e^{i\\theta_k}}{\\sum_k r_k}

    over the bins with a finite rate. Returns ``(R, phi)``; NaN where ``sum r_k <= 0``.
    """
    r = np.where(np.isfinite(curves), curves, 0.0)
    total = r.sum(axis=-1)
    z = (r * np.exp(1j * theta)).sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where(total > 0, z / total, np.nan)
    return np.abs(z), np.angle(z)


def unvisited_arc(counts):
    """The longest circular run of unvisited bins of each direction histogram
    ``counts (..., n_bins)``, in degrees (360 where no bin is visited)."""
    visited = np.asarray(counts) > 0
    n_bins = visited.shape[-1]
    flat = visited.reshape(-1, n_bins)
    longest = np.empty(len(flat))
    for k, row in enumerate(flat):
        if not row.any():
            longest[k] = n_bins
            continue
        # start after a visited bin so that no run wraps around the end
        row = np.roll(row, -(int(np.flatnonzero(row)[-1]) + 1))
        edges = np.flatnonzero(np.diff(np.r_[1, row.astype(np.int8), 1]))
        runs = edges[1::2] - edges[::2]            # lengths of the runs of False
        longest[k] = runs.max() if runs.size else 0
    return (longest * 360.0 / n_bins).reshape(visited.shape[:-1])


def too_narrow(counts):
    """Where ``counts (..., n_bins)`` leaves an unvisited arc longer than
    ``HEAD_DIRECTION.max_unvisited_arc``: no mean vector length there."""
    return unvisited_arc(counts) > HEAD_DIRECTION.max_unvisited_arc


def narrow_reason(arc):
    """Why a mean vector length is NaN under the coverage rule."""
    return (f"head direction left {arc:.0f} degrees unvisited, more than "
            f"max_unvisited_arc = {HEAD_DIRECTION.max_unvisited_arc:g} (a stuck or misread "
            f"sensor?)")


def flat_curve_length(arc):
    """The mean vector length of a flat curve over the circle less an unvisited arc
    (degrees): :math:`\\sin(\\pi f) / (\\pi f)` with :math:`f` the visited fraction. An
    untuned cell reads about this much; R must be judged against it (or by its p-value).
    """
    f = np.clip(1 - np.asarray(arc, dtype=float) / 360.0, 1e-12, 1.0)
    return np.sinc(f)     # numpy's sinc is sin(pi x) / (pi x)


def rayleigh_p(n, r):
    """Rayleigh test p-value for ``n`` independent angles with resultant length ``r``.

    .. math:: p = \\exp\\left(\\sqrt{1 + 4n + 4(n^2 - R_n^2)} - (1 + 2n)\\right),\\quad
              R_n = n r

    (Zar 1999, Biostatistical Analysis, eq. 27.4).
    """
    n = np.asarray(n, float)
    rn = n * np.asarray(r, float)
    with np.errstate(invalid="ignore"):
        p = np.exp(np.sqrt(1 + 4 * n + 4 * (n**2 - rn**2)) - (1 + 2 * n))
    return np.where(n > 0, np.minimum(p, 1.0), np.nan)


@fill_doc
def head_direction_tuning(rec, *, n_bins=None, sigma=0.0, n_shuffles=None, seed=None,
                          by=None, min_speed=None):
    """Occupancy-normalised head-direction tuning curves and their mean vector.

    .. math:: r_k = \\frac{\\sum_{t: \\theta_t \\in k} a_t}{N_k},\\qquad
              R\\,e^{i\\phi} = \\frac{\\sum_k r_k e^{i\\theta_k}}{\\sum_k r_k}

    ``R`` (mean vector length) and ``phi`` (preferred direction) come from the curve, so
    uneven sampling of directions does not bias them. Signed activity (the LSTM's h) is
    made non-negative per unit (``activity - min`` over the recording) first, as R is not
    offset-invariant. Significance: ``p_value`` is the fraction of ``n_shuffles`` circular
    time shifts of the activity against the head direction whose R is at least the
    observed one (time shifts keep both signals' autocorrelation, which the Rayleigh test
    ignores). For spike counts the Rayleigh test is also given, with the curve's R and
    n = the number of spikes (the raw spike directions would inherit the trajectory's
    uneven sampling of directions).

    Where the head direction left an arc of more than
    ``HeadDirectionConfig.max_unvisited_arc`` (180 degrees) unvisited, every direction
    visited lies within a shorter arc and any curve has a long mean vector (a stuck
    sensor gives R = 1): the length, the preferred direction and the p-values are NaN
    there, with the reason in ``attrs['nan_reasons']``. Over a shorter unvisited arc
    the length stands, but an untuned (flat) curve reads :math:`\\sin(\\pi f)/(\\pi f)`
    with :math:`f` the visited fraction of the circle (0.64 with half of it unvisited,
    0.11 with a tenth): that is ``attrs['untuned_length']``, warned about above 0.05.

    Bins of width :math:`w` shorten R by the factor :math:`\\sin(w/2)/(w/2)` (0.9995 for
    6 degrees); fewer than 8 bins are refused.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and ``head_direction`` (radians, 0 = +x,
        counter-clockwise); may be dask-backed.
    n_bins : int, optional
        Number of direction bins over [-pi, pi) (default 60, 6 degrees).
    sigma : float
        Circular Gaussian smoothing in bins (normalized convolution); default 0.
    %(n_shuffles)s
    %(seed)s
    %(by)s
    %(min_speed)s

    Returns
    -------
    xarray.Dataset
        ``tuning_curve`` (unit, [group], direction) with coord ``occupancy`` (s);
        ``rate_offset`` (unit): what was subtracted from the curve to make it a
        non-negative rate before the mean vector (signed activity: the unit's minimum);
        ``mean_vector_length``, ``preferred_direction`` (rad); with shuffles,
        ``p_value`` = (1 + k) / (1 + n) for k of n shuffled lengths at least the observed
        one, and ``shuffle_r95`` (the shuffles' 95th percentile); ``rayleigh_p`` (spike
        counts only).

    References
    ----------
    Taube, Muller & Ranck (1990), Head-direction cells recorded from the postsubiculum in
    freely moving rats, J. Neurosci. 10:420-435. Zar (1999), Biostatistical Analysis, 4th
    ed., ch. 27.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(5000) * 0.1
    >>> hd = 0.3 * t
    >>> rate = np.exp(4 * (np.cos(hd - 1.0) - 1))[:, None]
    >>> rec = from_arrays(t, np.zeros((5000, 2)), activity=rate, head_direction=hd,
    ...                   activity_kind="rate")
    >>> res = head_direction_tuning(rec, n_shuffles=0)
    >>> round(float(np.degrees(res.preferred_direction[0])))
    57
    """
    rec = _common.check_recording(rec, ["activity", "head_direction"], why="head-direction tuning")
    n_bins = check_number("n_bins", HEAD_DIRECTION.n_bins if n_bins is None else n_bins,
                          low=MIN_DIRECTION_BINS, low_inclusive=True, integer=True)
    sigma = check_number("sigma", sigma, low=0, low_inclusive=True)
    n_shuffles = _common.default_shuffles(n_shuffles, by, HEAD_DIRECTION.n_shuffles)
    dt = _common.sample_dt(rec)
    bins = direction_bins(_common.values(rec["head_direction"]), n_bins)
    n_dir_nan = int((bins < 0).sum())
    if min_speed is not None:
        check_number("min_speed", min_speed, low=0, low_inclusive=True)
        with np.errstate(invalid="ignore"):
            bins[~(_common.speed(rec) >= min_speed)] = -1
    if not (bins >= 0).any():
        raise ValueError("no sample left for head-direction tuning: `rec.head_direction` is "
                         "all NaN" + (" or slower than min_speed" if min_speed else ""))
    codes, labels, dim = _common.group_codes(rec, by)
    n_groups = 1 if labels is None else len(labels)
    shifts = _common.shifts_for(rec, n_shuffles, seed, by)
    check_allocation("n_bins", (rec.sizes["unit"], n_groups, n_bins),
                     shuffles=len(shifts))
    res = tuning_sums(rec, bins, codes, n_groups, n_bins, shifts)
    sums, counts = res.sums, res.counts
    warn_nonfinite(rec, res, "tuning curves")
    curves = smooth_normalized(sums, counts, sigma, n_axes=1, mode="wrap")
    curves[..., counts == 0] = np.nan
    scale, units, long_name = _common.rate_scale(rec)
    curves *= scale
    first = curves[0].reshape(curves.shape[1], -1)
    floor = np.where(np.isfinite(first), first, np.inf).min(axis=1)
    offset, why_offset = _common.nonnegative_offset(rec, res.amin * scale, floor)
    theta = -np.pi + (np.arange(n_bins) + 0.5) * 2 * np.pi / n_bins
    length, phase = mean_vector(curves - offset[None, :, None, None], theta)
    gap = unvisited_arc(counts)                                          # per group
    narrow = gap > HEAD_DIRECTION.max_unvisited_arc
    length[..., narrow] = np.nan
    phase[..., narrow] = np.nan
    flat = flat_curve_length(np.where(narrow, 0.0, gap))
    if flat.max() > FLAT_LENGTH_WARNING:
        _common.warn(f"head direction left up to {gap[~narrow].max():.0f} degrees of the "
                     f"circle unvisited: there a flat, untuned curve reads a mean vector "
                     f"length of {flat.max():.2f}; judge R against that (attrs "
                     f"'untuned_length') and by its p-value")

    squeeze = (lambda a: a[:, 0]) if dim is None else (lambda a: a)
    lead = ("unit",) if dim is None else ("unit", dim)
    coords = {name: c for name, c in rec["activity"].coords.items() if c.dims == ("unit",)}
    coords["direction"] = ("direction", theta, {"units": "rad",
                                                "long_name": "head direction"})
    if dim is not None:
        coords[dim] = (dim, labels, rec[dim].attrs)
    occ = counts * dt
    coords["occupancy"] = (lead[1:] + ("direction",), occ[0] if dim is None else occ,
                           {"units": "s", "long_name": "occupancy"})
    out = xr.Dataset(coords=coords)
    out["tuning_curve"] = (lead + ("direction",), squeeze(curves[0]),
                           {"units": units, "long_name": long_name})
    out["rate_offset"] = ("unit", offset, {
        "units": units, "long_name": "activity subtracted before the mean vector"})
    out["mean_vector_length"] = (lead, squeeze(length[0]), {
        "units": "1", "long_name": "mean vector length"})
    out["preferred_direction"] = (lead, squeeze(phase[0]), {
        "units": "rad", "long_name": "preferred direction"})
    if n_shuffles:
        exceed = (length[1:] >= length[:1]).sum(axis=0)
        p_value = np.where(np.isnan(length[0]), np.nan, (1 + exceed) / len(shifts))
        with warnings.catch_warnings():    # a unit or group without R: NaN, said below
            warnings.simplefilter("ignore", RuntimeWarning)
            r95 = np.nanpercentile(length[1:], 95, axis=0)
        out["p_value"] = (lead, squeeze(p_value), {
            "units": "1", "long_name": "fraction of time-shift shuffles with R at least as large"})
        out["shuffle_r95"] = (lead, squeeze(r95), {
            "units": "1", "long_name": "95th percentile of shuffled mean vector length"})
    notes = {}
    if _common.is_spike_data(rec):
        # R of the occupancy-normalised curve with n = the number of spikes: the spikes'
        # raw directions would inherit the trajectory's uneven sampling of directions
        n_spikes = np.where(np.isfinite(sums[0]), sums[0], 0.0).sum(axis=-1)
        out["rayleigh_p"] = (lead, squeeze(rayleigh_p(n_spikes, length[0])), {
            "units": "1", "long_name": "Rayleigh test p-value"})
        notes["rayleigh"] = ("R of the occupancy-normalised curve, n = number of spikes "
                             "(assumes independent spikes)")
    else:
        notes["rayleigh"] = ("not reported: the Rayleigh test assumes independent events "
                             "(spike data only)")
    attrs = _common.provenance(
        "head_direction_tuning", rec, n_bins=n_bins, sigma=sigma, sigma_units="bins",
        n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed), by=by, min_speed=min_speed,
        rate_offset=why_offset, samples_without_direction=n_dir_nan,
        mean_vector="from the occupancy-normalised curve (bin centres)",
        untuned_length=float(flat.max()), **notes)
    group_gap = np.broadcast_to(gap, length.shape[1:]).ravel()
    reasons = ["no visited direction bin" if not np.isfinite(c).any() else
               narrow_reason(g) if g > HEAD_DIRECTION.max_unvisited_arc
               else "curve sums to 0 (after the non-negative shift)" if not np.isfinite(r)
               else ""
               for c, r, g in zip(out["tuning_curve"].values.reshape(-1, n_bins),
                                  out["mean_vector_length"].values.ravel(), group_gap)]
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["mean_vector_length"]),
                                   reasons, "mean vector length")
    return out
