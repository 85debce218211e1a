"""What every baseline shares: its result type, task knowledge and the start prior."""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from .._validators import check_option
from .._version import __version__
from ..tasks import TaskConfig
from ..world.arena import sample_uniform, wall_distance
from .config import STREAM_TAGS, BaselineConfig

START_KNOWLEDGE = ("known", "unknown")


@dataclass
class BaselineResult:
    """Output of a baseline on a :class:`~hippo_probe.tasks.TrialBatch` of ``B`` trials of
    ``T`` steps.

    Attributes
    ----------
    method : str
        ``"pi"``, ``"sh"``, ``"nb"``, ``"pf"`` or ``"pfslam"``.
    estimate : (T, B, 2)
        Position estimate in the task's target frame (that of ``batch.target``), m.
    mean, cov : (T, B, 2), (T, B, 3) or None
        Particle filters: posterior mean and covariance (``xx, yy, xy``, m²) of the
        position in the arena frame.
    drift_mean, drift_sd : (T, B) or None
        Particle filters: posterior mean and s.d. of the heading drift (rad; sensed minus
        true heading, :attr:`~hippo_probe.tasks.TrialBatch.heading_drift`), unwrapped.
    class_probability : (T, B, n_arenas) float32 or None
        PF-SLAM: posterior probability of each arena.
    particles, particle_weights, particle_drifts : (K, B, N, 2), (K, B, N), (K, B, N)
        Particle filters asked to ``keep`` steps: the particles (arena frame), their
        normalized weights and drift hypotheses after the update of each kept step
        (before resampling); None otherwise.
    particle_arenas : (K, B, N) int or None
        PF-SLAM: the arena hypothesis of each kept particle.
    attrs : dict
        Provenance: method, task, parameters, package version, diagnostics.
    """

    method: str
    estimate: np.ndarray
    mean: np.ndarray | None = None
    cov: np.ndarray | None = None
    drift_mean: np.ndarray | None = None
    drift_sd: np.ndarray | None = None
    class_probability: np.ndarray | None = None
    particles: np.ndarray | None = None
    particle_weights: np.ndarray | None = None
    particle_drifts: np.ndarray | None = None
    particle_arenas: np.ndarray | None = None
    attrs: dict = field(default_factory=dict)

    def error(self, batch) -> np.ndarray:
        """Euclidean localization error ``|estimate - batch.target|`` (T, B), m."""
        return np.linalg.norm(self.estimate - batch.target, axis=-1)


def resolve_task(batch, config: TaskConfig | None) -> TaskConfig:
    """The task configuration that generated ``batch``
    (:meth:`~hippo_probe.tasks.TrialBatch.checked_config`): every baseline inverts the
    world the trials were made in."""
    return batch.checked_config(config)


def resolve_start(start: str | None, config: TaskConfig) -> str:
    """Whether a baseline knows the start: ``"unknown"`` by default only where the task hides
    it in the target frame (localization); the oracles know it elsewhere."""
    if start is None:
        return "unknown" if (config.start == "uniform" and config.target == "arena") \
            else "known"
    return check_option("start", start, START_KNOWLEDGE)


def provenance(method: str, batch, **params) -> dict:
    return {"method": method, "task": batch.task, "split": batch.split,
            "seed": int(batch.seed), "created_by": f"hippo_probe {__version__}", **params}


def start_prior_samples(vertices, rng, n: int, clearance: float) -> np.ndarray:
    """``n`` start positions drawn like the tasks draw them: uniform in the arena, at least
    ``clearance`` (the touch range) from every wall. (n, 2)."""
    out = np.empty((0, 2))
    while len(out) < n:
        points = sample_uniform(vertices, rng, 2 * (n - len(out)) + 16)
        distance, _, _ = wall_distance(vertices, points)
        out = np.concatenate([out, points[distance >= clearance]])
    return out[:n]


@functools.lru_cache(maxsize=64)
def _start_prior_moments(vertices_bytes: bytes, n_vertices: int, clearance: float,
                         n: int) -> tuple:
    vertices = np.frombuffer(vertices_bytes).reshape(n_vertices, 2)
    rng = np.random.default_rng(np.random.SeedSequence([STREAM_TAGS["start_prior"], n]))
    samples = start_prior_samples(vertices, rng, n, clearance)
    return samples.mean(axis=0), samples.var(axis=0).mean()


def start_prior_moments(vertices, clearance: float, config: BaselineConfig):
    """Mean (2,) and per-axis variance of the start prior of an arena (Monte Carlo with
    ``config.start_prior_samples`` draws from a fixed seed)."""
    v = np.ascontiguousarray(vertices, dtype=np.float64)
    mean, var = _start_prior_moments(v.tobytes(), len(v), float(clearance),
                                     int(config.start_prior_samples))
    return mean.copy(), float(var)


def start_guess(batch, config: TaskConfig, start: str, baseline: BaselineConfig):
    """Start position each baseline integrates from, arena frame (B, 2), and the per-axis
    variance of its error (B,): the true start if known, else the start prior's mean."""
    if start == "known":
        return np.asarray(batch.start, dtype=np.float64).copy(), np.zeros(len(batch))
    guess = np.empty((len(batch), 2))
    var = np.empty(len(batch))
    for b, vertices in enumerate(batch.arena_vertices):
        guess[b], var[b] = start_prior_moments(vertices, config.world.sensors.touch_range,
                                               baseline)
    return guess, var
