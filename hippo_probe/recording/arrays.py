"""``from_arrays``: a valid recording from plain numpy arrays; spike binning."""

from __future__ import annotations

import warnings

import numpy as np

from .._angles import wrap_angle
from .._validators import check_finite, check_option, check_real, check_shape
from ..errors import RecordingError
from .config import DEFAULTS
from .layout import assemble, trial_blocks
from .schema import annotate
from .validate import _v, check_activity_kind, validate

#: Metres per unit of the position units ``from_arrays`` accepts.
LENGTH_UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001}


def check_time(time, name="time"):
    """Return ``time`` as a finite, strictly increasing float64 1-D array."""
    time = check_real(name, time).astype(float)
    if time.ndim != 1 or time.size == 0:
        raise ValueError(f"`{name}` must be a non-empty 1-D array of seconds; got shape "
                         f"{time.shape}")
    check_finite(name, time)
    step = np.diff(time)
    if (step <= 0).any():
        i = int(np.flatnonzero(step <= 0)[0])
        raise RecordingError(f"`{name}` must be strictly increasing; {name}[{i}] = "
                             f"{_v(time[i])} is followed by {name}[{i + 1}] = {_v(time[i + 1])}")
    return time


def bin_spikes(spike_times, time, trial, trial_start, trial_stop, *, reach=None):
    r"""Count each unit's spikes on the tracking samples (nearest sample, within trials).

    Sample ``i`` of a trial covers the part of the trial's interval ``[trial_start,
    trial_stop]`` nearer to ``time[i]`` than to any other sample of the trial: from the
    midpoint with the previous sample (or ``trial_start``) to the midpoint with the next
    one (or ``trial_stop``, inclusive), but no further than ``reach`` from ``time[i]``.
    Every analysis takes a sample to stand for one ``dt``, so spikes where no position is
    known (the tracking paused or skipped frames, or started after the trial's start or
    stopped before its end) must not be piled onto the samples beside them. Spikes
    outside every trial are not counted, nor those in such a gap, which is warned about.

    Parameters
    ----------
    spike_times : sequence of 1-D arrays
        Spike times (s) of each unit, on the clock of ``time``.
    time, trial : (n,) arrays
        Sample times (strictly increasing) and trial id of each sample (contiguous).
    trial_start, trial_stop : (n_trials,) arrays
        Interval of each trial, in the order the trials appear in ``time``; intervals
        must not overlap.
    reach : float, optional
        How far from its sample (s) a spike may be counted. Default
        :math:`(1 + j)\,\mathrm{dt} / 2`, with ``dt`` the median sample interval within
        trials and ``j`` the clock jitter tolerated (``RecordingConfig.gap_jitter``, 10 %):
        jittered samples leave no hole between them, while a sample beside a gap stands
        for at most ``(1 + j) dt``.

    Returns
    -------
    numpy.ndarray
        ``(n, n_units)`` float32 spike counts.

    Examples
    --------
    >>> t = np.array([0.0, 1.0, 2.0])
    >>> bin_spikes([[0.4, 0.6, 2.0, 5.0]], t, np.zeros(3, int), [0.0], [2.0]).ravel()
    array([1., 1., 1.], dtype=float32)

    Tracking stopped between 1 s and 4 s: the spikes in the gap are not counted.

    >>> t = np.array([0.0, 1.0, 4.0, 5.0])
    >>> bin_spikes([[1.2, 2.5, 3.0, 3.9]], t, np.zeros(4, int), [0.0], [5.0]).ravel()
    array([0., 1., 1., 0.], dtype=float32)
    """
    time = np.asarray(time, dtype=float)
    trial = np.asarray(trial)
    starts, stops, _ = trial_blocks(trial)
    same = trial[1:] == trial[:-1]          # consecutive samples of one trial
    if reach is None:
        within = np.diff(time)[same]
        reach = (1 + DEFAULTS.gap_jitter) * float(np.median(within)) / 2 if within.size \
            else np.inf     # one sample a trial: its trial's interval is all it has
    mid = (time[1:] + time[:-1]) / 2
    left = np.empty_like(time)
    right = np.empty_like(time)
    left[1:], right[:-1] = mid, mid
    left[starts] = trial_start
    right[stops - 1] = trial_stop
    # an edge beyond reach leaves a hole: a gap in the tracking, or the part of a trial's
    # interval before its first sample or after its last (tracking started late, or
    # stopped early)
    left = np.maximum(left, time - reach)
    right = np.minimum(right, time + reach)
    is_last = np.zeros(time.size, dtype=bool)
    is_last[stops - 1] = True
    counts = np.zeros((time.size, len(spike_times)), dtype=np.float32)
    lost, in_gaps, n_in_trials = [], 0, 0
    trial_start = np.asarray(trial_start, dtype=float)
    trial_stop = np.asarray(trial_stop, dtype=float)
    for u, spikes in enumerate(spike_times):
        if np.ndim(spikes) == 0:
            # a flat list of times would make each time a unit of one spike
            raise ValueError(f"`spike_times` must be a sequence of 1-D arrays, one per unit; "
                             f"got the number {spikes!r} as spike_times[{u}] (one unit's "
                             f"spikes: pass [times] or a 1-D numpy array)")
        spikes = check_finite(f"spike_times[{u}]", check_real(
            f"spike_times[{u}]", spikes).astype(float).ravel())
        i = np.searchsorted(left, spikes, side="right") - 1
        inside = i >= 0
        i, spikes_in = i[inside], spikes[inside]
        inside = (spikes_in < right[i]) | ((spikes_in == right[i]) & is_last[i])
        counts[:, u] = np.bincount(i[inside], minlength=time.size)
        # spikes inside a trial's interval that no sample took: in a gap of the tracking
        k = np.searchsorted(trial_start, spikes, side="right") - 1
        ok = k >= 0
        n_here = int((spikes[ok] <= trial_stop[k[ok]]).sum())
        n_in_trials += n_here
        in_gaps += n_here - int(inside.sum())
        if spikes.size and not inside.any():
            lost.append(u)
    if lost:
        # every spike of a unit outside the samples' span: most often spike times in
        # another clock or unit (ms vs s) than `time`
        warnings.warn(f"every spike of {len(lost)} of {len(spike_times)} units (e.g. unit "
                      f"index {lost[0]}) falls outside the recording's trials "
                      f"([{time[0]:.6g}, {time[-1]:.6g}] s): are `spike_times` in seconds "
                      f"on the same clock as `time`?", UserWarning, stacklevel=3)
    elif in_gaps:
        _warn_gaps(time, same, starts, stops, trial_start, trial_stop, reach, in_gaps,
                   n_in_trials)
    return counts


