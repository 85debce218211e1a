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


def _spike_counts(n=20000, units=15, seed=0):
    """Poisson counts in 20 ms bins of units tuned to a slow 2-D trajectory: mostly
    zeros, so many states repeat exactly and neighbour distances tie."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 0.02
    xy = np.c_[np.cos(t / 7), np.sin(t / 5)]
    centres = rng.uniform(-1, 1, (units, 2))
    rate = 5 * np.exp(-((xy[:, None] - centres) ** 2).sum(-1) / 0.1)
    return rng.poisson(rate * 0.02).astype(float)


def test_discrete_states_are_refused_with_the_reason():
    """On spike counts both estimators break (TwoNN reads ~0, MLE far above the number
    of units): NaN, the reason in attrs and a warning, instead of a plausible number."""
    counts = _spike_counts()
    with pytest.warns(hp.AnalysisWarning, match="intrinsic dimension is NaN"):
        res = hp.intrinsic_dimension(counts)
    assert np.isnan(res.dimension.values).all()
    assert set(res.attrs["nan_reasons"]) == {"TwoNN", "MLE"}
    assert "spike counts" in res.attrs["nan_reasons"]["MLE"]
    assert res.attrs["n_skipped"] > 0.05 * res.attrs["n_points"]


def test_tied_distances_refuse_the_estimate_though_no_state_repeats():
    """Points on an integer lattice, every point distinct (none is skipped) but their
    neighbour distances tie: refused by the tie rule; jittered, they are estimated."""
    rng = np.random.default_rng(0)
    lattice = np.unique(rng.integers(0, 40, size=(6000, 3)), axis=0)[:4000]
    lattice = lattice[rng.permutation(len(lattice))].astype(float)
    with pytest.warns(hp.AnalysisWarning, match="tied neighbour distances"):
        res = hp.intrinsic_dimension(lattice @ np.eye(3, 10))
    assert res.attrs["n_skipped"] == 0
    assert np.isnan(res.dimension.values).all()
    jittered = (lattice + rng.normal(scale=1e-3, size=lattice.shape)) @ np.eye(3, 10)
    res = hp.intrinsic_dimension(jittered)
    assert "nan_reasons" not in res.attrs and np.isfinite(res.dimension).all()
    assert float(res.dimension.sel(estimator="MLE")) == pytest.approx(3, rel=0.15)


def test_continuous_states_keep_their_estimate_and_warn_nothing():
    x = np.random.default_rng(2).uniform(size=(2000, 2)) @ np.eye(2, 12)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error", hp.AnalysisWarning)
        res = hp.intrinsic_dimension(x)
    assert "nan_reasons" not in res.attrs
    np.testing.assert_allclose(res.dimension, 2, rtol=0.15)


def test_importing_scikit_dimension_leaves_the_warning_filters_alone():
    """scikit-dimension silences every warning of the process when imported; the first
    call in a fresh process must leave the filters as they were, so later warnings show."""
    import subprocess
    import sys
    code = (
        "import sys, warnings, numpy as np, hippo_probe as hp\n"
        "assert 'skdim' not in sys.modules\n"
        "hp.intrinsic_dimension(np.random.default_rng(0).normal(size=(300, 3)))\n"
        "assert 'skdim' in sys.modules\n"
        "blanket = [f for f in warnings.filters if f[0] == 'ignore' and f[1] is None\n"
        "           and f[2] is Warning]\n"
        "assert not blanket, blanket\n"
        "with warnings.catch_warnings(record=True) as w:\n"
        "    warnings.warn('still heard', hp.AnalysisWarning)\n"
        "assert len(w) == 1\n")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=False)
    assert run.returncode == 0, run.stderr
