"""Significance of a score against its circular time-shift shuffles, and the shuffled
rate maps the spatial scores share.

Every cell-class score (grid, border, place, head direction, speed, conjunctive) is judged
the same way: the score of the unit's activity against the behaviour, and the scores of
``n_shuffles`` copies of the activity shifted circularly in time against it
(:func:`hippo_probe.analysis._common.circular_shifts`), which keep both signals'
autocorrelation and break only their relation. :func:`summarize` turns the two into a
threshold (a percentile of the shuffles, the unit's own or all units' pooled), a p-value
and the shuffles' mean and s.d.; :func:`map_batches` makes the shuffled rate maps of the
map-based scores in one pass over the samples per batch of shifts.
"""

from __future__ import annotations

import warnings

import numpy as np

from .._validators import check_number, check_option
from . import _common
from ._common import AnalysisWarning, shifts_for
from .ratemaps import _maps_dataarray, _ratemap_parts, smooth_normalized, spatial_grid


def check_percentile(name, value):
    return check_number(name, value, low=0, high=100, low_inclusive=False,
                        high_inclusive=False)


def summarize(observed, shuffled, percentile, threshold="unit"):
    """Threshold, p-value, mean and s.d. of shuffled scores.

    Parameters
    ----------
    observed : ndarray (...)
        Each entry's score.
    shuffled : ndarray (K, ...)
        The scores of ``K`` shuffles of each entry.
    percentile : float
        The threshold is this percentile of the shuffles (NaN shuffles ignored).
    threshold : {'unit', 'pooled'}
        ``'unit'``: each entry's own shuffles; ``'pooled'``: all entries' shuffles
        together (one threshold for all, as Langston et al. 2010 and Kropff et al. 2015).

    Returns
    -------
    dict
        ``threshold``, ``p_value`` = (1 + k) / (1 + K) for k shuffles at least the
        observed score (NaN shuffles count as below it), ``mean``, ``std``.
    """
    check_option("threshold", threshold, ("unit", "pooled"))
    observed = np.asarray(observed, float)
    shuffled = np.asarray(shuffled, float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN entries stay NaN
        if threshold == "pooled":
            level = np.full(observed.shape, np.nanpercentile(shuffled, percentile)
                            if np.isfinite(shuffled).any() else np.nan)
        else:
            level = np.nanpercentile(shuffled, percentile, axis=0)
        mean = np.nanmean(shuffled, axis=0)
        std = np.nanstd(shuffled, axis=0)
    with np.errstate(invalid="ignore"):
        exceed = (shuffled >= observed[None]).sum(axis=0)
    p = np.where(np.isfinite(observed), (1 + exceed) / (1 + len(shuffled)), np.nan)
    return {"threshold": level, "p_value": p, "mean": mean, "std": std}


def add_significance(out, name, lead, observed, shuffled, percentile, threshold, units,
                     what):
    """Add ``<name>_threshold``, ``<name>_p_value``, ``<name>_shuffle_mean`` and
    ``<name>_shuffle_std`` to the Dataset ``out``; return the summary."""
    s = summarize(observed, shuffled, percentile, threshold)
    out[f"{name}_threshold"] = (lead, s["threshold"], {
        "units": units, "long_name": f"{percentile:g}th percentile of shuffled {what}",
        "percentile": percentile, "threshold": threshold})
    out[f"{name}_p_value"] = (lead, s["p_value"], {
        "units": "1", "long_name": f"fraction of shuffles with {what} at least as large"})
    out[f"{name}_shuffle_mean"] = (lead, s["mean"], {
        "units": units, "long_name": f"mean {what} of the shuffles"})
    out[f"{name}_shuffle_std"] = (lead, s["std"], {
        "units": units, "long_name": f"s.d. of the shuffles' {what}"})
    return s


class MapStack:
    """A recording's rate maps (smoothed and unsmoothed), and those of its shuffles.

    The samples are binned once per batch of shifts (:func:`_ratemap_parts`), unsmoothed;
    the smoothed maps come from the same sums by normalized convolution, so one pass gives
    both. Every shift shares the occupancy (a circular shift moves activity against a
    fixed trajectory). Shuffles with ``by=`` are refused (:func:`~._common.shifts_for`):
    a shift runs over the whole recording, so a group's shuffled maps would hold other
    groups' activity.

    Attributes
    ----------
    observed : xarray.DataArray
        The smoothed maps, exactly as :func:`hippo_probe.ratemaps` with ``sigma`` returns
        them (dims ``unit, [group], y, x``).
    observed_raw : ndarray
        The unsmoothed maps, same shape.
    shifts : ndarray
        ``[0, s_1, ... s_n]``.
    """

    def __init__(self, rec, *, n_shuffles, seed, bin_size, sigma, min_speed, by, extent,
                 batch=None):
        self.rec = rec
        self.shifts = shifts_for(rec, n_shuffles, seed, by)
        self.sigma = check_number("sigma", sigma, low=0, low_inclusive=True)
        self._kw = dict(bin_size=bin_size, sigma=0.0, min_occupancy=None,
                        min_speed=min_speed, by=by, extent=extent)
        # about 64 MB of float64 sums per batch, from the maps' real size: fine bins make
        # smaller batches, not a refusal
        grid = spatial_grid(rec, bin_size, extent)
        n_groups = 1 if by is None else len(np.unique(_common.values(rec[by]))) \
            if by in rec.variables else 1
        per_shift = rec.sizes["unit"] * n_groups * grid.nx * grid.ny
        self.batch = batch or max(1, int(8e6 // max(1, per_shift)))
        first = self.shifts[: self.batch]
        parts = _ratemap_parts(rec, shifts=first, batch=True, **self._kw)
        self.parts = parts
        self.scale = _common.rate_scale(rec)[0]
        smooth, raw = self._maps(parts, squeeze=False)
        parts_smoothed = dict(parts, sigma=self.sigma)
        self.observed = _maps_dataarray(rec, parts_smoothed, smooth[0] / self.scale,
                                        by=by, min_speed=min_speed)
        if parts["dim"] is None:
            smooth, raw = smooth[:, :, 0], raw[:, :, 0]
        self.observed_raw = raw[0]
        self._first = (smooth[1:], raw[1:])

    def _maps(self, parts, squeeze=True):
        """Smoothed and unsmoothed maps (K, U, [G,] ny, nx), scaled, NaN where unvisited
        (the group axis kept with ``squeeze=False`` when there are no groups)."""
        counts = parts["counts"]
        unvisited = counts == 0
        raw = parts["maps"] * self.scale
        smooth = smooth_normalized(parts["sums"], counts, self.sigma) * self.scale
        smooth[..., unvisited] = np.nan
        if squeeze and parts["dim"] is None:
            raw, smooth = raw[:, :, 0], smooth[:, :, 0]
        return smooth, raw

    def shuffle_batches(self):
        """Yield ``(smoothed, raw)`` maps of the shuffles, batch by batch (K_b, U, ...)."""
        if len(self._first[0]):
            yield self._first
        for start in range(self.batch, len(self.shifts), self.batch):
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", AnalysisWarning)  # said for the first batch
                parts = _ratemap_parts(self.rec, shifts=self.shifts[start:start + self.batch],
                                       batch=True, **self._kw)
            yield self._maps(parts)

    @property
    def n_shuffles(self):
        return len(self.shifts) - 1


def flat_maps(maps):
    """``(N, ny, nx)`` view of maps ``(..., ny, nx)`` and the leading shape."""
    maps = np.asarray(maps, float)
    return maps.reshape((-1,) + maps.shape[-2:]), maps.shape[:-2]