def _warn_gaps(time, same, starts, stops, trial_start, trial_stop, reach, in_gaps,
               n_in_trials):
    """Say how many spikes fell where the tracking has no sample, and where: the longest
    gap between samples of a trial (``same``: consecutive samples of one trial), and the
    trials whose interval their samples (``starts``, ``stops``) do not reach."""
    step = np.diff(time)
    gaps = np.flatnonzero(same & (step > 2 * reach))
    where = []
    if gaps.size:
        g = gaps[np.argmax(step[gaps])]
        where.append(f"{gaps.size} gaps between samples, the longest {step[g]:.3g} s after "
                     f"t = {time[g]:.6g} s")
    short = (time[starts] - reach > trial_start) | (time[stops - 1] + reach < trial_stop)
    if short.any():
        k = int(np.flatnonzero(short)[0])
        where.append(f"{int(short.sum())} trials whose samples do not reach their interval's "
                     f"ends (e.g. [{trial_start[k]:.6g}, {trial_stop[k]:.6g}] s, sampled "
                     f"from {time[starts[k]]:.6g} to {time[stops[k] - 1]:.6g} s)")
    warnings.warn(f"{in_gaps} of the {n_in_trials} spikes inside the trials "
                  f"({in_gaps / n_in_trials:.2%}) fall where the tracking has no sample "
                  f"within {reach:.3g} s ({'; '.join(where) or 'irregular sampling'}): they "
                  f"are not counted, as no position is known there", UserWarning,
                  stacklevel=3)


#: A tracked floor wider than this (m) is warned about: centimetres read as metres give
#: arenas 100 times too large, and rodent arenas and tracks stay below it (the largest
#: open fields are ~18 m across).
LARGE_FLOOR_M = 20.0


