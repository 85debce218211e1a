"""Turn what happened (true motion and contacts) into what the rat senses (noisy inputs).

The generative noise model is :class:`~hippo_probe.world.config.NoiseModel`; columns of the
result are :data:`~hippo_probe.world.config.FEATURES`.
"""

from __future__ import annotations

import numpy as np

from .._angles import wrap_angle
from .config import FEATURES, NoiseModel

#: Standard normal draws needed per trial and network step (rows of ``noise_draws``).
N_NOISE_DRAWS = 6


def heading_drift(noise: NoiseModel, drift_draws: np.ndarray | None,
                  dt: float) -> np.ndarray | None:
    r"""The heading drift :math:`\eta_t` (B, T) of trials, rad: a Wiener process from 0,
    :math:`\eta_t = \sigma_\eta \sqrt{dt} \sum_{u \le t} z_u`
    (:attr:`~hippo_probe.world.config.NoiseModel.heading_drift`).

    Parameters
    ----------
    noise : NoiseModel
    drift_draws : (B, T) standard normal draws, or None for no drift (then None is
        returned: the compass world draws none).
    dt : float
        Network step (s).
    """
    if drift_draws is None:
        return None
    return noise.heading_drift * np.sqrt(dt) * np.cumsum(drift_draws, axis=1)


def sense(motion: dict, noise: NoiseModel, noise_draws: np.ndarray,
          initial_heading: np.ndarray, drift: np.ndarray | None = None) -> np.ndarray:
    r"""Noisy network inputs (B, T, F) from a simulation (see ``simulate_motion``).

    Parameters
    ----------
    motion : dict
        Output of :func:`~hippo_probe.world.motion.simulate_motion` (arrays (B, T, ...)).
    noise : NoiseModel
    noise_draws : (B, 6, T) standard normal draws, one row per noise source in the order
        speed, rotation, head direction, turn, contact distance, contact angle.
    initial_heading : (B,) heading before the first step (for the first heading change).
    drift : (B, T), optional
        The heading drift :math:`\eta_t` at the end of each step (:func:`heading_drift`);
        None (the compass world) is no drift. It rotates the sensed displacement and
        shifts the sensed heading and turn; touch is egocentric and does not drift.
    """
    z = noise_draws
    disp = motion["displacement"]
    heading = motion["heading"]
    touched = motion["contact"]
    if drift is None:
        frame, turn_drift = 0.0, 0.0
    else:
        frame = drift
        turn_drift = np.diff(drift, axis=1, prepend=0.0)   # eta_0 = 0: oriented at start
    # each column is written straight into the float32 result (no float64 stack of all)
    out = np.empty(heading.shape + (len(FEATURES),), dtype=np.float32)
    col = {name: k for k, name in enumerate(FEATURES)}

    gain = 1.0 + noise.speed_sd * z[:, 0]
    rot = noise.rotation_sd * z[:, 1] + frame
    c, s = np.cos(rot), np.sin(rot)
    out[..., col["dx"]] = gain * (c * disp[..., 0] - s * disp[..., 1])
    out[..., col["dy"]] = gain * (s * disp[..., 0] + c * disp[..., 1])

    hd = heading + frame + noise.head_direction_sd * z[:, 2]
    out[..., col["cos_hd"]] = np.cos(hd)
    out[..., col["sin_hd"]] = np.sin(hd)
    previous = np.concatenate([initial_heading[:, None], heading[:, :-1]], axis=1)
    out[..., col["dhd"]] = (wrap_angle(heading - previous) + turn_drift
                            + noise.turn_sd * z[:, 3])

    out[..., col["contact"]] = touched
    out[..., col["contact_distance"]] = np.where(
        touched, motion["contact_distance"] + noise.contact_distance_sd * z[:, 4], 0.0)
    beta = motion["contact_angle"] + noise.contact_angle_sd * z[:, 5]
    out[..., col["cos_beta"]] = np.where(touched, np.cos(beta), 0.0)
    out[..., col["sin_beta"]] = np.where(touched, np.sin(beta), 0.0)
    return out
