"""Path integration: exact without noise, drifting with it."""

import numpy as np
import pytest

from hippo_probe.baselines import path_integration
from hippo_probe.tasks import make_trials, task_config
from hippo_probe.world import NoiseModel, WorldConfig


def noiseless(task):
    config = task_config(task)
    return task_config(task, world=WorldConfig(arena=config.world.arena,
                                               noise=NoiseModel.noiseless()))


@pytest.mark.parametrize("task", ["generalized", "specialized"])
def test_exact_without_noise(task):
    config = noiseless(task)
    batch = make_trials(task, 4, "test", 0, config=config)
    res = path_integration(batch, config=config)
    # inputs are float32: 500 steps of ~6 cm sum to ~1e-6 m of rounding at most
    assert np.abs(res.estimate - batch.target).max() < 1e-5
    assert res.estimate.shape == batch.target.shape


def test_error_grows_with_time():
    batch = make_trials("generalized", 32, "test", 0)
    error = path_integration(batch).error(batch).mean(axis=1)
    assert error[49] < error[249] < error[499]
    assert error[499] > 2 * error[49]


def test_unknown_start_uses_the_start_prior_mean():
    batch = make_trials("localization", 4, "test", 0)
    res = path_integration(batch)                      # localization: start unknown
    first = res.estimate[0] - batch.feature("dx")[0, :, None] * [1, 0] \
        - batch.feature("dy")[0, :, None] * [0, 1]
    assert np.allclose(first, first[0])                # the same guess for every trial
    assert res.attrs["start"] == "unknown"
    known = path_integration(batch, start="known")
    assert np.abs(known.estimate[0] - batch.start
                  - batch.inputs[0, :, :2]).max() < 1e-6


def test_bad_start_is_named():
    batch = make_trials("generalized", 1, "test", 0)
    with pytest.raises(ValueError, match="`start` must be one of"):
        path_integration(batch, start="maybe")
