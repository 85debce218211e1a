"""The study's three navigation tasks and their trial batches.

==============  ==========  =====================  ================================
task            arena       start                  target
==============  ==========  =====================  ================================
localization    one fixed   unknown, uniform       position in the arena frame
                R = 1 m
generalized     new random  random, uniform        position minus start position
                every trial
                R = 0.33 m
specialized     1 of 100    the centre, known      position in the arena frame,
                fixed,                             plus the arena's identity (class)
                R = 0.33 m
==============  ==========  =====================  ================================

Reproducibility: trial ``i`` of a split is a pure function of ``(task, split, seed, i)``:
all its random numbers come from ``numpy.random.SeedSequence([seed, task_code,
split_code, i])``, so it is the same however trials are batched, cached, resumed or
sharded. Splits differ in ``split_code`` and therefore never share a trial. The fixed
arenas (the localization arena, the 100 specialized arenas) come from
:data:`ARENA_SEED` alone, identical on every machine.

Examples
--------
>>> batch = make_trials("specialized", n_trials=8, split="validation", seed=0)
>>> batch.inputs.shape, batch.target.shape, batch.environment.shape
((500, 8, 9), (500, 8, 2), (8,))
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import warnings
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np

from ._atomic import atomic_path
from ._validators import check_nonnegative_int, check_option
from .world.arena import fan_points, fan_weights, random_vertices, wall_distance
from .world.config import FEATURES, ArenaConfig, WorldConfig, world_config
from .world.motion import simulate_motion
from .world.sensors import N_NOISE_DRAWS, heading_drift, sense

TASKS = ("localization", "generalized", "specialized")
SPLITS = ("train", "validation", "test")
_TASK_CODE = {name: k for k, name in enumerate(TASKS)}
_SPLIT_CODE = {name: k for k, name in enumerate(SPLITS)}

#: Seed of the fixed arenas (the localization arena and the 100 specialized arenas).
ARENA_SEED = 1609_09059  # the study's arXiv number: any fixed value would do


@dataclass(frozen=True)
class TaskConfig:
    """Definition of a task; defaults per task come from :func:`task_config`.

    Attributes
    ----------
    name : str
    world : WorldConfig
        The world (``"darkness"`` by default, or ``"compass"``; :func:`world_config`).
    arenas : {"fixed", "novel"}
        ``fixed``: ``n_arenas`` arenas drawn once from :data:`ARENA_SEED`; ``novel``: a new
        random arena every trial.
    n_arenas : int
        Number of fixed arenas (1 for localization, 100 for specialized).
    start : {"uniform", "centre"}
        Start position: uniform over the arena (at least the touch range from every wall,
        so no trial begins in contact), or the arena's centre.
    target : {"arena", "start_relative"}
        Frame of the regression target.
    classify : bool
        Whether the network also reports the arena's identity.
    train_trials : int
        The study's training-set size: 5,000 (localization), 300,000 (generalized),
        250,000 (specialized). Validation and test splits have 1,000 trials each.
    """

    name: str
    world: WorldConfig
    arenas: str
    n_arenas: int
    start: str
    target: str
    classify: bool
    train_trials: int
    validation_trials: int = 1000
    test_trials: int = 1000

    @property
    def n_classes(self) -> int:
        return self.n_arenas if self.classify else 0

    def split_size(self, split: str) -> int:
        check_option("split", split, SPLITS)
        return {"train": self.train_trials, "validation": self.validation_trials,
                "test": self.test_trials}[split]

    def fingerprint(self) -> str:
        """Short hash of everything that shapes a trial (names the cache)."""
        return hashlib.sha1(repr((self, ARENA_SEED, _FORMAT_VERSION)).encode()).hexdigest()[:10]


_FORMAT_VERSION = 3  # 2: blocks hold `heading_drift`, names the world; 3: sha1 digests

#: Mean arena radius (m) of each task: 1 m for localization, 0.33 m for the generalized
#: and specialized tasks (the study's Fig. 2-3).
TASK_ARENA_RADIUS = {"localization": 1.0, "generalized": 0.33, "specialized": 0.33}


def task_config(task: str, world="darkness", **overrides) -> TaskConfig:
    """The default :class:`TaskConfig` of a task in a world, optionally with fields
    replaced.

    Parameters
    ----------
    task : {"localization", "generalized", "specialized"}
    world : {"darkness", "compass"} or WorldConfig
        A named world gets the task's arena size; a :class:`WorldConfig` is used exactly
        as given (its arenas too).
    **overrides
        Fields of :class:`TaskConfig` to replace.

    Examples
    --------
    >>> task_config("generalized").world.arena.mean_radius
    0.33
    >>> task_config("generalized", "compass").world.noise.heading_drift
    0.0
    """
    check_option("task", task, TASKS)
    world = world_config(world, arena=ArenaConfig(mean_radius=TASK_ARENA_RADIUS[task]))
    defaults = {
        "localization": TaskConfig("localization", world, arenas="fixed", n_arenas=1,
                                   start="uniform", target="arena", classify=False,
                                   train_trials=5000),
        "generalized": TaskConfig("generalized", world, arenas="novel", n_arenas=0,
                                  start="uniform", target="start_relative", classify=False,
                                  train_trials=300_000),
        "specialized": TaskConfig("specialized", world, arenas="fixed", n_arenas=100,
                                  start="centre", target="arena", classify=True,
                                  train_trials=250_000),
    }[task]
    return replace(defaults, **overrides) if overrides else defaults


def resolve_config(task: str, world=None, config: TaskConfig | None = None) -> TaskConfig:
    """The :class:`TaskConfig` a call means: ``config`` if given (its world must agree
    with ``world`` if that is given too), else ``task_config(task, world or "darkness")``."""
    check_option("task", task, TASKS)
    if config is None:
        return task_config(task, "darkness" if world is None else world)
    if not isinstance(config, TaskConfig):
        raise TypeError(f"`config` must be a TaskConfig; got {config!r}")
    if config.name != task:
        raise ValueError(f"`config` is for task {config.name!r}; got task={task!r}")
    if world is not None and world_config(world, arena=config.world.arena) != config.world:
        raise ValueError(f"`world` ({_world_label(world)}) disagrees with the world of "
                         f"`config` ({_world_label(config.world)})")
    return config


def _world_label(world) -> str:
    return repr(world) if isinstance(world, str) else f"{world.name!r}: {world!r}"


@functools.lru_cache(maxsize=8)
def _fixed_arenas(task: str, n_arenas: int, arena: ArenaConfig) -> np.ndarray:
    rng = np.random.default_rng(np.random.SeedSequence([ARENA_SEED, _TASK_CODE[task]]))
    verts = np.stack([random_vertices(rng, arena) for _ in range(n_arenas)])
    verts.setflags(write=False)
    return verts


def fixed_arenas(task: str, config: TaskConfig | None = None) -> np.ndarray:
    """Vertices (n_arenas, V, 2) of a task's fixed arenas (empty for novel arenas)."""
    config = config or task_config(task)
    if config.arenas != "fixed":
        return np.empty((0, config.world.arena.n_vertices, 2))
    return _fixed_arenas(config.name, config.n_arenas, config.world.arena)


