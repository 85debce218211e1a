"""Shared machinery of the figure builders: configurations, cached recordings, output.

Every figure reads recordings of the shipped networks (``hippo_probe/pretrained``) with
the baselines' estimates added, made once and cached under the configuration's cache
folder (:attr:`FigureConfig.cache`: ``<cache_root>/paper-<size>/<world>-seed<k>/``;
``hippo-probe figures`` puts it under its ``--out`` unless given ``--cache``). A cached
recording is reused only if it was made from the same network file and the same
configuration (both hashed into its attrs); otherwise it is rebuilt. The reference
filters' estimates depend on the trials, not on the networks: they are made once per
world and shared by its runs (:attr:`FigureConfig.world_cache`, :func:`shared_arrays`).

Files of the repository that are not package data (the NWB test session, the
hand-written notes of RESULTS.md) are found by :func:`repository_file`: the modules that
need one take its path as an argument, defaulting to the repository's copy.
"""

from __future__ import annotations

import functools
import hashlib
import json
import shutil
import time
from dataclasses import asdict, dataclass, field, fields, replace
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp
from hippo_probe._atomic import atomic_path, exclusive_lock, save_figure, write_text
from hippo_probe.plot import ESTIMATE_LABELS
from hippo_probe.tasks import make_trials, task_config

from ._repository import PACKAGE, REPOSITORY, repository_file  # noqa: F401


@dataclass(frozen=True)
class FigureConfig:
    """Sizes of the data behind the figures.

    ``full`` (the default) regenerates the figures in minutes on 2 CPU cores; ``tiny``
    (tests) runs every code path on a handful of trials; ``paper`` is the study's scale
    (1,000 test trials, PF-SLAM up to 10,000 particles), for the documented rebuild.

    ``cache_root`` is where the cached recordings go
    (``<cache_root>/paper-<name>/<world>-seed<k>/``);
    it is not part of the figures' numbers (not in their JSON, not in cache keys). Give
    it with :func:`with_cache`.
    """

    name: str = "full"
    trials: int = 200            # test trials per recording
    # oracular particle filter; None: the baselines' defaults, converged in each task
    # (1,000 particles with a known start, 2,000 with an unknown one: analyses/README.md)
    particles: int | None = None
    slam_particles: tuple = (100, 1000, 10000)
    slam_trials: int = 50         # PF-SLAM at 10,000 particles: ~30 s on 2 cores
    map_trials: int = 60         # trials of the two-arena recordings (rate maps)
    remap_trials: int = 400      # specialized trials for remapping / selectivity
    dimension_samples: int = 20000   # Eckmann-Ruelle: D up to ~2 log10 N = 8.6 resolvable
    seed: int = 0
    # the run: the world of the networks (and of their trials) and the networks' training
    # seed; `hippo-probe figures` makes every figure once per shipped run (:func:`runs`)
    world: str = "darkness"
    network_seed: int = 0
    cache_root: str | None = field(default=None, repr=False, compare=False)

    def network(self, name: str) -> str:
        """The shipped network ``name`` (e.g. "generalized") of this world."""
        return network_name(name, self.world)

    @property
    def run(self) -> str:
        """The run's name, ``<world>-seed<k>``: its folder under the figures' output."""
        return f"{self.world}-seed{self.network_seed}"

    @property
    def cache(self) -> Path:
        """Folder of this run's cached recordings and arrays."""
        if self.cache_root is None:
            raise ValueError("the figures' cache folder is not set: give the configuration "
                             "one with `with_cache(config, folder)`")
        return Path(self.cache_root) / f"paper-{self.name}" / self.run

    @property
    def world_cache(self) -> Path:
        """Folder of what every run of this world shares: the reference filters'
        estimates, which depend on the world's trials and not on the networks."""
        return self.cache.parent / f"{self.world}-shared"

    def numbers(self) -> dict:
        """The configuration as it is written into each figure's JSON."""
        out = asdict(self)
        out.pop("cache_root")
        return out


