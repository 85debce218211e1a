"""poisson_spikes: each unit's activity as a rate, scaled to a mean rate, sampled."""

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.errors import RecordingError
from hippo_probe.recording import from_arrays, poisson_spikes, validate

DT = 0.02
N = 100_000                                   # 2,000 s


def _rec(kind="lstm_hidden"):
    t = np.arange(N) * DT
    act = np.stack([np.sin(2 * np.pi * t / 50.0) - 3.0,      # signed, tuned in time
                    np.where((t // 10) % 2 == 0, 0.0, 1.0),  # on/off, 10 s each
                    np.full(N, 0.7)], axis=1)                 # constant
    return from_arrays(t, np.zeros((N, 2)), activity=act, activity_kind=kind, dt=DT)


def test_each_unit_fires_at_the_mean_rate_following_its_activity():
    spikes = poisson_spikes(_rec(), mean_rate=4.0, seed=1)
    validate(spikes)
    counts = spikes.activity.values
    assert counts.dtype == np.float32 and spikes.attrs["activity_kind"] == "spike_count"
    rates = counts.sum(axis=0) / (N * DT)
    # 8,000 expected spikes: Poisson s.d. 0.045 Hz
    assert rates[:2] == pytest.approx([4.0, 4.0], abs=0.2)
    assert rates[2] == 0.0                                 # a constant unit has no rate
    # the signed unit, minus its minimum: rate 0 at the sine's trough, 8 Hz at its crest
    phase = (np.arange(N) * DT / 50.0) % 1.0
    crest, trough = np.abs(phase - 0.25) < 0.05, np.abs(phase - 0.75) < 0.05
    assert counts[crest, 0].mean() / DT == pytest.approx(8.0, rel=0.1)
    assert counts[trough, 0].mean() / DT < 0.2
    assert spikes.attrs["spikes_from"] == "lstm_hidden"


def test_a_rate_is_used_as_it_is_and_the_draw_is_seeded():
    rec = _rec(kind="rate")
    off = ((np.arange(N) * DT) // 10) % 2 == 0
    spikes = poisson_spikes(rec, mean_rate=4.0, seed=3)
    assert spikes.activity.values[off, 1].sum() == 0       # rate 0 when off: no shift
    assert spikes.activity.values[~off, 1].mean() / DT == pytest.approx(8.0, rel=0.05)
    # a constant positive rate is not shifted to 0: it fires steadily at the mean rate
    assert spikes.activity.values[:, 2].sum() / (N * DT) == pytest.approx(4.0, abs=0.2)
    again = poisson_spikes(rec, mean_rate=4.0, seed=3)
    other = poisson_spikes(rec, mean_rate=4.0, seed=4)
    assert np.array_equal(spikes.activity.values, again.activity.values)
    assert not np.array_equal(spikes.activity.values, other.activity.values)


def test_a_lazy_recording_stays_lazy(tmp_path):
    hp.save_recording(_rec(), tmp_path / "r.zarr")
    lazy = hp.open_recording(tmp_path / "r.zarr")
    spikes = poisson_spikes(lazy, mean_rate=4.0)
    assert hasattr(spikes.activity.data, "dask")
    rates = spikes.activity.values.sum(axis=0) / (N * DT)
    assert rates[:2] == pytest.approx([4.0, 4.0], abs=0.2) and rates[2] == 0


@pytest.mark.parametrize("rate", [0, -1.0, float("inf"), float("nan"), "4"])
def test_a_bad_mean_rate_is_refused_naming_it(rate):
    with pytest.raises((ValueError, TypeError), match="mean_rate"):
        poisson_spikes(_rec(), mean_rate=rate)


def test_spikes_and_a_bad_seed_are_refused():
    spikes = poisson_spikes(_rec(), mean_rate=1.0)
    with pytest.raises(RecordingError, match="already holds spike counts"):
        poisson_spikes(spikes, mean_rate=1.0)
    with pytest.raises(ValueError, match="seed"):
        poisson_spikes(_rec(), mean_rate=1.0, seed=-1)
