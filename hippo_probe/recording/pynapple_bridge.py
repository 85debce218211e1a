"""pynapple bridge: a recording as pynapple objects (``to_pynapple``) and back
(``from_pynapple``); pynapple is imported when called.

pynapple (Viejo et al. 2023, eLife 12:RP85786) is the community toolbox for time series
of neurophysiology: timestamps with a *time support* (the intervals where the data are
defined), ``Tsd``/``TsdFrame`` for sampled values, ``TsGroup`` for spike times and
``IntervalSet`` for epochs. The mapping:

==========================  =================================================
recording                   pynapple
==========================  =================================================
``activity`` (time, unit)   ``TsdFrame`` (columns = unit ids), or a ``TsGroup``
                            of spike times for ``activity_kind="spike_count"``;
                            unit coords (``region`` ...) as metadata
``position`` (time, space)  ``TsdFrame`` with columns ``x``, ``y`` (m)
``head_direction``          ``Tsd`` (rad, 0 = +x, counter-clockwise)
trial table                 ``IntervalSet`` [trial_start, trial_stop] with metadata
                            ``trial_id``, ``environment`` (``start_x``, ``start_y``
                            for ``start_position``; other trial columns by name)
other per-sample variables  ``Tsd`` / ``TsdFrame`` by name (``speed``, ``estimate``)
dataset attrs               a plain dict
==========================  =================================================

Every pynapple object shares one time support: the trial intervals.
"""

from __future__ import annotations

import warnings

import numpy as np

from .._validators import check_option
from ..errors import RecordingError
from .arrays import LENGTH_UNITS, _unit_ids, _warn_spikes_beyond_samples, bin_spikes, from_arrays
from .config import DEFAULTS
from .schema import SAMPLE_COORDS, TRIAL_TABLE, VARIABLES, annotate
from .validate import _v, validate

#: Metadata columns of the trials ``IntervalSet`` (pynapple side) -> trial table coords.
TRIAL_METADATA = {"trial_id": "trial_id", "environment": "trial_environment"}
#: Metadata columns holding ``start_position`` (x, y) of each trial.
START_METADATA = ("start_x", "start_y")
#: Keys of the dict :func:`to_pynapple` returns, in order (:func:`from_pynapple`'s
#: parameters).
KEYS = ("activity", "position", "head_direction", "trials", "time_support", "variables",
        "attrs")
#: Recording variables that the core keys carry (the rest go to ``variables`` or, without
#: a time axis, are reported as not carried).
_CORE = {"activity", "position", "head_direction", "time", "unit", "space", "trial_id",
         "environment_id", *SAMPLE_COORDS, *TRIAL_TABLE}
#: TsGroup metadata that pynapple computes itself (not a unit coord).
_TSGROUP_COMPUTED = ("rate",)


def _pynapple(what):
    """The pynapple module, or the shared "install the extra" error."""
    try:
        import pynapple
    except ImportError as err:
        from .._optional import missing

        raise missing("pynapple", what) from err
    return pynapple


def _unit_table(rec):
    """Unit ids and the unit coords other than ``unit`` (name -> values)."""
    coords = {name: np.asarray(c.values) for name, c in rec.coords.items()
              if c.dims == ("unit",) and name != "unit"}
    return np.asarray(rec["unit"].values), coords


def _spike_times(counts, time, ids):
    """Spike times of each unit: ``counts[i, u]`` copies of ``time[i]``."""
    rounded = np.rint(counts)
    bad = (counts < 0) | (np.abs(counts - rounded) > 1e-6)
    if bad.any():
        i, u = (int(k) for k in np.argwhere(bad)[0])
        raise RecordingError(
            f"`rec.activity` must hold non-negative whole spike counts to become spike "
            f"times (activity_kind 'spike_count'); unit {_v(ids[u])} has "
            f"{float(counts[i, u])!r} at time {time[i]:.6g} s. Use activity_as='tsdframe'")
    rounded = rounded.astype(np.int64)
    return [np.repeat(time, rounded[:, u]) for u in range(rounded.shape[1])]


