"""What every analysis needs from a recording: checked access, provenance, NaN reasons."""

from __future__ import annotations

import os
import sys
import warnings

import numpy as np
import xarray as xr

from .._validators import check_number, check_option, check_seed, check_variables
from .._version import __version__
from ..recording.validate import check_analysable
from .config import CONVENTIONS, SHUFFLE


class AnalysisWarning(UserWarning):
    """A result (or part of it) is NaN or approximate; the message says why."""


# as imported (code objects carry the path they were loaded from, links unresolved)
_PACKAGE = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep


def warn(message: str, category=AnalysisWarning) -> None:
    """Warn, pointing at the first line outside the package that led here (the user's
    call), however deep in the analysis the problem was found."""
    frame, level = sys._getframe(1), 2
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)


def warn_pooled_environments(rec, what: str) -> None:
    """Warn when ``rec`` spans several environments and ``what`` pools them (``by`` is
    None): each arena's positions would share one map, a mixture no arena has."""
    if "environment" not in rec.variables:
        return
    env = values(rec["environment"])
    if env.size and env.min() != env.max():
        n = len(np.unique(env))
        trials = values(rec["trial"]) if "trial" in rec.variables else None
        if trials is not None and n == len(np.unique(trials)):
            advice = ("each trial is in an arena of its own (a novel-arena task): record "
                      "several trials in a few fixed arenas instead (e.g. "
                      "hp.tasks.task_config(task, arenas=\"fixed\", n_arenas=2)) and pass "
                      "by=\"environment\"")
        else:
            advice = ("pass by=\"environment\" for one map per environment (or select "
                      "one with hp.select_trials(rec, environments=[...]))")
        warn(f"the recording spans {n} environments and `by` is None: the {what} pool "
             f"them, one map per unit over every arena's positions; {advice}")


def check_recording(rec, variables=(), *, why="", name="rec"):
    """Check that ``rec`` is a recording (xarray Dataset) holding ``variables`` and
    following the rules every analysis relies on
    (:func:`~hippo_probe.recording.check_analysable`)."""
    if not isinstance(rec, xr.Dataset):
        raise TypeError(
            f"`{name}` must be a recording (an xarray.Dataset, schema v1); "
            f"got {type(rec).__name__}"
        )
    check_variables(name, rec, variables, why=why)
    rec = check_analysable(rec, name=name)
    if rec.sizes.get("time", 1) == 0:
        raise ValueError(f"`{name}` has 0 samples (its `time` is empty): nothing to "
                         f"analyse" + (f" for {why}" if why else ""))
    return rec


def activity(rec) -> xr.DataArray:
    """``rec.activity`` as (time, unit), still lazy if the recording is."""
    act = rec["activity"]
    if set(act.dims) != {"time", "unit"}:
        raise ValueError(f"`rec.activity` must have dims ('time', 'unit'); got {act.dims}")
    return act.transpose("time", "unit")


def values(da) -> np.ndarray:
    """A small per-sample variable as a numpy array (computes it if lazy)."""
    return np.asarray(da.values if isinstance(da, xr.DataArray) else da)


def sample_dt(rec) -> float:
    """The recording's sample interval: ``attrs['dt']``, else the median time step."""
    dt = rec.attrs.get("dt")
    if dt is None or not np.isfinite(dt) or dt <= 0:
        t = values(rec["time"])
        if t.size < 2:
            raise ValueError("`rec` must have attrs['dt'] or at least 2 samples to infer it")
        dt = float(np.median(np.diff(t)))
    return float(dt)


def is_spike_data(rec) -> bool:
    return rec.attrs.get("activity_kind") in CONVENTIONS.spike_kinds


def rate_scale(rec) -> tuple[float, str, str]:
    """Factor turning mean activity per sample into the map's unit, its units, long name.

    Spike counts per sample become Hz (divide by ``dt``); other kinds are kept as the mean
    activity per sample in the activity's own units.
    """
    act = rec["activity"]
    if is_spike_data(rec):
        return 1.0 / sample_dt(rec), "Hz", "firing rate"
    name = act.attrs.get("long_name", "activity")
    return 1.0, act.attrs.get("units", "1"), f"mean {name}"


def tracks_minimum(rec) -> bool:
    """Whether each unit's minimum over the recording is needed (not a non-negative kind)."""
    return rec.attrs.get("activity_kind") not in CONVENTIONS.nonnegative_kinds


