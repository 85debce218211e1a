"""Trials in hand-made arenas, simulated by the world's own motion and sensor models."""

from dataclasses import replace

import numpy as np
import pytest

from hippo_probe.tasks import TrialBatch, task_config
from hippo_probe.world import sample_uniform, sense, simulate_motion, wall_distance
from hippo_probe.world.sensors import N_NOISE_DRAWS, heading_drift


def trials_in(vertices, n_trials, seed=0, n_steps=None, task="localization",
              world="darkness"):
    """``n_trials`` trials of ``task`` in ``world`` in the polygon ``vertices`` (V, 2),
    starts uniform at least the touch range from the walls; a TrialBatch in the arena
    frame."""
    config = task_config(task, world)
    world = config.world
    motion = world.motion
    if n_steps is not None:
        motion = replace(motion, n_steps=n_steps)
        world = replace(world, motion=motion)
        config = replace(config, world=world)
    rng = np.random.default_rng(seed)
    verts = np.repeat(np.asarray(vertices, float)[None], n_trials, axis=0)
    starts = []
    while len(starts) < n_trials:
        p = sample_uniform(vertices, rng, 64)
        d, _, _ = wall_distance(vertices, p)
        starts.extend(p[d >= world.sensors.touch_range][: n_trials - len(starts)])
    start = np.array(starts)
    heading0 = rng.uniform(-np.pi, np.pi, n_trials)
    n_fine = motion.n_steps * motion.substeps
    sim = simulate_motion(verts, start, heading0, rng.standard_normal((n_trials, n_fine)),
                          rng.standard_normal((n_trials, n_fine)), motion, world.sensors)
    draws = rng.standard_normal((n_trials, N_NOISE_DRAWS, motion.n_steps))
    drift = heading_drift(world.noise, rng.standard_normal((n_trials, motion.n_steps)),
                          motion.network_dt)
    inputs = sense(sim, world.noise, draws, heading0, drift)
    position = sim["position"].transpose(1, 0, 2)
    return TrialBatch(
        inputs=np.ascontiguousarray(inputs.transpose(1, 0, 2)), target=position.copy(),
        position=position, start=start, head_direction=sim["heading"].T,
        heading_drift=drift.T, contact=sim["contact"].T,
        environment=np.zeros(n_trials, np.int64), arena_vertices=verts,
        trial_index=np.arange(n_trials), dt=motion.network_dt, task=task, split="test",
        seed=seed, config=config)


@pytest.fixture(scope="session")
def make_trials_in():
    return trials_in
