"""from_arrays, spike binning and the per-trial helpers."""
import warnings

import numpy as np
import pytest

from hippo_probe.errors import RecordingError
from hippo_probe.recording import (bin_spikes, from_arrays, stack_trials, trial_aligned_chunks,
                                   trial_layout, validate)
from hippo_probe.recording.layout import is_trial_aligned

from .conftest import assert_trial_aligned


def test_spikes_binned_on_nearest_sample_within_trials():
    time = np.r_[0.0, 1.0, 2.0, 10.0, 11.0]
    trial = np.array([0, 0, 0, 1, 1])
    spikes = [np.array([-0.1, 0.0, 0.49, 0.51, 1.5, 2.0, 2.01, 9.99, 10.0, 10.6, 11.0, 11.2])]
    counts = bin_spikes(spikes, time, trial, [0.0, 10.0], [2.0, 11.0])[:, 0]
    # [0, .5) [.5, 1.5) [1.5, 2] | [10, 10.5) [10.5, 11]; outside the trials dropped
    np.testing.assert_array_equal(counts, [2, 1, 2, 1, 2])


def test_spikes_in_a_gap_of_the_tracking_are_not_piled_onto_its_edges():
    """A trial whose tracking pauses for 20 s: the samples beside the pause count only
    their own ~dt of spikes (not the pause's), and the loss is said with the gap."""
    time = np.r_[np.arange(100) * 0.1, 30 + np.arange(100) * 0.1]
    trial = np.zeros(200, int)
    spikes = [np.arange(0.005, time[-1], 0.01)]             # 100 Hz, everywhere
    with pytest.warns(UserWarning, match=r"spikes inside the trials \(.*\) fall where the "
                                         r"tracking has no sample.*longest 20\.1 s after "
                                         r"t = 9\.9 s"):
        counts = bin_spikes(spikes, time, trial, [0.0], [time[-1]])[:, 0]
    # each sample stands for 0.1 s, 10 spikes, those beside the gap too (at most 10%
    # more); all 2,000 spikes of the pause were on the two samples beside it before
    assert counts.max() <= 11 and counts[98:102].tolist() == [10, 10, 10, 10]


def test_spikes_of_a_trial_beyond_its_tracking_are_not_piled_onto_its_last_sample():
    """The camera stopped at 10 s in a trial of 20 s: the 1,000 spikes after it all sat
    on the last sample."""
    time = np.arange(100) * 0.1 + 0.05
    spikes = [np.arange(0.005, 20, 0.01)]                   # 100 Hz for the whole trial
    with pytest.warns(UserWarning, match=r"1 trials whose samples do not reach their "
                                         r"interval's ends \(e\.g\. \[0, 20\] s, sampled "
                                         r"from 0\.05 to 9\.95 s\)"):
        counts = bin_spikes(spikes, time, np.zeros(100, int), [0.0], [20.0])[:, 0]
    assert counts.max() <= 11 and counts.sum() == pytest.approx(1000, abs=2)


def test_jittered_samples_leave_no_spike_uncounted():
    rng = np.random.default_rng(0)
    time = np.cumsum(rng.uniform(0.095, 0.105, 1000))       # 5 % jitter of a 0.1 s clock
    spikes = [np.sort(rng.uniform(time[0], time[-1], 5000))]
    with warnings.catch_warnings():
        warnings.simplefilter("error")                       # no gap to warn about
        counts = bin_spikes(spikes, time, np.zeros(1000, int), [time[0]], [time[-1]])
    assert counts.sum() == 5000


PAIRS_REFUSED = (r"got a 2-D array of shape \(50, 2\): for \(time, unit id\) pairs")
MAPPING_REFUSED = (r"got a mapping: pass list\(d.values\(\)\) and unit=list\(d\)")


