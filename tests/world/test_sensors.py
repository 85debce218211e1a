"""Sensors: self-motion integrated over the fine steps, noise exactly as the model says."""

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from hippo_probe.tasks import TASKS, make_trials, task_config
from hippo_probe.world import FEATURES, NoiseModel, SensorConfig, sense, wrap_angle
from hippo_probe.world.sensors import N_NOISE_DRAWS


def noiseless_trials(task, n_trials=20, seed=0):
    config = task_config(task)
    config = replace(config, world=replace(config.world, noise=NoiseModel.noiseless()))
    return make_trials(task, n_trials, "test", seed, config=config)


@pytest.mark.parametrize("task", TASKS)
def test_path_integration_of_noise_free_inputs_recovers_the_trajectory(task):
    """Summing the noise-free displacement inputs retraces the true path: every PI error
    of the real inputs comes from the noise model, none from sampling the motion."""
    batch = noiseless_trials(task)
    step = batch.inputs[..., [FEATURES.index("dx"), FEATURES.index("dy")]]
    estimate = batch.start[None] + np.cumsum(step.astype(np.float64), axis=0)
    error = np.linalg.norm(estimate - batch.position, axis=-1)
    assert error.max() < 1e-5            # float32 inputs; "millimetres" with room to spare
    assert batch.contact.any()            # the walls turned the agent on the way
    # the path is not trivially short: it really wanders
    assert np.linalg.norm(np.diff(batch.position, axis=0), axis=-1).sum(axis=0).min() > 10


def test_noise_free_heading_and_contact_inputs_are_the_truth():
    batch = noiseless_trials("generalized")
    hd = batch.head_direction
    np.testing.assert_allclose(batch.feature("cos_hd"), np.cos(hd), atol=1e-6)
    np.testing.assert_allclose(batch.feature("sin_hd"), np.sin(hd), atol=1e-6)
    turned = wrap_angle(np.diff(hd, axis=0))
    np.testing.assert_allclose(batch.feature("dhd")[1:], turned, atol=1e-6)
    touched = batch.contact
    np.testing.assert_array_equal(batch.feature("contact"), touched.astype(np.float32))
    d = batch.feature("contact_distance")
    assert ((d[touched] > 0) & (d[touched] < SensorConfig().touch_range)).all()
    for name in ("contact_distance", "cos_beta", "sin_beta"):
        assert (batch.feature(name)[~touched] == 0).all()
    unit = batch.feature("cos_beta") ** 2 + batch.feature("sin_beta") ** 2
    np.testing.assert_allclose(unit[touched], 1.0, rtol=1e-6)
    # the agent was moving into the wall it touched: the heading is more than 90 degrees
    # away from the wall's inward normal (except when a sharp corner stopped it)
    assert np.mean(batch.feature("cos_beta")[touched] < 0) > 0.99


def _synthetic_motion(rng, n_trials, n_steps, contact_rate=0.3):
    heading = wrap_angle(np.cumsum(rng.normal(0, 0.3, (n_trials, n_steps)), axis=1))
    length = rng.uniform(0.01, 0.1, (n_trials, n_steps))
    direction = heading + rng.normal(0, 0.2, (n_trials, n_steps))
    contact = rng.random((n_trials, n_steps)) < contact_rate
    return {
        "displacement": length[..., None] * np.stack([np.cos(direction),
                                                      np.sin(direction)], axis=-1),
        "heading": heading,
        "contact": contact,
        "contact_distance": np.where(contact, rng.uniform(0.005, 0.05, contact.shape), 0.0),
        "contact_angle": np.where(contact, rng.uniform(-np.pi, np.pi, contact.shape), 0.0),
    }