def warn_large_floor(xy, read_as, fix, stacklevel=3):
    """Warn when positions ``xy`` (m) span more than :data:`LARGE_FLOOR_M`: ``read_as``
    says how their unit was taken, ``fix`` how to give centimetres."""
    if not np.isfinite(xy).any():
        return
    span = np.nanmax(xy, axis=0) - np.nanmin(xy, axis=0)
    if span.max() > LARGE_FLOOR_M:
        warnings.warn(f"the position spans {span[0]:.3g} m x {span[1]:.3g} m, larger than "
                      f"any rodent arena ({read_as}): if it is in centimetres, {fix}",
                      UserWarning, stacklevel=stacklevel + 1)


#: Share of a unit's spikes beyond the samples' span above which ``from_arrays`` warns.
BEYOND_SAMPLES_WARNING = 0.5


def _warn_spikes_beyond_samples(spike_times, time):
    """Warn when most of a unit's spikes fall before the first sample or after the last
    (``bin_spikes`` warns only when all of them fall outside the trials): tracking
    shorter than the spikes, or another clock, would otherwise give a plausible map from
    the few spikes left. Spikes between trials are dropped by design, unwarned."""
    worst = None
    for u, spikes in enumerate(spike_times):
        spikes = np.asarray(spikes, dtype=float).ravel()
        beyond = int(((spikes < time[0]) | (spikes > time[-1])).sum())
        # every spike lost: bin_spikes has said so
        if BEYOND_SAMPLES_WARNING * spikes.size < beyond < spikes.size and (
                worst is None or beyond / spikes.size > worst[1] / worst[2]):
            worst = (u, beyond, spikes.size)
    if worst is not None:
        u, beyond, n = worst
        warnings.warn(f"{beyond} of the {n} spikes of unit index {u} fall before the first "
                      f"sample or after the last ([{time[0]:.6g}, {time[-1]:.6g}] s) and "
                      f"are not counted (the unit that loses the largest share): is the "
                      f"tracking shorter than the spikes, or on another clock?",
                      UserWarning, stacklevel=3)


def degrees_wrap(head_direction):
    """The first sample after which an angle taken as radians wraps at 360 (a jump of more
    than 180 between consecutive samples, every value within 360 in magnitude): degrees,
    which would be read as radians. None where it does not: unwrapped radians change by
    less than pi a sample."""
    largest = np.nanmax(np.abs(head_direction), initial=0.0)
    if not 2 * np.pi + 1e-9 < largest <= 360 + 1e-9:
        return None
    jumps = np.flatnonzero(np.abs(np.diff(head_direction)) > 180)   # NaN steps: False
    return int(jumps[0]) if jumps.size else None


def _refuse_wrapped_degrees(head_direction) -> None:
    i = degrees_wrap(head_direction)
    if i is not None:
        raise ValueError(f"`head_direction` must be in radians; it wraps at 360 (from "
                         f"{head_direction[i]:.4g} to {head_direction[i + 1]:.4g} between "
                         f"samples {i} and {i + 1}): degrees? pass np.deg2rad(...)")


def _unit_coords(unit, n_units):
    """Unit ids and extra unit coords from ``None``, ids, or a table of columns."""
    if unit is None:
        return np.arange(n_units), {}
    if hasattr(unit, "keys"):      # dict of columns or a pandas DataFrame
        columns = {str(k): np.asarray(unit[k]) for k in unit.keys()}
        key = next((k for k in ("unit", "id") if k in columns), None)
        ids = columns.pop(key) if key else np.arange(n_units)
    else:
        ids, columns = _unit_ids(unit), {}
    check_shape("unit", ids, (n_units,))
    for name, values in columns.items():
        check_shape(f"unit[{name!r}]", values, (n_units,))
    return ids, columns


def _unit_ids(unit) -> np.ndarray:
    """Unit ids as an array, refusing mixed or non-integer kinds (numpy would turn
    ``[1, "a", 2.0]`` into the strings '1', 'a', '2.0' without a word)."""
    items = unit.tolist() if isinstance(unit, np.ndarray) else list(unit)
    kinds = {"integer" if isinstance(u, (int, np.integer)) and not isinstance(u, bool)
             else "string" if isinstance(u, str) else type(u).__name__ for u in items}
    if len(kinds) > 1 or not kinds <= {"integer", "string"}:
        raise TypeError(f"`unit` ids must be all integers or all strings; got "
                        f"{' and '.join(sorted(kinds))} ({_v(items[:5])[:80]})")
    return np.asarray(items)


