"""Synthetic recordings (schema v1) whose right answers are known analytically."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.recording.schema import annotate

#: Half side (m) of the square arena of the synthetic recordings.
HALF = 0.5
SQUARE = np.array([[-HALF, -HALF], [HALF, -HALF], [HALF, HALF], [-HALF, HALF]])


def trajectory(n, rng, *, dt=0.1, speed=0.2, half=HALF, turn=0.6):
    """A smooth random walk reflected inside the square [-half, half]^2, and its heading."""
    heading = np.cumsum(rng.normal(0, turn * np.sqrt(dt), n)) + rng.uniform(-np.pi, np.pi)
    step = speed * dt * np.c_[np.cos(heading), np.sin(heading)]
    raw = rng.uniform(-half, half, 2) + np.cumsum(step, axis=0)
    period = 4 * half
    folded = np.mod(raw + half, period)
    pos = np.where(folded > 2 * half, period - folded, folded) - half
    return pos, heading


def make_recording(position, activity, *, dt=0.1, trial=None, environment=None,
                   head_direction=None, arena_vertices=None, activity_kind="rate",
                   source="network", unit=None, **variables):
    """A schema-v1 recording from per-sample arrays (trials separated by a gap of dt)."""
    n = len(position)
    trial = np.zeros(n, np.int64) if trial is None else np.asarray(trial)
    environment = np.zeros(n, np.int64) if environment is None else np.asarray(environment)
    new = np.r_[True, trial[1:] != trial[:-1]]
    time = (np.arange(n) + np.cumsum(new) - 1) * dt
    start_idx = np.flatnonzero(new)
    trial_time = time - time[start_idx][np.cumsum(new) - 1]
    ids = trial[start_idx]
    unit = np.arange(activity.shape[1]) if unit is None else unit
    data = {
        "activity": (("time", "unit"), np.asarray(activity, np.float32)),
        "position": (("time", "space"), position, {"units": "m", "long_name": "position"}),
    }
    table = {
        "trial_start": ("trial_id", time[start_idx], {"units": "s", "long_name": "trial start"}),
        "trial_stop": ("trial_id", time[np.r_[start_idx[1:] - 1, n - 1]],
                       {"units": "s", "long_name": "trial stop"}),
        "trial_environment": ("trial_id", environment[start_idx],
                              {"units": "1", "long_name": "environment of the trial"}),
        "start_position": (("trial_id", "space"), position[start_idx],
                           {"units": "m", "long_name": "start position"}),
    }
    if head_direction is not None:
        hd = np.mod(np.asarray(head_direction) + np.pi, 2 * np.pi) - np.pi
        data["head_direction"] = ("time", hd, {"units": "rad", "long_name": "head direction"})
    env_ids = np.unique(environment)
    if arena_vertices is not None:
        verts = np.broadcast_to(arena_vertices, (len(env_ids),) + np.shape(arena_vertices)[-2:])
        data["arena_vertices"] = (("environment_id", "vertex", "space"), np.array(verts),
                                  {"units": "m", "long_name": "arena vertices"})
    for name, value in variables.items():
        data[name] = value
    coords = {
        "time": ("time", time, {"units": "s", "long_name": "time"}),
        "unit": ("unit", unit, {"units": "1", "long_name": "unit"}),
        "space": ["x", "y"],
        "trial": ("time", trial, {"units": "1", "long_name": "trial"}),
        "trial_time": ("time", trial_time, {"units": "s", "long_name": "time in trial"}),
        "environment": ("time", environment, {"units": "1", "long_name": "environment"}),
        "trial_id": ("trial_id", ids, {"units": "1", "long_name": "trial id"}),
        "environment_id": ("environment_id", env_ids, {"units": "1", "long_name": "arena"}),
        **table,
    }
    attrs = dict(schema_version=1, source=source, activity_kind=activity_kind, dt=dt,
                 task="synthetic", seed=0, checkpoint="", session_id="synthetic",
                 subject="", species="", created_by="tests")
    rec = annotate(xr.Dataset(data, coords=coords, attrs=attrs))
    hp.validate(rec)  # the fixtures themselves must follow schema v1
    return rec


def gaussian_fields(position, centres, width):
    """Rates (time, unit) of Gaussian place fields exp(-|p - c|^2 / (2 width^2))."""
    d2 = ((position[:, None, :] - np.asarray(centres)[None]) ** 2).sum(-1)
    return np.exp(-d2 / (2 * width**2))


def place_cell_recording(centres, *, width=0.08, n_samples=20000, dt=0.1, seed=0,
                         activity_kind="rate", n_trials=1, baseline=0.0):
    """Units with Gaussian place fields at ``centres`` in the square arena.

    ``activity_kind="spike_count"`` draws Poisson counts with rate 10 Hz x field per
    sample; ``"lstm_hidden"`` maps the field to tanh(2 field - 1), signed in (-1, 1).
    """
    rng = np.random.default_rng(seed)
    pos, heading = trajectory(n_samples, rng, dt=dt)
    rate = baseline + gaussian_fields(pos, centres, width)
    if activity_kind == "spike_count":
        act = rng.poisson(10.0 * rate * dt).astype(np.float32)
    elif activity_kind == "lstm_hidden":
        act = np.tanh(2 * rate - 1)
    else:
        act = rate
    trial = np.repeat(np.arange(n_trials), -(-n_samples // n_trials))[:n_samples]
    return make_recording(pos, act, dt=dt, trial=trial, head_direction=heading,
                          arena_vertices=SQUARE, activity_kind=activity_kind)


def hd_cell_recording(preferred, kappa, *, n_samples=20000, dt=0.1, seed=0,
                      activity_kind="rate"):
    """Units with von Mises head-direction tuning exp(kappa (cos(theta - mu) - 1))."""
    rng = np.random.default_rng(seed)
    pos, heading = trajectory(n_samples, rng, dt=dt, turn=2.0)
    kappa = np.broadcast_to(kappa, np.shape(preferred))
    rate = np.exp(kappa[None] * (np.cos(heading[:, None] - np.asarray(preferred)[None]) - 1))
    if activity_kind == "spike_count":
        act = rng.poisson(20.0 * rate * dt).astype(np.float32)
    else:
        act = rate
    return make_recording(pos, act, dt=dt, head_direction=heading, arena_vertices=SQUARE,
                          activity_kind=activity_kind)


def random_maps(rng, n_units, n_fields=3, width=0.15):
    """Each unit's smooth random map: the sum of a few Gaussian bumps at random places."""
    centres = rng.uniform(-HALF, HALF, (n_units, n_fields, 2))
    heights = rng.uniform(0.5, 1.0, (n_units, n_fields))

    def rate(pos):
        d2 = ((pos[:, None, None, :] - centres[None]) ** 2).sum(-1)
        return (heights[None] * np.exp(-d2 / (2 * width**2))).sum(-1)

    return rate


