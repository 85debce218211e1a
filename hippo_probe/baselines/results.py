"""Every baseline on a task's trials, in one labelled dataset that recordings can include.

``hippo-probe baselines --task TASK --split test --out FILE`` writes the dataset of
:func:`run_baselines` as a zarr store (written beside ``FILE`` and renamed into place;
an existing ``FILE`` is replaced only with ``--overwrite``). Layout, one row per trial:

=========================  ==================================  =======================
variable                   dims                                meaning
=========================  ==================================  =======================
``trial_id``               (trial_id)                          index coord: trial
                                                               index within the split
                                                               (``TrialBatch.trial_index``)
``trial_time``             (trial_time)                        index coord: s since the
                                                               trial's start, at the end
                                                               of each step (dt ... T dt)
``space``, ``cov``         coords                              ``["x", "y"]``,
                                                               ``["xx", "yy", "xy"]``
``environment_id``         (environment_id)                    coord: arena ids
                                                               (specialized only)
``position``               (trial_id, trial_time, space)       true position, arena frame
``estimate_pi``            (trial_id, trial_time, space)       path integration
``estimate_sh``            (trial_id, trial_time, space)       single hypothesis
``estimate_nb``            (trial_id, trial_time, space)       naive Bayes
``estimate_pf``            (trial_id, trial_time, space)       oracular particle filter
``pf_cov``                 (trial_id, trial_time, cov)         its posterior covariance
``estimate_pfslam``        (trial_id, trial_time, space)       PF-SLAM (specialized only)
``class_probability_``     (trial_id, trial_time,              PF-SLAM's posterior over
``pfslam``                 environment_id)                     arenas, float32
``heading_drift``          (trial_id, trial_time)              true heading drift (rad)
``estimate_drift_pf``,     (trial_id, trial_time)              the PF's posterior mean
``pf_drift_sd``                                                and s.d. of the drift
``estimate_drift_pfslam``  (trial_id, trial_time)              PF-SLAM's drift (mean)
``start_position``         (trial_id, space)                   start, arena frame
``trial_environment``      (trial_id)                          arena id of each trial
=========================  ==================================  =======================

All estimates are in the **arena frame** (metres), as recordings store them: for the
generalized task the start is added back to the start-relative estimate. Flattening
``(trial_id, trial_time)`` in C order gives the samples of a recording that concatenates
the same trials in the same order along ``time``. Every variable carries ``units`` and
``long_name``; dataset attrs hold the task, world, split, seed, ``dt``, particle counts, the
package version and each method's provenance (``attrs_<method>``, a JSON string).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .._atomic import atomic_path
from .._validators import check_option, check_positive
from .._version import __version__
from ..tasks import TaskConfig
from ._common import resolve_start, resolve_task
from .config import REPORT_TIMES, BaselineConfig
from .naive_bayes import naive_bayes, target_prior
from .particle_filter import particle_filter
from .path_integration import path_integration
from .pf_slam import pf_slam
from .single_hypothesis import single_hypothesis

#: Methods, in plotting order, with their long names.
METHODS = {"pi": "path integration", "sh": "single hypothesis", "nb": "naive Bayes",
           "pf": "particle filter (arena known)", "pfslam": "PF-SLAM"}


def run_baselines(batch, *, n_particles: int | None = None, slam_particles: int | None = None,
                  methods=None, chunk: int = 100, threads: int | None = None,
                  progress: bool = False, config: TaskConfig | None = None,
                  baseline: BaselineConfig | None = None):
    """Run PI, SH, NB, the PF (and PF-SLAM on the specialized task) on ``batch``.

    Parameters
    ----------
    batch : TrialBatch
    n_particles, slam_particles : int, optional
        Defaults from :class:`~hippo_probe.baselines.config.ParticleFilterConfig`.
    methods : sequence of str, optional
        Which to run, among ``"pi"``, ``"sh"``, ``"nb"``, ``"pf"`` and (tasks that
        classify) ``"pfslam"``; default all. The PF's covariance and drift come with
        ``"pf"``, PF-SLAM's arena posterior and drift with ``"pfslam"``.
    chunk : int
        Trials per call of each method (bounds memory; results do not depend on it).
    threads : int, optional
        Threads of the particle filters (default: all cores).
    progress : bool
        Show a progress bar over chunks.
    config : TaskConfig, optional
        Must be the batch's own (``batch.config``, the default) if given.
    baseline : BaselineConfig, optional

    Returns
    -------
    xarray.Dataset
        The layout of the module docstring.

    Examples
    --------
    >>> from hippo_probe.tasks import make_trials
    >>> from hippo_probe.baselines.config import BaselineConfig, NaiveBayesConfig
    >>> batch = make_trials("generalized", n_trials=2, split="test")
    >>> small = BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=50))
    >>> ds = run_baselines(batch, n_particles=100, baseline=small)
    >>> ds["estimate_pf"].dims
    ('trial_id', 'trial_time', 'space')
    """
    import xarray as xr

    config = resolve_task(batch, config)
    baseline = baseline or BaselineConfig()
    chunk = check_positive("chunk", chunk, integer=True)
    pf_config = baseline.particle_filter
    if n_particles is None:
        unknown = resolve_start(None, config) == "unknown"
        n_particles = pf_config.unknown_start_particles if unknown else pf_config.n_particles
    if slam_particles is None:
        slam_particles = pf_config.slam_particles
    n_particles = check_positive("n_particles", n_particles, integer=True)
    slam_particles = check_positive("slam_particles", slam_particles, integer=True)
    offered = [m for m in METHODS if m != "pfslam" or config.classify]
    methods = offered if methods is None else \
        [methods] if isinstance(methods, str) else list(methods)
    if not methods:
        raise ValueError(f"`methods` must name at least one of {offered}; got none")
    for m in methods:
        check_option("methods", m, offered)
    slam = "pfslam" in methods
    prior = target_prior(batch.task, seed=int(batch.seed), config=config,
                         naive_bayes=baseline.naive_bayes) if "nb" in methods else None
    every = {
        "pi": lambda b: path_integration(b, config=config, baseline=baseline),
        "sh": lambda b: single_hypothesis(b, config=config, baseline=baseline),
        "nb": lambda b: naive_bayes(b, prior=prior, config=config, baseline=baseline),
        "pf": lambda b: particle_filter(b, n_particles, threads=threads, config=config,
                                        baseline=baseline),
        "pfslam": lambda b: pf_slam(b, slam_particles, threads=threads, config=config,
                                    baseline=baseline),
    }
    runs = {name: every[name] for name in METHODS if name in methods}
    parts = {name: [] for name in runs}
    starts = range(0, len(batch), chunk)
    if progress:
        from tqdm.auto import tqdm

        starts = tqdm(starts, desc=f"baselines {batch.task}", unit="chunk")
    for lo in starts:
        part = batch.select(slice(lo, lo + chunk))
        for name, run in runs.items():
            parts[name].append(run(part))

    start = np.asarray(batch.start, dtype=np.float64)
    shift = start[:, None, :] if config.target == "start_relative" else 0.0

    def trial_major(results, field):
        return np.concatenate([np.swapaxes(getattr(r, field), 0, 1) for r in results])

    space_dims = ("trial_id", "trial_time", "space")
    data = {"position": (space_dims, np.swapaxes(batch.position, 0, 1),
                         {"units": "m", "long_name": "true position"})}
    attrs = {}
    for name, results in parts.items():
        data[f"estimate_{name}"] = (space_dims, trial_major(results, "estimate") + shift,
                                    {"units": "m", "long_name": f"{METHODS[name]} estimate"})
        attrs[f"attrs_{name}"] = json.dumps(_merge_attrs(results), default=float)
    time_dims = ("trial_id", "trial_time")
    data["heading_drift"] = (time_dims, np.swapaxes(batch.heading_drift, 0, 1),
                             {"units": "rad", "long_name": "true heading drift"})
    if "pf" in parts:
        data["pf_cov"] = (("trial_id", "trial_time", "cov"), trial_major(parts["pf"], "cov"),
                          {"units": "m^2",
                           "long_name": "particle filter posterior covariance"})
        data["estimate_drift_pf"] = (time_dims, trial_major(parts["pf"], "drift_mean"),
                                     {"units": "rad", "long_name": "particle filter heading "
                                                                   "drift, posterior mean"})
        data["pf_drift_sd"] = (time_dims, trial_major(parts["pf"], "drift_sd"),
                               {"units": "rad", "long_name": "particle filter heading "
                                                             "drift, posterior s.d."})
    if "pfslam" in parts:
        data["estimate_drift_pfslam"] = (
            time_dims, trial_major(parts["pfslam"], "drift_mean"),
            {"units": "rad", "long_name": "PF-SLAM heading drift, posterior mean"})
    coords = {
        "trial_id": ("trial_id", np.asarray(batch.trial_index, dtype=np.int64),
                     {"long_name": "trial index within the split"}),
        "trial_time": ("trial_time", batch.time,
                       {"units": "s", "long_name": "time since trial start"}),
        # object dtype: stored as variable-length strings
        "space": ("space", np.array(["x", "y"], dtype=object)),
        "cov": ("cov", np.array(["xx", "yy", "xy"], dtype=object)),
    }
    if slam:
        probability = trial_major(parts["pfslam"], "class_probability")
        coords["environment_id"] = ("environment_id", np.arange(probability.shape[-1]),
                                    {"long_name": "arena id"})
        data["class_probability_pfslam"] = (
            ("trial_id", "trial_time", "environment_id"), probability.astype(np.float32),
            {"units": "1", "long_name": "PF-SLAM posterior probability of each arena"})
    data["start_position"] = (("trial_id", "space"), start,
                              {"units": "m", "long_name": "start position"})
    data["trial_environment"] = ("trial_id", np.asarray(batch.environment, dtype=np.int64),
                                 {"long_name": "arena id of the trial"})
    return xr.Dataset(data, coords=coords, attrs={
        "schema": "hippo_probe.baselines/1", "task": batch.task, "split": batch.split,
        "seed": int(batch.seed), "dt": float(batch.dt), "frame": "arena",
        "world": config.world.name, "heading_drift": float(config.world.noise.heading_drift),
        "config_fingerprint": config.fingerprint(),
        "methods": list(runs),
        "n_particles": int(n_particles) if "pf" in parts else 0,
        "slam_particles": int(slam_particles) if slam else 0,
        "created_by": f"hippo_probe {__version__}", **attrs})


def _merge_attrs(results) -> dict:
    """One provenance dict for the chunks of a method (diagnostics summed or averaged)."""
    merged = dict(results[0].attrs)
    for key in ("n_skipped", "n_fallback_to_pi"):
        if key in merged:
            merged[key] = int(sum(r.attrs[key] for r in results))
    for key in ("mean_resamplings", "mean_resets"):
        if key in merged:
            merged[key] = float(np.mean([r.attrs[key] for r in results]))
    return merged


def localization_errors(ds):
    """Mean Euclidean error over trials of every ``estimate_*`` of ``ds``, vs trial time.

    The error is the same in the arena and in the start-relative frame (both shift
    estimate and truth alike). Returns a DataArray (method, trial_time) in metres.
    """
    import xarray as xr

    names = [m for m in METHODS if f"estimate_{m}" in ds]
    errors = [np.sqrt(((ds[f"estimate_{m}"] - ds["position"]) ** 2).sum("space"))
              .mean("trial_id") for m in names]
    out = xr.concat(errors, dim=xr.DataArray(names, dims="baseline", name="baseline"))
    out.name = "localization_error"
    out.attrs = {"units": "m", "long_name": "localization error",
                 "task": ds.attrs.get("task", ""), "n_trials": int(ds.sizes["trial_id"])}
    return out


def error_table(ds, times=REPORT_TIMES) -> str:
    """Plain-text table of the mean errors at ``times`` (s)."""
    errors = localization_errors(ds)
    head = f"{'method':<32}" + "".join(f"{f'{t:g} s':>10}" for t in times)
    rows = [f"{ds.attrs.get('task', '')} ({ds.attrs.get('world', 'compass')} world): mean "
            f"localization error (m) over {ds.sizes['trial_id']} {ds.attrs.get('split', '')} "
            f"trials", head,
            "-" * len(head)]
    for name in errors["baseline"].values:
        values = [float(errors.sel(baseline=name).sel(trial_time=t, method="nearest"))
                  for t in times]
        rows.append(f"{METHODS[str(name)]:<32}" + "".join(f"{v:>10.3f}" for v in values))
    return "\n".join(rows)


def plot_errors(ds, ax=None):
    """Localization error vs time of every baseline in ``ds``; returns the Figure."""
    import matplotlib.pyplot as plt

    errors = localization_errors(ds)
    if ax is None:
        fig, ax = plt.subplots(figsize=(7.5, 3.8), constrained_layout=True)
    else:
        fig = ax.figure
    for name in errors["baseline"].values:
        ax.plot(errors["trial_time"], errors.sel(baseline=name), lw=1.5,
                label=METHODS[str(name)])
    ax.set_xlabel("time since trial start (s)")
    ax.set_ylabel("localization error (m)")
    ax.set_ylim(bottom=0)
    ax.set_title(f"{ds.attrs.get('task', '')} · {ds.attrs.get('world', 'compass')} world · "
                 f"{ds.sizes['trial_id']} {ds.attrs.get('split', '')} trials")
    # beside the axes: inside, some curve crosses every corner in one task or another
    ax.legend(fontsize=8, frameon=False, loc="center left", bbox_to_anchor=(1.01, 0.5))
    return fig


def save_baselines(ds, path, *, overwrite: bool = False) -> Path:
    """Write ``ds`` as a zarr store at ``path`` atomically (beside, then renamed)."""
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"`path` {str(path)!r} exists; pass overwrite=True "
                              f"(--overwrite) to replace it")
    with atomic_path(path, overwrite=overwrite, what="path") as tmp:
        ds.to_zarr(tmp, mode="w", consolidated=False)
    return path


def open_baselines(path):
    """Open a store written by :func:`save_baselines` (loaded into memory)."""
    import xarray as xr

    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"`path` {str(path)!r} does not exist")
    with xr.open_zarr(path, consolidated=False) as ds:
        return ds.load()
