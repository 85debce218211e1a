"""The pynapple bridge: round trips, and analyses that agree with pynapple's own.

Conventions compared here (pynapple 0.11, ``nap.compute_tuning_curves``; the older
``compute_1d_tuning_curves``/``compute_2d_tuning_curves`` are deprecated wrappers of it):

- Spike rates: both divide the spike count in a bin by its occupancy. hippo_probe turns
  samples into seconds with the recording's ``dt`` (the *median* sample interval);
  pynapple with ``fs``, by default ``1 / mean`` sample interval within the epochs. On the
  mouse session's 120 Hz tracking the two differ by 0.2 %, so ``fs = 1 / dt`` is passed.
- Continuous activity (``TsdFrame``): both take the mean value per bin, no ``fs``.
- Bins: hippo_probe's bin ``k`` is ``[lo + k w, lo + (k + 1) w)``, the last one closed
  (NumPy's histogram rule); pynapple is given those edges. Head direction spans
  [-pi, pi) in both. Rate maps are (unit, y, x) here and (unit, x, y) in pynapple.
- Unvisited bins are NaN in both.
"""

import sys
import warnings

import numpy as np
import pynapple as nap
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.errors import RecordingError
from hippo_probe.recording import (
    from_arrays,
    from_nwb,
    from_pynapple,
    stack_trials,
    to_pynapple,
    trial_layout,
    validate,
)
from hippo_probe.recording.schema import annotate

from .conftest import NWB_PATH, make_animal_recording, make_network_recording


@pytest.fixture(scope="module")
def wake():
    return from_nwb(NWB_PATH, epoch="wake")


@pytest.fixture(scope="module")
def wake_nap(wake):
    return to_pynapple(wake)


def rate_recording(n_steps=30, n_trials=5, n_units=4, seed=1):
    """A small network-like recording: rate activity, several trials and environments."""
    rng = np.random.default_rng(seed)
    rec = trial_layout(n_steps, n_trials, 0.1, trial_id=np.arange(n_trials) * 2 + 3,
                       environment=np.arange(n_trials) % 2,
                       start_position=rng.uniform(-0.5, 0.5, (n_trials, 2)),
                       activity_kind="rate", task="generalized", seed=seed)
    xy = rng.uniform(-0.5, 0.5, (n_steps, n_trials, 2))
    rec["position"] = ("time", "space"), stack_trials(xy)
    rec["activity"] = ("time", "unit"), np.exp(-(stack_trials(xy) ** 2).sum(-1))[:, None] \
        * rng.uniform(1, 5, n_units).astype(np.float32)
    rec["activity"] = rec.activity.astype(np.float32)
    rec["speed"] = "time", rng.uniform(0, 0.3, rec.sizes["time"])
    rec["estimate"] = ("time", "space"), rec.position.values + 0.01
    rec = rec.assign_coords(unit=np.arange(n_units) + 100,
                            layer=("unit", np.array(["lstm"] * n_units, dtype=object)))
    rec.layer.attrs.update(units="", long_name="layer")
    return validate(annotate(rec))


# --------------------------------------------------------------------- what comes out


def test_to_pynapple_objects(wake, wake_nap):
    data = wake_nap
    assert list(data) == ["activity", "position", "head_direction", "trials",
                          "time_support", "variables", "attrs"]
    group = data["activity"]
    assert isinstance(group, nap.TsGroup)      # activity_kind "spike_count"
    assert list(group.keys()) == wake.unit.values.tolist()
    assert group.region.tolist() == wake.region.values.tolist()
    assert isinstance(data["position"], nap.TsdFrame)
    assert list(data["position"].columns) == ["x", "y"]
    np.testing.assert_array_equal(data["position"].values, wake.position.values)
    assert isinstance(data["head_direction"], nap.Tsd)
    trials = data["trials"]
    assert isinstance(trials, nap.IntervalSet)
    np.testing.assert_array_equal(trials.start, wake.trial_start.values)
    np.testing.assert_array_equal(trials.end, wake.trial_stop.values)
    assert trials.trial_id.tolist() == wake.trial_id.values.tolist()
    assert trials.environment.tolist() == wake.trial_environment.values.tolist()
    for obj in (group, data["position"], data["head_direction"]):
        np.testing.assert_array_equal(obj.time_support.values, data["time_support"].values)
    assert data["attrs"] == wake.attrs and data["variables"] == {}


