"""The contact model against the world it inverts."""

import numpy as np
import pytest

from hippo_probe.baselines import ContactModelConfig
from hippo_probe.baselines.contact import (ContactModel, Observations,
                                           post_contact_turn_variance, wall_angle_error,
                                           wall_table)
from hippo_probe.tasks import make_trials, task_config
from hippo_probe.world import (WORLDS, MotionConfig, NoiseModel, WorldConfig,
                               inward_normals, random_arena)


def test_turn_variance_matches_a_simulation():
    motion = MotionConfig()
    rng = np.random.default_rng(0)
    dt, tau, n = motion.fine_dt, motion.turn_tau, 200_000
    gain = motion.turn_sd * np.sqrt(2 * dt / tau)
    k = rng.integers(0, motion.substeps, n)              # fine steps left after a contact
    w, turn = np.zeros(n), np.zeros(n)
    for step in range(motion.substeps):
        live = step < k
        w = np.where(live, w - w * dt / tau + gain * rng.standard_normal(n), w)
        turn = np.where(live, turn + w * dt, turn)
    assert np.isclose(turn.var(), post_contact_turn_variance(motion), rtol=0.03)


def test_wall_table_geometry():
    v = random_arena(np.random.default_rng(1), 10, 0.33).vertices
    table = wall_table(v)
    assert np.allclose(table[:, 5:7], inward_normals(v))
    assert np.allclose(np.arctan2(table[:, 6], table[:, 5]), table[:, 7])
    assert np.allclose(table[:, 0:2] + table[:, 2:4], np.roll(v, -1, axis=0))


@pytest.mark.parametrize("world", WORLDS)
def test_angle_of_the_true_wall_is_calibrated(world):
    """The sensed contact angle differs from the touched wall's predicted one by
    N(0, angle_sd^2), the prediction made from the sensed heading minus the true drift
    (what the particle filters' particle at the true drift computes). The touched wall is
    named by a noise-free twin of the trials (same seeds, noiseless sensors: the same
    paths)."""
    config = task_config("generalized", world)
    exact = task_config("generalized", world=WorldConfig(arena=config.world.arena,
                                                          noise=NoiseModel.noiseless()))
    batch = make_trials("generalized", 60, "train", 0, world=world)
    twin = make_trials("generalized", 60, "train", 0, config=exact)
    assert np.array_equal(batch.contact, twin.contact)
    obs, true = Observations.from_batch(batch), Observations.from_batch(twin)
    model = ContactModel.from_config(config.world, ContactModelConfig())
    walls = wall_table(batch.arena_vertices)                     # (B, V, 8)
    b, t = np.nonzero(obs.contact)
    touched = np.argmin(np.abs(wall_angle_error(walls[b, :, 7], true.heading[b, t, None],
                                                true.angle[b, t, None])), axis=1)
    believed = obs.heading[b, t] - batch.heading_drift[t, b]
    error = wall_angle_error(walls[b, touched, 7], believed, obs.angle[b, t])
    z = error / model.angle_sd
    assert len(z) > 3000
    assert abs(np.std(z) - 1) < 0.05 and abs(np.mean(z)) < 0.05
    assert abs(np.mean(np.abs(z) < 1.96) - 0.95) < 0.015
    if world == "darkness":     # the sensed heading alone is off by the drift
        drifting = wall_angle_error(walls[b, touched, 7], obs.heading[b, t], obs.angle[b, t])
        assert np.std(drifting / model.angle_sd) > 1.5
