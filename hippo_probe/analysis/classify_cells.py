"""Cell classes (place, grid, border, head-direction, speed, conjunctive): one table."""

from __future__ import annotations


import numpy as np
import xarray as xr

from .._validators import check_number, check_option
from . import _common
from ._shuffles import MapStack, summarize
from .border_score import field_bins, resolve_walls, stack_border_stats
from .config import (BORDER, CELL_CLASS, CONJUNCTIVE, CONVENTIONS, GRID, PLACE_FIELD, SPEED,
                     CellClassConfig)
from .conjunctive_tuning import conjunctive_arrays
from .grid_score import grid_kwargs, grid_stats, shuffled_scores
from .grid_score import nan_reasons as grid_nan_reasons
from .place_fields import bin_coords, check_maps, detect_fields
from .spatial_information import skaggs_information
from .speed_score import speed_arrays
from .._docs import fill_doc

#: Class name -> (score column, config attribute of its percentile, paper).
CLASSES = {
    "grid": ("grid_score", "grid_percentile", "Langston et al. 2010"),
    "border": ("border_score", "border_percentile",
               "Solstad et al. 2008; Bjerknes et al. 2014"),
    "place": ("spatial_information", "place_percentile",
              "Skaggs et al. 1993; Langston et al. 2010"),
    "head_direction": ("hd_mean_vector_length", "hd_percentile", "Boccara et al. 2010"),
    "speed": ("speed_score", "speed_percentile", "Kropff et al. 2015"),
    "conjunctive": ("pxd_direction_length", "conjunctive_percentile",
                    "Burgess et al. 2005; Cacucci et al. 2004"),
}


def _warn_unresolved_percentiles(cfg, n_shuffles, threshold):
    """Warn when a unit's own ``n_shuffles`` shuffles cannot resolve a class's
    percentile: its 99th percentile needs at least 100 of them (with fewer, the threshold
    is about the largest shuffle and a class's false-positive rate is not the one its
    percentile names). Pooled thresholds draw on every unit's shuffles."""
    if threshold != "unit":
        return
    # a 100th percentile is the largest shuffle whatever their number: nothing to resolve
    short = {name: getattr(cfg, attr) for name, (_, attr, _) in CLASSES.items()
             if getattr(cfg, attr) < 100 and n_shuffles < 100.0 / (100.0 - getattr(cfg, attr))}
    if short:
        need = int(np.ceil(100.0 / (100.0 - max(short.values())) - 1e-9))
        _common.warn(
            f"`n_shuffles` = {n_shuffles} cannot resolve the percentile of "
            + ", ".join(f"{name} ({p:g}th)" for name, p in short.items())
            + f" against each unit's own shuffles: their classes are unreliable; use at "
            f"least {need} (or threshold=\"pooled\")")


def _one_environment(rec, environment):
    """The recording restricted to one environment (the most visited by default)."""
    if "environment" not in rec.variables:
        return rec, None
    env = _common.values(rec["environment"])
    ids, counts = np.unique(env, return_counts=True)
    if environment is None:
        if len(ids) == 1:
            return rec, int(ids[0])
        environment = ids[np.argmax(counts)]
        _common.warn(f"the recording spans {len(ids)} environments; cell classes are "
                      f"measured in the most visited one, {environment} "
                      f"({counts.max()} of {len(env)} samples); pass `environment` to "
                      "choose")
    elif environment not in ids:
        raise ValueError(f"`environment` must be one of the recording's environments "
                         f"{ids.tolist()}; got {environment!r}")
    from ..recording import select_trials

    if len(ids) == 1:
        return rec, int(ids[0])
    return select_trials(rec, environments=[environment]), int(environment)