def to_pynapple(rec, *, activity_as="auto"):
    """A recording as pynapple objects.

    The activity becomes a ``TsdFrame`` (one column per unit, named by the unit id) or,
    for spike counts, a ``TsGroup`` of spike times. Spike times are *reconstructed* from
    the counts: a count of ``k`` at sample ``t`` gives ``k`` spikes at time ``t``. The
    counts were binned onto the tracking samples, so the timing within a sample interval
    (``dt``) is lost: the spikes sit on the sample clock, and analyses finer than ``dt``
    (spike-time cross-correlograms at lags below ``dt``, phase precession within a cycle)
    are not meaningful on them. Binning them back onto the same samples
    (:func:`from_pynapple`) gives back the counts exactly.

    Every pynapple object has the trials as its time support. The data are loaded into
    memory (a dask-backed recording is read whole).

    Parameters
    ----------
    rec : xarray.Dataset
        A recording (schema v1).
    activity_as : {"auto", "tsdframe", "tsgroup"}
        ``"auto"``: a ``TsGroup`` when ``rec.attrs["activity_kind"] == "spike_count"``,
        else a ``TsdFrame``. ``"tsgroup"`` needs non-negative whole counts.

    Returns
    -------
    dict
        A plain dict of pynapple objects, keyed like :func:`from_pynapple`'s parameters,
        so ``from_pynapple(**to_pynapple(rec))`` rebuilds the recording:

        ``"activity"``
            ``nap.TsdFrame`` (columns = unit ids, unit coords such as ``region`` as
            metadata: ``frame.region``) or ``nap.TsGroup`` (keys = unit ids when they
            are increasing integers, else ``0 .. n_units - 1`` with the ids in metadata
            ``unit``, as a TsGroup sorts its keys; unit coords as metadata).
        ``"position"``
            ``nap.TsdFrame`` with columns ``x``, ``y`` (m).
        ``"head_direction"``
            ``nap.Tsd`` (rad), or None when the recording has none.
        ``"trials"``
            ``nap.IntervalSet`` of [trial_start, trial_stop] with metadata ``trial_id``
            and ``environment`` (and ``start_x``, ``start_y`` when the recording has
            ``start_position``; any other coord along ``trial_id`` by its name).
        ``"time_support"``
            ``nap.IntervalSet``: the same intervals, without metadata (the time support
            of every object above).
        ``"variables"``
            dict of the other per-sample variables (``speed``, ``estimate``,
            ``class_probability`` ...) as ``nap.Tsd`` or, for the schema's 2-D ones,
            ``nap.TsdFrame`` (columns = the labels of their second dim).
        ``"attrs"``
            dict: the recording's dataset attrs.

    Warns
    -----
    UserWarning
        Naming the variables pynapple has no place for (no time axis, e.g.
        ``arena_vertices``, ``readout_weight``, or 2-D along time but not in the
        schema): they are not carried. Attrs of the
        variables (other than what the schema fills in again) are not carried either.

    Raises
    ------
    RecordingError
        ``rec`` is not a valid recording; a trial of zero duration (a single sample:
        pynapple drops empty intervals); ``activity_as="tsgroup"`` on counts that are not
        whole and non-negative.

    See Also
    --------
    from_pynapple : the way back.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(100) * 0.1
    >>> rec = from_arrays(t, np.zeros((100, 2)), spike_times=[[0.5, 0.52, 3.0]],
    ...                   unit={"unit": [7], "region": ["ca1"]})
    >>> data = to_pynapple(rec)
    >>> data["activity"][7].t            # 0.52 s was binned to the 0.5 s sample
    array([0.5, 0.5, 3. ])
    >>> data["activity"].region.tolist()
    ['ca1']
    """
    nap = _pynapple("hippo_probe.to_pynapple")
    validate(rec)
    check_option("activity_as", activity_as, ("auto", "tsdframe", "tsgroup"))
    if activity_as == "auto":
        activity_as = ("tsgroup" if rec.attrs["activity_kind"] == "spike_count"
                       else "tsdframe")
    trials, support = _trials_to_pynapple(nap, rec)
    time = np.asarray(rec["time"].values, dtype=float)
    activity = _activity_to_pynapple(nap, rec, time, support, activity_as)
    position = nap.TsdFrame(
        t=time, d=np.asarray(rec["position"].sel(space=["x", "y"])
                             .transpose("time", "space").values, dtype=float),
        columns=["x", "y"], time_support=support)
    head_direction = None
    if "head_direction" in rec:
        head_direction = nap.Tsd(t=time, d=np.asarray(rec["head_direction"].values),
                                 time_support=support)
    return {"activity": activity, "position": position, "head_direction": head_direction,
            "trials": trials, "time_support": support,
            "variables": _variables_to_pynapple(nap, rec, time, support),
            "attrs": dict(rec.attrs)}