def trial_seed(task: str, split: str, seed: int, index: int) -> np.random.SeedSequence:
    """The SeedSequence of trial ``index`` of ``(task, split, seed)``."""
    return np.random.SeedSequence([seed, _TASK_CODE[task], _SPLIT_CODE[split], index])


@dataclass
class TrialBatch:
    """``B`` trials of ``T`` network steps (time-major, as the LSTM consumes them).

    Attributes
    ----------
    inputs : float32 (T, B, F)
        Noisy sensory inputs; columns named by ``features``.
    target : (T, B, 2)
        Regression target in the task's frame (m).
    position : (T, B, 2)
        True position at the end of each step, arena frame (m).
    start : (B, 2)
        Start position, arena frame (m).
    head_direction : (T, B)
        True head direction at the end of each step, rad in [-pi, pi).
    heading_drift : (T, B)
        True drift of the sensed heading at the end of each step, rad (sensed minus true
        heading, before the independent noise; zeros in the compass world).
    contact : bool (T, B)
        Whether the step had a boundary contact.
    environment : int (B,)
        Arena id: index of the fixed arena, or the trial index for novel arenas.
    arena_vertices : (B, V, 2)
    trial_index : int (B,)
        Index ``i`` of each trial within its split.
    dt : float
        Network step (s).
    task, split : str
    seed : int
    config : TaskConfig
        The whole task and world configuration that made the batch: baselines,
        recordings and the trial cache read the world from here.
    features : tuple of str
    """

    inputs: np.ndarray
    target: np.ndarray
    position: np.ndarray
    start: np.ndarray
    head_direction: np.ndarray
    heading_drift: np.ndarray
    contact: np.ndarray
    environment: np.ndarray
    arena_vertices: np.ndarray
    trial_index: np.ndarray
    dt: float
    task: str
    split: str
    seed: int
    config: TaskConfig
    features: tuple = FEATURES

    def __len__(self) -> int:
        return self.inputs.shape[1]

    @property
    def n_steps(self) -> int:
        return self.inputs.shape[0]

    @property
    def world(self) -> WorldConfig:
        """The world of the batch (``self.config.world``)."""
        return self.config.world

    def checked_config(self, config: TaskConfig | None = None) -> TaskConfig:
        """The batch's own configuration; an explicitly given ``config`` must be it.

        Whatever inverts or records the batch (baselines, recordings) reads the world
        from here, never from a default rebuilt elsewhere: a filter built for another
        world than the one that made the trials would be silently wrong.
        """
        own = self.config
        if config is None:
            return own
        if not isinstance(config, TaskConfig):
            raise TypeError(f"`config` must be a TaskConfig; got {config!r}")
        if config.name != self.task:
            raise ValueError(f"`config` is for task {config.name!r}; got a {self.task!r} "
                             f"batch")
        if config != own:
            listed = "; ".join(f"{name}: given {a!r}, batch {b!r}"
                               for name, (a, b) in _differing_fields(config, own).items())
            raise ValueError(
                f"`config` disagrees with the configuration the batch was made with "
                f"({listed}). Leave `config` out to use the batch's.")
        return config

    @property
    def time(self) -> np.ndarray:
        """Time (s) at the end of each step, since the trial's start."""
        return self.dt * np.arange(1, self.n_steps + 1)

    def feature(self, name: str) -> np.ndarray:
        """Column ``name`` of the inputs, (T, B)."""
        check_option("name", name, self.features)
        return self.inputs[..., self.features.index(name)]

    def select(self, index) -> "TrialBatch":
        """A batch of a subset of trials (``index`` into the trial axis)."""
        index = np.atleast_1d(np.arange(len(self))[index])
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in _TIME_MAJOR:
                value = value[:, index]
            elif f.name in _TRIAL_MAJOR:
                value = value[index]
            out[f.name] = value
        return TrialBatch(**out)

    @classmethod
    def concatenate(cls, batches) -> "TrialBatch":
        """Join batches of the same task/split/world along the trial axis."""
        batches = list(batches)
        first = batches[0]
        for other in batches[1:]:
            if other.config != first.config:
                raise ValueError(f"batches of different configurations cannot be joined: "
                                 f"{first.config!r} and {other.config!r}")
        out = {}
        for f in fields(cls):
            values = [getattr(b, f.name) for b in batches]
            if f.name in _TIME_MAJOR:
                out[f.name] = np.concatenate(values, axis=1)
            elif f.name in _TRIAL_MAJOR:
                out[f.name] = np.concatenate(values, axis=0)
            else:
                out[f.name] = getattr(first, f.name)
        return cls(**out)


