"""Trials in hand-made arenas, simulated by the world's own motion and sensor models."""

import numpy as np
import pytest

from hippo_probe.tasks import TrialBatch, task_config
from hippo_probe.world import sample_uniform, sense, simulate_motion, wall_distance
from hippo_probe.world.sensors import N_NOISE_DRAWS


def trials_in(vertices, n_trials, seed=0, n_steps=None, task="localization"):
    """``n_trials`` trials of ``task``'s world in the polygon ``vertices`` (V, 2), starts
    uniform at least the touch range from the walls; a TrialBatch in the arena frame."""
    config = task_config(task)
    world = config.world
    motion = world.motion
    if n_steps is not None:
        from dataclasses import replace
        motion = replace(motion, n_steps=n_steps)
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
    inputs = sense(sim, world.noise, rng.standard_normal((n_trials, N_NOISE_DRAWS,
                                                           motion.n_steps)), heading0)
    position = sim["position"].transpose(1, 0, 2)
    return TrialBatch(
        inputs=np.ascontiguousarray(inputs.transpose(1, 0, 2)), target=position.copy(),
        position=position, start=start, head_direction=sim["heading"].T,
        contact=sim["contact"].T, environment=np.zeros(n_trials, np.int64),
        arena_vertices=verts, trial_index=np.arange(n_trials), dt=motion.network_dt,
        task=task, split="test", seed=seed)


@pytest.fixture(scope="session")
def make_trials_in():
    return trials_in
