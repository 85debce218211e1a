"""Spatial selectivity: the fraction of a unit's activity variance explained by position."""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import _common
from .._docs import fill_doc
from .ratemaps import _maps_dataarray, _ratemap_parts


def variance_explained(sums, counts, sumsq):
    """Between-bin over total variance, per unit, from per-bin sufficient statistics.

    .. math:: \\eta^2 = \\frac{\\sum_i N_i (\\lambda_i - \\bar a)^2}
                              {\\sum_t (a_t - \\bar a)^2}
              = \\frac{\\sum_i S_i^2 / N_i - S^2/N}{\\sum_i Q_i - S^2/N}

    with :math:`S_i, Q_i, N_i` the sum, sum of squares and count of bin :math:`i`.
    ``sums``/``sumsq`` (..., n_bins), ``counts`` broadcastable; returns (eta2, total_var).
    """
    counts = np.broadcast_to(counts, sums.shape).astype(float)
    n = counts.sum(axis=-1)
    s = sums.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        between = np.where(counts > 0, sums**2 / counts, 0.0).sum(axis=-1) - s**2 / n
        total = sumsq.sum(axis=-1) - s**2 / n
        eta2 = between / total
    # total variance at the rounding level of the sums means a constant unit
    constant = ~(total > 1e-12 * np.maximum(sumsq.sum(axis=-1), 1e-300))
    return np.where(constant, np.nan, np.clip(eta2, 0.0, 1.0)), total / np.maximum(n, 1)


@fill_doc
def spatial_selectivity(rec, *, bin_size=None, min_speed=None, by=None, extent=None):
    """Fraction of each unit's activity variance explained by position.

    .. math:: \\mathrm{selectivity} = \\frac{\\sum_i p_i (\\lambda_i - \\bar a)^2}
                                          {\\mathrm{Var}_t(a_t)}

    the occupancy-weighted variance of the unsmoothed rate map :math:`\\lambda_i` over the
    variance of the activity across the same samples (the correlation ratio
    :math:`\\eta^2` of activity on spatial bin). It is invariant to the offset and scale of
    the activity, so it applies unchanged to the LSTM's signed h and to spike counts; 1 =
    activity is a function of the bin, 0 = no spatial modulation. A finite recording
    gives position-independent units about ``(bins - 1) / (samples - 1)`` (for independent
    samples), reported as ``chance``.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and ``position``; may be dask-backed.
    %(bin_size)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``selectivity`` (unit, [group]), ``variance`` (total variance of the activity) and
        ``chance`` ([group]).

    References
    ----------
    Kanitscheider & Fiete (2017), Training recurrent networks to generate hypotheses
    about how the brain solves hard navigation problems, NIPS 30 (spatial selectivity of
    LSTM units). Fisher (1925), Statistical Methods for Research Workers (correlation
    ratio).

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(4000) * 0.1
    >>> xy = np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> act = np.c_[3 * xy[:, 0] - 1, np.random.default_rng(0).normal(size=len(t))]
    >>> rec = from_arrays(t, xy, activity=act, activity_kind="lstm_hidden")
    >>> sel = spatial_selectivity(rec, bin_size=0.1)
    >>> bool(sel.selectivity[0] > 0.99), bool(sel.selectivity[1] < 0.2)
    (True, True)
    """
    parts = _ratemap_parts(rec, bin_size=bin_size, sigma=0.0, min_occupancy=0.0,
                           min_speed=min_speed, by=by, extent=extent, want_sq=True)
    res = parts["res"]
    sums = res.sums[0]  # (U, G, bins)
    eta2, variance = variance_explained(sums, res.counts[None], res.sumsq)
    maps = _maps_dataarray(rec, parts, parts["maps"][0], by=by, min_speed=min_speed)
    lead = ("unit",) if by is None else ("unit", by)
    squeeze = (lambda a: a[:, 0]) if by is None else (lambda a: a)
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    out = xr.Dataset(coords=coords)
    out["selectivity"] = (lead, squeeze(eta2), {
        "units": "1", "long_name": "spatial selectivity (variance explained by position)"})
    act_units = rec["activity"].attrs.get("units", "1")
    out["variance"] = (lead, squeeze(variance), {
        "units": f"({act_units})^2" if act_units not in ("", "1") else "1",
        "long_name": "activity variance"})
    visited = (res.counts > 0).sum(axis=-1)
    n = res.counts.sum(axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        chance = (visited - 1) / (n - 1)
    out["chance"] = (lead[1:], chance if by is not None else chance[0], {
        "units": "1", "long_name": "expected selectivity of a position-independent unit"})
    attrs = _common.provenance(
        "spatial_selectivity", rec, bin_size=parts["grid"].bin_size, by=by,
        min_speed=min_speed, extent=list(parts["grid"].extent), n_samples=parts["n_valid"],
        definition="occupancy-weighted variance of the unsmoothed rate map over the "
                   "activity variance (correlation ratio eta^2)")
    reasons = ["activity is constant: variance 0, selectivity undefined"
               if not np.isfinite(v) else "" for v in out["selectivity"].values.ravel()]
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["selectivity"]), reasons,
                                   "spatial selectivity")
    return out
