"""The two worlds: the darkness world's drifting heading, and the compass world unchanged."""

import hashlib
from dataclasses import replace

import numpy as np
import pytest

from hippo_probe.tasks import TASKS, make_trials, task_config
from hippo_probe.world import FEATURES, NoiseModel, WorldConfig, wrap_angle, world_config
from hippo_probe.trial_stats.stats import drift_rates

# sha1 of inputs + positions + starts of trials 0-2 of each task's test split, seed 0,
# computed from the compass world before the darkness world existed: the compass world's
# trials (and with them every network trained in it) must never change.
PINNED_COMPASS_TRIALS = {
    "localization": "fc8fc7e7e929962043b977fd1526ee94e49f853f",
    "generalized": "f066e689ef09574b218e8a59c38184b111b591f6",
    "specialized": "c74a4b9962fdcd30602fee533e85ed6b6b63055f",
}


def digest(batch):
    return hashlib.sha1(batch.inputs.tobytes() + batch.position.tobytes()
                        + batch.start.tobytes()).hexdigest()


@pytest.mark.parametrize("task", TASKS)
def test_the_compass_world_is_the_first_world_bit_for_bit(task):
    batch = make_trials(task, 3, "test", 0, world="compass")
    assert digest(batch) == PINNED_COMPASS_TRIALS[task]
    assert (batch.heading_drift == 0).all() and batch.world.name == "compass"


@pytest.mark.parametrize("task", TASKS)
def test_darkness_trials_share_everything_with_compass_trials_but_the_heading(task):
    """Same paths, same contacts, same touch; the heading inputs and the displacement's
    frame differ by the drift."""
    dark = make_trials(task, 6, "test", 0)
    compass = make_trials(task, 6, "test", 0, world="compass")
    assert dark.world.name == "darkness"
    for name in ("position", "head_direction", "contact", "start", "arena_vertices"):
        np.testing.assert_array_equal(getattr(dark, name), getattr(compass, name))
    for name in ("contact", "contact_distance", "cos_beta", "sin_beta"):
        np.testing.assert_array_equal(dark.feature(name), compass.feature(name))
    eta = dark.heading_drift
    assert np.abs(eta).max() > 0.1
    # the sensed heading is the compass world's turned by the drift
    hd_dark = np.arctan2(dark.feature("sin_hd"), dark.feature("cos_hd"))
    hd_compass = np.arctan2(compass.feature("sin_hd"), compass.feature("cos_hd"))
    np.testing.assert_allclose(wrap_angle(hd_dark - hd_compass - eta), 0, atol=1e-5)
    # and so is the sensed displacement (rotated by eta, same length)
    d, c = dark.inputs[..., :2].astype(float), compass.inputs[..., :2].astype(float)
    cos, sin = np.cos(eta), np.sin(eta)
    turned = np.stack([cos * c[..., 0] - sin * c[..., 1], sin * c[..., 0] + cos * c[..., 1]],
                      axis=-1)
    np.testing.assert_allclose(d, turned, atol=1e-6)
    turn = dark.feature("dhd") - compass.feature("dhd")
    np.testing.assert_allclose(turn, np.diff(eta, axis=0, prepend=0.0), atol=1e-5)


def test_the_drift_is_a_wiener_process_from_zero():
    batch = make_trials("generalized", 400, "test", 0)
    sigma = batch.world.noise.heading_drift
    steps = np.diff(batch.heading_drift, axis=0, prepend=0.0)           # eta_0 = 0
    assert abs(steps.std() / (sigma * np.sqrt(batch.dt)) - 1) < 0.01
    assert abs(steps.mean()) < 3 * sigma * np.sqrt(batch.dt / steps.size)
    # increments are independent: no lag-1 correlation
    assert abs(np.corrcoef(steps[1:].ravel(), steps[:-1].ravel())[0, 1]) < 0.01
    # variance grows linearly: sd sigma sqrt(t) at 200 s
    assert abs(batch.heading_drift[-1].std() / (sigma * np.sqrt(200.0)) - 1) < 0.1