def _text(values):
    """Store string arrays as variable-length strings (object dtype)."""
    return values.astype(object) if values.dtype.kind in "US" else values


def from_arrays(time, position, activity=None, spike_times=None, head_direction=None,
                trial=None, environment=None, unit=None, position_units="m", **attrs):
    """Build a valid recording from plain numpy arrays.

    Parameters
    ----------
    time : (n,) float
        Sample times (s since session start), strictly increasing.
    position : (n, 2) float
        Position (x, y) in ``position_units``; NaN where tracking was lost (kept as NaN).
    activity : (n, n_units), optional
        Activity per sample (finite); stored as float32. Give this or ``spike_times``.
    spike_times : sequence of 1-D arrays, optional
        Spike times (s) of each unit, binned onto the samples by :func:`bin_spikes`
        (nearest sample within its trial; spikes outside every trial are not counted,
        with a warning when most of a unit's fall before the first sample or after the
        last); ``activity_kind`` becomes ``"spike_count"``. One unit's spikes: a 1-D
        array, or ``[times]``.
    head_direction : (n,) float, optional
        Radians, allocentric, 0 = +x, counter-clockwise; wrapped into [-pi, pi); NaN
        allowed.
    trial : (n,) int, optional
        Trial id of each sample (default: one trial, id 0). Each trial's samples must be
        contiguous, and consecutive trials separated by at least one ``dt`` (the schema's
        gap). Each trial spans ``[time of its first sample, time of its last sample]``.
    environment : int or (n,) int, optional
        Environment (arena) id, constant within a trial (default 0).
    unit : optional
        Unit ids (1-D), or a table of unit columns (dict or pandas DataFrame; ids in
        column ``"unit"`` or ``"id"``, other columns such as ``"region"`` become unit
        coords). Default ``0 .. n_units - 1``.
    position_units : {"m", "cm", "mm"}
        Units of ``position``; converted to metres.
    **attrs
        Dataset attrs. Defaults: ``source="animal"``, ``activity_kind="spike_count"``
        with ``spike_times`` else ``"rate"``, ``dt`` = the median sample interval within
        trials.

    Returns
    -------
    xarray.Dataset
        A recording that passes :func:`validate`.

    Raises
    ------
    ValueError, RecordingError
        Mismatched lengths, non-monotonic time, NaN or inf in ``activity``, inf in
        ``position``, both or neither of ``activity`` and ``spike_times``, a trial split
        into several blocks or trials without a gap.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(1000) * 0.02
    >>> xy = np.c_[np.cos(t), np.sin(t)] * 50          # cm
    >>> spikes = [np.array([0.5, 3.1, 7.7]), np.array([1.0])]
    >>> rec = from_arrays(t, xy, spike_times=spikes, position_units="cm", subject="r1")
    >>> rec.activity.sum("time").values
    array([3., 1.], dtype=float32)
    >>> float(rec.position.max())
    0.5
    """
    time = check_time(time)
    n = time.size
    scale = LENGTH_UNITS[check_option("position_units", position_units, LENGTH_UNITS)]
    position = check_shape("position", check_real("position", position).astype(float), (n, 2))
    position = check_finite("position", position, allow_nan=True) * scale
    warn_large_floor(position, f"read as {position_units}",
                     "pass position_units='cm'")

    trial = np.zeros(n, dtype=int) if trial is None else np.asarray(trial)
    check_shape("trial", trial, (n,))
    if trial.dtype.kind not in "iu":
        raise ValueError(f"`trial` must hold integer ids; got dtype {trial.dtype}")
    starts, stops, trial_id = trial_blocks(trial)
    if np.unique(trial_id).size != trial_id.size:
        raise RecordingError("`trial` must keep each trial's samples contiguous in time; "
                             f"trial ids in order of appearance: {trial_id.tolist()[:20]}")
    environment = np.asarray(0 if environment is None else environment)
    if environment.ndim == 0:
        environment = np.full(n, environment)
    check_shape("environment", environment, (n,))
    if environment.dtype.kind not in "iu":
        raise ValueError(f"`environment` must hold integer ids; got dtype {environment.dtype}")
    trial_env = environment[starts]
    changes = environment != np.repeat(trial_env, stops - starts)
    if changes.any():
        i = int(np.flatnonzero(changes)[0])
        raise RecordingError(f"`environment` must be constant within a trial; trial "
                             f"{_v(trial[i])} changes environment at sample {i}")

    if "dt" in attrs:
        dt = attrs.pop("dt")
        if isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (int, float, np.number)) \
                or not (np.isfinite(dt) and dt > 0):
            raise ValueError(f"`dt` must be a number of seconds > 0; got {dt!r}")
        dt = float(dt)
    else:
        within = np.diff(time)[np.diff(trial) == 0]
        if within.size == 0:
            raise ValueError("`dt` must be given (as a keyword) when no trial has two samples")
        dt = float(np.median(within))
    table = {"trial_start": time[starts], "trial_stop": time[stops - 1],
             "trial_environment": trial_env}

    if (activity is None) == (spike_times is None):
        raise ValueError("give exactly one of `activity` and `spike_times`; got "
                         + ("both" if activity is not None else "neither"))
    if spike_times is not None:
        if hasattr(spike_times, "keys"):
            raise TypeError("`spike_times` must be a sequence of 1-D arrays, one per unit; "
                            "got a mapping: pass list(d.values()) and unit=list(d)")
        if isinstance(spike_times, np.ndarray) and spike_times.dtype != object:
            if spike_times.ndim != 1:
                # (time, unit id) pairs or one column of times would make a unit of each
                # row: the shape cannot say which axis is the units
                raise ValueError(
                    f"`spike_times` must be a sequence of 1-D arrays, one per unit; got a "
                    f"{spike_times.ndim}-D array of shape {spike_times.shape}: for (time, "
                    f"unit id) pairs pass [times[ids == u] for u in np.unique(ids)], for "
                    f"one unit per row list(array)")
            spike_times = [spike_times]
        values = bin_spikes(spike_times, time, trial, table["trial_start"],
                            table["trial_stop"])
        _warn_spikes_beyond_samples(spike_times, time)
        attrs.setdefault("activity_kind", "spike_count")
    else:
        activity = check_real("activity", activity)
        if activity.ndim == 1:
            activity = activity[:, None]
        check_shape("activity", activity, (n, None))
        values = check_finite("activity", activity)
        beyond = np.abs(values) > np.finfo(np.float32).max
        if beyond.any():        # stored as float32: it would become inf
            i = tuple(int(k) for k in np.argwhere(beyond)[0])
            raise ValueError(f"`activity` must fit float32 (|value| <= 3.4e38), as the "
                             f"recording stores it; found {values[i]:g} at index {i}")
        values = values.astype(np.float32)
        attrs.setdefault("activity_kind", "rate")
    attrs.setdefault("source", "animal")
    check_activity_kind(attrs["activity_kind"])

    rec = assemble(time=time, trial=trial, trial_time=time - np.repeat(time[starts],
                                                                          stops - starts),
                   trial_id=trial_id, table=table, dt=dt, attrs=attrs)
    ids, unit_columns = _unit_coords(unit, values.shape[1])
    rec = rec.assign_coords(unit=_text(ids))
    rec = rec.assign_coords({k: ("unit", _text(v)) for k, v in unit_columns.items()})
    for name in unit_columns:
        rec.variables[name].attrs.update(units="", long_name=name.replace("_", " "))
    rec["activity"] = ("time", "unit"), values
    rec["position"] = ("time", "space"), position
    if head_direction is not None:
        head_direction = check_shape("head_direction", check_real(
            "head_direction", head_direction).astype(float), (n,))
        check_finite("head_direction", head_direction, allow_nan=True)
        _refuse_wrapped_degrees(head_direction)
        largest = np.nanmax(np.abs(head_direction), initial=0.0)
        if largest > 2 * np.pi + 1e-9:
            warnings.warn(f"`head_direction` reaches {largest:.4g} in magnitude, more than "
                          f"2 pi: if it is in degrees, pass np.deg2rad(...) "
                          f"(unwrapped radians are fine: they are wrapped to [-pi, pi))", UserWarning,
                          stacklevel=2)
        rec["head_direction"] = "time", wrap_angle(head_direction)
    return validate(annotate(rec))
