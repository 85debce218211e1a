r"""PF-SLAM for the specialized task: position and arena identity, jointly.

Each particle carries a position, a heading drift (darkness world) and one of the task's
fixed arenas as its hypothesis;
the filter is the oracular particle filter of :mod:`~hippo_probe.baselines.particle_filter`
(same motion model, contact and no-contact likelihoods, resampling) with each particle's
likelihood computed in its own arena. The posterior probability of arena ``a`` is the
total weight of its particles,

.. math:: P(a \mid \text{inputs}_{1..t}) = \sum_{i:\,a_i = a} w_i,

and the position estimate is the posterior mean over all particles (marginalized over
arenas). Particles start at the known start (the arenas' common centre) spread evenly
over the arenas (a uniform prior; ``N / n_arenas`` particles each). Once resampling has
removed every particle of an arena its probability stays 0: with too few particles the
true arena can be lost, which is why 10,000 particles are the default.

Particles are kept sorted by arena (systematic resampling preserves the order), so each
arena's particles form one contiguous block and the wall-distance kernel runs over a
block with that arena's walls fixed.

References
----------
Montemerlo, M., Thrun, S., Koller, D., & Wegbreit, B. (2002). FastSLAM: a factored
solution to the simultaneous localization and mapping problem. AAAI-02, 593-598 (particles
carrying map hypotheses).
Kanitscheider, I., & Fiete, I. (2017). NIPS 30 (PF-SLAM over the specialized task's
arenas as the reference of the network's classification).
"""

from __future__ import annotations

import numpy as np

from .._docs import fill_doc
from .._validators import check_positive
from ..tasks import TaskConfig, fixed_arenas
from ._common import BaselineResult, provenance, resolve_task
from .config import BaselineConfig
from .contact import wall_table
from .particle_filter import run_filter


@fill_doc
def pf_slam(batch, n_particles: int | None = None, *, keep=(), threads: int | None = None,
            config: TaskConfig | None = None,
            baseline: BaselineConfig | None = None) -> BaselineResult:
    """Particle filter over position and arena identity (specialized task).

    Parameters
    ----------
    batch : TrialBatch
        Trials of a task with fixed arenas and a known start (``specialized``).
    n_particles : int, optional
        Particles per trial, at least the number of arenas (default
        ``ParticleFilterConfig.slam_particles`` = 10,000).
    keep : sequence of int
        Steps whose particles, weights and arena hypotheses to return.
    %(threads)s
    %(baseline_config)s

    Returns
    -------
    BaselineResult
        ``estimate`` (T, B, 2) (arena frame), ``mean``, ``cov`` (T, B, 3),
        ``drift_mean``, ``drift_sd`` (T, B) and ``class_probability`` (T, B, n_arenas)
        float32.

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> batch = make_trials("specialized", n_trials=2, split="test")
    >>> res = pf_slam(batch, n_particles=500)
    >>> res.class_probability.shape
    (500, 2, 100)
    """
    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    if config.arenas != "fixed" or config.start != "centre":
        raise ValueError(f"`batch` must come from a task with fixed arenas and a known start "
                         f"(specialized); got task {batch.task!r}")
    if n_particles is None:
        n_particles = baseline.particle_filter.slam_particles
    n_particles = check_positive("n_particles", n_particles, integer=True)
    tables = wall_table(fixed_arenas(config.name, config))[None]      # (1, A, V, 8)
    run = run_filter(batch, tables, np.zeros(len(batch), np.int64), n_particles, "known",
                     config, baseline, "pf_slam", keep=keep, threads=threads,
                     class_output=True)
    return BaselineResult(
        "pfslam", run["estimate"], mean=run["mean"], cov=run["cov"],
        drift_mean=run["drift_mean"], drift_sd=run["drift_sd"],
        class_probability=run["class_probability"], particles=run["particles"],
        particle_weights=run["weights"], particle_drifts=run["drifts"],
        particle_arenas=run["arenas"],
        attrs=provenance("pfslam", batch, n_particles=n_particles,
                         n_arenas=int(tables.shape[1]),
                         regularization=baseline.particle_filter.regularization,
                         **run["diagnostics"]))