def _trials_to_pynapple(nap, rec):
    """The trials as an ``IntervalSet`` with their metadata, and the bare time support."""
    starts = np.asarray(rec["trial_start"].values, dtype=float)
    stops = np.asarray(rec["trial_stop"].values, dtype=float)
    trial_ids = np.asarray(rec["trial_id"].values)
    empty = stops <= starts
    if empty.any():
        raise RecordingError(
            f"`rec` has trials of zero duration (trial_start == trial_stop, a single "
            f"sample), which pynapple's IntervalSet drops: trial ids "
            f"{trial_ids[empty].tolist()[:10]}; leave them out first with "
            f"hippo_probe.select_trials")
    support = nap.IntervalSet(start=starts, end=stops)
    meta = {"trial_id": trial_ids,
            "environment": np.asarray(rec["trial_environment"].values)}
    if "start_position" in rec.variables:
        start = np.asarray(rec["start_position"].transpose("trial_id", "space")
                           .sel(space=["x", "y"]).values, dtype=float)
        meta.update(zip(START_METADATA, start.T))
    for name, var in rec.variables.items():       # other trial columns, e.g. a trial type
        if var.dims == ("trial_id",) and name not in _CORE:
            if name in meta:
                raise RecordingError(f"`rec.{name}` (along trial_id) clashes with the "
                                     f"trials metadata {sorted(meta)}; rename it first")
            meta[name] = np.asarray(var.values)
    return nap.IntervalSet(start=starts, end=stops, metadata=meta), support


def _activity_to_pynapple(nap, rec, time, support, activity_as):
    """The activity as a ``TsdFrame`` or, rebuilt as spike times, a ``TsGroup``."""
    ids, unit_coords = _unit_table(rec)
    values = np.asarray(rec["activity"].transpose("time", "unit").values)
    if activity_as != "tsgroup":
        return nap.TsdFrame(t=time, d=values, columns=ids.tolist(), time_support=support,
                            metadata=unit_coords or None)
    # a TsGroup sorts its keys: ids that are not increasing go into metadata, in order
    if ids.dtype.kind in "iu" and (np.diff(ids) > 0).all():
        keys, metadata = ids.tolist(), dict(unit_coords)
    else:
        keys, metadata = list(range(ids.size)), {"unit": ids, **unit_coords}
    clash = [name for name in metadata if name in _TSGROUP_COMPUTED]
    if clash:
        raise RecordingError(f"unit coords {clash} clash with what pynapple's TsGroup "
                             "computes itself; rename them first (rec.rename(...))")
    spikes = _spike_times(values, time, ids)
    return nap.TsGroup({k: nap.Ts(t=s, time_support=support) for k, s in zip(keys, spikes)},
                       time_support=support, metadata=metadata or None)


