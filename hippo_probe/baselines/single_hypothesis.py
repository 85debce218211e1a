"""Single hypothesis (SH): path integration with a hard reset onto a wall at each contact."""

from __future__ import annotations

import numpy as np

from .._docs import fill_doc
from ..tasks import TaskConfig
from ._common import BaselineResult, provenance, resolve_start, resolve_task, start_guess
from .config import BaselineConfig
from .contact import ContactModel, Observations, mean_retreat, wall_angle_error, wall_table
from .path_integration import to_target_frame


@fill_doc
def single_hypothesis(batch, *, start: str | None = None, config: TaskConfig | None = None,
                      baseline: BaselineConfig | None = None) -> BaselineResult:
    r"""Path integration that jumps onto the most plausible wall position at each contact.

    One position hypothesis :math:`\hat x` (arena known, like the particle filter's) is
    integrated from the sensed displacements. At a contact it is replaced by the nearest
    point consistent with what was sensed:

    1. candidate walls are those whose inward normal :math:`\phi_k` agrees with the
       sensed angle, :math:`|\mathrm{wrap}(\beta - (\phi_k + \pi - h))| \le g\,\sigma`
       (``g = single_hypothesis_gate``, :math:`\sigma` the contact model's angle s.d.,
       see :mod:`~hippo_probe.baselines.contact`); if none agrees, the best-agreeing
       wall;
    2. on each candidate wall, the point of the wall nearest to :math:`\hat x`, moved
       inwards by the expected end-of-step distance :math:`d + (S - 1)\Delta_k / 2`
       (sensed distance plus the mean retreat after the contact);
    3. :math:`\hat x` jumps to the nearest of these points.

    No uncertainty is carried: a reset onto the wrong wall is believed until the next
    contact. In the darkness world :math:`h` is the sensed, drifting heading (the
    hypothesis does not estimate the drift), so its resets go wrong more and more often as
    the drift grows.

    Parameters
    ----------
    %(batch)s
    start : {"known", "unknown"}, optional
        Default: unknown (start prior's mean) for localization, known otherwise.
    %(baseline_config)s

    Returns
    -------
    BaselineResult
        ``estimate`` (T, B, 2) in the task's target frame.

    References
    ----------
    Cheung, A., Ball, D., Milford, M., Wyeth, G., & Wiles, J. (2012). PLoS Comput Biol
    8:e1002651 (the single-hypothesis boundary-reset model they compare with particle
    filters).

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> batch = make_trials("specialized", n_trials=2, split="test")
    >>> single_hypothesis(batch).estimate.shape
    (500, 2, 2)
    """
    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    start = resolve_start(start, config)
    model = ContactModel.from_config(config.world, baseline.contact)
    gate = baseline.contact.single_hypothesis_gate * model.angle_sd
    obs = Observations.from_batch(batch)
    walls = wall_table(batch.arena_vertices)                     # (B, V, 8)
    origin, _ = start_guess(batch, config, start, baseline)
    estimate = origin.copy()
    track = np.empty((batch.n_steps, len(batch), 2))
    n_resets = np.zeros(len(batch), dtype=np.int64)
    for t in range(batch.n_steps):
        estimate += obs.displacement[:, t]
        touched = np.flatnonzero(obs.contact[:, t])
        if touched.size:
            heading, angle = obs.heading[touched, t, None], obs.angle[touched, t, None]
            offset = obs.distance[touched, t, None] + mean_retreat(
                model, walls[touched, :, 7], heading, angle, obs.path_length[touched, t, None])
            estimate[touched] = _reset(estimate[touched], walls[touched], heading, angle,
                                       offset, gate)
            n_resets[touched] += 1
        track[t] = estimate
    return BaselineResult("sh", to_target_frame(track, origin, config),
                          attrs=provenance("sh", batch, start=start,
                                           gate_rad=float(gate),
                                           mean_resets=float(n_resets.mean())))


def _reset(points, walls, heading, angle, offset, gate):
    """New hypotheses (n, 2) for n contacts: see :func:`single_hypothesis`, steps 1-3."""
    error = np.abs(wall_angle_error(walls[..., 7], heading, angle))
    candidate = error <= gate
    best = np.argmin(error, axis=1)
    candidate[np.arange(len(points)), best] |= ~candidate.any(axis=1)
    a, e, n = walls[..., 0:2], walls[..., 2:4], walls[..., 5:7]
    p = points[:, None, :]
    along = np.clip(np.sum((p - a) * e, axis=-1) * walls[..., 4], 0.0, 1.0)
    target = a + along[..., None] * e + offset[..., None] * n
    jump = np.where(candidate, np.linalg.norm(target - p, axis=-1), np.inf)
    return target[np.arange(len(points)), np.argmin(jump, axis=1)]