def test_spike_times_sit_on_the_samples(wake, wake_nap):
    """Binning to samples loses sub-sample timing: reconstructed spikes are sample times."""
    time = wake.time.values
    for unit, counts in zip(wake.unit.values, wake.activity.values.T):
        spikes = wake_nap["activity"][unit].t
        assert spikes.size == counts.sum()
        assert np.isin(spikes, time).all()
        np.testing.assert_array_equal(np.bincount(np.searchsorted(time, spikes),
                                                  minlength=time.size), counts)


def test_activity_as_tsdframe_carries_unit_metadata(wake):
    frame = to_pynapple(wake, activity_as="tsdframe")["activity"]
    assert isinstance(frame, nap.TsdFrame)
    assert list(frame.columns) == wake.unit.values.tolist()
    np.testing.assert_array_equal(frame.values, wake.activity.values)
    assert frame.region.tolist() == wake.region.values.tolist()
    assert frame.metadata.columns.tolist() == ["region", "group", "electrode_group"]


def test_rate_recording_gives_tsdframe_and_variables():
    rec = rate_recording()
    data = to_pynapple(rec)
    assert isinstance(data["activity"], nap.TsdFrame)
    assert data["head_direction"] is None
    assert set(data["variables"]) == {"speed", "estimate"}
    assert list(data["variables"]["estimate"].columns) == ["x", "y"]
    np.testing.assert_array_equal(data["trials"].start_x,
                                  rec.start_position.sel(space="x").values)
    assert data["activity"].layer.tolist() == ["lstm"] * 4


# ----------------------------------------------------------------------- round trips


@pytest.mark.parametrize("activity_as", ["tsgroup", "tsdframe"])
def test_mouse_session_round_trip(wake, activity_as):
    back = from_pynapple(**to_pynapple(wake, activity_as=activity_as))
    # every variable both carry, with its attrs (unit ids, region, trial table ...)
    xr.testing.assert_identical(back, wake)


def test_network_like_round_trip():
    rec = rate_recording()
    back = from_pynapple(**to_pynapple(rec))
    # trial_time is rebuilt as time - trial_start: trial_layout's (s + 1) dt to rounding
    np.testing.assert_allclose(back.trial_time.values, rec.trial_time.values, atol=1e-12)
    xr.testing.assert_identical(back.drop_vars("trial_time"), rec.drop_vars("trial_time"))
    assert back.trial_time.attrs == rec.trial_time.attrs
    assert back.sizes["trial_id"] == 5 and back.trial_environment.values.tolist() == \
        [0, 1, 0, 1, 0]


def test_round_trip_of_every_per_sample_variable():
    """The fixture with every optional variable: what has no time axis is reported."""
    rec = make_network_recording()
    with pytest.warns(UserWarning, match="not carried.*readout_weight.*arena_vertices.*; a "
                                         "recording rebuilt from them has no arena outline, "
                                         "so its rate maps span the positions' extent"):
        data = to_pynapple(rec)
    assert set(data["variables"]) == {"estimate", "contact", "pf_cov", "class_probability"}
    back = from_pynapple(**data)
    expected = rec.drop_vars(["readout_weight", "arena_vertices"])
    xr.testing.assert_allclose(back, expected, rtol=0, atol=1e-12)   # hd re-wrapped
    for name in expected.variables:
        assert back[name].attrs == expected[name].attrs, name
    assert back.attrs == expected.attrs


def test_string_unit_ids_go_to_tsgroup_metadata():
    rec = make_animal_recording()            # ids "u1".."u4", NaN positions, 3 trials
    data = to_pynapple(rec)
    group = data["activity"]
    assert list(group.keys()) == [0, 1, 2, 3]
    assert group.unit.tolist() == ["u1", "u2", "u3", "u4"]
    xr.testing.assert_identical(from_pynapple(**data), rec)


def test_tsgroup_is_binned_like_from_arrays():
    """Real spike times (not on the sample clock): the same counts as from_arrays."""
    rng = np.random.default_rng(3)
    t = np.arange(500) * 0.02
    xy = rng.uniform(0, 1, (500, 2))
    spikes = [np.sort(rng.uniform(-1, 11, 300)) for _ in range(3)]
    group = nap.TsGroup({i + 10: nap.Ts(s) for i, s in enumerate(spikes)},
                        metadata={"region": ["ca1", "ca1", "adn"]})
    position = nap.TsdFrame(t=t, d=xy, columns=["x", "y"])
    rec = from_pynapple(group, position)
    ref = from_arrays(t, xy, spike_times=spikes, unit=[10, 11, 12])
    np.testing.assert_array_equal(rec.activity.values, ref.activity.values)
    assert rec.attrs["activity_kind"] == "spike_count"
    assert rec.region.values.tolist() == ["ca1", "ca1", "adn"]