def two_environment_recording(*, n_units=40, n_trials=12, samples_per_trial=1500, dt=0.1,
                              seed=0, noise=0.02):
    """Trials alternate between two environments whose maps are independent and random."""
    rng = np.random.default_rng(seed)
    maps = [random_maps(rng, n_units), random_maps(rng, n_units)]
    pos_all, act_all, trial, env = [], [], [], []
    for k in range(n_trials):
        pos, _ = trajectory(samples_per_trial, rng, dt=dt)
        e = k % 2
        pos_all.append(pos)
        act_all.append(maps[e](pos) + noise * rng.standard_normal((len(pos), n_units)))
        trial.append(np.full(len(pos), k))
        env.append(np.full(len(pos), e))
    return make_recording(np.concatenate(pos_all), np.concatenate(act_all), dt=dt,
                          trial=np.concatenate(trial), environment=np.concatenate(env),
                          arena_vertices=SQUARE, activity_kind="rate")


@pytest.fixture
def place_rec():
    centres = np.array([[-0.3, -0.2], [0.25, 0.3], [0.0, 0.0], [0.3, -0.3]])
    return place_cell_recording(centres), centres


@pytest.fixture(scope="module")
def place():
    """Three place cells (fields at known centres), 6,000 samples: the plot tests' data."""
    return place_cell_recording(np.array([[0.2, 0.2], [-0.2, 0.1], [0.0, -0.3]]),
                                n_samples=6000)


@pytest.fixture(autouse=True)
def _close_figures():
    """Figures made by a test do not pile up across tests."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