@fill_doc
def classify_cells(rec, *, n_shuffles=None, seed=None, threshold=None, environment=None,
                   walls=None, bin_size=None, sigma=None, min_speed=None, config=None):
    """Every unit's cell-class scores, their shuffle thresholds and its class: one table.

    For each unit (one environment; the most visited when the recording has several):

    ========================  =================================================  ========
    class                     rule (defaults: ``CellClassConfig``)               source
    ========================  =================================================  ========
    ``grid``                  grid score > 95th pct of shuffles (*)              [1]
    ``border``                border score > 99th pct of shuffles and > 0.5 (*)  [2, 3]
    ``place``                 Skaggs information > 95th pct and >= 1 field (+)   [4, 1]
    ``head_direction``        mean vector length > 99th pct of shuffles (+)      [5]
    ``speed``                 speed score > 99th pct of shuffles                 [6]
    ``conjunctive``           both factors of the position x direction model     [7, 8]
                              > 99th pct of their shuffles: place x direction,
                              significant on both factors (additive tuning
                              counts too), not Sargolini's grid x direction
    ========================  =================================================  ========

    (*) and, with ``config.spatial_gate`` (default), significant spatial information as
    for place cells: the grid or border score of a spatially flat map is noise.
    (+) and, with ``config.factorial_gate`` (default), the position (place) or direction
    (head direction) factor of the factorial model above the same percentile of its
    shuffles [7]: where direction and position are sampled together, a head-direction
    cell has a structured rate map and a place cell a tuned direction curve.

    Shuffles are circular time shifts of the activity against the behaviour (each at
    least 20 s), the same shifts for every score; a threshold is each unit's own
    shuffles' percentile (``threshold="unit"``) or that of all units' shuffles pooled
    (``"pooled"``, as the papers; the ``*_p_value`` columns are always against the unit's
    own shuffles). The maps are made once (:func:`ratemaps`, one bin of
    smoothing for fields, grid and border scores, unsmoothed for information) and each
    shift is binned once for the three spatial scores. A unit may be in several classes
    (the ``is_*`` columns); ``cell_class`` names the first of
    ``config.precedence`` it belongs to, or ``"unclassified"``.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and ``position`` (and ``head_direction`` for the
        head-direction and conjunctive classes: NaN without it); may be dask-backed.
    n_shuffles : int, optional
        Circular time shifts of the activity against the behaviour, each by at least
        ``SHUFFLE.min_shift`` (20) s (default 100, >= 1: every class is decided against
        them). A unit's own 99th percentile needs at least 100 (warned if fewer).
    %(seed)s
    threshold : {'unit', 'pooled'}, optional
        Each class's threshold from the unit's own shuffles (default) or from every
        unit's shuffles pooled.
    environment : int, optional
        The environment to classify in (default: the most visited).
    walls : None, 'occupancy' or array (V, 2)
        The arena for the border score (see :func:`border_score`).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    config : CellClassConfig, optional
        Percentiles and precedence (default :data:`~.config.CELL_CLASS`).

    Returns
    -------
    xarray.Dataset
        Along ``unit``: ``grid_score``, ``grid_spacing``, ``grid_orientation``,
        ``border_score``, ``border_coverage``, ``spatial_information``, ``n_fields``,
        ``hd_mean_vector_length``, ``speed_score``, ``pxd_direction_length``,
        ``pxd_position_information``, each score with ``<score>_threshold`` and
        ``<score>_p_value``; booleans ``is_grid``, ``is_border``, ``is_place``,
        ``is_head_direction``, ``is_speed``, ``is_conjunctive``; ``cell_class`` (str).
        ``table.to_dataframe()`` gives a pandas DataFrame.

    Warns
    -----
    AnalysisWarning
        On a noise-free kind (``CONVENTIONS.noise_free_kinds``, a network's units): with
        thousands of samples almost any tuning beats the shuffles. Classify spikes drawn
        at a cell's rate instead, ``classify_cells(hp.poisson_spikes(rec, mean_rate))``,
        over a recording as long as the session compared with.

    References
    ----------
    [1] Langston et al. (2010), Science 328:1576-1580. [2] Solstad et al. (2008), Science
    322:1865-1868. [3] Bjerknes, Moser & Moser (2014), Neuron 82:71-78. [4] Skaggs et al.
    (1993), NIPS 5. [5] Boccara et al. (2010), Nat. Neurosci. 13:987-994. [6] Kropff et
    al. (2015), Nature 523:419-424. [7] Burgess et al. (2005), Hippocampus 15:149-153.
    [8] Cacucci, Lever, Wills, Burgess & O'Keefe (2004), J. Neurosci. 24:8265-8277.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> rng = np.random.default_rng(0)
    >>> n = 20000
    >>> hd = np.cumsum(rng.normal(0, 0.3, n))
    >>> xy = np.cumsum(0.02 * np.c_[np.cos(hd), np.sin(hd)], 0)
    >>> xy = np.abs((xy + 0.5) % 2 - 1) - 0.5                 # reflected in a 1 m box
    >>> place = np.exp(-((xy - 0.2) ** 2).sum(1) / 0.01)
    >>> rec = from_arrays(np.arange(n) * 0.1, xy, activity=place[:, None],
    ...                   head_direction=hd, activity_kind="rate")
    >>> table = classify_cells(rec)
    >>> str(table.cell_class[0].values)
    'place'
    """
    cfg = CELL_CLASS if config is None else config
    if not isinstance(cfg, CellClassConfig):
        raise TypeError(f"`config` must be a CellClassConfig; got {type(cfg).__name__}")
    rec = _common.check_recording(rec, ["activity", "position"], why="cell classes")
    n_shuffles = cfg.n_shuffles if n_shuffles is None else n_shuffles
    if isinstance(n_shuffles, (int, np.integer)) and not isinstance(n_shuffles, bool) \
            and n_shuffles < 1:
        raise ValueError(f"`n_shuffles` must be >= 1: every class is decided against the "
                         f"unit's shuffles; got {n_shuffles}")
    n_shuffles = check_number("n_shuffles", n_shuffles, low=1, low_inclusive=True,
                              integer=True)
    threshold = check_option("threshold", cfg.threshold if threshold is None else threshold,
                             ("unit", "pooled"))
    _warn_unresolved_percentiles(cfg, n_shuffles, threshold)
    rec, env = _one_environment(rec, environment)
    sigma = GRID.sigma if sigma is None else sigma
    kind = rec.attrs.get("activity_kind")
    if kind in CONVENTIONS.noise_free_kinds:
        _common.warn(
            f"activity_kind {kind!r} has no counting noise: with {rec.sizes['time']} samples "
            "almost any tuning beats the time-shift shuffles, so most units pass every "
            "test. To compare with recorded cells, classify spikes drawn at a cell's rate "
            "over a session's duration: classify_cells(hp.poisson_spikes(rec, mean_rate=5.0))")

    maps, spatial, columns = _spatial_columns(rec, walls, n_shuffles=n_shuffles, seed=seed,
                                              bin_size=bin_size, sigma=sigma,
                                              min_speed=min_speed)
    n_units = maps.sizes["unit"]
    hd_phase, notes = _direction_columns(rec, columns, n_units, n_shuffles=n_shuffles,
                                         seed=seed, min_speed=min_speed)
    r, _, _, _, _ = speed_arrays(rec, n_shuffles=n_shuffles, seed=seed, sigma=SPEED.sigma,
                                 min_speed=SPEED.min_speed, max_speed=SPEED.max_speed)
    columns["speed_score"] = (r[:, 0], r[:, 1:].T)

    coords = {k: c for k, c in maps.coords.items() if c.dims == ("unit",)}
    out = xr.Dataset(coords=coords)
    above, gate_above = _score_table(out, columns, cfg, threshold, n_shuffles,
                                     info_units="bits/spike" if maps.attrs.get("units") == "Hz"
                                     else "bits per unit of activity",
                                     gated="head_direction" in rec.variables)
    grid_obs, border_obs, fields = spatial["grid"], spatial["border"], spatial["fields"]
    out["grid_spacing"] = ("unit", grid_obs["spacing"] * spatial["size"],
                           {"units": "m", "long_name": "grid spacing"})
    out["grid_orientation"] = ("unit", grid_obs["orientation"], {
        "units": "rad", "long_name": "grid orientation (axes mod 60 deg, from +x)"})
    out["border_coverage"] = ("unit", border_obs["coverage"], {
        "units": "1", "long_name": "largest wall coverage by one field"})
    out["n_fields"] = ("unit", fields.count, {"units": "1",
                                              "long_name": "number of place fields"})
    out["hd_preferred_direction"] = ("unit", hd_phase, {"units": "rad",
                                                        "long_name": "preferred direction"})
    _assign_classes(out, above, gate_above, border_obs["score"], fields.count, cfg)
    geo = spatial["walls"]
    attrs = _common.provenance(
        "classify_cells", rec, n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed),
        threshold=threshold,
        environment="None" if env is None else env, bin_size=spatial["size"], sigma=sigma,
        sigma_units="bins", min_speed=min_speed, rate_offset=spatial["why_offset"],
        walls_source=geo[0].source, wall_vertices=geo[0].vertices.tolist(),
        rules={name: _rule(name, cfg) for name in CLASSES},
        sources={name: CLASSES[name][2] for name in CLASSES}, **notes)
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["grid_score"]),
                                   grid_nan_reasons(grid_obs), "grid score")
    return out


