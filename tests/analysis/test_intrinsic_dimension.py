import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp

pytest.importorskip("skdim")


@pytest.mark.parametrize("d", [2, 5])
def test_both_estimators_find_the_dimension_of_a_flat_set(d):
    """Uniform points on a d-dimensional subspace of 30 dimensions."""
    rng = np.random.default_rng(1)
    x = rng.uniform(size=(3000, d)) @ np.linalg.qr(rng.normal(size=(30, d)))[0].T
    res = hp.intrinsic_dimension(x)
    assert list(res.estimator.values) == ["TwoNN", "MLE"]
    # both estimators are biased low in higher d at 3,000 points; within 15%
    np.testing.assert_allclose(res.dimension.values, d, rtol=0.15)
    assert res.attrs["n_points"] == 3000 and res.attrs["n_skipped"] == 0


def _slow_states(n_trials=100, steps=400, hold=4, seed=0):
    """States of a slow system: each trial visits uniform points of a 3-D cube, lingering
    at each for ``hold`` samples while drifting slightly along one direction; embedded in
    20 dimensions. In time order it is locally a curve (the drift), as a set 3-D."""
    rng = np.random.default_rng(seed)
    n = n_trials * steps
    visits = rng.uniform(size=(n // hold, 3))
    drift = 1e-3 * np.outer(np.arange(n) % hold, rng.normal(size=3))
    act = ((np.repeat(visits, hold, axis=0) + drift) @ rng.normal(size=(3, 20)))
    t = np.arange(n) * 0.1
    trial = np.repeat(np.arange(n_trials), steps)
    return xr.Dataset({"activity": (("time", "unit"), act.astype(np.float32))},
                      coords={"time": t, "trial": ("time", trial),
                              "unit": np.arange(20)}, attrs={"dt": 0.1})


def test_the_theiler_window_keeps_slow_states_from_looking_like_a_curve():
    rec = _slow_states()
    full = hp.intrinsic_dimension(rec, max_points=2000, seed=0)
    none = hp.intrinsic_dimension(rec, max_points=2000, seed=0, theiler=0)
    # without the window a state's nearest neighbours are its own near past and future
    # (the drift, a line): both estimates fall, TwoNN (first two neighbours) toward 1
    assert (none.dimension < full.dimension).all()
    assert float(none.dimension.sel(estimator="TwoNN")) < 2
    # with it MLE finds the set's 3; TwoNN comes out high (3.4 here): the few states of
    # one visit sampled together make near-equal first and second distances (mu ~ 1),
    # the estimator's known sensitivity to clustered samples
    assert float(full.dimension.sel(estimator="MLE")) == pytest.approx(3, rel=0.15)
    assert 2.5 < float(full.dimension.sel(estimator="TwoNN")) < 5


def test_bad_input_is_named():
    x = np.random.default_rng(0).normal(size=(100, 5))
    with pytest.raises(ValueError, match="`estimators`"):
        hp.intrinsic_dimension(x, estimators=["PCA"])
    with pytest.raises(ValueError, match="more than"):
        hp.intrinsic_dimension(x[:20])
    with pytest.raises(ValueError, match="NaN"):
        hp.intrinsic_dimension(np.full((100, 5), np.nan))
