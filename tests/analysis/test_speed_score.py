"""Speed score (Kropff et al. 2015): speed cells, random units against their shuffles."""

import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.analysis import _common
from hippo_probe.analysis.speed_score import smooth_in_trials

from .cell_fixtures import ou, square_walk
from .conftest import SQUARE, make_recording


@pytest.fixture(scope="module")
def speed_rec():
    rng = np.random.default_rng(8)
    n = 24000
    pos, heading, speed = square_walk(n, rng)
    units = [2.0 + 10 * speed, 1.0 - 2 * speed, 2.0 + 10 * speed + rng.normal(0, 1.0, n)]
    act = np.c_[np.stack(units, 1), ou(n, rng, 8)]
    trial = np.repeat(np.arange(4), n // 4)
    return make_recording(pos, act, trial=trial, head_direction=heading,
                          arena_vertices=SQUARE)


def test_speed_cells_score_high_and_their_linear_fit(speed_rec):
    res = hp.speed_score(speed_rec, n_shuffles=50)
    score = res.speed_score.values
    assert score[0] > 0.95 and score[2] > 0.5
    assert score[1] < -0.95                      # negative speed cell: not above threshold
    assert (score[[0, 2]] > res.speed_score_threshold.values[[0, 2]]).all()
    assert score[1] < res.speed_score_threshold.values[1]
    np.testing.assert_allclose(res.speed_slope.values[:2], [10.0, -2.0], rtol=0.05)
    np.testing.assert_allclose(res.speed_intercept.values[:2], [2.0, 1.0], atol=0.1)
    assert res.attrs["min_speed"] == 0.02 and res.attrs["sigma"] == 0.25


def test_speed_score_is_the_pearson_correlation_of_the_smoothed_signals(speed_rec):
    res = hp.speed_score(speed_rec, n_shuffles=0)
    trial = speed_rec.trial.values
    dt = speed_rec.attrs["dt"]
    v = smooth_in_trials(_common.speed(speed_rec), trial, 0.25 / dt)
    a = smooth_in_trials(speed_rec.activity.values, trial, 0.25 / dt)
    ok = (v >= 0.02) & (v <= 0.5)
    expected = [np.corrcoef(a[ok, u], v[ok])[0, 1] for u in range(a.shape[1])]
    np.testing.assert_allclose(res.speed_score.values, expected, atol=1e-9)
    assert int(res.n_samples) == ok.sum()


def test_smoothing_stays_within_trials():
    x = np.r_[np.zeros(50), np.ones(50)][:, None]
    out = smooth_in_trials(x, np.repeat([0, 1], 50), 3.0)
    np.testing.assert_allclose(out[:, 0], x[:, 0])  # no mixing across the boundary


def test_random_units_score_near_their_shuffles(speed_rec):
    res = hp.speed_score(speed_rec, n_shuffles=100, seed=2)
    rand = slice(3, None)
    z = ((res.speed_score - res.speed_score_shuffle_mean)
         / res.speed_score_shuffle_std).values[rand]
    assert np.abs(z).max() < 4, z
    assert (res.speed_score_p_value.values[rand] < 0.01).sum() <= 1


def test_lazy_recording_gives_the_same_scores(speed_rec):
    eager = hp.speed_score(speed_rec, n_shuffles=20)
    lazy = hp.speed_score(speed_rec.chunk({"time": 5000}), n_shuffles=20)
    xr.testing.assert_allclose(eager, lazy)


def test_arguments_are_checked(speed_rec):
    with pytest.raises(ValueError, match="`max_speed` must be > 0.02; got 0.01"):
        hp.speed_score(speed_rec, max_speed=0.01)
    with pytest.raises(ValueError, match="no sample with a speed in"):
        hp.speed_score(speed_rec, min_speed=5.0, max_speed=6.0)
    with pytest.raises(ValueError, match="`threshold` must be one of 'unit', 'pooled'"):
        hp.speed_score(speed_rec, threshold="all")


def test_a_spike_units_slope_is_in_hz_per_metre_per_second():
    """Spike counts per sample become Hz, as the rate maps do (Kropff et al. report the
    slope in Hz per cm/s)."""
    rng = np.random.default_rng(3)
    n, dt = 40000, 0.1
    pos, heading, speed = square_walk(n, rng, dt=dt)
    counts = rng.poisson((2.0 + 10 * speed) * dt)[:, None].astype(float)
    rec = make_recording(pos, counts, dt=dt, activity_kind="spike_count")
    res = hp.speed_score(rec, n_shuffles=0, sigma=0)
    assert res.speed_slope.attrs["units"] == "Hz per m/s"
    np.testing.assert_allclose(res.speed_slope.values[0], 10.0, rtol=0.15)
    np.testing.assert_allclose(res.speed_intercept.values[0], 2.0, atol=0.3)