def test_drift_rates_match_cheung_et_al():
    """Calibration: median absolute drift over 1-minute windows in 5-27 deg/min (Cheung et
    al. 2012, head-direction cells without vision: 5.1-26.6 deg/min)."""
    rates = drift_rates(make_trials("localization", 500, "test", 0))
    assert len(rates) == 500 * 3
    assert 5 < np.median(rates) < 27
    # a half-normal: the median is 0.674 sigma sqrt(60 s)
    sigma = world_config("darkness").noise.heading_drift
    expected = np.degrees(0.6745 * sigma * np.sqrt(60.0))
    assert abs(np.median(rates) / expected - 1) < 0.1
    assert (drift_rates(make_trials("localization", 20, "test", 0, world="compass")) == 0).all()


@pytest.mark.parametrize("task", TASKS)
def test_noise_free_inputs_path_integrate_exactly(task):
    """Both worlds: with every noise zero (the drift too) the displacement inputs sum to
    the path (the darkness world with no drift makes the compass world's inputs)."""
    config = task_config(task, "darkness")
    exact = replace(config, world=replace(config.world, noise=NoiseModel.noiseless()))
    batch = make_trials(task, 10, "test", 0, config=exact)
    step = batch.inputs[..., [FEATURES.index("dx"), FEATURES.index("dy")]]
    estimate = batch.start[None] + np.cumsum(step.astype(np.float64), axis=0)
    assert np.abs(estimate - batch.position).max() < 1e-5


@pytest.mark.parametrize("task", TASKS)
def test_drift_alone_path_integrates_exactly_in_the_true_frame(task):
    """With every noise zero but the drift, turning each sensed step back by the true
    drift retraces the path: the drift is the only thing between sensed and true."""
    config = task_config(task)
    drift_only = NoiseModel(0, 0, 0, 0, 0, 0, heading_drift=config.world.noise.heading_drift)
    batch = make_trials(task, 10, "test", 0,
                        config=replace(config, world=replace(config.world, noise=drift_only)))
    d = batch.inputs[..., :2].astype(np.float64)
    cos, sin = np.cos(-batch.heading_drift), np.sin(-batch.heading_drift)
    true_step = np.stack([cos * d[..., 0] - sin * d[..., 1], sin * d[..., 0] + cos * d[..., 1]],
                         axis=-1)
    error = batch.start[None] + np.cumsum(true_step, axis=0) - batch.position
    assert np.abs(error).max() < 1e-5
    naive = batch.start[None] + np.cumsum(d, axis=0) - batch.position
    assert np.linalg.norm(naive, axis=-1)[-1].mean() > 0.05     # ... and the drift matters
    hd = np.arctan2(batch.feature("sin_hd"), batch.feature("cos_hd"))
    np.testing.assert_allclose(wrap_angle(hd - batch.head_direction - batch.heading_drift), 0,
                               atol=1e-5)


def test_worlds_by_name_and_bad_worlds():
    assert world_config("compass").noise.heading_drift == 0
    assert world_config("darkness").noise.heading_drift > 0
    assert WorldConfig().name == "darkness" and WorldConfig().noise.heading_drift > 0
    # a darkness world built from a modified noise model keeps its drift
    assert WorldConfig(noise=NoiseModel(speed_sd=0.1)).noise.heading_drift > 0
    assert task_config("generalized", "compass").world.arena.mean_radius == 0.33
    with pytest.raises(ValueError, match="`world` must be one of 'darkness', 'compass'; "
                                         "got 'dark'"):
        make_trials("generalized", 1, world="dark")
    with pytest.raises(ValueError, match="`heading_drift` must be >= 0; got -0.1"):
        NoiseModel(heading_drift=-0.1)
    with pytest.raises(ValueError, match="compass world has no heading drift"):
        WorldConfig(name="compass", noise=NoiseModel(heading_drift=0.05))
    with pytest.raises(TypeError, match="`world` must be one of"):
        task_config("generalized", world=3)
    with pytest.raises(ValueError, match=r"`world` \('compass'\) disagrees with the world "
                                         r"of `config` \('darkness'"):
        make_trials("generalized", 1, world="compass", config=task_config("generalized"))