#: Range of the correlation sum searched for the scaling region (fig5). C(r) of
#: high-dimensional sets is steep: half a decade of r (the analysis' default shortest
#: scaling range) spans 4+ decades of C once D > 8, so the search goes down to C = 1e-6
#: (200 pairs among the 20,000 points of the full size).
DIMENSION_C_RANGE = (1e-6, 0.1)

CONFIGS = {
    "full": FigureConfig(),
    "tiny": FigureConfig(name="tiny", trials=4, particles=50, slam_particles=(100, 200),
                         slam_trials=2, map_trials=6, remap_trials=12,
                         dimension_samples=1500),
    "paper": FigureConfig(name="paper", trials=1000, slam_trials=100, map_trials=100,
                          remap_trials=1000, dimension_samples=20000),
}


def with_cache(cfg: FigureConfig, folder) -> FigureConfig:
    """``cfg`` with its cached recordings under ``folder``
    (``folder/paper-<size>/<world>-seed<k>/``)."""
    return replace(cfg, cache_root=str(folder))


def cached_under(cfg: FigureConfig, out) -> FigureConfig:
    """``cfg`` as given if it has a cache folder, else with one under ``out/cache``: a
    figure builder called with a bare configuration writes only under its ``out``."""
    return cfg if cfg.cache_root is not None else with_cache(cfg, Path(out) / "cache")


# ----------------------------------------------------------------------- networks
#: The worlds of the figures, in the order of the results table: the study's first.
WORLDS = ("darkness", "compass")


def network_name(name: str, world: str) -> str:
    """The shipped name of network ``name`` (e.g. "generalized_readout") in ``world``:
    the darkness world's carry the task's name, the others a ``_<world>`` after it."""
    if world == "darkness":
        return name
    task, _, rest = name.partition("_")
    return f"{task}_{world}" + (f"_{rest}" if rest else "")


def network_file(name: str, seed: int = 0) -> Path:
    from hippo_probe.pretrained import resolve_network_file
    return resolve_network_file(name, seed)


def shipped_runs(worlds=WORLDS) -> list[tuple[str, int]]:
    """(world, training seed) of every run whose networks are all shipped.

    A run needs each network the figures record (:data:`RECORDINGS`) at that seed.
    """
    from hippo_probe.pretrained import shipped_seeds

    needed = sorted({network for network, *_ in RECORDINGS.values()})
    runs = []
    for world in worlds:
        seeds = set.intersection(*(set(shipped_seeds(network_name(n, world)))
                                   for n in needed))
        runs += [(world, seed) for seed in sorted(seeds)]
    return runs


def for_run(cfg: FigureConfig, world: str, seed: int) -> FigureConfig:
    """``cfg`` for the networks of ``world`` trained with ``seed``."""
    return replace(cfg, world=world, network_seed=seed)


def first_run(cfg: FigureConfig) -> FigureConfig:
    """``cfg`` for the run whose figures are shown: the first of :func:`shipped_runs`
    (the darkness world's first seed once its networks are shipped)."""
    runs = shipped_runs()
    if not runs:
        raise FileNotFoundError("no world has all of the figures' networks shipped "
                                "(hippo_probe/pretrained)")
    return for_run(cfg, *runs[0])


@functools.cache
def code_version() -> str:
    """Hash of the package's sources: a cached recording made by other code is rebuilt.

    Read once per process, so that a process goes on naming its results by the code it
    runs even if the sources are edited while it works."""
    h = hashlib.sha1()
    for path in sorted(PACKAGE.rglob("*.py")):
        h.update(path.read_bytes())
    return h.hexdigest()[:12]


def _digest(*parts) -> str:
    h = hashlib.sha1()
    for p in parts:
        h.update(p if isinstance(p, bytes) else repr(p).encode())
    return h.hexdigest()[:12]


