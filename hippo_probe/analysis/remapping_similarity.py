"""Remapping: population-vector similarity of trial pairs, same vs different environment."""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from .._validators import check_bool, check_number, check_seed
from . import _common
from .._docs import fill_doc
from .config import REMAPPING
from .ratemaps import _ratemap_parts

COMPARISONS = ("same", "different", "same_permuted", "different_permuted")


def pair_correlations(maps, min_common):
    """Pearson r of every pair of trials' population vectors over bins visited in both.

    ``maps`` (U, T, B) holds per-trial rate maps, NaN where a trial did not visit a bin.
    All sums come from matrix products, so every pair is exact without a loop:

    .. math:: r_{ab} = \\frac{n S_{xy} - S_x S_y}
                            {\\sqrt{(n S_{xx} - S_x^2)(n S_{yy} - S_y^2)}}

    with the sums over units and the bins visited in both trials. Returns (r, n_bins),
    both (T, T); r is NaN where fewer than ``min_common`` bins are shared.
    """
    n_units, n_trials, n_bins = maps.shape
    visited = np.isfinite(maps).all(axis=0)  # (T, B): a bin counts if every unit has it
    x = np.where(visited[None], maps, 0.0)
    m = visited.astype(float)
    s1 = x.sum(axis=0)  # (T, B)
    s2 = (x**2).sum(axis=0)
    flat = np.moveaxis(x, 1, 0).reshape(n_trials, -1)
    common = m @ m.T
    n = n_units * common
    sx = s1 @ m.T  # sum of a's values over bins visited by b
    sxx = s2 @ m.T
    sxy = flat @ flat.T
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (n * sxy - sx * sx.T) / np.sqrt((n * sxx - sx**2) * (n * sxx.T - sx.T**2))
    r = np.where(common >= min_common, r, np.nan)
    return np.clip(r, -1.0, 1.0), common


