"""Bayesian baselines: the naive and optimal references the networks are measured against.

========================  ==========================================================
:func:`path_integration`  dead reckoning of the noisy self-motion (PI)
:func:`single_hypothesis` PI with a hard reset onto a wall at each contact (SH)
:func:`naive_bayes`       PI times a learnt prior over targets, no boundaries (NB)
:func:`particle_filter`   oracular particle filter, arena known (PF)
:func:`pf_slam`           particle filter over position and arena identity (PF-SLAM)
:func:`run_baselines`     all of them on a batch, as one labelled dataset
========================  ==========================================================

Each takes a :class:`~hippo_probe.tasks.TrialBatch` and returns a
:class:`BaselineResult` with ``estimate (T, B, 2)`` in the task's target frame (the
frame of ``batch.target``); the particle filters add ``mean`` and ``cov (T, B, 3)``
(xx, yy, xy), PF-SLAM ``class_probability (T, B, 100)``. They invert the world's own
noise model and geometry (:mod:`hippo_probe.world`); their own constants live in
:mod:`hippo_probe.baselines.config`.

Examples
--------
>>> import hippo_probe as hp
>>> batch = hp.tasks.make_trials("localization", n_trials=2, split="test")
>>> res = hp.baselines.particle_filter(batch, n_particles=200)
>>> res.estimate.shape, res.cov.shape
((500, 2, 2), (500, 2, 3))
"""

from ._common import BaselineResult
from .config import (BaselineConfig, ContactModelConfig, NaiveBayesConfig,
                     ParticleFilterConfig)
from .naive_bayes import TargetPrior, naive_bayes, target_prior
from .particle_filter import particle_filter
from .path_integration import path_integration
from .pf_slam import pf_slam
from .results import (error_table, localization_errors, open_baselines, plot_errors,
                      run_baselines, save_baselines)
from .single_hypothesis import single_hypothesis

__all__ = [
    "BaselineConfig", "BaselineResult", "ContactModelConfig", "NaiveBayesConfig",
    "ParticleFilterConfig", "TargetPrior", "error_table", "localization_errors",
    "naive_bayes", "open_baselines", "particle_filter", "path_integration", "pf_slam",
    "plot_errors", "run_baselines", "save_baselines", "single_hypothesis", "target_prior",
]
