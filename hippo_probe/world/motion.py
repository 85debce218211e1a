"""The rat's correlated random walk with boundary contacts, compiled with numba.

One call simulates many trials, each in its own arena, at the fine step and reports what
happened in each network step: true end position and heading, true displacement, and the
first boundary contact (distance and angle to the touched wall). All randomness is passed
in (drawn per trial by the caller), so a trial is a pure function of its own random
numbers, however trials are batched.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from .._angles import wrap_angle_scalar
from .config import MotionConfig, SensorConfig


#: Slack (m) for rounding in the far-from-walls shortcut of ``_simulate``: a move is taken
#: without the exact wall test only if it provably ends more than the touch range plus
#: this from every wall; rounding errors are ~1e-16 m, so the shortcut never changes a
#: decision (trials are bit-identical with and without it).
_CLEAR_MARGIN = 1e-9


@numba.njit(cache=True, fastmath=False, inline="always")
def _nearest_wall(verts, px, py):
    """Distance to the nearest wall, its index, and whether (px, py) is inside."""
    n = verts.shape[0]
    best = np.inf
    best_k = 0
    inside = False
    for k in range(n):
        ax, ay = verts[k, 0], verts[k, 1]
        j = k + 1 if k + 1 < n else 0
        bx, by = verts[j, 0], verts[j, 1]
        ex, ey = bx - ax, by - ay
        t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
        t = min(max(t, 0.0), 1.0)
        dx, dy = px - (ax + t * ex), py - (ay + t * ey)
        d2 = dx * dx + dy * dy
        if d2 < best:
            best, best_k = d2, k
        if (ay > py) != (by > py):
            if px < ax + (py - ay) * ex / ey:
                inside = not inside
    return math.sqrt(best), best_k, inside


@numba.njit(cache=True, parallel=True)
def _simulate(verts, start, heading0, speed_noise, turn_noise, n_steps, substeps,
              fine_dt, mean_speed, speed_sd, speed_tau, min_speed, max_speed, turn_sd,
              turn_tau, touch_range, min_clearance):
    n_trials = verts.shape[0]
    n_verts = verts.shape[1]
    pos = np.empty((n_trials, n_steps, 2))
    heading = np.empty((n_trials, n_steps))
    disp = np.empty((n_trials, n_steps, 2))
    contact = np.zeros((n_trials, n_steps), dtype=np.bool_)
    c_dist = np.zeros((n_trials, n_steps))
    c_beta = np.zeros((n_trials, n_steps))
    speed_gain = speed_sd * math.sqrt(2.0 * fine_dt / speed_tau)
    turn_gain = turn_sd * math.sqrt(2.0 * fine_dt / turn_tau)
    for b in numba.prange(n_trials):
        v = verts[b]
        x, y = start[b, 0], start[b, 1]
        th = heading0[b]
        s = mean_speed
        w = 0.0
        k = 0
        clear = -1.0        # a lower bound of the distance from (x, y) to every wall
        for t in range(n_steps):
            x0, y0 = x, y
            touched = False
            for _ in range(substeps):
                s += (mean_speed - s) * fine_dt / speed_tau + speed_gain * speed_noise[b, k]
                s = min(max(s, min_speed), max_speed)
                w += -w * fine_dt / turn_tau + turn_gain * turn_noise[b, k]
                th += w * fine_dt
                k += 1
                ux, uy = math.cos(th), math.sin(th)
                nx_, ny_ = x + s * fine_dt * ux, y + s * fine_dt * uy
                step = s * fine_dt
                if clear - step > touch_range + _CLEAR_MARGIN:
                    # Far from every wall: the move ends inside, out of touch range, so
                    # the exact test below could only say "go on"; skip it.
                    x, y = nx_, ny_
                    clear -= step
                    continue
                d, wall, inside = _nearest_wall(v, nx_, ny_)
                refused = not inside or d < min_clearance
                if refused:
                    # refuse the step (sharp corner): stay, feel the wall at our position
                    d, wall, inside = _nearest_wall(v, x, y)
                    nx_, ny_ = x, y
                x, y = nx_, ny_
                clear = d
                if d >= touch_range:
                    continue
                j = wall + 1 if wall + 1 < n_verts else 0
                ex, ey = v[j, 0] - v[wall, 0], v[j, 1] - v[wall, 1]
                el = math.sqrt(ex * ex + ey * ey)
                nnx, nny = -ey / el, ex / el          # inward normal (CCW polygon)
                toward = refused or ux * nnx + uy * nny < 0.0
                if toward:
                    if not touched:
                        touched = True
                        contact[b, t] = True
                        c_dist[b, t] = d
                        # angle from the wall's inward normal to the heading
                        c_beta[b, t] = math.atan2(nnx * uy - nny * ux, nnx * ux + nny * uy)
                    # turn away: specular reflection of the heading off the wall
                    dot = ux * nnx + uy * nny
                    if dot < 0.0:
                        th = math.atan2(uy - 2.0 * dot * nny, ux - 2.0 * dot * nnx)
                    else:
                        th = math.atan2(nny, nnx)
                    w = 0.0
            # keep the heading in [-pi, pi)
            th = wrap_angle_scalar(th)
            pos[b, t, 0], pos[b, t, 1] = x, y
            heading[b, t] = th
            disp[b, t, 0], disp[b, t, 1] = x - x0, y - y0
    return pos, heading, disp, contact, c_dist, c_beta


def simulate_motion(vertices, start, heading0, speed_noise, turn_noise,
                    motion: MotionConfig, sensors: SensorConfig) -> dict:
    """Simulate trials of the random walk; see the module docstring.

    Parameters
    ----------
    vertices : (B, V, 2) arena of each trial (counter-clockwise, metres)
    start : (B, 2) start positions, inside the arenas
    heading0 : (B,) initial headings (rad)
    speed_noise, turn_noise : (B, n_steps * substeps) standard normal draws

    Returns
    -------
    dict of arrays with leading dims (B, T): ``position`` (B, T, 2) at the end of each
    network step, ``heading`` (B, T), ``displacement`` (B, T, 2) over the step, ``contact``
    (B, T) bool, ``contact_distance`` and ``contact_angle`` (B, T) of the step's first
    contact (0 where none).
    """
    n_fine = motion.n_steps * motion.substeps
    for name, arr in (("speed_noise", speed_noise), ("turn_noise", turn_noise)):
        if arr.shape != (len(vertices), n_fine):
            raise ValueError(f"`{name}` must have shape ({len(vertices)}, {n_fine}); "
                             f"got {arr.shape}")
    out = _simulate(np.ascontiguousarray(vertices, dtype=np.float64),
                    np.ascontiguousarray(start, dtype=np.float64),
                    np.ascontiguousarray(heading0, dtype=np.float64),
                    np.ascontiguousarray(speed_noise, dtype=np.float64),
                    np.ascontiguousarray(turn_noise, dtype=np.float64),
                    motion.n_steps, motion.substeps, motion.fine_dt, motion.mean_speed,
                    motion.speed_sd, motion.speed_tau, motion.min_speed, motion.max_speed,
                    motion.turn_sd, motion.turn_tau, sensors.touch_range,
                    sensors.min_clearance)
    keys = ("position", "heading", "displacement", "contact", "contact_distance",
            "contact_angle")
    return dict(zip(keys, out))
