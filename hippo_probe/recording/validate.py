"""``validate``: check a recording against schema v1."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_bool
from ..errors import RecordingError
from .config import DEFAULTS
from .layout import trial_blocks
from .schema import COV, REQUIRED_ATTRS, SCHEMA_VERSION, SOURCES, SPACE, VARIABLES

# Per-sample variables whose values are checked (cheap on in-memory recordings; a full
# pass over the data on lazy ones, so only when asked): name -> NaN allowed.
_FINITE_CHECKS = {
    "activity": False,
    "position": True,
    "head_direction": True,
    "speed": True,
    "estimate": True,
    "estimate_pi": True,
    "estimate_sh": True,
    "estimate_nb": True,
    "estimate_pf": True,
    "estimate_pfslam": True,
    "pf_cov": True,
    "class_probability": True,
    "class_probability_pfslam": True,
}


#: float32's spacing near pi: an angle in [-pi, pi) stored as float32 may read this far out
_ANGLE_ROUNDING = 2.5e-7


def _v(value):
    """repr of a value, numpy scalars shown as plain Python numbers."""
    return repr(value.item() if isinstance(value, np.generic) else value)


def _fail(name, rule):
    raise RecordingError(f"`{name}` {rule}")


def _first_bad(mask):
    return int(np.flatnonzero(mask)[0])


def validate(rec, *, check_data=None, config=DEFAULTS):
    """Check that ``rec`` follows the recording schema v1; return it unchanged.

    Checks the dataset attrs, the presence, dims, dtypes, ``units`` and ``long_name`` of
    every schema variable, the time axis (finite, strictly increasing), the trial
    structure (each trial one contiguous block of samples listed in the trial table, in
    table order, inside ``[trial_start, trial_stop]``, its samples ``dt`` apart (median
    within 10 %), ``trial_time = time -
    trial_start``, consecutive trials separated by a gap of at least one ``dt``), the
    environments (constant within a trial, equal to ``trial_environment``, listed in
    ``environment_id``) and, when ``check_data``, the values (``activity`` finite; no inf
    anywhere; ``head_direction`` in [-pi, pi); probabilities in [0, 1]).

    Parameters
    ----------
    rec : xarray.Dataset
        The recording.
    check_data : bool or None
        Check the values of the per-sample data variables. ``None`` (default) checks them
        when they are in memory and skips them on lazy (dask-backed) variables, where the
        check would read the whole recording.
    config : RecordingConfig
        Tolerances (``gap_jitter``, ``time_atol``).

    Returns
    -------
    xarray.Dataset
        ``rec`` itself, so ``rec = validate(build())`` reads naturally.

    Raises
    ------
    RecordingError
        Naming the variable (or attr) and the rule broken.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays, validate
    >>> t = np.arange(100) * 0.1
    >>> rec = from_arrays(time=t, position=np.zeros((100, 2)), activity=np.ones((100, 3)))
    >>> validate(rec) is rec
    True
    """
    if not isinstance(rec, xr.Dataset):
        raise RecordingError(f"a recording must be an xarray.Dataset; got {type(rec).__name__}")
    check_data = check_bool("check_data", check_data, allow_none=True)
    _check_attrs(rec)
    _check_variables(rec)
    _check_time(rec)
    _check_trials(rec, config)
    _check_environments(rec)
    _check_values(rec, check_data)
    return rec


def _check_attrs(rec):
    for name, types in REQUIRED_ATTRS.items():
        if name not in rec.attrs:
            _fail(name, "(dataset attr) is missing; every recording carries "
                        f"{sorted(REQUIRED_ATTRS)}")
        value = rec.attrs[name]
        if isinstance(value, bool) or not isinstance(value, types):
            _fail(name, f"(dataset attr) must be of type {types[0].__name__}; got {_v(value)}")
    if rec.attrs["schema_version"] != SCHEMA_VERSION:
        _fail("schema_version", f"(dataset attr) must be {SCHEMA_VERSION}; "
                                f"got {_v(rec.attrs['schema_version'])}")
    if rec.attrs["source"] not in SOURCES:
        _fail("source", f"(dataset attr) must be one of {SOURCES}; got {_v(rec.attrs['source'])}")
    if not rec.attrs["activity_kind"]:
        _fail("activity_kind", "(dataset attr) must be a non-empty string, e.g. 'spike_count'")
    check_activity_kind(rec.attrs["activity_kind"])
    dt = rec.attrs["dt"]
    if not (np.isfinite(dt) and dt > 0):
        _fail("dt", f"(dataset attr) must be a finite number of seconds > 0; got {_v(dt)}")
    for name, value in rec.attrs.items():
        if not _storable(value):
            _fail(name, f"(dataset attr) must be a string, number, bool, None or a list or "
                        f"array of them (attrs are stored as JSON); got "
                        f"{type(value).__name__} {_v(value)[:60]}")


def json_ready(value):
    """An attr value as plain Python, however deeply numpy scalars and arrays sit in its
    lists and dicts (stores and NWB files keep attrs as JSON)."""
    if isinstance(value, (np.generic, np.ndarray)):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [json_ready(v) for v in value]
    if isinstance(value, dict):
        return {k: json_ready(v) for k, v in value.items()}
    return value


def check_text_variables(rec, what):
    """Refuse a text (object) variable holding anything but strings: a missing label
    (None, NaN) or a mixed type would be written as '' or 'nan' or the text of a number,
    and read back as a label of its own."""
    for name, var in rec.variables.items():
        if var.dtype != object:
            continue
        flat = np.ravel(np.asarray(var.values))
        odd = [k for k, v in enumerate(flat) if not isinstance(v, str)]
        if odd:
            k = odd[0]
            raise RecordingError(
                f"`{name}` holds {len(odd)} values that are not strings (first "
                f"{flat[k]!r} at {k}) among its labels: {what} keeps text labels as strings "
                f"only, so a missing label, or a value of another type, would come back as "
                f"a label of its own; label them (e.g. 'unknown'), or give one type")


def _storable(value) -> bool:
    if value is None or isinstance(value, (str, bool, int, float, np.bool_, np.number)):
        return True
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "biufUS"
    if isinstance(value, (list, tuple)):
        return all(_storable(v) for v in value)
    if isinstance(value, dict):
        return all(isinstance(k, str) and _storable(v) for k, v in value.items())
    return False


def _check_variables(rec):
    for name, spec in VARIABLES.items():
        if name not in rec.variables:
            if spec.required:
                _fail(name, "is missing; every recording has it (schema v1)")
            continue
        if spec.coord and name not in rec.coords:
            _fail(name, "must be a coordinate, not a data variable")
        if not spec.coord and name in rec.coords:
            _fail(name, "must be a data variable, not a coordinate")
        var = rec.variables[name]
        if var.dims != spec.dims:
            _fail(name, f"must have dims {spec.dims}; got {var.dims}")
        if var.dtype.kind not in spec.kind:
            _fail(name, f"must have a dtype of kind {_v(spec.kind)}; got {var.dtype}")
    if rec["activity"].dtype != np.float32:
        _fail("activity", f"must be float32; got {rec['activity'].dtype}")
    for name, var in rec.variables.items():
        for key in ("units", "long_name"):
            if not isinstance(var.attrs.get(key), str):
                _fail(name, f"has no `{key}` attr (a string); every variable carries "
                            "`units` and `long_name` (see hippo_probe.recording.schema)")
        if not var.attrs["long_name"]:
            _fail(name, "has an empty `long_name` attr")
    labels = {"space": SPACE, "cov": COV}
    for name, want in labels.items():
        if name in rec.coords and tuple(map(str, rec[name].values)) != want:
            _fail(name, f"must be {list(want)}; got {list(map(str, rec[name].values))}")
    for name in ("unit", "trial_id", "environment_id"):
        values = rec[name].values
        uniq, counts = np.unique(values, return_counts=True)
        if (counts > 1).any():
            _fail(name, f"must hold unique ids; {_v(uniq[counts > 1][0])} appears "
                        f"{counts[counts > 1][0]} times")


def _check_time(rec):
    time = rec["time"].values
    if time.size == 0:
        _fail("time", "must hold at least one sample; got a recording of 0 samples")
    if not np.isfinite(time).all():
        _fail("time", f"must be finite; got {_v(time[_first_bad(~np.isfinite(time))])} at "
                      f"index {_first_bad(~np.isfinite(time))}")
    step = np.diff(time)
    if (step <= 0).any():
        i = _first_bad(step <= 0)
        _fail("time", f"must be strictly increasing; time[{i}] = {_v(time[i])} is followed by "
                      f"time[{i + 1}] = {_v(time[i + 1])}")
    _check_sample_interval(rec.attrs["dt"], step, rec["trial"].values, "rec")


def _check_trials(rec, config):
    time = rec["time"].values
    trial = rec["trial"].values
    trial_ids = rec["trial_id"].values
    starts, stops, block_ids = trial_blocks(trial)
    seen, counts = np.unique(block_ids, return_counts=True)
    if (counts > 1).any():
        _fail("trial", f"samples of each trial must be contiguous in time; trial "
                       f"{_v(seen[counts > 1][0])} appears in {counts[counts > 1][0]} separate "
                       "blocks")
    unknown = ~np.isin(block_ids, trial_ids)
    if unknown.any():
        _fail("trial", f"value {_v(block_ids[unknown][0])} is missing from the trial table "
                       f"(`trial_id` = {trial_ids.tolist()[:10]}...)")
    if len(block_ids) != len(trial_ids) or (block_ids != trial_ids).any():
        empty = np.setdiff1d(trial_ids, block_ids)
        if empty.size:
            _fail("trial_id", f"lists trial {_v(empty[0])}, which has no samples; the trial "
                              "table describes the samples present")
        _fail("trial_id", "must list the trials in the order their samples appear in time; "
                          f"got {trial_ids.tolist()[:10]}, samples in order "
                          f"{block_ids.tolist()[:10]}")
    t_start = rec["trial_start"].values
    t_stop = rec["trial_stop"].values
    first, last = time[starts], time[stops - 1]
    for name, bad, rule in (
            ("trial_start", ~np.isfinite(t_start), "must be finite"),
            ("trial_stop", ~np.isfinite(t_stop), "must be finite"),
            ("trial_start", t_start > first, "must be <= the time of the trial's first sample"),
            ("trial_stop", t_stop < last, "must be >= the time of the trial's last sample"),
            ("trial_start", np.r_[False, t_start[1:] < t_stop[:-1]],
             "must be >= the previous trial's trial_stop (trials must not overlap)")):
        if bad.any():
            k = _first_bad(bad)
            _fail(name, f"{rule}; trial {_v(trial_ids[k])} has trial_start {_v(t_start[k])}, "
                        f"trial_stop {_v(t_stop[k])}, samples from {_v(first[k])} to {_v(last[k])}")
    expected = time - np.repeat(t_start, stops - starts)
    off = np.abs(rec["trial_time"].values - expected) > config.time_atol
    if off.any():
        i = _first_bad(off)
        _fail("trial_time", f"must equal time - trial_start of the sample's trial; at index "
                            f"{i} it is {_v(rec['trial_time'].values[i])}, expected "
                            f"{_v(expected[i])}")
    dt = float(rec.attrs["dt"])
    gap = first[1:] - last[:-1]
    short = gap < 2 * dt * (1 - config.gap_jitter)
    if short.any():
        k = _first_bad(short)
        _fail("time", f"consecutive trials must be separated by a gap of at least one dt "
                      f"(first sample of a trial >= 2 dt = {_v(2 * dt)} s after the last of the "
                      f"previous one); trials {_v(trial_ids[k])} and {_v(trial_ids[k + 1])} are "
                      f"{_v(gap[k])} s apart")


def _check_environments(rec):
    env = rec["environment"].values
    trial_env = rec["trial_environment"].values
    starts, stops, _ = trial_blocks(rec["trial"].values)
    expected = np.repeat(trial_env, stops - starts)
    off = env != expected
    if off.any():
        i = _first_bad(off)
        _fail("environment", f"must be constant within a trial and equal its "
                             f"`trial_environment`; at index {i} it is {_v(env[i])}, the trial "
                             f"table says {_v(expected[i])}")
    unknown = ~np.isin(trial_env, rec["environment_id"].values)
    if unknown.any():
        _fail("environment", f"value {_v(trial_env[unknown][0])} is missing from "
                             "`environment_id`")


def _check_values(rec, check_data):
    if rec.sizes.get("unit", 0) == 0:
        _fail("activity", "must have at least one unit; got 0 units")
    for name in _FINITE_CHECKS:
        if name not in rec.data_vars:
            continue
        var = rec[name]
        if check_data is False or (check_data is None and var.chunks is not None):
            continue
        check_block(name, np.asarray(var.values), kind=rec.attrs["activity_kind"])


def check_block(name, values, origin=None, kind=None):
    """Check the values of (a block of) the data variable ``name`` against the schema.

    ``origin`` is the block's first index in the whole variable, so that the error names
    the index in the recording (used when a lazy recording is checked block by block as
    it is written). ``kind`` is the recording's ``activity_kind``: spike counts
    (``"spike_count"``) must also be whole numbers >= 0. Returns ``values`` unchanged.
    """
    allow_nan = _FINITE_CHECKS.get(name)
    if allow_nan is None:
        return values
    origin = tuple(origin) if origin is not None else (0,) * values.ndim

    def where(mask):
        return tuple(int(i) + o for i, o in zip(np.argwhere(mask)[0], origin))

    def value_at(idx):
        return _v(values[tuple(i - o for i, o in zip(idx, origin))])

    bad = np.isinf(values) if allow_nan else ~np.isfinite(values)
    if bad.any():
        idx = where(bad)
        what = "inf" if allow_nan else "NaN or inf"
        _fail(name, f"must not contain {what}; found {value_at(idx)} at index {idx}")
    if name == "head_direction":
        # float32 storage may round an angle just below pi up to float32(pi)
        out = (values < -np.pi - _ANGLE_ROUNDING) | (values >= np.pi + _ANGLE_ROUNDING)
        if out.any():
            idx = where(out)
            _fail(name, f"must be in radians in [-pi, pi); got {value_at(idx)} at index "
                        f"{idx[0] if len(idx) == 1 else idx}")
    if name.startswith("class_probability"):
        out = (values < 0) | (values > 1)
        if out.any():
            idx = where(out)
            _fail(name, f"must be in [0, 1]; got {value_at(idx)} at index {idx}")
    if name == "activity" and kind == "spike_count":
        bad = _first_non_count(values)
        if bad is not None:
            idx = tuple(i + o for i, o in zip(bad, origin))
            _fail(name, f"holds spike counts (activity_kind 'spike_count'): they must be "
                        f"whole numbers >= 0; got {value_at(idx)} at index {idx}")
    return values


def _first_non_count(values):
    """Index of the first entry of ``values`` that is not a whole number >= 0, or None;
    rows a slice at a time, so that no temporary is the size of ``values``."""
    if values.ndim == 0:
        values = values.reshape(1)
    rows = max(1, (1 << 20) // max(1, values[:1].size))
    for lo in range(0, len(values), rows):
        part = values[lo:lo + rows]
        bad = part < 0
        if part.dtype.kind == "f":
            bad |= part != np.trunc(part)
        if bad.any():
            first = np.argwhere(bad)[0]
            return (int(first[0]) + lo, *(int(i) for i in first[1:]))
    return None


#: How far the median sample interval within trials may be from ``dt`` (a fraction of
#: ``dt``): tracking clocks jitter by well under 1 %; a mislabelled ``dt`` (ms for s, or
#: the rate of another stream) is off by a factor.
DT_TOLERANCE = 0.1


def _check_sample_interval(dt, step, trial, name) -> None:
    """``dt`` must be the recording's sample interval: the median step between samples of
    one trial within :data:`DT_TOLERANCE` of it (analyses divide counts by ``dt``)."""
    if dt is None or not len(step):
        return
    within = step if trial is None else step[trial[1:] == trial[:-1]]
    if not len(within):
        return
    median = float(np.median(within))
    if abs(median / float(dt) - 1) > DT_TOLERANCE:
        _fail("dt", f"(dataset attr of `{name}`) must be the sample interval; it is "
                    f"{_v(dt)} s but samples within a trial are a median {median:.6g} s "
                    f"apart (fix `dt`, or resample the session)")


def check_activity_kind(kind, *, name="activity_kind") -> bool:
    """Refuse an ``activity_kind`` that is a near miss of a known one (``"spike_counts"``
    for ``"spike_count"``: its counts would be read as a generic signal, not as spikes
    per sample); return whether ``kind`` is unknown (any other name: a generic signal)."""
    import difflib

    from .schema import ACTIVITY_UNITS

    if kind in ACTIVITY_UNITS:
        return False
    close = difflib.get_close_matches(str(kind).lower(), list(ACTIVITY_UNITS), n=1,
                                      cutoff=0.8)
    if close:
        _fail(name, f"must be one of the kinds the analyses know {sorted(ACTIVITY_UNITS)} "
                    f"or another name for a generic signal; got {_v(kind)}: did you mean "
                    f"{close[0]!r}?")
    return True


def check_analysable(rec, *, name="rec"):
    """The cheap rules of :func:`validate` that every analysis relies on; raise if broken.

    Run on entry by every public analysis, so that a damaged or mislabelled session is
    refused rather than analysed into a plausible wrong number. Only what the recording
    holds is checked (analyses also accept partial recordings, e.g. without a trial
    table):

    - ``time``: finite, strictly increasing within each trial (across the whole
      recording when it has no ``trial``); each trial's samples one contiguous block;
    - ``attrs["dt"]``, when present: a real number of seconds, finite and > 0, and the
      sample interval (the median step within trials within 10 % of it);
    - ``attrs["activity_kind"]``, when present: a non-empty string; a kind the analyses do
      not know (:data:`~hippo_probe.recording.schema.ACTIVITY_UNITS`) is warned about, as
      it is read as a generic signal (no division by ``dt``, no offset for signed units);
    - ``position``, ``head_direction``: real numbers, no inf (NaN is lost tracking);
      ``head_direction`` in radians, [-pi, pi);
    - ``activity``: real numbers (not complex, text or bool), at least one unit, finite
      where in memory, and there whole numbers >= 0 if ``activity_kind`` is
      ``"spike_count"``;
    - ``environment``: integer ids, one value per trial;
    - ``position``: dims ``('time', 'space')``.

    Costs O(samples) on the per-sample coordinates and on ``position`` and
    ``head_direction`` (8-16 bytes a sample). A lazy (dask-backed) ``position`` or
    ``head_direction`` is read here once and returned in memory (every analysis reads
    them whole anyway); the values of a lazy ``activity`` are not read (its dtype is):
    NaN in them is caught by ``validate(rec, check_data=True)``, or named by the
    analysis's own pass (e.g. ``ratemaps`` warns with the unit).

    Returns
    -------
    xarray.Dataset
        ``rec``, or a shallow copy of it with ``position`` and ``head_direction`` loaded
        when they were lazy: analyses continue with the returned dataset.

    Raises
    ------
    RecordingError
        Naming the variable, the rule and the first offending value.
    """
    import warnings

    from .schema import ACTIVITY_UNITS

    attrs = rec.attrs
    if "dt" in attrs:
        dt = attrs["dt"]
        if isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (int, float, np.number)):
            _fail("dt", f"(dataset attr of `{name}`) must be a number of seconds; got "
                        f"{type(dt).__name__} {_v(dt)[:40]}")
        if not (np.isfinite(dt) and dt > 0):
            _fail("dt", f"(dataset attr of `{name}`) must be a finite number of seconds "
                        f"> 0; got {_v(dt)}")
    if "activity_kind" in attrs:
        kind = attrs["activity_kind"]
        if not isinstance(kind, str) or not kind:
            _fail("activity_kind", f"(dataset attr of `{name}`) must be a non-empty "
                                   f"string, e.g. 'spike_count'; got {_v(kind)}")
        if check_activity_kind(kind):
            warnings.warn(f"`{name}` has activity_kind {kind!r}, which the analyses do "
                          f"not know ({sorted(ACTIVITY_UNITS)}): its activity is read as a "
                          "generic signal (no division by dt, no offset for signed units)",
                          UserWarning, stacklevel=4)
    trial = None
    if "trial" in rec.coords and rec["trial"].dims == ("time",):
        trial = np.asarray(rec["trial"].values)
    if "time" in rec.coords:
        time = np.asarray(rec["time"].values)
        if time.dtype.kind not in "iuf":
            _fail("time", f"must hold seconds as real numbers; got dtype {time.dtype}")
        if not np.isfinite(time).all():
            i = _first_bad(~np.isfinite(time))
            _fail("time", f"must be finite; got {_v(time[i])} at index {i}")
        step = np.diff(time.astype(np.float64))     # unsigned times would wrap
        bad = step <= 0
        if trial is not None:
            bad &= trial[1:] == trial[:-1]
        if bad.any():
            i = _first_bad(bad)
            within = " within a trial" if trial is not None else ""
            _fail("time", f"must be strictly increasing{within}; time[{i}] = "
                          f"{_v(time[i])} is followed by time[{i + 1}] = {_v(time[i + 1])}")
        _check_sample_interval(attrs.get("dt"), step, trial, name)
    if trial is not None and len(trial):
        _, _, ids = trial_blocks(trial)
        seen, counts = np.unique(ids, return_counts=True)
        if (counts > 1).any():
            _fail("trial", f"(of `{name}`) samples of each trial must be contiguous in "
                           f"time; trial {_v(seen[counts > 1][0])} appears in "
                           f"{counts[counts > 1][0]} separate blocks")
    for var in ("position", "head_direction", "activity"):
        if var not in rec.variables:
            continue
        dtype = rec[var].dtype
        if dtype.kind not in "iuf":
            what = {"c": "complex", "b": "bool", "O": "objects", "U": "text",
                    "S": "text"}.get(dtype.kind, str(dtype))
            _fail(var, f"must hold real numbers; got {what} (dtype {dtype})")
    if "activity" in rec.data_vars and 0 in rec["activity"].shape:
        sizes = dict(rec["activity"].sizes)
        if sizes.get("unit", 1) == 0:
            _fail("activity", f"(of `{name}`) must have at least one unit; got 0 units")
    if "position" in rec.data_vars and set(rec["position"].dims) != {"time", "space"}:
        _fail("position", f"(of `{name}`) must have dims ('time', 'space') with space = "
                          f"['x', 'y']; got dims {rec['position'].dims}")
    loaded = {}
    for var in ("position", "head_direction"):
        if var in rec.data_vars:
            da = rec[var]
            if da.chunks is not None:         # read once here; the analysis reuses it
                da = loaded[var] = da.compute()
            check_block(var, np.asarray(da.values))
    if "activity" in rec.variables and rec["activity"].chunks is None:
        check_block("activity", np.asarray(rec["activity"].values),
                    kind=attrs.get("activity_kind"))
    if "environment" in rec.coords and rec["environment"].dtype.kind not in "iu":
        _fail("environment", f"(of `{name}`) must hold integer ids (schema v1); got dtype "
                             f"{rec['environment'].dtype} (text labels: number them, e.g. "
                             f"np.unique(labels, return_inverse=True))")
    if trial is not None and "environment" in rec.coords and rec["environment"].dims == ("time",):
        env = np.asarray(rec["environment"].values)
        change = (env[1:] != env[:-1]) & (trial[1:] == trial[:-1])
        if change.any():
            i = _first_bad(change)
            _fail("environment", f"must be constant within a trial; trial {_v(trial[i])} "
                                 f"changes from {_v(env[i])} to {_v(env[i + 1])} at index "
                                 f"{i + 1}")
    return rec.assign(loaded) if loaded else rec