def _variables_to_pynapple(nap, rec, time, support) -> dict:
    """The other per-sample variables as ``Tsd`` (or ``TsdFrame`` for the schema's 2-D
    ones); a warning names those with no place in a time series."""
    variables, left_out = {}, []
    for name, var in rec.variables.items():
        if (name in _CORE or name in rec.dims or var.dims == ("trial_id",)
                or (name in rec.coords and var.dims == ("unit",))):
            continue     # carried above (index coords travel as columns)
        if var.dims == ("time",):
            variables[name] = nap.Tsd(t=time, d=np.asarray(var.values), time_support=support)
        elif (name in VARIABLES and VARIABLES[name].dims == var.dims and len(var.dims) == 2
              and var.dims[0] == "time" and var.dims[1] in rec.coords):
            # a schema variable: from_pynapple knows its second dim from the schema
            variables[name] = nap.TsdFrame(
                t=time, d=np.asarray(var.values), time_support=support,
                columns=np.asarray(rec[var.dims[1]].values).tolist())
        else:
            left_out.append(f"{name} {var.dims}")
    if left_out:
        # the arena's outline sets the rate maps' extent: without it they take the
        # positions', other bins, and other spatial information
        arena = ("; a recording rebuilt from them has no arena outline, so its rate maps "
                 "span the positions' extent instead of the arena's: other bins, other "
                 "map statistics" if "arena_vertices" in rec.variables else "")
        warnings.warn(f"not carried to pynapple (no place for them in a time series): "
                      f"{', '.join(left_out)}{arena}", UserWarning, stacklevel=3)
    return variables


def _is(nap, obj, names):
    return any(isinstance(obj, getattr(nap, n)) for n in names)


def _check_type(nap, name, obj, names, hint=""):
    if not _is(nap, obj, names):
        kinds = " or ".join(f"pynapple {n}" for n in names)
        raise TypeError(f"`{name}` must be a {kinds}; got {type(obj).__module__}."
                        f"{type(obj).__name__}{hint}")
    return obj


def _check_same_clock(name, t, time, config):
    """``t`` (the timestamps of ``name``) must be the position's ``time``."""
    t = np.asarray(t, dtype=float)
    if t.shape != time.shape:
        raise ValueError(
            f"`{name}` must share the timestamps of `position` ({time.size} samples, "
            f"{time[0]:.6g}-{time[-1]:.6g} s); got {t.size} samples"
            + (f" ({t[0]:.6g}-{t[-1]:.6g} s)" if t.size else "")
            + f"; resample it first, e.g. position.value_from({name})")
    off = np.abs(t - time) > config.time_atol
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise ValueError(f"`{name}` must share the timestamps of `position`; sample {i} is "
                         f"at {_v(t[i])} s in `{name}` and {_v(time[i])} s in `position`")


def _labels(values):
    """Text as an object array of Python ``str`` (pandas and pynapple hand back
    ``numpy.str_`` or their own string dtypes); other values unchanged."""
    values = np.asarray(values)
    if values.dtype.kind in "USOT" and all(isinstance(v, str) for v in values.ravel()):
        return np.array([str(v) for v in values.ravel()], dtype=object).reshape(values.shape)
    return values


def _metadata(obj):
    """Metadata columns of a pynapple object as arrays (name -> values)."""
    table = getattr(obj, "metadata", None)
    if table is None:
        return {}
    return {str(col): _labels(table[col]) for col in table.columns}