def _spatial_columns(rec, walls, *, n_shuffles, seed, bin_size, sigma, min_speed):
    """Grid score, border score and Skaggs information, observed and shuffled, from one
    binning per batch of shifts for all three (:class:`~._shuffles.MapStack`).

    Returns (maps, {grid, border, fields, walls, size, why_offset}, {column: (observed
    (U,), shuffled (S, U))}).
    """
    stack = MapStack(rec, n_shuffles=n_shuffles, seed=seed, bin_size=bin_size, sigma=sigma,
                     min_speed=min_speed, by=None, extent=None)
    maps, lead = check_maps("maps", stack.observed)
    x, y, size = bin_coords(maps)
    occupancy = maps["occupancy"].values
    geo = resolve_walls(walls, maps, lead, x, y, size, search_width=BORDER.search_width,
                        merge_angle=np.radians(BORDER.merge_angle),
                        min_wall_bins=BORDER.min_wall_bins)
    offset, why_offset = _common.map_rate_offset(rec, maps)
    border_kw = dict(threshold=BORDER.threshold,
                     min_bins=field_bins(size, BORDER.min_area, BORDER.min_bins))
    grid_kw = grid_kwargs(None, None)

    def info_of(raw):                                   # raw maps (..., U, ny, nx)
        shifted = raw - offset.reshape(-1, 1, 1)
        return skaggs_information(shifted, occupancy, axes=(-2, -1))[0]

    obs = maps.values
    grid_obs = grid_stats(obs, **grid_kw)
    border_obs = stack_border_stats(obs, offset, geo, **border_kw)
    info_obs = info_of(stack.observed_raw)
    fields = detect_fields(obs, threshold=PLACE_FIELD.threshold,
                           min_bins=PLACE_FIELD.min_bins,
                           min_peak=-np.inf if PLACE_FIELD.min_peak is None
                           else PLACE_FIELD.min_peak,
                           connectivity=PLACE_FIELD.connectivity)
    grid_sh, border_sh, info_sh = [], [], []
    for smooth, raw in stack.shuffle_batches():
        grid_sh.append(shuffled_scores(smooth, grid_obs["score"], grid_kw))
        border_sh.append(stack_border_stats(smooth, offset, geo, **border_kw)["score"])
        info_sh.append(info_of(raw))
    empty = np.zeros((0, obs.shape[0]))

    def cat(parts):
        return np.concatenate(parts) if parts else empty

    columns = {
        "grid_score": (grid_obs["score"], cat(grid_sh)),
        "border_score": (border_obs["score"], cat(border_sh)),
        "spatial_information": (info_obs, cat(info_sh)),
    }
    spatial = {"grid": grid_obs, "border": border_obs, "fields": fields, "walls": geo,
               "size": size, "why_offset": why_offset}
    return maps, spatial, columns


