import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.remapping_similarity import pair_correlations

from .conftest import two_environment_recording


@pytest.fixture(scope="module")
def two_env():
    return two_environment_recording()


def test_independent_environments_remap_globally(two_env):
    sim = hp.remapping_similarity(two_env)
    mean = sim["mean"].to_series()
    assert mean["same"] > 0.9
    assert abs(mean["different"]) < 0.1
    # the control erases the difference
    assert abs(mean["same_permuted"] - mean["different_permuted"]) < 0.5 * (
        mean["same"] - mean["different"])
    n = len(np.unique(two_env.trial))
    assert sim.sizes["pair"] == n * (n - 1) // 2
    assert sim.n_pairs.sel(comparison="same") == 2 * (6 * 5 // 2)
    assert (sim.similarity.where(sim.same_environment, drop=True) > 0.8).all()


def test_pair_correlations_equal_masked_corrcoef():
    rng = np.random.default_rng(13)
    maps = rng.normal(size=(5, 6, 40))
    for t in range(6):  # each trial misses some bins (for every unit)
        maps[:, t, rng.choice(40, 12, replace=False)] = np.nan
    r, common = pair_correlations(maps, 3)
    for a in range(6):
        for b in range(6):
            ok = np.isfinite(maps[0, a]) & np.isfinite(maps[0, b])
            ref = np.corrcoef(maps[:, a, ok].ravel(), maps[:, b, ok].ravel())[0, 1]
            assert r[a, b] == pytest.approx(ref, abs=1e-10)
            assert common[a, b] == ok.sum()


def test_lazy_equals_eager(two_env):
    eager = hp.remapping_similarity(two_env)
    lazy = hp.remapping_similarity(two_env.chunk({"time": 1500}))
    np.testing.assert_allclose(lazy.similarity, eager.similarity, rtol=1e-9)


def test_single_environment_warns_and_single_trial_errors(two_env):
    one_env = two_env.sel(time=two_env.environment == 0)
    with pytest.warns(AnalysisWarning, match="summaries are NaN"):
        sim = hp.remapping_similarity(one_env)
    assert np.isnan(sim["mean"].sel(comparison="different"))
    one_trial = two_env.sel(time=two_env.trial == 0)
    with pytest.raises(ValueError, match="at least 2 trials"):
        hp.remapping_similarity(one_trial)


def test_center_units_removes_arena_independent_offsets(two_env):
    """Large per-unit offsets shared by both environments make every pair look alike in
    the pooled correlation; centring each unit on its own mean recovers global remapping."""
    rng = np.random.default_rng(1)
    offsets = rng.uniform(-1.0, 1.0, two_env.sizes["unit"]) * 5 * float(two_env.activity.std())
    shifted = two_env.copy()
    shifted["activity"] = two_env.activity + offsets
    raw = hp.remapping_similarity(shifted)["mean"].to_series()
    centred = hp.remapping_similarity(shifted, center_units=True)
    mean = centred["mean"].to_series()
    assert raw["different"] > 0.8                      # the offsets dominate ...
    assert abs(mean["different"]) < 0.1 and mean["same"] > 0.9   # ... until removed
    assert centred.attrs["center_units"] is True
