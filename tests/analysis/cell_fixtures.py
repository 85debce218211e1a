"""Synthetic cells whose class is known: grid, border, place, head-direction, speed,
conjunctive and random units, on trajectories with varying speed (shared by the tests of
the cell-class analyses)."""

from __future__ import annotations

import numpy as np

from hippo_probe.analysis.border_score import inside_polygon

from .conftest import HALF, SQUARE, make_recording

#: An irregular convex pentagon (m): its walls are not aligned with the bins.
PENTAGON = np.array([[-0.5, -0.4], [0.45, -0.5], [0.55, 0.2], [0.0, 0.55], [-0.5, 0.3]])


def square_walk(n, rng, *, dt=0.1, half=HALF, mean_speed=0.2, speed_tau=3.0, turn=0.6):
    """A random walk reflected in the square [-half, half]^2 whose speed wanders
    (log-normal, correlation time ``speed_tau`` s). Returns position, heading, speed."""
    a = np.exp(-dt / speed_tau)
    z = np.empty(n)
    z[0] = rng.normal()
    noise = rng.normal(size=n) * np.sqrt(1 - a * a)
    for t in range(1, n):
        z[t] = a * z[t - 1] + noise[t]
    speed = mean_speed * np.exp(0.6 * z - 0.18)
    heading = np.cumsum(rng.normal(0, turn * np.sqrt(dt), n)) + rng.uniform(-np.pi, np.pi)
    step = (speed * dt)[:, None] * np.c_[np.cos(heading), np.sin(heading)]
    raw = rng.uniform(-half, half, 2) + np.cumsum(step, axis=0)
    period = 4 * half
    folded = np.mod(raw + half, period)
    pos = np.where(folded > 2 * half, period - folded, folded) - half
    return pos, heading, speed


def polygon_walk(n, rng, polygon, *, dt=0.1, speed=0.2, turn=0.6):
    """A random walk that never leaves a polygon: a step that would leave it is replaced
    by one in a new random direction. Returns position and heading."""
    lo, hi = polygon.min(0), polygon.max(0)
    p = (lo + hi) / 2
    heading = rng.uniform(-np.pi, np.pi)
    pos, hd = np.empty((n, 2)), np.empty(n)
    turns = rng.normal(0, turn * np.sqrt(dt), n)
    for t in range(n):
        heading += turns[t]
        for _ in range(50):
            q = p + speed * dt * np.array([np.cos(heading), np.sin(heading)])
            if inside_polygon(q[None], polygon)[0]:
                break
            heading = rng.uniform(-np.pi, np.pi)
        else:
            q = p
        p = q
        pos[t], hd[t] = p, heading
    return pos, hd


def hex_rate(pos, spacing, orientation, phase=(0.03, -0.05), gain=0.9):
    """A hexagonal grid: its fields lie on a triangular lattice of ``spacing`` (m) whose
    axes point at ``orientation`` (rad, counter-clockwise from +x) and +60, +120 deg.

    Sum of three plane waves whose wave vectors are 30 deg off the lattice axes (Solstad,
    Moser & Einevoll 2006); peak rate 1."""
    k = 4 * np.pi / (np.sqrt(3) * spacing)
    total = 0.0
    for a in (0, 60, 120):
        t = orientation + np.radians(30 + a)
        total = total + np.cos(k * ((pos[:, 0] - phase[0]) * np.cos(t)
                                    + (pos[:, 1] - phase[1]) * np.sin(t)))
    return np.exp(gain * (total - 3))


def wall_rate(pos, a, b, width=0.05):
    """Fires along the wall (segment a-b): exp(-distance to its line / width)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    normal = np.array([-d[1], d[0]]) / np.hypot(*d)
    return np.exp(-np.abs((pos - a) @ normal) / width)


def ou(n, rng, n_units, *, dt=0.1, tau=5.0):
    """Ornstein-Uhlenbeck activity (time, unit), unrelated to behaviour: random units."""
    a = np.exp(-dt / tau)
    x = np.empty((n, n_units))
    x[0] = rng.normal(size=n_units)
    noise = rng.normal(size=(n, n_units)) * np.sqrt(1 - a * a)
    for t in range(1, n):
        x[t] = a * x[t - 1] + noise[t]
    return x


def gaussian(pos, centre, width):
    return np.exp(-((pos - np.asarray(centre)) ** 2).sum(-1) / (2 * width**2))


def mixed_population(n=30000, seed=0, activity_kind="rate", n_random=4):
    """One recording in the 1 m square with a unit of every class and random units.

    Units: 0 grid (0.4 m, 12 deg), 1 border (west wall), 2 place (one field),
    3 head direction, 4 speed, 5 conjunctive (place x direction), 6.. random.
    """
    rng = np.random.default_rng(seed)
    pos, heading, speed = square_walk(n, rng)
    hd = np.mod(heading + np.pi, 2 * np.pi) - np.pi
    units = [
        hex_rate(pos, 0.4, np.radians(12)),
        wall_rate(pos, SQUARE[3], SQUARE[0]),
        gaussian(pos, (0.2, 0.15), 0.08),
        np.exp(3 * (np.cos(hd - 1.0) - 1)),
        speed / speed.max(),
        gaussian(pos, (-0.2, -0.2), 0.1) * np.exp(2 * (np.cos(hd + 2.0) - 1)),
    ]
    act = np.c_[np.stack(units, 1), 0.3 + 0.1 * ou(n, rng, n_random)]
    if activity_kind == "lstm_hidden":
        act = np.tanh(2 * act - 1)
    return make_recording(pos, act, head_direction=heading, arena_vertices=SQUARE,
                          activity_kind=activity_kind)


NAMES = ["grid", "border", "place", "head_direction", "speed", "conjunctive"]