def test_trials_bounds_and_metadata_are_kept():
    t = np.r_[np.arange(10) * 0.1 + 0.05, np.arange(10) * 0.1 + 2.05]
    position = nap.TsdFrame(t=t, d=np.zeros((20, 2)), columns=["x", "y"])
    activity = nap.TsdFrame(t=t, d=np.ones((20, 2)), columns=[0, 1])
    trials = nap.IntervalSet([0.0, 2.0], [1.0, 3.0],
                             metadata={"trial_id": [7, 8], "environment": [1, 2],
                                       "kind": ["a", "b"]})
    rec = from_pynapple(activity, position, trials=trials)
    assert rec.trial_start.values.tolist() == [0.0, 2.0]
    assert rec.trial_stop.values.tolist() == [1.0, 3.0]
    np.testing.assert_allclose(rec.trial_time.values[:2], [0.05, 0.15])
    assert rec.trial_id.values.tolist() == [7, 8]
    assert rec.trial_environment.values.tolist() == [1, 2]
    assert rec.kind.values.tolist() == ["a", "b"]
    assert to_pynapple(rec)["trials"].kind.tolist() == ["a", "b"]


def test_top_level_names():
    assert hp.to_pynapple is to_pynapple and hp.from_pynapple is from_pynapple
    assert {"to_pynapple", "from_pynapple"} <= set(dir(hp))


# ------------------------------------------------- analyses agree with pynapple's own


def test_head_direction_tuning_matches_pynapple(wake, wake_nap):
    group = wake_nap["activity"]
    adn = group[group.region == "adn"]
    assert len(adn) == 7
    ours = hp.head_direction_tuning(wake, n_shuffles=0)
    n_bins = ours.sizes["direction"]
    edges = np.linspace(-np.pi, np.pi, n_bins + 1)         # our bins of [-pi, pi)
    dt = wake.attrs["dt"]
    theirs = nap.compute_tuning_curves(adn, wake_nap["head_direction"], bins=edges,
                                       fs=1 / dt)            # Hz, as ours
    np.testing.assert_allclose(theirs.coords[theirs.dims[1]].values,
                               ours.direction.values, atol=1e-12)
    np.testing.assert_allclose(ours.tuning_curve.sel(unit=list(adn.keys())).values,
                               theirs.values, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ours.occupancy.values, theirs.attrs["occupancy"] * dt)
    # pynapple's default fs (1 / mean interval) differs from 1 / dt (median) by 0.2 %
    default = nap.compute_tuning_curves(adn, wake_nap["head_direction"], bins=edges)
    assert default.attrs["fs"] == pytest.approx(1 / dt, rel=5e-3)
    assert default.attrs["fs"] != pytest.approx(1 / dt, rel=1e-4)


def _grid_edges(maps):
    lo_x, _, lo_y, _ = maps.attrs["extent"]
    size = maps.attrs["bin_size"]
    return (lo_x + size * np.arange(maps.sizes["x"] + 1),
            lo_y + size * np.arange(maps.sizes["y"] + 1))


def test_ratemaps_match_pynapple_spikes(wake, wake_nap):
    ours = hp.ratemaps(wake, sigma=0)
    dt = wake.attrs["dt"]
    theirs = nap.compute_tuning_curves(wake_nap["activity"], wake_nap["position"],
                                       bins=list(_grid_edges(ours)), fs=1 / dt)
    assert theirs.dims[1:] == ("x", "y")
    theirs = theirs.transpose("unit", "y", "x")
    np.testing.assert_allclose(theirs.x.values, ours.x.values, atol=1e-12)
    np.testing.assert_allclose(ours.values, theirs.values, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ours.occupancy.values, theirs.attrs["occupancy"].T * dt)


def test_ratemaps_match_pynapple_rates():
    rec = rate_recording(n_steps=200, n_trials=4)
    data = to_pynapple(rec)
    ours = hp.ratemaps(rec, sigma=0, bin_size=0.1)
    theirs = nap.compute_tuning_curves(data["activity"], data["position"],
                                       bins=list(_grid_edges(ours)))   # mean per bin
    np.testing.assert_allclose(ours.values, theirs.transpose("unit", "y", "x").values,
                               rtol=1e-6)                   # float32 activity


# ------------------------------------------------------------------------ bad input


def _simple(n=20):
    t = np.arange(n) * 0.1
    position = nap.TsdFrame(t=t, d=np.zeros((n, 2)), columns=["x", "y"])
    activity = nap.TsdFrame(t=t, d=np.ones((n, 2)), columns=[0, 1])
    return t, position, activity


