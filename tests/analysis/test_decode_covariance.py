import numpy as np
import pytest

import hippo_probe as hp

from .conftest import make_recording, trajectory

N_TRIALS, PER_TRIAL, N_UNITS = 10, 400, 30


def _recording(seed=15):
    """Activity with slow, trial-specific structure; target 'xx', 'yy' linear in the
    activity (plus noise), 'xy' independent of it."""
    rng = np.random.default_rng(seed)
    pos = np.concatenate([trajectory(PER_TRIAL, rng)[0] for _ in range(N_TRIALS)])
    n = len(pos)
    trial = np.repeat(np.arange(N_TRIALS), PER_TRIAL)
    latent = np.cumsum(rng.standard_normal((n, 5)), axis=0) / 20
    act = np.tanh(latent @ rng.standard_normal((5, N_UNITS)) / 2
                  + 0.1 * rng.standard_normal((n, N_UNITS)))
    beta = rng.standard_normal((N_UNITS, 2))
    linear = act @ beta + 0.1 * rng.standard_normal((n, 2))
    random = rng.standard_normal(n)
    cov = np.c_[linear, random]
    rec = make_recording(pos, act, trial=trial, activity_kind="lstm_hidden",
                         pf_cov=(("time", "cov"), cov, {"units": "m2",
                                                        "long_name": "PF covariance"}))
    return rec.assign_coords(cov=["xx", "yy", "xy"])


def test_linear_target_recovered_and_random_target_not():
    rec = _recording()
    res = hp.decode_covariance(rec)
    r2 = res.r2.to_series()
    assert r2["xx"] > 0.95 and r2["yy"] > 0.95
    assert -0.05 < r2["xy"] < 0.02
    assert res.prediction.dims == ("time", "cov")
    assert res.alpha.dims == ("fold", "cov")


def test_equals_scikit_learn_ridge_with_group_folds():
    from sklearn.linear_model import Ridge
    from sklearn.metrics import r2_score

    rec = _recording()
    res = hp.decode_covariance(rec, n_folds=5, alphas=[3.0], seed=2)
    x = rec.activity.values.astype(float)
    y = rec.pf_cov.values
    pred = np.full_like(y, np.nan)
    trial = rec.trial.values
    # the same folds as decode_covariance: trials dealt at random (seed 2) into 5 folds
    order = np.random.default_rng(2).permutation(N_TRIALS)
    fold = np.empty(N_TRIALS, int)
    fold[order] = np.arange(N_TRIALS) % 5
    sample_fold = fold[trial]
    for f in range(5):
        test = sample_fold == f
        model = Ridge(alpha=3.0).fit(x[~test], y[~test])
        pred[test] = model.predict(x[test])
    np.testing.assert_allclose(res.prediction.values, pred, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(res.r2.values, r2_score(y, pred, multioutput="raw_values"),
                               rtol=1e-7)


def test_lazy_equals_eager_and_nan_targets_are_skipped():
    rec = _recording()
    cov = rec.pf_cov.values.copy()
    cov[:50] = np.nan
    rec["pf_cov"] = (("time", "cov"), cov, rec.pf_cov.attrs)
    eager = hp.decode_covariance(rec)
    lazy = hp.decode_covariance(rec.chunk({"time": 700}))
    np.testing.assert_allclose(lazy.r2, eager.r2, rtol=1e-9)
    assert hasattr(lazy.prediction.data, "dask")
    # sums in a different order: agreement to rounding
    np.testing.assert_allclose(lazy.prediction.values, eager.prediction.values, rtol=1e-9,
                               atol=1e-8)
    assert eager.attrs["n_samples"] == N_TRIALS * PER_TRIAL - 50


def test_bad_input():
    rec = _recording()
    with pytest.raises(ValueError, match=r"must contain \['pf_cov'\]"):
        hp.decode_covariance(rec.drop_vars("pf_cov"))
    with pytest.raises(ValueError, match="`n_folds` must be <= the number of trials"):
        hp.decode_covariance(rec, n_folds=20)
    with pytest.raises(ValueError, match="`alphas` must be"):
        hp.decode_covariance(rec, alphas=[-1.0])
