"""Intrinsic dimension of the population's states by nearest-neighbour estimators
(scikit-dimension), beside the correlation dimension."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from .._validators import check_number, check_option
from . import _common
from .config import INTRINSIC_DIMENSION as CFG
from .correlation_dimension import _points, sampling_options

#: The estimators offered, by scikit-dimension's class name, with their papers.
ESTIMATORS = {
    "TwoNN": "Facco, d'Errico, Rodriguez & Laio (2017), Sci. Rep. 7:12140",
    "MLE": "Levina & Bickel (2005), NIPS 17",
}

#: Both estimators model continuous distances: where more of the states than this share
#: lack neighbours at a distance > 0, or have tied neighbour distances, the states are
#: discrete (spike counts in short bins repeat exactly) and the estimate is refused (NaN).
#: Continuous states give no ties at all (the shipped networks' 20,000: none).
MAX_DISCRETE_SHARE = 0.05


def _import_skdim():
    """scikit-dimension, imported without its side effect: one of its modules
    (``skdim.id._FisherS``, 0.3) calls ``warnings.filterwarnings("ignore")`` when
    imported, which would silence every later warning of the process, ours included."""
    with warnings.catch_warnings():       # restores the filters as they were
        import skdim
    return skdim


def _discrete_reasons(names, n_points, dist, kept, k):
    """Why each estimator in ``names`` cannot be trusted on these states ("" if it can):
    states without ``k`` neighbours at a distance > 0 (repeated states), or tied
    neighbour distances among those it reads (TwoNN the first two, MLE the first k)."""
    hint = ("the states repeat exactly or lie on a lattice (discrete activity, e.g. spike "
            "counts: estimate on smoothed rates or coarser bins)")
    skipped = 1 - kept.sum() / n_points
    if skipped > MAX_DISCRETE_SHARE:
        why = (f"{n_points - kept.sum()} of {n_points} states lack {k} neighbours at a "
               f"distance > 0 outside the Theiler window: {hint}")
        return [why] * len(names)
    reasons = []
    for name in names:
        read = dist[:, :2] if name == "TwoNN" else dist
        tied = float((np.diff(read, axis=1) == 0).any(axis=1).mean()) if len(read) else 0.0
        reasons.append(f"{tied:.0%} of the states have tied neighbour distances, which "
                       f"{name} cannot use: {hint}" if tied > MAX_DISCRETE_SHARE else "")
    return reasons


def _neighbours(points, order, trial, k, theiler):
    """Distances and indices of each point's ``k`` nearest neighbours, skipping those of
    the same trial fewer than ``theiler`` samples from it (and exact duplicates); and which
    points have ``k`` such neighbours (the rows returned)."""
    from sklearn.neighbors import NearestNeighbors

    # fewer than 2 * theiler sampled points fall within the window, plus the point itself
    extra = k + 2 * theiler + 1
    extra = min(extra, len(points) - 1)
    dist, idx = NearestNeighbors(n_neighbors=extra + 1, algorithm="brute").fit(
        points).kneighbors(points)
    # the window of C(r)'s pair counts: same trial and |i - j| < theiler samples apart
    near_in_time = (trial[idx] == trial[:, None]) & \
        (np.abs(order[idx] - order[:, None]) < theiler)
    ok = ~near_in_time & (dist > 0)
    # the first k allowed neighbours of each point, in order of distance
    rank = np.cumsum(ok, axis=1)
    take = ok & (rank <= k)
    counts = take.sum(axis=1)
    full = counts == k
    d = dist[full][take[full]].reshape(-1, k)
    i = idx[full][take[full]].reshape(-1, k)
    return d, i, full


def intrinsic_dimension(rec_or_array, *, estimators=None, n_neighbors=None,
                        max_points=None, theiler=None, transient=None, seed=None):
    """Intrinsic dimension of the activity's states by TwoNN and MLE (scikit-dimension).

    Two estimators that need no scaling range, to set beside
    :func:`correlation_dimension` (whose value rests on the range of ``C(r)`` fitted):

    - TwoNN (Facco et al. 2017): with :math:`\\mu_i = r_2(i) / r_1(i)` the ratio of the
      second to the first neighbour distance, :math:`F(\\mu) = 1 - \\mu^{-d}`, fitted as
      :math:`-\\log(1 - F) = d \\log \\mu` (the largest 10% of ratios dropped).
    - MLE (Levina & Bickel 2005): :math:`\\hat d_k(x) = \\bigl[\\frac{1}{k-1}
      \\sum_{j<k} \\log \\frac{T_k(x)}{T_j(x)}\\bigr]^{-1}` from the first ``k`` neighbour
      distances :math:`T_j`, combined over points as :math:`1 / \\langle 1/\\hat d_k
      \\rangle` (MacKay & Ghahramani's correction).

    The states are drawn exactly as :func:`correlation_dimension` draws them (same
    ``max_points``, ``transient`` and ``seed``: the same points); neighbours within
    ``theiler`` samples of a state in its own trial are skipped, as pairs are in
    ``C(r)``. Neighbours are found once (scikit-learn, exact) and given to
    scikit-dimension's estimators.

    TwoNN reads only the first two neighbours, so states that linger (several samples of
    one visit to a region, drawn together) give ratios near 1 and push it high: on a
    synthetic 3-D set of such visits it reads ~3.4 where MLE reads 2.8-3.0 (tests).
    Compare the two, and with fewer ``max_points``, before trusting either.

    Parameters
    ----------
    rec_or_array : xarray.Dataset or array (samples, dims)
        A recording (its ``activity``, trials from ``trial``) or points in time order.
    estimators : sequence of str, optional
        Among ``"TwoNN"`` and ``"MLE"`` (default both).
    n_neighbors : int, optional
        ``k`` of MLE (default 20).
    max_points, theiler, transient, seed : optional
        As for :func:`correlation_dimension` (defaults 4000, 10, 0.1 for recordings and
        0 for arrays, 0).

    Both estimators assume continuous distances. Where more than 5% of the states lack
    ``k`` neighbours at a distance > 0 (states that repeat exactly, as spike counts in
    short bins do), or have tied distances among the neighbours an estimator reads, its
    dimension is NaN with the reason in ``attrs["nan_reasons"]`` and an
    :class:`~hippo_probe.AnalysisWarning`: on such states TwoNN reads ~0 and MLE far more
    than the number of units.

    Returns
    -------
    xarray.Dataset
        ``dimension`` over ``estimator``; attrs ``n_points``, ``n_skipped`` (points with
        fewer than ``k`` neighbours at a distance > 0 outside the Theiler window),
        ``nan_reasons`` where an estimate is refused, and the parameters.

    References
    ----------
    Facco, d'Errico, Rodriguez & Laio (2017), Estimating the intrinsic dimension of
    datasets by a minimal neighborhood information, Sci. Rep. 7:12140. Levina & Bickel
    (2005), Maximum likelihood estimation of intrinsic dimension, NIPS 17. Bac, Mirkes,
    Gorban, Tyukin & Zinovyev (2021), Scikit-dimension: a Python package for intrinsic
    dimension estimation, Entropy 23:1368.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).uniform(size=(3000, 3)) @ np.eye(3, 20)
    >>> d = intrinsic_dimension(x).dimension
    >>> bool(np.all(abs(d - 3) < 0.4))
    True
    """
    try:
        skdim = _import_skdim()
    except ModuleNotFoundError:
        from .._optional import missing
        raise missing("skdim", "intrinsic_dimension") from None
    is_rec = isinstance(rec_or_array, xr.Dataset)
    names = list(CFG.estimators if estimators is None else
                 ([estimators] if isinstance(estimators, str) else estimators))
    for name in names:
        check_option("estimators", name, tuple(ESTIMATORS))
    k = check_number("n_neighbors", CFG.n_neighbors if n_neighbors is None else n_neighbors,
                     low=2, low_inclusive=True, integer=True)
    max_points, theiler, transient = sampling_options(CFG, is_rec, max_points, theiler,
                                                      transient)
    seed = CFG.seed if seed is None else seed
    points, order, trial, info = _points(rec_or_array, max_points=max_points,
                                         transient=transient, seed=seed)
    if not np.isfinite(points).all():
        raise ValueError("`rec_or_array` holds NaN or inf in the selected samples: distances "
                         "are undefined")
    if len(points) <= k + 2 * theiler + 1:
        raise ValueError(f"intrinsic dimension needs more than {k + 2 * theiler + 1} "
                         f"samples (n_neighbors + the Theiler window); got {len(points)}")
    dist, idx, kept = _neighbours(points, order, trial, k, theiler)
    reasons = _discrete_reasons(names, len(points), dist, kept, k)
    values = []
    for name, why in zip(names, reasons):
        if why:
            values.append(np.nan)
        elif name == "TwoNN":
            est = skdim.id.TwoNN(discard_fraction=CFG.twonn_discard, dist=True)
            est.fit(dist[:, :2])
        else:
            est = skdim.id.MLE()
            est.fit(points[kept], precomputed_knn_arrays=(dist, idx))
        if not why:
            values.append(float(est.dimension_))
    out = xr.Dataset(
        {"dimension": ("estimator", values, {"units": "1",
                                             "long_name": "intrinsic dimension"})},
        coords={"estimator": ("estimator", np.array(names, dtype=object))})
    out.attrs = _common.provenance(
        "intrinsic_dimension", rec_or_array if is_rec else None, estimators=names,
        references=[ESTIMATORS[n] for n in names], n_neighbors=k, theiler=theiler,
        max_points=max_points, seed=seed, n_points=len(points), n_skipped=int((~kept).sum()),
        skdim=skdim.__version__, **info)
    out.attrs = _common.report_nan(out.attrs, names, reasons, "intrinsic dimension")
    return out