# ----------------------------------------------------------------------- baselines
def baseline_estimates(batch, which, n_particles: int | None) -> dict:
    """Baselines' estimates in the ARENA frame (as recordings hold them), by name.

    ``which`` among "pi", "sh", "nb", "pf"; the PF also gives ``pf_cov`` and its drift.
    ``n_particles`` None: the particle filter's default for the batch's start.
    """
    from hippo_probe.baselines.results import run_baselines
    from hippo_probe.model.record import baselines_from_dataset

    return baselines_from_dataset(run_baselines(batch, n_particles=n_particles,
                                                methods=which), batch)


# ----------------------------------------------------------------------- recordings
RECORDINGS = {
    # name: (network, task, task-config overrides, baselines, n trials attr)
    "localization": ("localization", "localization", {}, ("pi", "sh", "pf"), "trials"),
    "generalized": ("generalized", "generalized", {}, ("pi", "sh", "nb", "pf"), "trials"),
    "specialized": ("specialized", "specialized", {}, ("pi", "sh", "pf"), "trials"),
    "specialized_many": ("specialized", "specialized", {}, (), "remap_trials"),
    "specialized_maps": ("specialized", "specialized", {"n_arenas": 2}, (), "map_trials"),
    "generalized_maps": ("generalized", "generalized", {"arenas": "fixed", "n_arenas": 2},
                         (), "map_trials"),
    "readout": ("generalized_readout", "specialized", {}, (), "trials"),
}


def _recording_key(name: str, cfg: FigureConfig) -> str:
    """What the data set ``name``'s recording depends on: its network file, its trials
    (their number, seed and task overrides), its baselines and their particles, and this
    code."""
    network, _, overrides, which, size_attr = RECORDINGS[name]
    net_path = network_file(cfg.network(network), cfg.network_seed)
    return _digest(net_path.read_bytes(), name, getattr(cfg, size_attr), cfg.particles,
                   cfg.seed, sorted(overrides.items()), which, code_version())


def _cached_recording(name: str, cfg: FigureConfig):
    """The data set ``name``'s recording in ``cfg.cache``, if there and current; else
    None."""
    path = cfg.cache / f"{name}.zarr"
    if path.exists():
        try:
            rec = hp.open_recording(path)
            if rec.attrs.get("paper_key") == _recording_key(name, cfg):
                return rec
        except ValueError:
            pass            # unreadable or half-written: rebuild it
    return None


def _session_id(name: str, cfg: FigureConfig) -> str:
    return f"paper-{name}-{cfg.run}"


def _from_another_recording(name: str, cfg: FigureConfig):
    """The data set ``name``, which has no baselines, read from the cached recording of
    another data set of the same network on the same trials, with that one's baselines
    dropped and this one's attributes: the network is not run and saved again. At the
    paper's size fig4's ``specialized_many`` is fig3's ``specialized``. None when no such
    recording is cached.

    The data set returned reads the other's store lazily: removing or rewriting that
    store while it is in use (another process making figures in the same cache with other
    code) makes its reads fail with an error.
    """
    from hippo_probe.model.record import BASELINE_VARIABLES

    network, task, overrides, which, size_attr = RECORDINGS[name]
    if which:
        return None
    for other, (other_network, other_task, other_overrides, _, other_size_attr) in \
            RECORDINGS.items():
        same_trials = ((other_network, other_task, other_overrides)
                       == (network, task, overrides)
                       and getattr(cfg, other_size_attr) == getattr(cfg, size_attr))
        rec = _cached_recording(other, cfg) if other != name and same_trials else None
        if rec is not None:
            # a stale store of this data set would have been overwritten by a new
            # recording; nothing will read it now
            shutil.rmtree(cfg.cache / f"{name}.zarr", ignore_errors=True)
            rec = rec.drop_vars([v for v in BASELINE_VARIABLES if v in rec])
            if "cov" in rec.coords:
                rec = rec.drop_vars("cov")
            rec.attrs.update(session_id=_session_id(name, cfg),
                             paper_key=_recording_key(name, cfg), paper_dataset=name)
            return rec
    return None


