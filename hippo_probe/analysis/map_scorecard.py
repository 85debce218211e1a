"""Does a population hold place fields and remap globally? One scorecard, fixed rules.

The scorecard of the map-ingredient study (:mod:`hippo_probe.model.variants`): the same
measures for every network variant, on the same trials, with verdicts by rules written
down before any variant was trained (:class:`~.config.ScorecardConfig`).
"""

from __future__ import annotations

import warnings

import numpy as np
import xarray as xr

from . import _common
from .._docs import fill_doc
from .config import SCORECARD as CFG
from .place_field_stability import pearson_masked, place_field_stability
from .place_fields import place_fields
from .ratemaps import ratemaps


def treves_rolls(rates, axis) -> np.ndarray:
    """Treves & Rolls (1991) sparseness ``a = <r>^2 / <r^2>`` of non-negative rates along
    ``axis``: 1 for a uniform code, 1/n when one of n entries is active (NaN ignored)."""
    rates = np.asarray(rates, float)
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)     # all-NaN entries stay NaN
        return np.nanmean(rates, axis) ** 2 / np.nanmean(rates ** 2, axis)


@fill_doc
def map_scorecard(rec, *, bin_size=None, sigma=None, min_speed=None, config=None):
    """Place fields, remapping and sparsity of a recording in two or more environments.

    Measures, per environment and then averaged over environments (maps from
    :func:`ratemaps`, ``by="environment"``; a signed activity such as the LSTM's ``h`` is
    shifted by each unit's minimum over the recording to a non-negative rate):

    - ``fraction_place_like``: of the units active in an environment (not silent, below),
      those with 1 to ``config.max_fields`` fields (:func:`place_fields`) whose fields
      cover at most ``config.max_field_fraction`` of the visited area (a smooth
      gradient's single "field" covers most of it);
    - ``median_field_area`` (m^2) of those units' fields;
    - ``within_map_correlation``: median over units of the split-half stability of each
      unit's map (:func:`place_field_stability`);
    - ``across_map_correlation``: median over units and environment pairs of the
      correlation of a unit's maps in two environments (bins visited in both); a unit
      silent in one environment and active in the other counts as 0 (it remapped), one
      silent in both is left out;
    - ``population_vector_correlation``: mean over bins visited in both environments of
      the correlation between the population vectors (each unit's mean over the bins
      removed, so a change of mean rates alone does not count as remapping);
    - ``lifetime_sparseness`` (median over units) and ``population_sparseness`` (median
      over bins): Treves & Rolls (1991) ``<r>^2 / <r^2>``; ``fraction_silent``: units
      whose peak rate is 0 or below ``config.silent_fraction`` of the active units' median
      peak;
    - ``fraction_active_in_one_environment``: per pair of environments, of the units
      active in at least one of the two, those silent (as in ``fraction_silent``) in the
      other; averaged over pairs (0 when no unit is active). The on/off part of
      remapping: in CA1's global remapping many cells active in one room are silent in
      the other (Leutgeb et al. 2004). ``across_map_correlation`` already scores such a
      unit 0, but as a median over all active units it barely moves when few switch;
      this fraction reports them directly. Descriptive: no verdict reads it.

    Verdicts (``attrs``), rules fixed in :class:`~.config.ScorecardConfig`:
    ``place_fields`` if ``fraction_place_like >= config.place_fraction``;
    ``global_remapping`` if ``across_map_correlation < config.global_across`` while
    ``within_map_correlation > config.global_within``.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity``, ``position``, ``trial`` and ``environment``, with
        trials in at least two environments (several trials in each).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    config : ScorecardConfig, optional

    Returns
    -------
    xarray.Dataset
        The measures above as scalars, with per-environment ``n_units_place_like``;
        attrs ``place_fields`` and ``global_remapping`` (bool) and the rules.

    References
    ----------
    Treves, A. & Rolls, E. T. (1991). What determines the capacity of autoassociative
    memories in the brain? Network 2, 371-397.

    Leutgeb, S. et al. (2004). Distinct ensemble codes in hippocampal areas CA3 and CA1.
    Science 305, 1295-1298.

    Leutgeb, S. et al. (2005). Independent codes for spatial and episodic memory in
    hippocampal neuronal ensembles. Science 309, 619-623 (global vs rate remapping).

    Muller, R. U. & Kubie, J. L. (1987). The effects of changes in the environment on the
    spatial firing of hippocampal complex-spike cells. J. Neurosci. 7, 1951-1968.
    """
    cfg = CFG if config is None else config
    rec = _common.check_recording(rec, ["activity", "position", "trial", "environment"],
                                  why="the map scorecard")
    envs = np.unique(_common.values(rec["environment"]))
    if len(envs) < 2:
        raise ValueError(f"`rec` must hold trials in at least 2 environments for the "
                         f"scorecard's remapping measures; got {len(envs)}")
    opts = dict(bin_size=bin_size, sigma=sigma, min_speed=min_speed)
    maps = ratemaps(rec, by="environment", **opts)
    values = np.asarray(maps.transpose("unit", "environment", ...).values, float)
    offset, why_offset = _common.map_rate_offset(rec, maps)
    values = values - offset[:, None, None, None]
    n_units = values.shape[0]
    flat = values.reshape(n_units, len(envs), -1)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")          # units without fields are expected
        fields = place_fields(maps)
    n_fields = np.asarray(fields["n_fields"].transpose("unit", "environment").values, float)
    area = np.asarray(fields["field_area"].transpose("unit", "environment", "field").values,
                      float)
    visited = np.isfinite(flat).sum(-1) * float(maps.attrs.get("bin_size", 0.0)) ** 2
    covered = np.nansum(area, axis=-1)
    with np.errstate(invalid="ignore"):
        place_like = ((n_fields >= 1) & (n_fields <= cfg.max_fields)
                      & (covered <= cfg.max_field_fraction * visited))
    peak = np.nanmax(flat, axis=-1)                                  # (unit, env)
    # silent: no activity at all, or a peak far below the active units' median peak (the
    # median over the active ones: where most units are silent it would be 0)
    with warnings.catch_warnings(), np.errstate(invalid="ignore"):
        warnings.simplefilter("ignore", RuntimeWarning)           # no active unit: NaN
        active_median = np.nanmedian(np.where(peak > 0, peak, np.nan), axis=0,
                                     keepdims=True)
        silent = (peak <= 0) | (peak < cfg.silent_fraction * active_median)
    place_like &= ~silent
    field_areas = area[place_like] if place_like.any() else np.array([np.nan])

    within = place_field_stability(rec, **opts)["stability"].values
    pairs = [(i, j) for i in range(len(envs)) for j in range(i + 1, len(envs))]
    across = []
    for i, j in pairs:
        # each unit's maps in two environments, over the bins visited in both; a unit
        # active in one and silent in the other has remapped (correlation 0, where
        # Pearson's is undefined or noise), one silent in both says nothing (NaN)
        r = pearson_masked(flat[:, i], flat[:, j], cfg.min_bins)[0]
        r = np.where(silent[:, i] != silent[:, j], 0.0, r)
        across.append(np.where(silent[:, i] & silent[:, j], np.nan, r))
    across = np.concatenate(across)
    # of the units active in one or both environments of a pair, those active in one only
    switched = [(silent[:, i] != silent[:, j]).sum()
                / max((~(silent[:, i] & silent[:, j])).sum(), 1) for i, j in pairs]
    pv = []
    for i, j in pairs:
        both = np.isfinite(flat[:, i]).all(0) & np.isfinite(flat[:, j]).all(0)
        a, b = flat[:, i][:, both], flat[:, j][:, both]
        a = a - a.mean(1, keepdims=True)
        b = b - b.mean(1, keepdims=True)
        # population vectors: one per bin, the units along the last axis
        pv.append(pearson_masked(a.T, b.T, 2)[0])
    pv = np.concatenate(pv) if pv else np.array([])

    lifetime = treves_rolls(flat, axis=-1)                           # (unit, env)
    population = treves_rolls(flat, axis=0)                          # (env, bins)

    def med(x):
        x = np.asarray(x, float)
        return float(np.nanmedian(x)) if np.isfinite(x).any() else np.nan

    scalars = {
        "fraction_place_like": (float(place_like[~silent].mean()) if (~silent).any()
                                else np.nan, "1",
                                f"active units with 1-{cfg.max_fields} compact fields"),
        "median_field_area": (med(field_areas), "m^2", "median area of their fields"),
        "within_map_correlation": (med(within), "1",
                                   "median split-half map correlation, same environment"),
        "across_map_correlation": (med(across), "1",
                                   "median map correlation across environments"),
        "population_vector_correlation": (float(np.nanmean(pv)) if np.isfinite(pv).any()
                                          else np.nan,
                                          "1", "population-vector correlation across "
                                          "environments, unit means removed"),
        "lifetime_sparseness": (med(lifetime), "1", "Treves-Rolls lifetime sparseness"),
        "population_sparseness": (med(population), "1",
                                  "Treves-Rolls population sparseness"),
        "fraction_silent": (float(silent.mean()), "1", "units silent in an environment"),
        "fraction_active_in_one_environment": (
            float(np.mean(switched)), "1", "active units silent in the other environment"),
    }
    out = xr.Dataset({k: ((), v, {"units": u, "long_name": n})
                      for k, (v, u, n) in scalars.items()})
    out["n_units_place_like"] = ("environment", place_like.sum(0),
                                 {"units": "1", "long_name": "place-like units"})
    out = out.assign_coords(environment=("environment", envs,
                                         {"units": "1", "long_name": "environment"}))
    place = bool(out.fraction_place_like >= cfg.place_fraction)
    remap = bool(out.across_map_correlation < cfg.global_across
                 and out.within_map_correlation > cfg.global_within)
    out.attrs = _common.provenance(
        "map_scorecard", rec, place_fields=place, global_remapping=remap,
        place_rule=f"fraction_place_like >= {cfg.place_fraction} (1-{cfg.max_fields} "
                   f"fields covering <= {cfg.max_field_fraction:g} of the visited area)",
        remapping_rule=f"across_map_correlation < {cfg.global_across} and "
                       f"within_map_correlation > {cfg.global_within}",
        rate_offset=why_offset, **{k: ("None" if v is None else v) for k, v in opts.items()})
    return out