def map_rate_offset(rec, maps) -> tuple[np.ndarray, str]:
    """Per-unit offset that makes rate maps of :func:`~.ratemaps.ratemaps` non-negative,
    and why: :func:`nonnegative_offset` with the recording's minimum (the maps'
    ``activity_min``) or, where it was not tracked, each map's own minimum."""
    kind_rec = rec if rec is not None else xr.Dataset(attrs=maps.attrs)
    amin = maps["activity_min"].values if "activity_min" in maps.coords else \
        np.full(maps.sizes["unit"], np.nan)
    floor = maps.min([d for d in maps.dims if d != "unit"], skipna=True).values
    return nonnegative_offset(kind_rec, amin, floor)


def nonnegative_offset(rec, amin, floor=None) -> tuple[np.ndarray, str]:
    """Per-unit offset subtracted to make activity a non-negative rate, and why.

    Signed kinds (``CONVENTIONS.signed_kinds``, e.g. the LSTM's h) are shifted by each
    unit's minimum over the recording (``amin``). Other kinds are used as they are unless
    they hold negative values, which are shifted the same way with a warning; when the
    minimum was not tracked (non-negative kinds), ``floor`` (each unit's minimum of its
    map or curve) stands in for it.
    """
    amin = np.asarray(amin, float)
    kind = rec.attrs.get("activity_kind")
    if kind in CONVENTIONS.signed_kinds:
        return amin, (f"activity_kind {kind!r} is signed: each unit's activity minus its "
                      "minimum over the recording")
    tracked = np.isfinite(amin).all()
    low = amin if tracked or floor is None else np.asarray(floor, float)
    if np.any(low < 0):
        what = "activity" if tracked else "map"
        warn(f"activity (kind {kind!r}) has negative values; each unit's {what} minus its "
             "minimum is used as a non-negative rate")
        return np.minimum(np.nan_to_num(low, nan=0.0), 0.0), (
            f"negative values found: each unit's {what} minus its minimum (units with "
            "min >= 0 unchanged)")
    return np.zeros_like(amin), "none: activity is non-negative"


def provenance(analysis: str, rec=None, **params) -> dict:
    """attrs that say how a result was made."""
    attrs = {"analysis": analysis, "hippo_probe_version": __version__}
    if rec is not None:
        for key in ("source", "activity_kind", "session_id", "task", "dt"):
            if key in rec.attrs:
                attrs[key] = rec.attrs[key]
    for key, value in params.items():
        attrs[key] = "None" if value is None else value
    return attrs


def shuffle_seed(seed):
    """The seed the shuffles' shifts are drawn with: ``seed``, or ``SHUFFLE.seed`` when
    None (what :func:`circular_shifts` uses; recorded in a result's provenance)."""
    return SHUFFLE.seed if seed is None else seed


def report_nan(attrs: dict, labels, reasons, what: str):
    """Record why entries are NaN (attrs['nan_reasons']) and warn once."""
    reasons = {str(k): r for k, r in zip(labels, reasons) if r}
    if not reasons:
        return attrs
    attrs = dict(attrs)
    attrs["nan_reasons"] = reasons
    sample = "; ".join(f"{k}: {r}" for k, r in list(reasons.items())[:3])
    more = f" (and {len(reasons) - 3} more)" if len(reasons) > 3 else ""
    warn(f"{what} is NaN for {len(reasons)} entries: {sample}{more}; "
         "see attrs['nan_reasons']")
    return attrs


def group_codes(rec, by):
    """Integer group of each sample for ``by`` in {None, 'environment', 'trial'}.

    Returns ``(codes (time,), labels, dim)``; ``dim`` is None when ``by`` is None.
    """
    check_option("by", by, (None, "environment", "trial"))
    n = rec.sizes["time"]
    if by is None:
        return np.zeros(n, np.int64), None, None
    check_recording(rec, [by], why=f"by={by!r}")
    raw = values(rec[by])
    labels, codes = np.unique(raw, return_inverse=True)
    return codes.astype(np.int64), labels, by