_TIME_MAJOR = ("inputs", "target", "position", "head_direction", "heading_drift",
               "contact")
_TRIAL_MAJOR = ("start", "environment", "arena_vertices", "trial_index")


def make_trials(task: str, n_trials: int, split: str = "train", seed: int = 0, *,
                first: int = 0, world=None, config: TaskConfig | None = None
                ) -> TrialBatch:
    """Generate trials ``first, ..., first + n_trials - 1`` of a task's split.

    Parameters
    ----------
    task : {"localization", "generalized", "specialized"}
    n_trials : int
        Number of trials (>= 0).
    split : {"train", "validation", "test"}
    seed : int
        Seed of the whole split; trial ``i`` depends only on ``(task, split, seed, i)``.
    first : int
        Index of the first trial, so ``make_trials(..., 10, first=0)`` equals
        ``make_trials(..., 5, first=0)`` joined with ``make_trials(..., 5, first=5)``.
    world : {"darkness", "compass"} or WorldConfig, optional
        The world (default ``"darkness"``, the study's). The compass world's trials are
        those of this project's first world, bit for bit; a darkness trial shares every
        random number with the compass trial of the same index and adds its drift.
    config : TaskConfig, optional
        A modified task (e.g. ``task_config("generalized", world=...)`` for a noiseless
        world); defaults to :func:`task_config(task, world) <task_config>`.

    Returns
    -------
    TrialBatch
    """
    check_option("task", task, TASKS)
    check_option("split", split, SPLITS)
    n_trials = check_nonnegative_int("n_trials", n_trials)
    first = check_nonnegative_int("first", first)
    seed = check_nonnegative_int("seed", seed)
    config = resolve_config(task, world, config)
    world = config.world
    motion = world.motion
    n_steps = motion.n_steps
    trial_index = np.arange(first, first + n_trials, dtype=np.int64)
    verts = np.empty((n_trials, world.arena.n_vertices, 2))
    start = np.zeros((n_trials, 2))
    environment = np.empty(n_trials, dtype=np.int64)
    inputs = np.empty((n_steps, n_trials, len(FEATURES)), dtype=np.float32)
    position = np.empty((n_steps, n_trials, 2))
    head_direction = np.empty((n_steps, n_trials))
    drift = np.zeros((n_steps, n_trials))
    contact = np.empty((n_steps, n_trials), dtype=bool)

    # Chunks bound the memory of the random draws; within a chunk, threads share the
    # per-trial draws (numpy releases the GIL while filling arrays) and the sensing.
    # Every trial still uses only its own generator, so the result is the same.
    workers = _n_threads()
    with ThreadPoolExecutor(max_workers=workers) as pool:
        for lo in range(0, n_trials, _CHUNK):
            chunk = slice(lo, min(lo + _CHUNK, n_trials))
            heading0, speed_noise, turn_noise, draws, drift_draws = _draw_trials(
                pool, workers, task, split, seed, config, trial_index[chunk], verts[chunk],
                start[chunk], environment[chunk])
            sim = simulate_motion(verts[chunk], start[chunk], heading0, speed_noise,
                                  turn_noise, motion, world.sensors)
            del speed_noise, turn_noise
            position[:, chunk] = sim["position"].transpose(1, 0, 2)
            head_direction[:, chunk] = sim["heading"].T
            contact[:, chunk] = sim["contact"].T
            eta = heading_drift(world.noise, drift_draws, motion.network_dt)
            if eta is not None:
                drift[:, chunk] = eta.T
            sense_rows = functools.partial(_sense_into, inputs[:, chunk], sim=sim,
                                           noise=world.noise, draws=draws, heading0=heading0,
                                           drift=eta)
            list(pool.map(sense_rows, _row_blocks(len(heading0), workers)))

    target = position - start[None] if config.target == "start_relative" else position.copy()
    return TrialBatch(
        inputs=inputs,
        target=target,
        position=position,
        start=start,
        head_direction=head_direction,
        heading_drift=drift,
        contact=contact,
        environment=environment,
        arena_vertices=verts,
        trial_index=trial_index,
        dt=motion.network_dt,
        task=task,
        split=split,
        seed=seed,
        config=config,
    )


