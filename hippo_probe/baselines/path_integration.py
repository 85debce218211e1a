"""Path integration (PI): sum the sensed displacements, ignore every boundary."""

from __future__ import annotations

import numpy as np

from .._docs import fill_doc
from ..tasks import TaskConfig
from ._common import BaselineResult, provenance, resolve_start, resolve_task, start_guess
from .config import BaselineConfig


@fill_doc
def path_integration(batch, *, start: str | None = None, config: TaskConfig | None = None,
                     baseline: BaselineConfig | None = None) -> BaselineResult:
    r"""Dead reckoning from the sensed self-motion.

    .. math:: \hat x_t = \hat x_0 + \sum_{u \le t} D^{obs}_u

    with :math:`\hat x_0` the start (0 in the start-relative frame of the generalized
    task) or, when the start is unknown (localization), the mean of the start prior
    (uniform in the arena at least the touch range from its walls). Noise-free inputs give
    the exact trajectory; every error comes from the noise model (its variance grows
    linearly in time, Cheung et al. 2012).

    Parameters
    ----------
    %(batch)s
    start : {"known", "unknown"}, optional
        Default: unknown for the localization task, known otherwise.
    %(baseline_config)s

    Returns
    -------
    BaselineResult
        ``estimate`` (T, B, 2) in the task's target frame.

    References
    ----------
    Cheung, A., Ball, D., Milford, M., Wyeth, G., & Wiles, J. (2012). PLoS Comput Biol
    8:e1002651.

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> batch = make_trials("generalized", n_trials=2, split="test")
    >>> path_integration(batch).estimate.shape
    (500, 2, 2)
    """
    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    start = resolve_start(start, config)
    origin, _ = start_guess(batch, config, start, baseline)
    track = origin[None] + np.cumsum(displacements(batch), axis=0)
    return BaselineResult("pi", to_target_frame(track, origin, config),
                          attrs=provenance("pi", batch, start=start))


def displacements(batch) -> np.ndarray:
    """Sensed displacement of each step (T, B, 2), float64."""
    return np.stack([batch.feature("dx"), batch.feature("dy")], axis=-1).astype(np.float64)


def to_target_frame(track, origin, config: TaskConfig) -> np.ndarray:
    """Arena-frame positions (T, B, 2) in the task's target frame, relative to the start
    ``origin`` (B, 2) the method itself assumed (never the true start it may not know)."""
    if config.target == "start_relative":
        return track - origin[None]
    return track