def _direction_columns(rec, columns, n_units, *, n_shuffles, seed, min_speed):
    """Head-direction mean vector length and the position x direction model's factors,
    observed and shuffled, into ``columns``; returns (preferred direction (U,), notes).
    NaN without ``head_direction``."""
    if "head_direction" not in rec.variables:
        for name in ("hd_mean_vector_length", "pxd_direction_length",
                     "pxd_position_information"):
            columns[name] = (np.full(n_units, np.nan), np.full((n_shuffles, n_units), np.nan))
        return np.full(n_units, np.nan), {
            "head_direction": "NaN: the recording has no head_direction"}
    conj = conjunctive_arrays(rec, n_shuffles=n_shuffles, seed=seed,
                              n_bins=CONJUNCTIVE.n_bins, n_dir=CONJUNCTIVE.n_directions,
                              min_speed=min_speed, extent=None)
    for name, key in (("hd_mean_vector_length", "hd_len"),
                      ("pxd_direction_length", "length"),
                      ("pxd_position_information", "info")):
        columns[name] = (conj[key][0], conj[key][1:])
    return conj["hd_phase"][0], {}


def _score_table(out, columns, cfg, threshold, n_shuffles, *, info_units, gated):
    """Each score, its shuffles' threshold and p-value into ``out``; returns which units
    are above each threshold, and above the factorial gates (``gated``: the position x
    direction model exists, so the place and head-direction classes are gated by it)."""
    percentiles = {
        "grid_score": cfg.grid_percentile, "border_score": cfg.border_percentile,
        "spatial_information": cfg.place_percentile,
        "hd_mean_vector_length": cfg.hd_percentile, "speed_score": cfg.speed_percentile,
        "pxd_direction_length": cfg.conjunctive_percentile,
        "pxd_position_information": cfg.conjunctive_percentile,
    }
    described = {
        "grid_score": ("1", "grid score"), "border_score": ("1", "border score"),
        "spatial_information": (info_units, "Skaggs spatial information"),
        "hd_mean_vector_length": ("1", "head-direction mean vector length"),
        "speed_score": ("1", "speed score"),
        "pxd_direction_length": ("1", "direction-factor mean vector length"),
        "pxd_position_information": (info_units, "position-factor information"),
    }
    gates = {"pxd_position_information": cfg.place_percentile,
             "pxd_direction_length": cfg.hd_percentile}
    nan = np.full(out.sizes["unit"], np.nan)
    above, gate_above = {}, {}
    for name, (observed, shuffled) in columns.items():
        units, long_name = described[name]
        out[name] = ("unit", np.asarray(observed, float), {"units": units,
                                                           "long_name": long_name})
        if n_shuffles:
            s = summarize(observed, shuffled, percentiles[name], threshold)
        else:
            s = {"threshold": nan, "p_value": nan}
        out[f"{name}_threshold"] = ("unit", s["threshold"], {
            "units": units, "long_name": f"{percentiles[name]:g}th percentile of the "
                                         f"shuffles' {long_name}",
            "percentile": percentiles[name]})
        out[f"{name}_p_value"] = ("unit", s["p_value"], {
            "units": "1", "long_name": f"fraction of shuffles with {long_name} at least as "
                                       "large"})
        with np.errstate(invalid="ignore"):
            above[name] = np.asarray(observed) > s["threshold"]
        # the factorial gate needs the position x direction model: without head direction
        # there is none, and the place class is decided without it
        if name in gates and cfg.factorial_gate and gated:
            g = summarize(observed, shuffled, gates[name], threshold)["threshold"] \
                if n_shuffles else nan
            out[f"{name}_gate_threshold"] = ("unit", g, {
                "units": units, "long_name": f"{gates[name]:g}th percentile of the "
                                             f"shuffles' {long_name} (factorial gate)",
                "percentile": gates[name]})
            with np.errstate(invalid="ignore"):
                gate_above[name] = np.asarray(observed) > g
    return above, gate_above