def test_wrong_types():
    _, position, activity = _simple()
    with pytest.raises(TypeError, match="`activity` must be a pynapple TsdFrame or "
                                        "pynapple TsGroup; got numpy.ndarray.*from_arrays"):
        from_pynapple(np.ones((20, 2)), position)
    with pytest.raises(TypeError, match="`position` must be a pynapple TsdFrame; got "
                                        "pynapple.core.time_series.Tsd"):
        from_pynapple(activity, position["x"])
    with pytest.raises(TypeError, match="`head_direction` must be a pynapple Tsd"):
        from_pynapple(activity, position, head_direction=position)
    with pytest.raises(TypeError, match="`trials` must be a pynapple IntervalSet; got"):
        from_pynapple(activity, position, trials=[(0, 1)])
    with pytest.raises(TypeError, match="`attrs` must be a dict"):
        from_pynapple(activity, position, attrs=["rate"])
    with pytest.raises(TypeError, match="`variables` must be a dict"):
        from_pynapple(activity, position, variables=[position])
    with pytest.raises(RecordingError, match="must be an xarray.Dataset"):
        to_pynapple({"activity": 1})


def test_mismatched_timestamps():
    t, position, activity = _simple()
    with pytest.raises(ValueError, match=r"`activity` must share the timestamps of "
                                         r"`position` \(20 samples.*got 19 samples"):
        from_pynapple(activity[:19], position)
    shifted = nap.Tsd(t=t + 0.01, d=np.zeros(20))
    with pytest.raises(ValueError, match=r"`head_direction` must share the timestamps.*"
                                         r"sample 0 is at 0.01 s"):
        from_pynapple(activity, position, head_direction=shifted)
    with pytest.raises(ValueError, match=r"`variables\['speed'\]` must share"):
        from_pynapple(activity, position, variables={"speed": shifted})


def test_bad_position_columns():
    t, _, activity = _simple()
    xyz = nap.TsdFrame(t=t, d=np.zeros((20, 3)), columns=["x", "y", "z"])
    with pytest.raises(ValueError, match=r"`position` must have two columns \(x, y\); "
                                         r"got \['x', 'y', 'z'\].*position\[\['x', 'z'\]\]"):
        from_pynapple(activity, xyz)


@pytest.mark.parametrize("columns, refused", [
    (["z", "x"], r"the column 'x' would become the recording's y.*\['x', 'z'\]"),
    (["y", "z"], r"the column 'y' would become the recording's x.*\['z', 'y'\]")])
def test_a_column_named_x_or_y_never_becomes_the_other_axis(columns, refused):
    t, _, activity = _simple()
    frame = nap.TsdFrame(t=t, d=np.c_[np.arange(20.0), -np.arange(20.0)], columns=columns)
    with pytest.raises(ValueError, match=refused):
        from_pynapple(activity, frame)


def test_x_and_y_columns_are_found_in_any_case_and_order():
    t, _, activity = _simple()
    frame = nap.TsdFrame(t=t, d=np.c_[-np.arange(20.0), np.arange(20.0)], columns=["Y", "X"])
    rec = from_pynapple(activity, frame)
    np.testing.assert_array_equal(rec.position.sel(space="x").values, np.arange(20.0))


def test_spikes_after_the_tracking_and_outside_their_support_are_said():
    """Spike times in ms leave a few spikes inside a 20 s session; spikes recorded only
    from 1 s read the first second of a 2 s session as silence."""
    _, position, _ = _simple(200)                            # 0 to 19.9 s
    in_ms = nap.TsGroup({0: nap.Ts(np.arange(0.01, 2.0, 0.02) * 1000)})
    with pytest.warns(UserWarning, match=r"99 of the 100 spikes of unit index 0 fall before "
                                         r"the first sample or after the last"):
        from_pynapple(in_ms, position)
    _, position, _ = _simple()
    late = nap.TsGroup({0: nap.Ts(np.arange(1.01, 1.9, 0.1))},
                       time_support=nap.IntervalSet(1.0, 1.9))
    with pytest.warns(UserWarning, match=r"55% of the position's samples .* lie outside "
                                         r"`activity.time_support`"):
        from_pynapple(late, position)
    # pynapple's default support, first to last spike, says nothing of the recording
    sparse = nap.TsGroup({0: nap.Ts(np.arange(1.01, 1.9, 0.1))})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from_pynapple(sparse, position)


