r"""Naive Bayes (NB): path integration combined with a learnt prior over targets.

What a navigator could do without ever using a boundary contact: integrate its
self-motion, and shrink that estimate towards where targets usually are at this time of
a trial. Exactly:

* **Prior.** The distribution :math:`p_t(r)` of the task's target ``r`` (position minus
  start in the generalized task, the arena-frame position otherwise) ``t`` steps into a
  trial, across the task's ensemble of arenas and trajectories, estimated from
  ``prior_trials`` trials of the *training* split: a 2-D histogram on a ``G x G`` grid
  (cell ``h``), pooling steps ``t - w ... t + w`` (``w <= t``, so the first steps,
  where the prior widens quickly, pool only their neighbours), read as a mixture of
  isotropic Gaussian kernels of variance ``s^2 = h^2 / 12`` (that of a uniform cell) at
  the cell centres :math:`c_j` with the cell counts as weights :math:`\pi_{tj}`. The
  prior knows nothing of the trial's own arena (its walls are novel in the generalized
  task).
* **Likelihood.** Path integration gives :math:`m_t = \hat r_0 + \sum_{u \le t}
  D^{obs}_u` with an isotropic Gaussian error of per-axis variance

  .. math:: \sigma_t^2 = \tfrac12(\sigma_s^2 + \sigma_r^2) \sum_{u \le t}|D^{obs}_u|^2
            + \sigma_0^2,

  the first-order error of the multiplicative speed and rotation noise of
  :class:`~hippo_probe.world.config.NoiseModel` (independent steps), plus
  :math:`\sigma_0^2`, the per-axis variance of the start prior when the start is
  unknown (localization; :math:`\hat r_0` is then the start prior's mean), plus, in the
  darkness world, the error of the drifting heading frame. To first order each sensed
  step is off by :math:`\eta_u J D^{obs}_u` (``J`` the quarter turn) with
  :math:`\mathrm{E}[\eta_u\eta_v] = \sigma_\eta^2\,\delta t\,\min(u, v)`, so the
  errors of the steps are correlated and add up to a per-axis variance

  .. math:: \sigma_{\eta,t}^2 = \tfrac12\sigma_\eta^2\,\delta t \sum_{k=1}^{t}
            \big|P_t - P_{k-1}\big|^2,\qquad P_k = \sum_{u \le k} D^{obs}_u,

  (the path still to come after step ``k`` turned by the drift accumulated by then),
  computed from running sums in O(T). Measured on 400 generalized trials of the darkness
  world at 200 s, the drift term alone is within 15% of the drift's own error (0.035 vs
  0.031 m² per axis; the small-angle expansion overstates ``1 - cos``), but the sum of the
  two terms overstates PI's mean squared error by ~20% (0.096 vs 0.078 m²): the drift's
  shrinkage of the sensed path correlates with the speed noise's error. A naive
  reference keeps the independent-sum approximation.
* **Posterior mean.** Each kernel times the likelihood is Gaussian, so

  .. math:: \hat r_t = \frac{\sigma_t^2\,\bar c_t + s^2\,m_t}{\sigma_t^2 + s^2},\qquad
            \bar c_t = \frac{\sum_j \pi_{tj}\,\mathcal N(c_j; m_t, (\sigma_t^2 + s^2) I)
            \,c_j}{\sum_j \pi_{tj}\,\mathcal N(c_j; m_t, (\sigma_t^2 + s^2) I)},

  computed with separable Gaussians as two matrix products per step. Early in a trial
  (:math:`\sigma_t \ll h`) the estimate is path integration; late, it is pulled towards
  the bulk of the prior. If no prior cell has weight near the estimate (the weights
  underflow) the estimate stays path integration (counted in ``attrs``).

Boundary contacts, the trial's arena and the correlation of the prior across time are
ignored: this is the "naive" combination.

References
----------
Kanitscheider, I., & Fiete, I. (2017). NIPS 30 (the naive-Bayes reference of the
generalization task).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from .._docs import fill_doc
from ..tasks import TaskConfig, make_trials
from ._common import BaselineResult, provenance, resolve_start, resolve_task, start_guess
from .config import BaselineConfig, NaiveBayesConfig
from .path_integration import displacements


@dataclass(frozen=True)
class TargetPrior:
    """Histogram prior :math:`p_t(r)` of a task's targets (see the module docstring).

    Attributes
    ----------
    centres_x, centres_y : (G,) cell centres (m).
    counts : (T, G, G) pooled target counts per step, x along axis 1, y along axis 2.
    cell : float
        Cell size ``h`` (m).
    task, split : str
    seed, n_trials, time_window : int
    """

    centres_x: np.ndarray
    centres_y: np.ndarray
    counts: np.ndarray
    cell: float
    task: str
    split: str
    seed: int
    n_trials: int
    time_window: int

    @property
    def kernel_variance(self) -> float:
        """``h^2 / 12``: the variance of a uniform cell."""
        return self.cell ** 2 / 12.0


def target_prior(task: str, *, seed: int = 0, config: TaskConfig | None = None,
                 naive_bayes: NaiveBayesConfig | None = None) -> TargetPrior:
    """The prior over a task's targets at each step, from its training trials (cached).

    Examples
    --------
    >>> from hippo_probe.baselines.config import NaiveBayesConfig
    >>> prior = target_prior("generalized", naive_bayes=NaiveBayesConfig(prior_trials=50))
    >>> prior.counts.shape
    (500, 64, 64)
    """
    from ..tasks import task_config

    config = config or task_config(task)      # the darkness world unless given
    if config.name != task:
        raise ValueError(f"`config` is for task {config.name!r}; got task={task!r}")
    return _target_prior(task, int(seed), config, naive_bayes or NaiveBayesConfig())


@functools.lru_cache(maxsize=8)
def _target_prior(task, seed, config, nb: NaiveBayesConfig) -> TargetPrior:
    batch = make_trials(task, nb.prior_trials, nb.prior_split, seed, config=config)
    target = batch.target                                        # (T, B, 2)
    lo, hi = target.min(axis=(0, 1)), target.max(axis=(0, 1))
    cell = float(np.max(hi - lo)) / (nb.grid_size - 2)           # one spare cell per side
    middle = 0.5 * (lo + hi)
    first = middle - 0.5 * nb.grid_size * cell
    centres = first[:, None] + cell * (np.arange(nb.grid_size) + 0.5)
    index = np.clip(np.floor((target - first) / cell).astype(np.int64), 0,
                    nb.grid_size - 1)
    n_steps = target.shape[0]
    flat = (np.arange(n_steps)[:, None] * nb.grid_size + index[..., 0]) * nb.grid_size \
        + index[..., 1]
    per_step = np.bincount(flat.ravel(), minlength=n_steps * nb.grid_size ** 2).reshape(
        n_steps, nb.grid_size, nb.grid_size).astype(np.float64)
    cumulative = np.concatenate([np.zeros((1,) + per_step.shape[1:]),
                                 np.cumsum(per_step, axis=0)])
    steps = np.arange(n_steps)
    window = np.minimum(steps, nb.time_window)       # early on the prior changes fast
    upper = np.minimum(steps + window + 1, n_steps)
    lower = steps - window
    counts = cumulative[upper] - cumulative[lower]
    counts.setflags(write=False)
    return TargetPrior(centres[0], centres[1], counts, cell, task, nb.prior_split, seed,
                       nb.prior_trials, nb.time_window)


@fill_doc
def naive_bayes(batch, *, start: str | None = None, prior: TargetPrior | None = None,
                config: TaskConfig | None = None,
                baseline: BaselineConfig | None = None) -> BaselineResult:
    """Path integration times the learnt prior over targets; see the module docstring.

    Parameters
    ----------
    %(batch)s
    start : {"known", "unknown"}, optional
        Default: unknown for localization, known otherwise (only the localization task
        needs the start to express its target).
    prior : TargetPrior, optional
        Default: :func:`target_prior` of the batch's task and seed, from
        ``NaiveBayesConfig.prior_trials`` training trials.
    %(baseline_config)s

    Returns
    -------
    BaselineResult
        ``estimate`` (T, B, 2) in the task's target frame.

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> from hippo_probe.baselines.config import BaselineConfig, NaiveBayesConfig
    >>> batch = make_trials("generalized", n_trials=2, split="test")
    >>> small = BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=50))
    >>> naive_bayes(batch, baseline=small).estimate.shape
    (500, 2, 2)
    """
    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    start = resolve_start(start, config)
    prior = prior or target_prior(batch.task, seed=int(batch.seed), config=config,
                                  naive_bayes=baseline.naive_bayes)
    if prior.counts.shape[0] < batch.n_steps:
        raise ValueError(f"`prior` must cover the batch's {batch.n_steps} steps; got "
                         f"{prior.counts.shape[0]}")
    disp = displacements(batch)
    if config.target == "start_relative":      # the start drops out of the target
        origin, start_var = np.zeros((len(batch), 2)), np.zeros(len(batch))
    else:
        origin, start_var = start_guess(batch, config, start, baseline)
    pi = origin[None] + np.cumsum(disp, axis=0)                      # (T, B, 2)
    noise = config.world.noise
    step_var = 0.5 * (noise.speed_sd ** 2 + noise.rotation_sd ** 2)
    pi_var = (step_var * np.cumsum(np.sum(disp ** 2, axis=-1), axis=0) + start_var[None]
              + drift_variance(disp, noise.heading_drift, batch.dt))
    s2 = prior.kernel_variance
    estimate = np.empty_like(pi)
    n_fallback = 0
    for t in range(batch.n_steps):
        var = pi_var[t] + s2                                          # (B,)
        gx = _gauss(prior.centres_x, pi[t, :, 0], var)                # (B, G)
        gy = _gauss(prior.centres_y, pi[t, :, 1], var)
        q = gy @ prior.counts[t].T                                    # (B, G): sum over y
        qy = (gy * prior.centres_y) @ prior.counts[t].T
        z = np.sum(gx * q, axis=1)
        sx = (gx * q) @ prior.centres_x
        sy = np.sum(gx * qy, axis=1)
        ok = z > 0
        n_fallback += int(np.count_nonzero(~ok))
        safe = np.where(ok, z, 1.0)
        bar = np.stack([sx / safe, sy / safe], axis=-1)
        blend = (pi_var[t][:, None] * bar + s2 * pi[t]) / var[:, None]
        estimate[t] = np.where(ok[:, None], blend, pi[t])
    return BaselineResult("nb", estimate, attrs=provenance(
        "nb", batch, start=start, prior_trials=prior.n_trials, prior_split=prior.split,
        prior_cell_m=prior.cell, time_window=prior.time_window,
        n_fallback_to_pi=n_fallback))


def drift_variance(disp, heading_drift: float, dt: float) -> np.ndarray:
    r"""Per-axis variance (T, B) of path integration's error from the heading drift
    (module docstring): :math:`\tfrac12\sigma_\eta^2\delta t\sum_{k \le t}|P_t -
    P_{k-1}|^2 = \tfrac12\sigma_\eta^2\delta t\,(t|P_t|^2 - 2P_t\cdot Q_t + R_t)` with
    :math:`Q_t = \sum_{k<t} P_k`, :math:`R_t = \sum_{k<t}|P_k|^2`, :math:`P_0 = 0`.

    ``disp`` (T, B, 2) are the sensed displacements; zeros without drift.
    """
    if heading_drift == 0:
        return np.zeros(disp.shape[:2])
    track = np.cumsum(disp, axis=0)                                    # P_1 ... P_T
    before = np.concatenate([np.zeros_like(track[:1]), track[:-1]])     # P_0 ... P_{T-1}
    q = np.cumsum(before, axis=0)
    r = np.cumsum(np.sum(before ** 2, axis=-1), axis=0)
    t = np.arange(1, len(disp) + 1)[:, None]
    total = t * np.sum(track ** 2, axis=-1) - 2 * np.sum(track * q, axis=-1) + r
    return 0.5 * heading_drift ** 2 * dt * np.maximum(total, 0.0)


def _gauss(centres, mean, var):
    """``exp(-(c - m)^2 / (2 var))`` (B, G), scaled so each row's largest entry is 1 (the
    scale cancels in the posterior mean and keeps rows from underflowing together)."""
    e = (centres[None, :] - mean[:, None]) ** 2 / (2.0 * var[:, None])
    return np.exp(-(e - e.min(axis=1, keepdims=True)))