def _trial_table(nap, trials, time_support, position):
    """(starts, stops, ids, environments, start positions or None, other columns) of
    the trials."""
    if trials is None:
        source = "time_support" if time_support is not None else "position.time_support"
        trials = position.time_support if time_support is None else time_support
    else:
        source = "trials"
    _check_type(nap, source, trials, ("IntervalSet",))
    starts = np.asarray(trials.start, dtype=float)
    stops = np.asarray(trials.end, dtype=float)
    if starts.size == 0:
        raise ValueError(f"`{source}` must hold at least one interval; got none")
    meta = _metadata(trials) if source == "trials" else {}
    ids = meta.get("trial_id", np.arange(starts.size))
    env = meta.get("environment", np.zeros(starts.size, dtype=np.int64))
    for col, values in (("trial_id", ids), ("environment", env)):
        if values.dtype.kind not in "iu":
            raise ValueError(f"`trials` metadata {col!r} must hold integers; got dtype "
                             f"{values.dtype} ({_v(values[:5].tolist())})")
    if np.unique(ids).size != ids.size:
        raise ValueError(f"`trials` metadata 'trial_id' must be unique; got "
                         f"{ids.tolist()[:20]}")
    start_position = None
    present = [c for c in START_METADATA if c in meta]
    if present:
        if len(present) != 2:
            raise ValueError(f"`trials` metadata must hold both {START_METADATA} or "
                             f"neither; got only {present}")
        start_position = np.column_stack([meta[c].astype(float) for c in START_METADATA])
    if time_support is not None and source == "trials":
        _check_type(nap, "time_support", time_support, ("IntervalSet",))
        s0 = np.asarray(time_support.start, float)
        s1 = np.asarray(time_support.end, float)
        _, inside = _interval_of(starts, s0, s1, until=stops)
        if not inside.all():
            j = int(np.flatnonzero(~inside)[0])
            raise ValueError(f"`trials` must lie inside `time_support`; trial "
                             f"{_v(ids[j])} [{starts[j]:.6g}, {stops[j]:.6g}] s does not")
    extra = {k: v for k, v in meta.items()
             if k not in TRIAL_METADATA and k not in START_METADATA}
    return starts, stops, ids, env, start_position, extra


def _interval_of(t, starts, stops, until=None):
    """Index of the interval (sorted, closed, as in pynapple) holding each time ``t``, and
    whether it does; with ``until``, whether ``[t, until]`` lies inside that interval."""
    k = np.searchsorted(starts, t, side="right") - 1
    return k, (k >= 0) & ((t if until is None else until) <= stops[k.clip(0)])


def _sample_trials(time, starts, stops, ids):
    """Index of the trial holding each sample (intervals closed, as in pynapple)."""
    k, inside = _interval_of(time, starts, stops)
    if not inside.all():
        i = int(np.flatnonzero(~inside)[0])
        raise RecordingError(
            f"`position` has {int((~inside).sum())} samples outside every trial (first at "
            f"{time[i]:.6g} s); restrict the data to the trials first, e.g. "
            f"position.restrict(trials)")
    empty = np.setdiff1d(np.arange(starts.size), k)
    if empty.size:
        raise RecordingError(
            f"`trials` {ids[empty].tolist()[:10]} hold no `position` sample; select the "
            f"trials with samples first (a recording's trial table lists only those)")
    return k


#: Share of the position's samples outside the spikes' ``time_support`` above which
#: ``from_pynapple`` warns (pynapple's default support, first to last spike, leaves a
#: little of a session's ends outside).
OUTSIDE_SUPPORT_WARNING = 0.01


def _warn_outside_support(support, time, spikes):
    """Warn when many samples lie outside the TsGroup's time support: if the units were
    not recorded there, their zero counts read as silence. pynapple's default support
    (each unit's first to last spike) says nothing about when they were recorded: only
    a support given explicitly (bounds that are not spike times) is held against."""
    s0, s1 = np.asarray(support.start, float), np.asarray(support.end, float)
    every = np.concatenate(spikes) if spikes else np.empty(0)
    if np.isin(s0, every).all() and np.isin(s1, every).all():
        return
    outside = ~_interval_of(time, s0, s1)[1]
    if outside.mean() > OUTSIDE_SUPPORT_WARNING:
        first = time[np.flatnonzero(outside)[0]]
        warnings.warn(f"{outside.mean():.0%} of the position's samples (the first at "
                      f"{first:.6g} s) lie outside `activity.time_support` "
                      f"({s0.size} intervals from {s0[0]:.6g} to {s1[-1]:.6g} s): if the "
                      f"units were not recorded there, their zero counts read as silence; "
                      f"restrict the position and trials to activity.time_support first",
                      UserWarning, stacklevel=4)


