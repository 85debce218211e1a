r"""Is a particle filter calibrated? Ranks of the truth among its particles.

For a calibrated posterior the probability mass that lies "below" the truth is uniform on
[0, 1] (the probability integral transform; e.g. Gneiting, Balabdaoui & Raftery 2007,
"Probabilistic forecasts, calibration and sharpness", J R Stat Soc B 69:243-268). Three
such ranks, from the particles a filter kept (``keep=...``):

* ``mahalanobis``: the posterior mass of the particles closer to the weighted mean than
  the truth, in the particles' own Mahalanobis metric (whatever the posterior's shape);
* ``projection``: the mass below the truth along a random direction per trial and step;
* ``drift``: the mass of drift hypotheses below the true heading drift (darkness world).

Ranks taken 20 s or more apart within a trial are nearly independent, so a
Kolmogorov-Smirnov test against the uniform distribution applies to them.
"""

from __future__ import annotations

import numpy as np

from .._angles import wrap_angle
from .._validators import check_positive, check_seed


def posterior_ranks(result, batch, *, seed: int = 0) -> dict:
    """Ranks (K * B,) of the truth among the kept particles of ``result`` (module
    docstring): ``{"mahalanobis", "projection", "drift"}``.

    Parameters
    ----------
    result : BaselineResult
        Of :func:`~hippo_probe.baselines.particle_filter` (or PF-SLAM) run with ``keep``.
    batch : TrialBatch
        The trials it ran on.
    seed : int
        Seed of the random projection directions.

    Returns
    -------
    dict of (K * B,) float arrays in [0, 1].
    """
    if result.particles is None:
        raise ValueError("`result` has no kept particles: run the filter with `keep=` the "
                         "steps to rank")
    steps = np.asarray(result.attrs["kept_steps"], dtype=np.int64)
    truth = batch.position[steps]                                  # (K, B, 2)
    p, w = result.particles, result.particle_weights               # (K, B, N, 2), (K, B, N)
    mean = np.einsum("kbn,kbnd->kbd", w, p)
    d = p - mean[:, :, None]
    cov = np.einsum("kbn,kbnd,kbne->kbde", w, d, d)
    inv = np.linalg.inv(cov + 1e-12 * np.eye(2))
    own = np.einsum("kbnd,kbde,kbne->kbn", d, inv, d)
    e = truth - mean
    true = np.einsum("kbd,kbde,kbe->kb", e, inv, e)
    angle = np.random.default_rng(check_seed("seed", seed)).uniform(0, 2 * np.pi, truth.shape[:2])
    u = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    along = np.einsum("kbnd,kbd->kbn", p, u)
    true_along = np.einsum("kbd,kbd->kb", truth, u)
    # the drift is an angle: ranked as its wrapped offset from the posterior's circular
    # mean, so a filter started unoriented (drift uniform on the circle) ranks correctly
    # too; for the small drifts of an oriented start this is the plain ordering
    drifts = result.particle_drifts
    centre = np.angle(np.einsum("kbn,kbn->kb", w, np.exp(1j * drifts)))[..., None]
    offset = wrap_angle(drifts - centre)
    true_offset = wrap_angle(batch.heading_drift[steps][..., None] - centre)
    ranks = {
        "mahalanobis": np.sum(w * (own < true[..., None]), axis=-1),
        "projection": np.sum(w * (along < true_along[..., None]), axis=-1),
        "drift": np.sum(w * (offset < true_offset), axis=-1),
    }
    # a truth beyond every particle ranks at the weights' float sum, which can exceed 1
    # by a rounding error and then falls outside a histogram's [0, 1] range
    return {k: np.clip(v, 0.0, 1.0).ravel() for k, v in ranks.items()}


def filter_ranks(batch, n_particles: int | None = None, *, keep, chunk: int = 100,
                 seed: int = 0, progress: bool = False, baseline=None) -> dict:
    """Ranks of the truth under the oracular particle filter, run on chunks of trials.

    The filter keeps its particles at ``keep`` (K steps), which costs
    ``K * chunk * n_particles`` particles of memory at a time instead of ``K * B * ...``:
    tens of thousands of particles then fit. Each trial's random numbers depend on its
    index only, so the Mahalanobis and drift ranks do not depend on ``chunk``; the random
    projection's directions are drawn per chunk (seed ``seed + first trial``).

    Parameters
    ----------
    batch : TrialBatch
    n_particles : int, optional
        The filter's (default: its own default for the task).
    keep : sequence of int
        Steps at which to rank.
    chunk : int
        Trials per filter run.
    seed : int
        Seed of the projection directions of the first chunk.
    progress : bool
        A tqdm bar over the chunks.
    baseline : BaselineConfig, optional
        The filter's configuration (default ``BaselineConfig()``).

    Returns
    -------
    dict
        ``"mahalanobis"``, ``"projection"``, ``"drift"``: ranks (K, B), time-major (one
        row per kept step, as :func:`posterior_ranks` orders its flat output);
        ``"mean"`` (K, B, 2) and ``"cov"`` (K, B, 3): the posterior at the kept steps.
    """
    from tqdm.auto import tqdm

    from .particle_filter import particle_filter

    chunk = check_positive("chunk", chunk, integer=True)
    seed = check_seed("seed", seed)
    parts = []
    for lo in tqdm(range(0, len(batch), chunk), disable=not progress, desc="filter chunks"):
        part = batch.select(slice(lo, lo + chunk))
        result = particle_filter(part, n_particles, keep=keep, baseline=baseline)
        ranks = posterior_ranks(result, part, seed=seed + lo)
        steps = np.asarray(result.attrs["kept_steps"], dtype=np.int64)
        out = {k: v.reshape(steps.size, -1) for k, v in ranks.items()}
        out["mean"], out["cov"] = result.mean[steps], result.cov[steps]
        parts.append(out)
    return {k: np.concatenate([p[k] for p in parts], axis=1) for k in parts[0]}