def test_bad_trials():
    _, position, activity = _simple()
    with pytest.raises(RecordingError, match="`position` has 10 samples outside every "
                                             "trial.*position.restrict"):
        from_pynapple(activity, position, trials=nap.IntervalSet(0, 0.95))
    with pytest.raises(RecordingError, match=r"`trials` \[1\] hold no `position` sample"):
        from_pynapple(activity, position, trials=nap.IntervalSet([0, 5], [2, 6]))
    with pytest.raises(ValueError, match="'trial_id' must be unique"):
        from_pynapple(activity, position, trials=nap.IntervalSet(
            [0, 1.05], [0.95, 2], metadata={"trial_id": [1, 1]}))
    with pytest.raises(ValueError, match="'environment' must hold integers"):
        from_pynapple(activity, position, trials=nap.IntervalSet(
            [0, 1.05], [0.95, 2], metadata={"environment": ["a", "b"]}))
    with pytest.raises(ValueError, match="`trials` must lie inside `time_support`"):
        from_pynapple(activity, position, trials=nap.IntervalSet(0, 2),
                      time_support=nap.IntervalSet(0, 1))
    with pytest.raises(RecordingError, match="gap"):          # touching trials, from_arrays
        from_pynapple(activity, position, trials=nap.IntervalSet([0, 1.0], [0.95, 2]))


def test_bad_activity():
    t, position, _ = _simple()
    support = nap.IntervalSet(0, 2)
    group = nap.TsGroup({0: nap.Ts([0.5], time_support=support)}, time_support=support)
    with pytest.raises(ValueError, match="`attrs\\['activity_kind'\\]` must be "
                                         "'spike_count' when `activity` is a TsGroup"):
        from_pynapple(group, position, attrs={"activity_kind": "rate"})
    nan = nap.TsdFrame(t=t, d=np.full((20, 1), np.nan))
    with pytest.raises(ValueError, match="`activity` must not contain NaN"):
        from_pynapple(nan, position)
    frame = nap.TsdFrame(t=t, d=np.ones((20, 1)), metadata={"unit": [3]})
    with pytest.raises(ValueError, match="metadata must not have a column 'unit'"):
        from_pynapple(frame, position)
    with pytest.raises(ValueError, match="`variables\\['mystery'\\]` is a TsdFrame"):
        from_pynapple(nap.TsdFrame(t=t, d=np.ones((20, 1))), position,
                      variables={"mystery": position})


def test_bad_to_pynapple_options():
    rec = rate_recording()
    with pytest.raises(ValueError, match="`activity_as` must be one of 'auto', "
                                         "'tsdframe', 'tsgroup'; got 'spikes'"):
        to_pynapple(rec, activity_as="spikes")
    with pytest.raises(RecordingError, match="non-negative whole spike counts"):
        to_pynapple(rec, activity_as="tsgroup")
    t = np.r_[0.0, np.arange(5) * 0.1 + 1.0]
    one_sample = from_arrays(t, np.zeros((6, 2)), activity=np.ones((6, 1)),
                             trial=[0, 1, 1, 1, 1, 1])
    with pytest.raises(RecordingError, match=r"zero duration.*trial ids \[0\]"):
        to_pynapple(one_sample)


def test_missing_pynapple_names_the_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pynapple", None)
    with pytest.raises(ImportError, match=r"pynapple.*pip install 'hippo_probe\[pynapple\]'"):
        to_pynapple(rate_recording())
    with pytest.raises(ImportError, match="pip install"):
        from_pynapple(None, None)


def test_a_variable_outside_the_schema_comes_back_from_pynapple():
    """pynapple carries no attrs: an extra per-sample variable failed validation on the
    way back ("lick has no units attr"); it comes back, its units said to be unknown."""
    t, position, activity = _simple()
    licks = nap.Tsd(t=t, d=np.arange(20) % 3)
    rec = from_pynapple(activity, position, variables={"lick": licks})
    np.testing.assert_array_equal(rec["lick"].values, np.arange(20) % 3)
    assert rec["lick"].attrs["units"] == "" and "unknown" in rec["lick"].attrs["note"]
    back = from_pynapple(**to_pynapple(rec))
    np.testing.assert_array_equal(back["lick"].values, rec["lick"].values)


def test_units_keep_their_order_through_a_tsgroup():
    """A TsGroup sorts its keys: units 30, 10, 20 came back as 10, 20, 30."""
    t = np.arange(200) * 0.02
    rec = from_arrays(t, np.zeros((200, 2)), unit=[30, 10, 20],
                      spike_times=[np.arange(k) * 0.03 for k in (5, 30, 90)])
    back = from_pynapple(**to_pynapple(rec))
    assert back.unit.values.tolist() == [30, 10, 20]
    np.testing.assert_array_equal(back.activity.values, rec.activity.values)