@pytest.mark.parametrize("spike_times, said", [
    (np.c_[np.linspace(0, 9, 50), np.arange(50) % 2], PAIRS_REFUSED),
    ({0: np.array([1.0]), 1: np.array([2.0])}, MAPPING_REFUSED),
], ids=["time-unit pairs", "dict"])
def test_spike_times_in_another_layout_are_refused(spike_times, said):
    """(time, unit id) pairs made one unit of each spike (50 units)."""
    time = np.arange(100) * 0.1
    with pytest.raises((ValueError, TypeError), match=said):
        from_arrays(time, np.zeros((100, 2)), spike_times=spike_times)


def test_a_floor_of_centimetres_read_as_metres_is_warned_about():
    time = np.arange(100) * 0.1
    xy = np.c_[np.linspace(0, 80, 100), np.linspace(0, 60, 100)]       # an 80 x 60 cm box
    with pytest.warns(UserWarning, match=r"spans 80 m x 60 m, larger than any rodent arena "
                                         r"\(read as m\): if it is in centimetres, pass "
                                         r"position_units='cm'"):
        from_arrays(time, xy, activity=np.ones(100))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        from_arrays(time, xy, activity=np.ones(100), position_units="cm")


def test_from_arrays_spike_counts_add_up_and_units_convert():
    rng = np.random.default_rng(1)
    time = np.r_[np.arange(500) * 0.02, 20 + np.arange(300) * 0.02]
    trial = np.repeat([0, 1], [500, 300])
    spikes = [rng.uniform(-5, 35, 1000) for _ in range(3)]
    xy = rng.uniform(0, 100, (800, 2))
    xy[10] = np.nan
    rec = from_arrays(time, xy, spike_times=spikes, trial=trial, position_units="cm",
                      head_direction=np.full(800, 3 * np.pi / 2), unit=[7, 8, 9])
    inside = [((s >= 0) & (s <= time[499])).sum() + ((s >= 20) & (s <= time[-1])).sum()
              for s in spikes]
    np.testing.assert_array_equal(rec.activity.sum("time").values, inside)
    np.testing.assert_allclose(rec.position.values[11], xy[11] / 100)
    assert np.isnan(rec.position.values[10]).all()
    np.testing.assert_allclose(rec.head_direction.values, -np.pi / 2)
    assert rec.attrs["activity_kind"] == "spike_count" and rec.attrs["source"] == "animal"
    assert rec.attrs["dt"] == pytest.approx(0.02)
    assert rec.activity.dtype == np.float32 and rec.unit.values.tolist() == [7, 8, 9]
    assert rec.trial_start.values.tolist() == [0.0, 20.0]


def test_from_arrays_activity_and_unit_table():
    t = np.arange(10) * 0.1
    rec = from_arrays(t, np.zeros((10, 2)), activity=np.ones((10, 2)),
                      unit={"id": ["a", "b"], "region": ["ca1", "adn"]}, environment=4,
                      activity_kind="lstm_hidden", source="network")
    assert rec.region.values.tolist() == ["ca1", "adn"]
    assert rec.environment_id.values.tolist() == [4]
    assert rec.activity.attrs["units"] == "1"