def _assign_classes(out, above, gate_above, border_score, n_fields, cfg):
    """Each class's membership (``is_<class>``) and the one ``cell_class`` per unit, by
    ``cfg.precedence``, into ``out``."""
    with np.errstate(invalid="ignore"):
        gate = above["spatial_information"] if cfg.spatial_gate else True
        member = {
            "grid": above["grid_score"] & gate,
            "border": above["border_score"] & (border_score > cfg.border_min_score) & gate,
            "place": above["spatial_information"] & (n_fields >= 1)
            & gate_above.get("pxd_position_information", True),
            "head_direction": above["hd_mean_vector_length"]
            & gate_above.get("pxd_direction_length", True),
            "speed": above["speed_score"],
            "conjunctive": above["pxd_direction_length"] & above["pxd_position_information"],
        }
    for name in CLASSES:
        out[f"is_{name}"] = ("unit", member[name], {
            "units": "1", "long_name": f"{name.replace('_', '-')} cell",
            "rule": _rule(name, cfg), "source": CLASSES[name][2]})
    labels = np.full(out.sizes["unit"], "unclassified", dtype=object)
    for name in reversed(tuple(cfg.precedence)):
        labels[member[name]] = name
    out["cell_class"] = ("unit", labels.astype(str), {
        "long_name": "cell class", "precedence": list(cfg.precedence)})


def _rule(name, cfg):
    pct = getattr(cfg, CLASSES[name][1])
    gate = (f" and Skaggs information > {cfg.place_percentile:g}th percentile of shuffles"
            if cfg.spatial_gate else "")
    return {
        "grid": f"grid score > {pct:g}th percentile of shuffles{gate}",
        "border": f"border score > {pct:g}th percentile of shuffles and > "
                  f"{cfg.border_min_score:g}{gate}",
        "place": f"Skaggs information > {pct:g}th percentile of shuffles and >= 1 field"
                 + (" and position-factor information > the same percentile of its "
                    "shuffles" if cfg.factorial_gate else ""),
        "head_direction": f"mean vector length > {pct:g}th percentile of shuffles"
                          + (" and direction-factor length > the same percentile of its "
                             "shuffles" if cfg.factorial_gate else ""),
        "speed": f"speed score > {pct:g}th percentile of shuffles",
        "conjunctive": f"direction-factor length and position-factor information > "
                       f"{pct:g}th percentile of their shuffles",
    }[name]
