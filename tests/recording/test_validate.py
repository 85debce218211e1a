"""validate: every rule of schema v1 names the variable and the rule broken."""

import numpy as np
import pytest
import xarray as xr

from hippo_probe.errors import RecordingError
from hippo_probe.recording import validate
from hippo_probe.recording.schema import VARIABLES, annotate, attrs_for


def test_network_and_animal_recordings_validate(network_recording, animal_recording):
    assert validate(network_recording) is network_recording
    assert validate(animal_recording) is animal_recording


def _drop_units(rec):
    rec = rec.copy()
    rec["position"].attrs.pop("units")
    return rec


def _set(name, values):
    def mutate(rec):
        rec = rec.copy()
        new = np.asarray(values(rec))
        if name in rec.coords:
            return rec.assign_coords({name: (rec[name].dims, new, rec[name].attrs)})
        rec[name] = rec[name].dims, new, rec[name].attrs
        return rec
    return mutate


def _swap_time(rec):
    time = rec.time.values.copy()
    time[[10, 11]] = time[[11, 10]]
    return rec.assign_coords(time=("time", time, rec.time.attrs))


def _attr(key, value):
    def mutate(rec):
        rec = rec.copy()
        if value is None:
            del rec.attrs[key]
        else:
            rec.attrs[key] = value
        return rec
    return mutate


def _with_nan(name):
    def values(rec):
        v = rec[name].values.copy()
        v[3] = np.nan
        return v
    return values


def _close_gaps(rec):
    """Every trial moved earlier so that consecutive trials are one sample interval apart
    (the rule asks for two); the trial table follows the samples."""
    dt, ids = rec.attrs["dt"], rec.trial_id.values
    k = np.searchsorted(ids, rec.trial.values)              # each sample's trial index
    gap = rec.time.values[np.searchsorted(k, 1)] - rec.time.values[np.searchsorted(k, 1) - 1]
    time = rec.time.values - k * (gap - dt)
    first = np.array([time[k == j][0] for j in range(len(ids))])
    last = np.array([time[k == j][-1] for j in range(len(ids))])
    return rec.assign_coords(time=("time", time, rec.time.attrs),
                             trial_start=("trial_id", first, rec.trial_start.attrs),
                             trial_stop=("trial_id", last, rec.trial_stop.attrs),
                             trial_time=("time", time - first[k], rec.trial_time.attrs))


CASES = {
    "trial value missing from the table":
        (_set("trial", lambda r: np.where(r.trial == 5, 99, r.trial)), "`trial` value 99"),
    "time not increasing": (_swap_time, "`time` must be strictly increasing"),
    "variable without units": (_drop_units, "`position` has no `units`"),
    "missing schema attr": (_attr("dt", None), "`dt` (dataset attr) is missing"),
    "zero dt": (_attr("dt", 0.0), "`dt` (dataset attr) must be a finite number of seconds > 0"),
    "negative dt": (_attr("dt", -0.1), "`dt` (dataset attr) must be a finite number"),
    "NaN dt": (_attr("dt", float("nan")), "`dt` (dataset attr) must be a finite number"),
    "bad source": (_attr("source", "robot"), "`source` (dataset attr) must be one of"),
    "wrong schema version": (_attr("schema_version", 2), "`schema_version`"),
    "float64 activity": (lambda r: r.assign(activity=r.activity.astype("f8")),
                         "`activity` must be float32"),
    "activity with NaN": (_set("activity", _with_nan("activity")), "`activity` must not"),
    "head direction out of range": (_set("head_direction", lambda r: r.head_direction + 4),
                                    "`head_direction` must be in radians in [-pi, pi)"),
    "probability above 1": (_set("class_probability", lambda r: r.class_probability * 5),
                            "`class_probability` must be in [0, 1]"),
    "environment changes within a trial":
        (_set("environment", lambda r: np.r_[1, r.environment.values[1:]]),
         "`environment` must be constant within a trial"),
    "trial_time off": (_set("trial_time", lambda r: r.trial_time + 0.1),
                       "`trial_time` must equal time - trial_start"),
    "no gap between trials": (_close_gaps, "separated by a gap of at least one dt"),
    "dt not the sample interval": (_attr("dt", 0.5), "`dt` .* must be the sample interval; "
                                                     "it is 0.5 s but .* median 0.4 s apart"),
    "trial split in two blocks": (_set("trial", lambda r: np.r_[r.trial.values[40:60],
                                                                r.trial.values[20:]]),
                                  "contiguous"),
    "wrong dims": (lambda r: r.assign(position=r.position.T), "`position` must have dims"),
    "missing required variable": (lambda r: r.drop_vars("activity"), "`activity` is missing"),
    "duplicate unit ids": (lambda r: r.assign_coords(
        unit=("unit", np.zeros(r.sizes["unit"], int), r.unit.attrs)),
                           "`unit` must hold unique ids"),
    "trial start after first sample": (_set("trial_start", lambda r: r.trial_start + 0.5),
                                       "`trial_start` must be <="),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_each_rule_is_named(network_recording, case):
    mutate, message = CASES[case]
    with pytest.raises(RecordingError, match=message.replace("[", r"\[").replace("(", r"\(")
                       .replace(")", r"\)").replace("]", r"\]")):
        validate(mutate(network_recording))


def test_recording_error_is_a_value_error():
    with pytest.raises(ValueError, match="must be an xarray.Dataset"):
        validate({"time": [0.0]})


def test_lazy_data_skipped_unless_asked(network_recording):
    bad = _set("activity", _with_nan("activity"))(network_recording).chunk({"time": 40})
    validate(bad)                       # lazy: values not read by default
    with pytest.raises(RecordingError, match="`activity` must not contain NaN"):
        validate(bad, check_data=True)


def test_schema_table_fills_units_and_long_names():
    ds = annotate(xr.Dataset({"position": (("time", "space"), np.zeros((2, 2)))},
                             coords={"time": [0.0, 1.0]}, attrs={"activity_kind": "rate"}))
    assert ds.position.attrs == attrs_for("position") == {"units": "m", "long_name": "position"}
    assert ds.time.attrs["units"] == "s"
    assert all(spec.units is not None and spec.long_name for spec in VARIABLES.values())