def _activity_values(nap, activity, time, trial_index, starts, stops, attrs, config):
    """(values (n, n_units), unit ids, unit coords, activity_kind) from a TsdFrame or
    TsGroup."""
    if _is(nap, activity, ("TsGroup",)):
        kind = attrs.get("activity_kind", "spike_count")
        if kind != "spike_count":
            raise ValueError(f"`attrs['activity_kind']` must be 'spike_count' when "
                             f"`activity` is a TsGroup (spike times are binned to counts); "
                             f"got {kind!r}")
        meta = _metadata(activity)
        for name in _TSGROUP_COMPUTED:
            meta.pop(name, None)
        keys = np.asarray(activity.keys())
        if keys.size == 0:
            raise ValueError("`activity` must hold at least one unit; got an empty TsGroup")
        ids = meta.pop("unit") if "unit" in meta else keys
        spikes = [np.asarray(activity[k].t, dtype=float) for k in keys.tolist()]
        # the trial of each sample, by its interval; spikes outside every trial are not
        # counted (bin_spikes), as with from_arrays and from_nwb
        values = bin_spikes(spikes, time, trial_index, starts, stops)
        _warn_spikes_beyond_samples(spikes, time)
        _warn_outside_support(activity.time_support, time, spikes)
        return values, ids, meta, kind
    _check_same_clock("activity", activity.t, time, config)
    if activity.values.ndim != 2:
        raise ValueError(f"`activity` must be 2-D (time, unit); got shape "
                         f"{activity.values.shape}")
    meta = _metadata(activity)
    if "unit" in meta:
        raise ValueError("`activity` metadata must not have a column 'unit': the unit ids "
                         "are the TsdFrame's columns")
    return (np.asarray(activity.values), _labels(activity.columns), meta,
            attrs.get("activity_kind", "rate"))


def _add_variables(nap, rec, variables, time, config):
    """Per-sample variables (Tsd by name -> ("time",); TsdFrame -> the schema's dims)."""
    if not hasattr(variables, "items"):
        raise TypeError(f"`variables` must be a dict of name -> pynapple Tsd or TsdFrame; "
                        f"got {type(variables).__name__}")
    for name, obj in variables.items():
        label = f"variables[{name!r}]"
        if not isinstance(name, str) or name in _CORE or name in rec.variables:
            raise ValueError(f"`variables` must not name a variable the recording already "
                             f"has or builds from the other arguments; got {name!r}")
        _check_type(nap, label, obj, ("Tsd", "TsdFrame"))
        _check_same_clock(label, obj.t, time, config)
        if _is(nap, obj, ("TsdFrame",)):
            spec = VARIABLES.get(name)
            if spec is None or len(spec.dims) != 2 or spec.dims[0] != "time":
                raise ValueError(f"`{label}` is a TsdFrame, so it must be a schema "
                                 f"variable with dims (time, ...) to know its second dim; "
                                 f"got {name!r}")
            dim = spec.dims[1]
            labels = _labels(obj.columns)
            if dim not in rec.coords:
                rec = rec.assign_coords({dim: labels})
            elif not np.array_equal(rec[dim].values, labels):
                # the environment table may list environments no trial visits (the
                # classifier's classes), as long as it lists those the trials visit
                if dim == "environment_id" and np.isin(rec["environment"].values,
                                                       labels).all():
                    rec = rec.assign_coords(environment_id=labels)
                else:
                    raise ValueError(f"`{label}` columns must be the recording's {dim} "
                                     f"{rec[dim].values.tolist()}; got {labels.tolist()}")
            rec[name] = ("time", dim), np.asarray(obj.values)
        else:
            if np.asarray(obj.values).ndim != 1:
                raise ValueError(f"`{label}` must be 1-D; got shape {obj.values.shape}")
            # a variable outside the schema: pynapple carries no units (annotate gives a
            # schema variable its own)
            rec[name] = "time", np.asarray(obj.values), ({} if name in VARIABLES else {
                "units": "", "long_name": name.replace("_", " "),
                "note": "units unknown: not carried by pynapple"})
    return rec