#: Trials generated at once inside :func:`make_trials` (bounds its working memory: about
#: 90 kB of random draws per trial).
_CHUNK = 256
#: Candidate start points drawn per trial; the first one clear of every wall is taken.
_START_TRIES = 16


def _n_threads() -> int:
    """Threads for trial generation: as many as the simulation kernel is allowed."""
    import numba

    return max(1, numba.get_num_threads())


def _row_blocks(n: int, parts: int) -> list:
    """``parts`` contiguous slices covering ``range(n)``."""
    edges = np.linspace(0, n, max(1, min(parts, n)) + 1).astype(int)
    return [slice(a, b) for a, b in zip(edges[:-1], edges[1:])]


def _draw_trials(pool, workers, task, split, seed, config, index, verts, start, environment):
    """Every random number of trials ``index``, each from its own generator.

    Fills ``verts``, ``start`` and ``environment`` (rows of the batch) in place and returns
    the initial headings and the noise arrays. The draws of one trial come in a fixed
    order from ``trial_seed(task, split, seed, i)``: arena (novel) or arena id (fixed),
    start candidates (uniform starts, as :func:`~hippo_probe.world.arena.sample_uniform`
    draws them), initial heading, speed noise, turning noise, sensor noise, and last,
    only in a world with drift, the drift's increments (so every other draw, and hence
    the compass world's trial, is the same with and without drift).
    """
    world = config.world
    motion = world.motion
    n = len(index)
    n_fine = motion.n_steps * motion.substeps
    heading0 = np.empty(n)
    speed_noise = np.empty((n, n_fine))
    turn_noise = np.empty((n, n_fine))
    draws = np.empty((n, N_NOISE_DRAWS, motion.n_steps))
    drifts = world.noise.heading_drift > 0
    drift_draws = np.empty((n, motion.n_steps)) if drifts else None
    uniform = config.start == "uniform"
    triangle = np.empty((n, _START_TRIES), dtype=np.int64)
    u = np.empty((n, 2, _START_TRIES))
    fixed = fixed_arenas(task, config)
    n_verts = world.arena.n_vertices

    def draw(rows):
        generators = []
        for b in range(rows.start, rows.stop):
            rng = np.random.default_rng(trial_seed(task, split, seed, int(index[b])))
            if config.arenas == "novel":
                verts[b] = random_vertices(rng, world.arena)
                environment[b] = index[b]
            else:
                environment[b] = rng.integers(config.n_arenas) if config.n_arenas > 1 else 0
                verts[b] = fixed[environment[b]]
            generators.append(rng)
        # the start's triangle weights of all these trials at once, then the rest
        weights = fan_weights(verts[rows]) if uniform else None
        for j, (b, rng) in enumerate(zip(range(rows.start, rows.stop), generators)):
            if uniform:
                triangle[b] = rng.choice(n_verts, size=_START_TRIES, p=weights[j])
                rng.random(out=u[b, 0])
                rng.random(out=u[b, 1])
            heading0[b] = rng.uniform(-np.pi, np.pi)
            rng.standard_normal(out=speed_noise[b])
            rng.standard_normal(out=turn_noise[b])
            rng.standard_normal(out=draws[b])
            if drifts:
                rng.standard_normal(out=drift_draws[b])

    list(pool.map(draw, _row_blocks(n, workers)))
    if uniform:
        candidates = fan_points(verts, triangle, u[:, 0], u[:, 1])
        start[:] = _clear_starts(verts, candidates, world.sensors.touch_range)
    return heading0, speed_noise, turn_noise, draws, drift_draws


