import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp

pytest.importorskip("sklearn")


def _recording(n_trials=60, steps=30, n_env=3, units=12, signal=1.0, seed=0):
    """Trials in ``n_env`` environments; each environment shifts the population along
    its own direction by ``signal`` (in units of the per-sample noise)."""
    rng = np.random.default_rng(seed)
    env_of_trial = rng.integers(n_env, size=n_trials)
    env = np.repeat(env_of_trial, steps)
    codes = rng.normal(size=(n_env, units))
    act = rng.normal(size=(n_trials * steps, units)) + signal * codes[env]
    n = n_trials * steps
    return xr.Dataset(
        {"activity": (("time", "unit"), act.astype(np.float32))},
        coords={"time": np.arange(n) * 1.0 + np.repeat(np.arange(n_trials), steps),
                "unit": np.arange(units), "trial": ("time", np.repeat(np.arange(n_trials),
                                                                      steps)),
                "trial_time": ("time", np.tile(np.arange(1.0, steps + 1), n_trials)),
                "environment": ("time", env)}, attrs={"dt": 1.0})


def test_an_encoded_environment_is_decoded_and_an_absent_one_is_not():
    coded = hp.decode_environment(_recording(signal=1.0), times=[5.0, 20.0])
    assert (coded.accuracy > 0.9).all()
    assert coded.attrs["chance"] == pytest.approx(1 / 3)
    assert coded.attrs["validation"] == "5-fold by trial"
    assert list(coded.n_scored.values) == [60, 60]    # every trial held out once
    absent = hp.decode_environment(_recording(signal=0.0), times=[5.0, 20.0])
    assert (abs(absent.accuracy - 1 / 3) < 0.2).all()


def test_memorizing_shows_as_a_gap_between_train_and_held_out_accuracy():
    """Many units, few trials, no signal: the fit separates its own trials, not others."""
    res = hp.decode_environment(_recording(n_trials=30, units=200, signal=0.0), times=[10.0],
                                c=100.0)
    assert res.train_accuracy.item() > 0.9 and res.accuracy.item() < 0.6


def test_a_separate_test_recording_and_a_lazy_one():
    train = _recording(seed=1)
    test = _recording(seed=1).isel(time=slice(0, 600))       # 20 of the same trials
    other = _recording(seed=2)                              # other codes: nothing carries
    same = hp.decode_environment(train.chunk({"time": 300}), test=test, times=[10.0])
    assert same.attrs["validation"] == "separate test recording"
    assert same.accuracy.item() > 0.9 and same.n_scored.item() == 20
    assert hp.decode_environment(train, test=other, times=[10.0]).accuracy.item() < 0.7


def test_times_beyond_the_trials_are_nan_and_bad_input_is_named():
    rec = _recording()
    res = hp.decode_environment(rec, times=[10.0, 500.0])
    assert np.isnan(res.accuracy.values[1]) and res.n_scored.values[1] == 0
    with pytest.raises(ValueError, match="n_folds"):
        hp.decode_environment(rec.isel(time=slice(0, 90)), times=[5.0])   # 3 trials
    with pytest.raises(ValueError, match="`test` must have the units"):
        hp.decode_environment(rec, test=rec.isel(unit=slice(0, 3)))
    with pytest.raises(ValueError, match="environment"):
        hp.decode_environment(rec.drop_vars("environment"))


def test_an_environment_of_one_trial_is_left_out_of_the_score():
    """Its trial, held out, leaves no training trial of its environment: it cannot be
    named, so it is not counted as a miss (it was, with chance still 1 / environments)."""
    rec = _recording(signal=3.0)
    env = rec.environment.values.copy()
    env[rec.trial.values == 7] = 9                  # trial 7 alone in environment 9
    rec = rec.assign_coords(environment=("time", env))
    with pytest.warns(hp.AnalysisWarning, match="cannot be named and are left out"):
        res = hp.decode_environment(rec, times=[5.0])
    assert int(res.n_unseen[0]) == 1 and int(res.n_scored[0]) == 59
    assert float(res.accuracy[0]) == 1.0            # every trial that can be named is
    # a separate test recording holding an environment the decoder never saw
    env[rec.trial.values == 45] = 9
    rec = rec.assign_coords(environment=("time", env))
    train = rec.isel(time=(rec.trial.values < 40) & (rec.trial.values != 7))
    test = rec.isel(time=rec.trial.values >= 40)
    with pytest.warns(hp.AnalysisWarning, match="left out of `accuracy`"):
        res = hp.decode_environment(train, test=test, times=[5.0])
    assert (int(res.n_unseen[0]), int(res.n_scored[0])) == (1, 19)
    assert float(res.accuracy[0]) == 1.0