def _floor_columns(position):
    """The position's two columns as (x, y): by name where they are x and y (any case),
    else in order; a column named x or y never becomes the other axis."""
    columns = [str(c) for c in position.columns]
    if len(columns) != 2:
        raise ValueError(f"`position` must have two columns (x, y); got {columns}; select "
                         f"the floor axes first, e.g. position[['x', 'z']]")
    names = [c.lower() for c in columns]
    values = np.asarray(position.values, dtype=float)
    if sorted(names) == ["x", "y"]:
        return values[:, [names.index("x"), names.index("y")]]
    for k, axis in enumerate("xy"):
        if axis in names and names.index(axis) != k:
            j = names.index(axis)
            raise ValueError(f"`position` columns {columns}: the column {columns[j]!r} "
                             f"would become the recording's {'xy'[j]}; give the floor axes "
                             f"as (x, y), e.g. position[{columns[::-1]!r}]")
    return values


def from_pynapple(activity, position, head_direction=None, trials=None, time_support=None,
                  variables=None, attrs=None, *, position_units="m", config=DEFAULTS):
    """Build a recording (schema v1) from pynapple objects.

    The position's timestamps become the recording's samples (``time``). A ``TsdFrame``
    of activity must share them; a ``TsGroup`` of spike times is binned onto them with
    :func:`~hippo_probe.recording.bin_spikes` (nearest sample within its trial, so the
    counts hold the spikes inside the trials' intervals; spikes outside every trial are
    not counted). The trials' intervals become the trial table; each sample belongs to
    the trial whose closed interval [start, end] holds it. The recording is built with
    :func:`~hippo_probe.recording.from_arrays` and validated.

    Parameters
    ----------
    activity : nap.TsdFrame or nap.TsGroup
        One column per unit (column names = unit ids; metadata columns such as
        ``region`` become unit coords), or spike times (keys = unit ids, or metadata
        ``unit`` when present; metadata except pynapple's own ``rate`` become unit
        coords; ``activity_kind`` is then ``"spike_count"``).
    position : nap.TsdFrame
        Two columns: ``x`` and ``y`` (by name, or the only two in order), in
        ``position_units``; NaN where tracking was lost. Select the floor axes first,
        e.g. ``position[["x", "z"]]``.
    head_direction : nap.Tsd, optional
        Radians, allocentric, 0 = +x, counter-clockwise, on the position's timestamps;
        wrapped into [-pi, pi).
    trials : nap.IntervalSet, optional
        One interval per trial, with optional metadata ``trial_id`` (int, default
        ``0 .. n - 1``), ``environment`` (int, default 0), ``start_x`` and ``start_y``
        (start position, ``position_units``); other metadata columns become coords
        along ``trial_id``. Default: the intervals of
        ``time_support``, or else of ``position.time_support``. Every position sample
        must lie in a trial and every trial hold a sample; consecutive trials must be
        separated by at least one ``dt`` (the schema's gap).
    time_support : nap.IntervalSet, optional
        The intervals where the data are defined; the trials when ``trials`` is not
        given, else checked to hold every trial.
    variables : dict, optional
        More per-sample variables on the position's timestamps: name -> ``nap.Tsd``
        (dims ``("time",)``) or ``nap.TsdFrame`` (a schema variable such as
        ``estimate``, its columns the labels of its second dim).
    attrs : dict, optional
        Dataset attrs (e.g. the ``"attrs"`` of :func:`to_pynapple`). Defaults as in
        :func:`~hippo_probe.recording.from_arrays`: ``source="animal"``,
        ``activity_kind="rate"`` for a TsdFrame, ``dt`` = the median sample interval
        within trials.
    position_units : {"m", "cm", "mm"}
        Units of ``position`` (and of ``start_x``, ``start_y``); converted to metres.
    config : RecordingConfig
        ``time_atol``: how far (s) the timestamps of ``activity``, ``head_direction`` and
        ``variables`` may be from the position's.

    Returns
    -------
    xarray.Dataset
        A recording that passes :func:`~hippo_probe.recording.validate`, with
        ``trial_start``/``trial_stop`` the trials' interval bounds.

    Raises
    ------
    TypeError
        An argument of the wrong type (a numpy array instead of a pynapple object: use
        :func:`~hippo_probe.recording.from_arrays`).
    ValueError, RecordingError
        Timestamps that differ from the position's; position without two floor columns;
        samples outside every trial or trials without samples; trial metadata that is
        not integer or not unique; what :func:`from_arrays` refuses (NaN activity,
        trials without a gap).

    See Also
    --------
    to_pynapple : the way there.

    Examples
    --------
    >>> import numpy as np
    >>> import pynapple as nap
    >>> t = np.arange(200) * 0.05
    >>> pos = nap.TsdFrame(t=t, d=np.c_[np.cos(t), np.sin(t)], columns=["x", "y"])
    >>> spikes = nap.TsGroup({3: nap.Ts(t=[1.01, 2.0, 2.02])}, metadata={"region": ["adn"]})
    >>> rec = from_pynapple(spikes, pos)
    >>> rec.activity.sum("time").values, rec.region.values.tolist()
    (array([3.], dtype=float32), ['adn'])
    """
    nap = _pynapple("hippo_probe.from_pynapple")
    hint = " (for numpy arrays use hippo_probe.from_arrays)"
    _check_type(nap, "activity", activity, ("TsdFrame", "TsGroup"), hint)
    _check_type(nap, "position", position, ("TsdFrame",), hint)
    if head_direction is not None:
        _check_type(nap, "head_direction", head_direction, ("Tsd",), hint)
    attrs = {} if attrs is None else attrs
    if not hasattr(attrs, "items"):
        raise TypeError(f"`attrs` must be a dict of dataset attrs; got "
                        f"{type(attrs).__name__}")
    attrs = dict(attrs)

    time = np.asarray(position.t, dtype=float)
    if time.size == 0:
        raise ValueError("`position` must hold at least one sample; got none")
    xy = _floor_columns(position)
    starts, stops, ids, env, start_position, trial_columns = _trial_table(
        nap, trials, time_support, position)
    index = _sample_trials(time, starts, stops, ids)
    if head_direction is not None:
        _check_same_clock("head_direction", head_direction.t, time, config)
    values, unit_ids, unit_coords, kind = _activity_values(
        nap, activity, time, index, starts, stops, attrs, config)
    attrs["activity_kind"] = kind
    if unit_ids.dtype.kind not in "iu":
        unit_ids = _unit_ids(unit_ids)
    rec = from_arrays(time, xy, activity=values,
                      head_direction=None if head_direction is None
                      else np.asarray(head_direction.values),
                      trial=ids[index], environment=env[index],
                      unit={"unit": unit_ids, **unit_coords}, position_units=position_units,
                      **attrs)
    # from_arrays spans each trial from its first to its last sample; the intervals are
    # the trials' own bounds (an epoch may start before the first tracking sample)
    rec = rec.assign_coords(
        trial_start=rec["trial_start"].copy(data=starts),
        trial_stop=rec["trial_stop"].copy(data=stops),
        trial_time=rec["trial_time"].copy(data=time - starts[index]))
    if start_position is not None:
        rec = rec.assign_coords(start_position=(
            ("trial_id", "space"), start_position * LENGTH_UNITS[position_units]))
    for name, values in trial_columns.items():
        if name in rec.variables:
            raise ValueError(f"`trials` metadata {name!r} clashes with the recording's "
                             f"own {name!r}; rename it first")
        rec = rec.assign_coords({name: ("trial_id", values, {
            "units": "", "long_name": name.replace("_", " ")})})
    if variables:
        rec = _add_variables(nap, rec, variables, time, config)
    return validate(annotate(rec), config=config)