def _sense_into(out, rows, sim, noise, draws, heading0, drift):
    """Sensed inputs of trials ``rows`` of a simulation, into ``out`` (T, B, F)."""
    part = {key: value[rows] for key, value in sim.items()}
    out[:, rows] = sense(part, noise, draws[rows], heading0[rows],
                         None if drift is None else drift[rows]).transpose(1, 0, 2)


def _clear_starts(vertices, candidates, clearance) -> np.ndarray:
    """Per trial, the first candidate (B, K, 2) at least ``clearance`` from every wall (the
    arena's centre if none is)."""
    dist, _, _ = wall_distance(vertices, candidates)
    ok = dist >= clearance
    first = np.argmax(ok, axis=1)
    chosen = candidates[np.arange(len(candidates)), first]
    return np.where(ok.any(axis=1)[:, None], chosen, 0.0)


def _differing_fields(a, b, prefix="") -> dict:
    """Dotted field names where two (nested) dataclasses differ: name -> (a's, b's)."""
    if not (hasattr(a, "__dataclass_fields__") and type(a) is type(b)):
        return {prefix.rstrip("."): (a, b)} if a != b else {}
    found = {}
    for f in fields(a):
        found.update(_differing_fields(getattr(a, f.name), getattr(b, f.name),
                                       f"{prefix}{f.name}."))
    return found


# --------------------------------------------------------------------------- cache
CACHE_CHUNK = 1000
_CACHED_FIELDS = ("inputs", "position", "head_direction", "heading_drift", "contact",
                  "start", "environment", "arena_vertices", "trial_index")


def _write_block(zarr, batch, path) -> None:
    """Write a block's arrays, with the sha1 of each, to ``path`` (atomically)."""
    try:
        with atomic_path(path, what="trial cache block") as tmp:
            group = zarr.open_group(str(tmp), mode="w")
            digests = {}
            for name in _CACHED_FIELDS:
                value = np.ascontiguousarray(getattr(batch, name))
                group.create_array(name, data=value, chunks=value.shape)
                digests[name] = _sha1(value)
            group.attrs["sha1"] = digests
    except FileExistsError:   # another process wrote it meanwhile; its block is identical
        pass