@fill_doc
def remapping_similarity(rec, *, bin_size=None, sigma=None, min_speed=None, extent=None,
                         min_common_bins=None, seed=None, center_units=False):
    r"""Population-vector correlation of trial pairs in the same vs different environments.

    For trials *a* and *b*, the population vector is the concatenation of all units'
    per-trial rate maps over the bins both trials visited, and

    .. math:: s_{ab} = \\mathrm{corr}\\bigl(\\{\\lambda^{a}_{u,i}\\},
              \\{\\lambda^{b}_{u,i}\\}\\bigr)_{u,\\; i \\in V_a \\cap V_b}

    one Pearson correlation over every unit and shared bin at once. Leutgeb et al. (2005)
    correlate the population vectors bin by bin and average the bins' correlations; the
    pooled one also counts how the population's mean rate varies over the bins, which
    the bin-by-bin one removes, so compare values of one kind only.

    Pairs are labelled same- or different-environment; global remapping shows as high
    similarity within and near-zero similarity across environments. Control: the same
    split after permuting the trials' environment labels (it must erase the difference).

    The pooled correlation keeps the differences between units' mean levels (as a
    population-vector correlation does), so units with large, arena-independent
    offsets — an LSTM's h often has them — raise the similarity of *every* pair, across
    environments too. ``center_units=True`` removes them first: each unit's maps minus
    its mean over all trials and bins, :math:`\lambda_{u,i} - \bar\lambda_u`, so only
    where and how much a unit departs from its own average counts.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity``, ``position``, ``trial`` and ``environment``; at
        least two trials. May be dask-backed.
    bin_size : float, optional
        Default: the extent's longer side / 16 (single-trial maps need coarse bins).
    sigma : float, optional
        Smoothing in bins (default 1).
    %(min_speed)s
    %(extent)s
    min_common_bins : int, optional
        Pairs sharing fewer visited bins give NaN (default 5).
    seed : int, optional
        Seed of the label permutation.
    center_units : bool
        Subtract each unit's mean over every trial and bin before correlating (default
        False: the classic pooled correlation).

    Returns
    -------
    xarray.Dataset
        Over ``pair``: ``similarity``, ``trial_a``, ``trial_b``, ``same_environment``,
        ``same_environment_permuted``, ``n_common_bins``; over ``comparison`` (same,
        different, same_permuted, different_permuted): ``mean``, ``median``, ``n_pairs``.

    References
    ----------
    Leutgeb et al. (2005), Independent codes for spatial and episodic memory in
    hippocampal neuronal ensembles, Science 309:619-623 (population-vector correlation).
    Kanitscheider & Fiete (2017), NIPS 30 (Fig. 4, remapping of LSTM units).

    Examples
    --------
    Eight trials alternate between two environments with unrelated maps:

    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> trial = np.arange(8000) // 1000
    >>> t = (np.arange(8000) + trial) * 0.1
    >>> xy = 0.5 * np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> env = trial % 2
    >>> act = np.where(env[:, None] == 0, np.cos(4 * xy), np.sin(4 * xy[:, ::-1]))
    >>> rec = from_arrays(t, xy, activity=act, trial=trial, environment=env,
    ...                   activity_kind="rate")
    >>> sim = remapping_similarity(rec)
    >>> sim["mean"].sel(comparison=["same", "different"]).values.round(1)
    array([1. , 0.1])
    """
    center_units = check_bool("center_units", center_units)
    rec = _common.check_recording(rec, ["activity", "position", "trial", "environment"],
                            why="remapping similarity")
    min_common = check_number(
        "min_common_bins", REMAPPING.min_common_bins if min_common_bins is None
        else min_common_bins, low=1, low_inclusive=True, integer=True)
    parts = _ratemap_parts(rec, bin_size=bin_size,
                           sigma=REMAPPING.sigma if sigma is None else sigma,
                           min_occupancy=None, min_speed=min_speed, by="trial", extent=extent,
                           n_bins=REMAPPING.n_bins)
    trials = parts["labels"]
    if len(trials) < 2:
        raise ValueError(f"`rec` must hold at least 2 trials for remapping similarity; got "
                         f"{len(trials)}")
    maps = parts["maps"][0]
    n_units, n_trials = maps.shape[:2]
    maps = maps.reshape(n_units, n_trials, -1)
    if center_units:
        with warnings.catch_warnings():   # a unit without any visited bin stays all-NaN
            warnings.simplefilter("ignore", RuntimeWarning)
            maps = maps - np.nanmean(maps.reshape(n_units, -1), axis=1)[:, None, None]
    r, common = pair_correlations(maps, min_common)
    env = _common.values(rec["environment"])[np.unique(parts["codes"], return_index=True)[1]]
    rng = np.random.default_rng(REMAPPING.seed if seed is None
                                else check_seed("seed", seed))
    permuted = rng.permutation(env)
    ia, ib = np.triu_indices(n_trials, k=1)
    sim = r[ia, ib]
    same = env[ia] == env[ib]
    same_p = permuted[ia] == permuted[ib]
    out = xr.Dataset(coords={"pair": np.arange(len(ia)), "comparison": list(COMPARISONS)})
    out["similarity"] = ("pair", sim, {"units": "1",
                                       "long_name": "population-vector correlation"})
    out["trial_a"] = ("pair", trials[ia], {"units": "1", "long_name": "first trial"})
    out["trial_b"] = ("pair", trials[ib], {"units": "1", "long_name": "second trial"})
    out["same_environment"] = ("pair", same, {"units": "1", "long_name": "same environment"})
    out["same_environment_permuted"] = ("pair", same_p, {
        "units": "1", "long_name": "same environment (labels permuted)"})
    out["n_common_bins"] = ("pair", common[ia, ib], {"units": "1",
                                                     "long_name": "bins visited in both"})
    masks = [same, ~same, same_p, ~same_p]
    ok = np.isfinite(sim)
    stats = np.array([[np.mean(sim[k & ok]) if (k & ok).any() else np.nan,
                       np.median(sim[k & ok]) if (k & ok).any() else np.nan,
                       (k & ok).sum()] for k in masks])
    out["mean"] = ("comparison", stats[:, 0], {"units": "1", "long_name": "mean similarity"})
    out["median"] = ("comparison", stats[:, 1], {"units": "1",
                                                 "long_name": "median similarity"})
    out["n_pairs"] = ("comparison", stats[:, 2].astype(int), {"units": "1",
                                                              "long_name": "pairs"})
    attrs = _common.provenance(
        "remapping_similarity", rec, bin_size=parts["grid"].bin_size, sigma=parts["sigma"],
        sigma_units="bins", min_speed=min_speed, min_common_bins=min_common,
        seed=REMAPPING.seed if seed is None else seed,
        center_units=bool(center_units),
        control="environment labels of the trials randomly permuted")
    # worded for the NaN pairs only: a session of 1,000 trials has 499,500 pairs
    na, nb = ia[~ok], ib[~ok]
    reasons = [f"the trials share {c} visited bins (< {min_common})" if c < min_common
               else "a trial's population vector is constant" for c in common[na, nb]]
    labels = [f"trials {a}-{b}" for a, b in zip(trials[na], trials[nb])]
    empty = [c for c, k in zip(COMPARISONS, masks) if not (k & ok).any()]
    if empty:
        attrs["empty_comparisons"] = (f"{empty}: no pair of that kind (e.g. only one "
                                      "environment); their summaries are NaN")
        _common.warn(f"remapping summaries are NaN for {attrs['empty_comparisons']}")
    out.attrs = _common.report_nan(attrs, labels, reasons, "remapping similarity")
    return out
