"""Fixtures: small recordings shaped like the network's and like an animal's."""

import os

import numpy as np
import pytest

from hippo_probe.recording import annotate, from_arrays, stack_trials, trial_layout, validate
from hippo_probe.recording.layout import is_trial_aligned
from hippo_probe.recording.schema import COV

NWB_PATH = __import__("pathlib").Path(__file__).parents[1] / "data" / "A2929-200711.nwb"


def make_network_recording(n_steps=40, n_trials=6, n_units=12, n_env=3, seed=0):
    """A recording with every optional variable ``record(network, batch)`` produces."""
    rng = np.random.default_rng(seed)
    env = np.arange(n_trials) % n_env
    rec = trial_layout(n_steps, n_trials, 0.4, trial_id=np.arange(n_trials) * 3 + 5,
                       environment=env, start_position=rng.uniform(-0.3, 0.3, (n_trials, 2)),
                       task="specialized", seed=seed, checkpoint="specialized.pt")
    rec = rec.assign_coords(unit=np.arange(n_units), environment_id=np.arange(n_env),
                            cov=np.array(COV, dtype=object))
    angle = rng.uniform(-np.pi, np.pi, (n_steps, n_trials))
    prob = rng.random((n_steps * n_trials, n_env))
    rec["activity"] = ("time", "unit"), np.tanh(
        stack_trials(rng.standard_normal((n_steps, n_trials, n_units)))).astype(np.float32)
    rec["position"] = ("time", "space"), stack_trials(
        rng.uniform(-0.3, 0.3, (n_steps, n_trials, 2)))
    rec["estimate"] = ("time", "space"), rec.position.values + 0.01
    rec["head_direction"] = "time", stack_trials(angle)
    rec["contact"] = "time", stack_trials(rng.random((n_steps, n_trials)) < 0.05)
    rec["pf_cov"] = ("time", "cov"), rng.random((n_steps * n_trials, 3))
    rec["class_probability"] = ("time", "environment_id"), (
        prob / prob.sum(1, keepdims=True)).astype(np.float32)
    rec["readout_weight"] = ("environment_id", "unit"), rng.standard_normal(
        (n_env, n_units)).astype(np.float32)
    rec["arena_vertices"] = ("environment_id", "vertex", "space"), rng.uniform(
        -0.4, 0.4, (n_env, 10, 2))
    return validate(annotate(rec))


def make_animal_recording(n=3000, seed=0):
    """Three trials of a tracked animal with spikes, NaN gaps, string unit coords."""
    rng = np.random.default_rng(seed)
    dt = 0.01
    time = np.concatenate([np.arange(1000) * dt + k * 12.0 for k in range(3)])[:n]
    position = rng.uniform(0, 80, (time.size, 2))
    position[100:120] = np.nan
    spikes = [np.sort(rng.uniform(0, 36, 200)) for _ in range(4)]
    return from_arrays(time, position, spike_times=spikes,
                       head_direction=rng.uniform(-4, 4, time.size),
                       trial=np.repeat([0, 1, 2], 1000)[:n],
                       environment=np.repeat([0, 0, 1], 1000)[:n],
                       unit={"unit": np.array(["u1", "u2", "u3", "u4"]),
                             "region": np.array(["ca1", "ca1", "adn", "adn"])},
                       position_units="cm", subject="m1", species="Mus musculus")


def spy_chunk_files(monkeypatch, method):
    """Record the names of the variables on which ``ChunkFiles.<method>`` ran, and the
    flags of every file the chunk-file module opened: ``{"names": set, "flags": list}``."""
    from hippo_probe.recording import chunk_files

    seen = {"names": set(), "flags": []}
    original, os_open = getattr(chunk_files.ChunkFiles, method), os.open

    def counted(self, *args, **kwargs):
        seen["names"].add(self.name)
        return original(self, *args, **kwargs)

    def opened(path, flags, *args, **kwargs):
        seen["flags"].append(flags)
        return os_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(chunk_files.ChunkFiles, method, counted)
    monkeypatch.setattr(chunk_files.os, "open", opened)
    return seen


def assert_trial_aligned(trial, chunks):
    """Each chunk along time holds whole trials or a piece of a single trial."""
    edges = np.cumsum((0,) + tuple(chunks))
    assert edges[-1] == trial.size
    for a, b in zip(edges[:-1], edges[1:]):
        whole = ((a == 0 or trial[a - 1] != trial[a])
                 and (b == trial.size or trial[b] != trial[b - 1]))
        assert whole or np.unique(trial[a:b]).size == 1, (a, b)
    assert is_trial_aligned(trial, chunks)


@pytest.fixture
def network_recording():
    return make_network_recording()


@pytest.fixture
def animal_recording():
    return make_animal_recording()