def _sha1(value: np.ndarray) -> str:
    return hashlib.sha1(np.ascontiguousarray(value).tobytes()).hexdigest()


def _read_block(zarr, path):
    """The arrays of a cached block, or None if it is unreadable or any array differs from
    the digest written with it (a flipped byte, a deleted chunk that zarr would read as
    zeros, a block of an older format)."""
    try:
        group = zarr.open_group(str(path), mode="r")
        digests = group.attrs.get("sha1") or {}
        data = {name: group[name][...] for name in _CACHED_FIELDS}
    except Exception:        # zarr and the codecs raise many types for a damaged store
        return None
    if any(digests.get(name) != _sha1(value) for name, value in data.items()):
        return None
    return data


def _discard(path: Path) -> None:
    """Remove a damaged block (renamed aside first, so no reader sees half of it)."""
    aside = path.with_name(f".{path.name}.damaged-{os.getpid()}")
    try:
        os.rename(path, aside)
    except OSError:
        return                       # another process already replaced it
    shutil.rmtree(aside, ignore_errors=True)


def default_cache_dir() -> Path:
    """``$HIPPO_PROBE_CACHE`` or ``~/.cache/hippo_probe/trials``."""
    return Path(os.environ.get("HIPPO_PROBE_CACHE",
                               Path.home() / ".cache" / "hippo_probe" / "trials"))


def cached_trials(task: str, n_trials: int, split: str = "train", seed: int = 0, *,
                  first: int = 0, cache_dir=None, world=None,
                  config: TaskConfig | None = None) -> TrialBatch:
    """Like :func:`make_trials`, but stored on disk (zarr) and reused.

    Trials are stored in blocks of :data:`CACHE_CHUNK` consecutive indices, one zarr
    group per block, each written beside and renamed into place (atomic: concurrent
    processes and interrupted runs never see half a block). The store's name carries the
    world's name and a fingerprint of the task's whole configuration, so a change to the
    world never reuses stale trials. Each block carries the sha1 of its arrays, checked
    on every read: a damaged block (a flipped byte, a lost chunk) is regenerated, with a
    ``RuntimeWarning``, never trained on.
    """
    import zarr

    check_option("task", task, TASKS)
    check_option("split", split, SPLITS)
    n_trials = check_nonnegative_int("n_trials", n_trials)
    first = check_nonnegative_int("first", first)
    config = resolve_config(task, world, config)
    seed = check_nonnegative_int("seed", seed)
    name = f"{task}-{config.world.name}-{split}-seed{seed}-{config.fingerprint()}"
    root = Path(cache_dir or default_cache_dir()) / name
    root.mkdir(parents=True, exist_ok=True)
    blocks = []
    stop = first + n_trials
    for block in range(first // CACHE_CHUNK, -(-stop // CACHE_CHUNK)):
        path = root / f"block{block:06d}.zarr"
        present = path.exists()
        whole = _read_block(zarr, path) if present else None
        if whole is None:
            if present:
                warnings.warn(f"trial cache block {path} is damaged (its arrays do not "
                              f"match their digests); regenerating it", RuntimeWarning,
                              stacklevel=2)
                _discard(path)
            batch = make_trials(task, CACHE_CHUNK, split, seed, first=block * CACHE_CHUNK,
                                config=config)
            _write_block(zarr, batch, path)
            whole = {name: getattr(batch, name) for name in _CACHED_FIELDS}
        lo = max(first, block * CACHE_CHUNK) - block * CACHE_CHUNK
        hi = min(stop, (block + 1) * CACHE_CHUNK) - block * CACHE_CHUNK
        blocks.append({name: (value[:, lo:hi] if name in _TIME_MAJOR else value[lo:hi])
                       for name, value in whole.items()})
    data = {name: (np.concatenate([b[name] for b in blocks],
                                  axis=1 if name in _TIME_MAJOR else 0)
                   if blocks else None) for name in _CACHED_FIELDS}
    if not blocks:
        return make_trials(task, 0, split, seed, config=config)
    start = data["start"]
    target = data["position"] - start[None] if config.target == "start_relative" \
        else data["position"]
    return TrialBatch(target=target, dt=config.world.motion.network_dt, task=task,
                      split=split, seed=seed, config=config, **data)
