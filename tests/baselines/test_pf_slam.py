"""PF-SLAM: the posterior over arenas concentrates on the true one."""

import numpy as np
import pytest

from hippo_probe.baselines import pf_slam
from hippo_probe.tasks import make_trials


def test_posterior_concentrates_on_the_true_arena():
    batch = make_trials("specialized", 8, "test", 0)
    res = pf_slam(batch, 3000)
    prob = res.class_probability                                # (T, B, 100)
    assert prob.shape == (500, 8, 100) and prob.dtype == np.float32
    assert np.allclose(prob.sum(axis=-1), 1.0, atol=1e-5)
    assert np.allclose(prob[0], prob[0, 0, 0], atol=0.02)      # near uniform at first
    true = prob[:, np.arange(8), batch.environment]
    assert true[-1].mean() > 0.7
    assert (prob[-1].argmax(axis=-1) == batch.environment).mean() >= 0.75
    assert true[-1].mean() > 10 * true[0].mean()
    assert res.error(batch)[-100:].mean() < 0.08


def test_needs_fixed_arenas_and_enough_particles():
    with pytest.raises(ValueError, match="fixed arenas and a known start"):
        pf_slam(make_trials("generalized", 1, "test", 0), 200)
    with pytest.raises(ValueError, match="`n_particles` must be >= the number of arena"):
        pf_slam(make_trials("specialized", 1, "test", 0), 50)