def speed(rec) -> np.ndarray:
    """Speed (m/s) of every sample: ``rec.speed`` if present, else from ``position``.

    Derived speed is |p_t - p_{t-1}| / (t_t - t_{t-1}) within a trial (the first sample of
    a trial takes its successor's value); NaN where position is NaN.
    """
    if "speed" in rec:
        return values(rec["speed"]).astype(float)
    pos = values(rec["position"].transpose("time", "space")).astype(float)
    t = values(rec["time"]).astype(float)
    trial = values(rec["trial"]) if "trial" in rec.coords or "trial" in rec else np.zeros(len(t))
    step = np.full(len(t), np.nan)
    if len(t) > 1:
        step[1:] = np.linalg.norm(np.diff(pos, axis=0), axis=1) / np.diff(t)
        first = np.r_[True, trial[1:] != trial[:-1]]
        step[first] = np.r_[step[1:], np.nan][first]
        step[first & np.r_[first[1:], True]] = np.nan  # one-sample trials: unknown
    return step


def circular_shifts(n: int, dt: float, n_shuffles: int, seed: int | None) -> np.ndarray:
    """``n_shuffles`` random circular shifts (samples), at least ``SHUFFLE.min_shift`` s.

    For recordings shorter than ``4 * min_shift`` the bound is a quarter of the duration.
    """
    n_shuffles = check_number("n_shuffles", n_shuffles, low=0, low_inclusive=True,
                              integer=True)
    low = int(round(SHUFFLE.min_shift / dt))
    low = min(low, n // 4)
    if n_shuffles and n < 4:
        raise ValueError(f"`n_shuffles` = {n_shuffles} time-shift shuffles need a recording "
                         f"of at least 4 samples; got {n} (pass n_shuffles=0 to skip the "
                         "significance test)")
    rng = np.random.default_rng(check_seed("seed", shuffle_seed(seed)))
    return rng.integers(max(low, 1), n - max(low, 1) + 1, size=n_shuffles)


def default_shuffles(n_shuffles, by, default: int) -> int:
    """``n_shuffles`` as given, else ``default`` shuffles, or none with ``by`` (refused
    there by :func:`shifts_for`)."""
    if n_shuffles is not None:
        return n_shuffles
    return 0 if by is not None else default


def shifts_for(rec, n_shuffles, seed, by=None):
    """``[0, s_1, ..., s_n]``: no shift (the observed score), then the random shifts of
    :func:`circular_shifts`.

    Refused with ``by`` (per environment or trial): a shift runs over the whole
    recording, so one group's shuffled maps would hold other groups' activity, and its
    null distribution would be the pooled recording's, not its own (a unit flat in one
    arena and firing in the other reads as significant in the first).
    """
    if n_shuffles and by is not None:
        raise ValueError(
            f"`n_shuffles` = {n_shuffles} with `by` = {by!r}: the time shifts run over the "
            f"whole recording, so each {by}'s shuffles would mix in the other {by}s' "
            f"activity and give a wrong null. Shuffle each {by} alone: select its trials "
            f"(e.g. hp.select_trials(rec, environments=k)) and call without `by`, or pass "
            f"n_shuffles=0 for the scores alone")
    return np.r_[0, circular_shifts(rec.sizes["time"], sample_dt(rec), n_shuffles,
                                    seed)].astype(np.int64)


def entry_labels(da) -> list[str]:
    """A readable label for every entry of ``da`` (e.g. 'unit=3, environment=1')."""
    names = list(da.dims)
    index = [_common_coord(da, d) for d in names]
    return [", ".join(f"{n}={index[k][i]}" for k, (n, i) in enumerate(zip(names, idx)))
            for idx in np.ndindex(da.shape)]


def _common_coord(da, dim):
    return da[dim].values if dim in da.coords else np.arange(da.sizes[dim])


def refuse_map_options(n_shuffles=None, **options):
    """Options that only act on a recording (map making, shuffles) refused when rate maps
    are given instead: silently ignoring them would mislead."""
    if n_shuffles:
        raise ValueError("`n_shuffles` needs a recording (the shuffles re-bin the "
                         f"samples); got rate maps and n_shuffles={n_shuffles}")
    given = {k: v for k, v in options.items() if v is not None}
    if not given:
        return
    names = ", ".join(f"`{k}`" for k in given)
    verb = "applies" if len(given) == 1 else "apply"
    map_options = [k for k in given if k != "seed"]
    hint = (f"; pass {', '.join(map_options)} to ratemaps() instead" if map_options else "")
    raise ValueError(f"{names} only {verb} when a recording is given (the maps are already "
                     f"made); got rate maps and "
                     f"{', '.join(f'{k}={v!r}' for k, v in given.items())}{hint}")
