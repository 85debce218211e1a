import numpy as np
import pytest

import hippo_probe as hp

from .conftest import SQUARE, make_recording, trajectory

N_TRIALS, STEPS, DT = 6, 200, 0.4


def _recording(**variables):
    rng = np.random.default_rng(11)
    pos = np.concatenate([trajectory(STEPS, rng, dt=DT)[0] for _ in range(N_TRIALS)])
    trial = np.repeat(np.arange(N_TRIALS), STEPS)
    env = trial % 3
    rec = make_recording(pos, np.zeros((len(pos), 1)), dt=DT, trial=trial, environment=env,
                         arena_vertices=SQUARE, **variables)
    return rec, pos, trial


def _space(a, name):
    return (("time", "space"), a, {"units": "m", "long_name": name})


def test_error_growing_with_time_in_trial():
    rec, pos, trial = _recording()
    tt = rec.trial_time.values
    drift = 0.01 * tt[:, None] * np.array([[0.6, 0.8]])  # 1 cm/s in a fixed direction
    rec["estimate"] = _space(pos + drift, "estimate")
    err = hp.localization_error(rec)
    np.testing.assert_allclose(err.euclidean.values, 0.01 * err.trial_time.values, atol=1e-12)
    assert (err.n_trials == N_TRIALS).all()
    assert err.euclidean.attrs["units"] == "m"
    assert err.trial_time.values[1] == pytest.approx(DT)


def test_rotation_about_centre_is_pure_angular_error():
    rec, pos, _ = _recording()
    a = 0.3
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    rec["estimate"] = _space(pos @ rot.T, "estimate")
    err = hp.localization_error(rec)
    np.testing.assert_allclose(err.radial.values, 0, atol=1e-12)
    np.testing.assert_allclose(err.angular.values, a, atol=1e-9)
    r = np.linalg.norm(pos, axis=1).reshape(N_TRIALS, STEPS).mean(axis=0)
    np.testing.assert_allclose(err.euclidean.values, 2 * np.sin(a / 2) * r, rtol=1e-9)


def test_several_estimates_and_nan_samples():
    rec, pos, trial = _recording()
    pf = pos + 0.05
    pf[trial == 0] = np.nan  # lost in one trial
    rec["estimate"] = _space(pos + 0.1, "estimate")
    rec["estimate_pf"] = _space(pf, "estimate_pf")
    err = hp.localization_error(rec, ["estimate", "estimate_pf"])
    assert err.euclidean.dims == ("estimate", "trial_time")
    np.testing.assert_allclose(err.euclidean.sel(estimate="estimate"), 0.1 * np.sqrt(2))
    np.testing.assert_allclose(err.euclidean.sel(estimate="estimate_pf"), 0.05 * np.sqrt(2))
    assert (err.n_trials.sel(estimate="estimate_pf") == N_TRIALS - 1).all()


def test_missing_or_empty_estimate_is_a_clear_error():
    rec, pos, _ = _recording()
    with pytest.raises(ValueError, match=r"must contain \['estimate'\]"):
        hp.localization_error(rec)
    rec["estimate"] = _space(pos * np.nan, "estimate")
    with pytest.raises(ValueError, match="no sample where both are finite"):
        hp.localization_error(rec)


def test_classification_accuracy_vs_time():
    rec, _, trial = _recording()
    env = rec.environment.values
    n_env = 3
    k = np.tile(np.arange(STEPS), N_TRIALS)
    prob = np.full((len(env), n_env), 0.1)
    # the true class wins from step 100 on in every trial; before, class (env+1) % 3 wins
    winner = np.where(k >= 100, env, (env + 1) % n_env)
    prob[np.arange(len(env)), winner] = 0.8
    rec = rec.assign_coords(environment_id=np.arange(n_env))
    rec["class_probability"] = (("time", "environment_id"), prob,
                                {"units": "1", "long_name": "p"})
    acc = hp.classification_accuracy(rec)
    np.testing.assert_array_equal(acc.accuracy.values, (np.arange(STEPS) >= 100).astype(float))
    np.testing.assert_allclose(acc.true_class_probability.values,
                               np.where(np.arange(STEPS) >= 100, 0.8, 0.1))
    assert acc.attrs["chance"] == pytest.approx(1 / 3)
    with pytest.raises(ValueError, match="all NaN"):
        hp.classification_accuracy(rec.assign(class_probability=rec.class_probability * np.nan))


def test_curves_cover_only_times_that_occur():
    from hippo_probe.recording.layout import trial_layout
    from hippo_probe.recording.schema import annotate

    rec = trial_layout(50, 3, DT)  # samples at the end of each step: trial_time = dt, 2 dt ..
    pos = np.zeros((150, 2)) + 0.1
    rec["position"] = (("time", "space"), pos)
    rec["estimate"] = (("time", "space"), pos + 0.03)
    rec["activity"] = (("time", "unit"), np.zeros((150, 1), np.float32))
    rec = annotate(rec.assign_coords(unit=[0]))
    err = hp.localization_error(rec)
    assert err.trial_time.values[0] == pytest.approx(DT)
    assert err.sizes["trial_time"] == 50
    assert np.isfinite(err.euclidean).all() and np.isfinite(err.euclidean_sem).all()