BAD = {
    "mismatched lengths": (dict(position=np.zeros((9, 2))), ValueError,
                           "`position` must have shape"),
    "non-monotonic time": (dict(time=np.r_[0, 2, 1, 3:10]), RecordingError,
                           "`time` must be strictly increasing"),
    "activity with NaN": (dict(activity=np.r_[np.nan, np.ones(9)]), ValueError,
                          "`activity` must not contain NaN or inf"),
    "activity with inf": (dict(activity=np.r_[np.inf, np.ones(9)]), ValueError,
                          "`activity` must not contain NaN or inf"),
    "position with inf": (dict(position=np.r_[[[np.inf, 0]], np.zeros((9, 2))]), ValueError,
                          "`position` must not contain inf"),
    "unknown units": (dict(position_units="inch"), ValueError, "`position_units` must be one of"),
    "both activity and spikes": (dict(spike_times=[np.r_[0.1]]), ValueError, "exactly one"),
    "trials without a gap": (dict(trial=np.repeat([0, 1], 5)), RecordingError,
                             "gap of at least one dt"),
    "trial split": (dict(trial=np.r_[0, 0, 1, 1, 0, 0, 0, 0, 0, 0]), RecordingError, "contiguous"),
    "environment changes in a trial": (dict(environment=np.r_[0, 1, np.zeros(8, int)]),
                                       RecordingError, "constant within a trial"),
    "unit ids of the wrong length": (dict(unit=[1, 2]), ValueError, "`unit` must have shape"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_from_arrays_bad_input(case):
    change, error, message = BAD[case]
    args = dict(time=np.arange(10) * 0.1, position=np.zeros((10, 2)), activity=np.ones(10))
    args.update(change)
    with pytest.raises(error, match=message):
        from_arrays(**args)


def test_trial_layout_matches_stack_trials_order():
    T, B, dt = 4, 3, 0.5
    rec = trial_layout(T, B, dt, environment=[2, 2, 5], trial_id=[10, 11, 12],
                       start_position=np.zeros((B, 2)))
    steps = np.arange(T)[:, None] * np.ones(B)        # (T, B): step index
    trials = np.ones(T)[:, None] * np.arange(B)
    assert (stack_trials(trials) == np.repeat(np.arange(B), T)).all()
    np.testing.assert_allclose(rec.trial_time.values, (stack_trials(steps) + 1) * dt)
    assert rec.trial.values.tolist() == np.repeat([10, 11, 12], T).tolist()
    assert rec.environment_id.values.tolist() == [2, 5]
    # one empty dt between trials: last sample of a trial + 2 dt = first of the next
    assert rec.time.values[T] - rec.time.values[T - 1] == pytest.approx(2 * dt)
    rec["activity"] = ("time", "unit"), np.zeros((T * B, 1), np.float32)
    rec["position"] = ("time", "space"), np.zeros((T * B, 2))
    from hippo_probe.recording import annotate
    validate(annotate(rec.assign_coords(unit=[0])))


def test_trial_aligned_chunks_never_straddle_trials():
    trial = np.repeat(np.arange(6), [5, 5, 20, 3, 3, 9])
    chunks = trial_aligned_chunks(trial, 8)
    assert chunks == (5, 5, 8, 8, 4, 6, 8, 1)
    assert not is_trial_aligned(trial, (4, 7, 9, 12, 11))
    assert_trial_aligned(trial, chunks)


def test_a_flat_list_of_spike_times_is_refused_not_read_as_many_units():
    """[0.1, 0.5, ...] is one unit's spikes or a mistake; read as a sequence of units it
    would be one unit per spike, each perfectly 'tuned'."""
    t = np.arange(100) * 0.1
    xy = np.c_[np.linspace(0, 1, 100), np.zeros(100) + np.linspace(0, 0.1, 100)]
    with pytest.raises(ValueError, match=r"`spike_times` must be a sequence of 1-D arrays.*"
                                         r"spike_times\[0\]"):
        from_arrays(t, xy, spike_times=[0.15, 0.42, 3.3])
    one = from_arrays(t, xy, spike_times=np.array([0.15, 0.42, 3.3]))
    assert one.sizes["unit"] == 1 and one.activity.sum() == 3


def test_a_unit_losing_most_of_its_spikes_beyond_the_samples_is_warned_about():
    """Spikes beyond the tracking are not counted (documented); when they are most of a
    unit's, the map would rest on the few left, so say so."""
    t = np.arange(400) * 0.1                                     # 0 to 39.9 s
    xy = np.c_[np.linspace(0, 1, 400), np.linspace(0, 0.5, 400)]
    inside, after = np.linspace(1, 30, 10), np.linspace(45, 80, 400)
    with pytest.warns(UserWarning, match=r"400 of the 410 spikes of unit index 1"):
        rec = from_arrays(t, xy, spike_times=[inside, np.r_[inside, after]])
    assert rec.activity.sum("time").values.tolist() == [10, 10]
    with warnings.catch_warnings():
        warnings.simplefilter("error")                           # a few beyond: quiet
        from_arrays(t, xy, spike_times=[np.r_[inside, 45.0]])