def recording(name: str, cfg: FigureConfig):
    """A cached recording of the paper's data set ``name`` (see :data:`RECORDINGS`):
    its own, or one of the same network on the same trials with more baselines
    (:func:`_from_another_recording`), else recorded now."""
    rec = _cached_recording(name, cfg)
    if rec is None:
        rec = _from_another_recording(name, cfg)
    if rec is not None:
        return rec
    network, task, overrides, which, size_attr = RECORDINGS[name]
    network = cfg.network(network)
    n_trials = getattr(cfg, size_attr)
    net_path = network_file(network, cfg.network_seed)
    key = _recording_key(name, cfg)
    path = cfg.cache / f"{name}.zarr"
    t0 = time.time()
    net = hp.load_pretrained(net_path)
    if net.world != cfg.world:
        raise ValueError(f"network {network!r} is of the {net.world!r} world; the figures "
                         f"are of the {cfg.world!r} world")
    config = task_config(task, cfg.world, **overrides)
    batch = make_trials(task, n_trials, "test", cfg.seed, config=config)
    extra = shared_arrays(f"baselines-{task}-{'-'.join(which)}", cfg,
                          lambda: baseline_estimates(batch, which, cfg.particles),
                          batch_digest(batch), which, cfg.particles) if which else None
    rec = hp.record(net, batch, baselines=extra, checkpoint=net_path.name, config=config,
                    session_id=_session_id(name, cfg))
    rec.attrs["paper_key"] = key
    rec.attrs["paper_dataset"] = name
    cfg.cache.mkdir(parents=True, exist_ok=True)
    hp.save_recording(rec, path, overwrite=True)
    print(f"  recorded {name}: {n_trials} trials in {time.time() - t0:.0f} s -> {path}")
    return hp.open_recording(path)


def cached_arrays(name: str, cfg: FigureConfig, make, *key_parts) -> dict:
    """``make()`` -> dict of arrays, cached as ``<cache>/<name>.npz`` under a key."""
    return _cached_npz(cfg.cache / f"{name}.npz",
                       _digest(name, cfg, *key_parts, code_version()), make)


def batch_digest(batch) -> str:
    """Digest of everything in a :class:`~hippo_probe.tasks.TrialBatch` (its arrays, its
    task, split, seed and whole configuration): what a reference filter's estimates
    depend on."""
    h = hashlib.sha1()
    for field_ in fields(batch):
        value = getattr(batch, field_.name)
        h.update(field_.name.encode())
        if isinstance(value, np.ndarray):
            h.update(repr((value.dtype.str, value.shape)).encode())
            h.update(np.ascontiguousarray(value).tobytes())
        else:
            h.update(repr(value).encode())
    return h.hexdigest()[:16]


def shared_arrays(name: str, cfg: FigureConfig, make, *key_parts) -> dict:
    """``make()`` -> dict of arrays, made once for every run of ``cfg.world``
    (``<world_cache>/<name>.npz``) under the key ``key_parts``: for what depends on the
    world's trials and not on the run's networks (the reference filters; key them on
    :func:`batch_digest`). Runs made at once take turns (a lock file, on systems with
    POSIX locks): the second waits for the first's arrays instead of making them again,
    and says in its log whom it waits for."""
    key = _digest(name, *key_parts, code_version())
    folder = cfg.world_cache
    folder.mkdir(parents=True, exist_ok=True)

    def wait(holder):
        print(f"  waiting for process {holder}, which is making the world's {name}",
              flush=True)

    with exclusive_lock(folder / f"{name}.lock", wait):
        return _cached_npz(folder / f"{name}.npz", key, make)