def test_sensed_noise_has_the_magnitudes_of_the_noise_model():
    """Each sensed quantity deviates from the truth with the model's s.d. (and no bias)."""
    rng = np.random.default_rng(3)
    n_trials, n_steps = 200, 500
    motion = _synthetic_motion(rng, n_trials, n_steps)
    model = NoiseModel()
    heading0 = rng.uniform(-np.pi, np.pi, n_trials)
    z = rng.standard_normal((n_trials, N_NOISE_DRAWS, n_steps))
    inputs = sense(motion, model, z, heading0)
    assert inputs.shape == (n_trials, n_steps, len(FEATURES)) and inputs.dtype == np.float32
    col = {name: inputs[..., k].astype(np.float64) for k, name in enumerate(FEATURES)}

    true = motion["displacement"]
    gain = np.hypot(col["dx"], col["dy"]) / np.linalg.norm(true, axis=-1)
    rotation = wrap_angle(np.arctan2(col["dy"], col["dx"])
                          - np.arctan2(true[..., 1], true[..., 0]))
    hd_error = wrap_angle(np.arctan2(col["sin_hd"], col["cos_hd"]) - motion["heading"])
    previous = np.concatenate([heading0[:, None], motion["heading"][:, :-1]], axis=1)
    turn_error = col["dhd"] - wrap_angle(motion["heading"] - previous)
    touched = motion["contact"]
    distance_error = (col["contact_distance"] - motion["contact_distance"])[touched]
    angle_error = wrap_angle(np.arctan2(col["sin_beta"], col["cos_beta"])
                             - motion["contact_angle"])[touched]

    for error, mean, sd in ((gain, 1.0, model.speed_sd),
                            (rotation, 0.0, model.rotation_sd),
                            (hd_error, 0.0, model.head_direction_sd),
                            (turn_error, 0.0, model.turn_sd),
                            (distance_error, 0.0, model.contact_distance_sd),
                            (angle_error, 0.0, model.contact_angle_sd)):
        # |1 + speed_sd z| is a folded normal, but 1 + 0.18 z < 0 has probability 1e-8
        assert error.mean() == pytest.approx(mean, abs=5 * sd / np.sqrt(error.size))
        assert error.std() == pytest.approx(sd, rel=0.03)
    # noise is independent across steps
    rho = np.corrcoef(hd_error[:, 1:].ravel(), hd_error[:, :-1].ravel())[0, 1]
    assert abs(rho) < 0.01
    # no contact, no contact input
    for name in ("contact_distance", "cos_beta", "sin_beta"):
        assert (col[name][~touched] == 0).all()
    np.testing.assert_array_equal(col["contact"], touched)


def test_a_noiseless_model_senses_the_truth_exactly():
    rng = np.random.default_rng(4)
    motion = _synthetic_motion(rng, 5, 50)
    heading0 = rng.uniform(-np.pi, np.pi, 5)
    z = rng.standard_normal((5, N_NOISE_DRAWS, 50))
    inputs = sense(motion, NoiseModel.noiseless(), z, heading0)
    np.testing.assert_allclose(inputs[..., :2], motion["displacement"], rtol=1e-6, atol=1e-9)
    touched = motion["contact"]
    np.testing.assert_allclose(inputs[..., 6][touched], motion["contact_distance"][touched],
                               rtol=1e-6)


@given(st.floats(-1e4, 1e4, allow_nan=False))
def test_wrap_angle_lands_in_minus_pi_to_pi_and_keeps_the_direction(angle):
    wrapped = wrap_angle(angle)
    assert -np.pi <= wrapped < np.pi
    assert np.cos(wrapped) == pytest.approx(np.cos(angle), abs=1e-9)
    assert np.sin(wrapped) == pytest.approx(np.sin(angle), abs=1e-9)


def test_features_name_every_input_column():
    batch = make_trials("localization", 2, "validation", 0)
    assert batch.inputs.shape[-1] == len(FEATURES) == len(set(FEATURES))
    assert batch.features == FEATURES
    np.testing.assert_array_equal(batch.feature("contact"), batch.contact)
    with pytest.raises(ValueError, match=r"`name`.*'speed'"):
        batch.feature("speed")


@pytest.mark.parametrize("name", ["speed_sd", "rotation_sd", "head_direction_sd", "turn_sd",
                                  "contact_distance_sd", "contact_angle_sd"])
def test_negative_noise_raises_naming_parameter_and_value(name):
    with pytest.raises(ValueError, match=rf"`{name}`.*-0.1"):
        NoiseModel(**{name: -0.1})


def test_wrap_angle_just_below_minus_pi():
    assert wrap_angle(np.nextafter(-np.pi, -4.0)) < np.pi