def _cached_npz(path: Path, key: str, make) -> dict:
    """The arrays of ``path`` if it holds ``key``'s, else ``make()``'s, written there
    atomically (a file that cannot be read is made again)."""
    import zipfile

    try:
        with np.load(path, allow_pickle=False) as f:
            if str(f["_key"]) == key:
                return {k: f[k] for k in f.files if k != "_key"}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        pass                               # absent, half-copied or of another format
    out = make()
    with atomic_path(path, overwrite=True) as tmp, open(tmp, "wb") as f:
        np.savez(f, _key=key, **out)
    return out


# ----------------------------------------------------------------------- output
COLORS = {"network": "k", "estimate": "k", "estimate_pf": "tab:blue",
          "estimate_sh": "tab:orange", "estimate_pi": "tab:red", "estimate_nb": "tab:green",
          "estimate_pfslam": "tab:purple"}
LABELS = ESTIMATE_LABELS


def jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        # six significant digits, not decimals: a p-value of 2e-9 must not become 0
        return None if not np.isfinite(obj) else float(f"{float(obj):.6g}")
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def save(fig, name: str, numbers: dict, cfg: FigureConfig, out: Path) -> None:
    """Write ``<out>/<name>.png``, ``.pdf`` and ``.json`` (the plotted numbers), each
    atomically."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    save_figure(fig, out / f"{name}.png", dpi=130)
    # the PDF takes the PNG's layout instead of solving it again (constrained layout
    # measures every tick label: a second of each figure's saving)
    fig.set_layout_engine("none")
    save_figure(fig, out / f"{name}.pdf")
    plt.close(fig)
    payload = {"figure": name, "size": cfg.numbers(), "run": cfg.run,
               "hippo_probe": hp.__version__, "networks": network_info(cfg), **numbers}
    write_text(out / f"{name}.json", json.dumps(jsonable(payload), indent=1),
               what="figure data", overwrite=True)
    print(f"  wrote {out / name}.png/.pdf/.json")


def network_info(cfg: FigureConfig) -> dict:
    """Training state of the run's networks (steps done, finished or not), by name."""
    from hippo_probe.pretrained import HERE
    info = {}
    for network in sorted({network for network, *_ in RECORDINGS.values()}):
        name = cfg.network(network)
        stem = name if cfg.network_seed == 0 else f"{name}_seed{cfg.network_seed}"
        path = HERE / f"{stem}.log.json"
        if not path.exists():
            continue
        log = json.loads(path.read_text())
        info[stem] = {
            "steps_done": log.get("steps_done"), "steps_budget": log["config"]["steps"],
            "finished": log.get("finished"), "stopped": log.get("stopped"),
            "wall_time_s": log.get("wall_time_s"),
            "base_network_steps": (log.get("base_network") or {}).get("steps_done"),
            "base_network": (log.get("base_network") or {}).get("init_from"),
            # a readout fitted as a convex problem has no steps, a training-set size
            "fit_trials": (log.get("fit") or {}).get("train_trials"),
            "fit_c": (log.get("fit") or {}).get("c")}
    return info


def at_times(time, curve, times=(50.0, 100.0, 200.0)) -> dict:
    """Values of a curve (over ``time``, s) at the samples nearest given times (s)."""
    time, curve = np.asarray(time), np.asarray(curve)
    return {f"{int(t)}s": float(curve[np.argmin(np.abs(time - t))]) for t in times}


def window_mean(time, curve, start=180.0, stop=200.0) -> float:
    """Mean of a curve (over ``time``, s) within ``[start, stop]``: steadier than one
    sample when few trials make the curve noisy."""
    time, curve = np.asarray(time), np.asarray(curve, float)
    return float(np.nanmean(curve[(time >= start) & (time <= stop)]))


def step_times(rec) -> np.ndarray:
    """Times in trial (s) of the network steps, ``dt, 2 dt, ..., T dt``."""
    n = int(round(float(rec.trial_time.max()) / rec.attrs["dt"]))
    return rec.attrs["dt"] * np.arange(1, n + 1)


def with_size(cfg: FigureConfig, **changes) -> FigureConfig:
    return replace(cfg, **changes)
