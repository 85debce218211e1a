"""Record a network like an electrophysiology session: ``record(network, batch)``.

The result is a recording (schema v1, see ``recordings/README.md``) holding everything an
analysis needs, so no analysis ever needs torch: the LSTM's hidden state as ``activity``,
the true pose, the network's estimate in the arena frame, class probabilities and the
classifier's weights, the arena geometry, and optionally the baselines' estimates.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import torch

from ..recording import annotate, stack_trials, trial_layout, validate
from ..tasks import fixed_arenas, task_config
from .lstm import reused_buffers

#: baseline result names accepted by ``record(..., baselines=...)``, with their dims
BASELINE_VARIABLES = {
    "estimate_pi": ("time", "space"), "estimate_sh": ("time", "space"),
    "estimate_nb": ("time", "space"), "estimate_pf": ("time", "space"),
    "estimate_pfslam": ("time", "space"), "pf_cov": ("time", "cov"),
    "class_probability_pfslam": ("time", "environment_id"),
    "estimate_drift_pf": ("time",), "pf_drift_sd": ("time",),
    "estimate_drift_pfslam": ("time",),
}


def baselines_from_dataset(ds, batch) -> dict:
    """Arrays (T, B, ...) for ``record(..., baselines=...)`` from the dataset written by
    ``hippo-probe baselines`` (:mod:`hippo_probe.baselines.results`), matched to the
    batch's trials by trial index; checks that its true positions are the batch's."""
    missing = sorted(set(batch.trial_index.tolist()) - set(ds.trial_id.values.tolist()))
    if missing:
        raise ValueError(f"`baselines` file lacks trials {missing[:5]} of the batch "
                         f"(it has {ds.sizes['trial_id']} trials)")
    # positions are the same in both worlds (only the heading is sensed differently), so
    # the world must be checked by name; files from before the darkness world are compass
    world = ds.attrs.get("world", "compass")
    if world != batch.world.name:
        raise ValueError(f"`baselines` file was made in the {world!r} world; the batch is "
                         f"of the {batch.world.name!r} world: rerun `hippo-probe baselines "
                         f"--world {batch.world.name}`")
    made = ds.attrs.get("config_fingerprint")
    if made is not None and made != batch.config.fingerprint():
        raise ValueError("`baselines` file was made with another task or world configuration "
                         "than the batch's (its config_fingerprint differs): rerun "
                         "`hippo-probe baselines` on these trials")
    ds = ds.sel(trial_id=batch.trial_index)
    position = np.moveaxis(ds["position"].values, 0, 1)
    if position.shape != batch.position.shape or not np.allclose(position, batch.position,
                                                                 atol=1e-6):
        raise ValueError("`baselines` file was made from other trials (its positions differ "
                         "from the batch's): rerun `hippo-probe baselines` with the same "
                         "task, split and seed")
    return {name: np.moveaxis(ds[name].values, 0, 1) for name in BASELINE_VARIABLES
            if name in ds}


def _in_arenas(batch, verts) -> bool:
    """Whether every trial of ``batch`` is in the arena ``verts[its environment id]``."""
    env = np.asarray(batch.environment)
    if env.size and (env.min() < 0 or env.max() >= len(verts)):
        return False
    ids, first = np.unique(env, return_index=True)
    trial_verts = np.asarray(batch.arena_vertices)[first]
    return trial_verts.shape[1:] == verts.shape[1:] and \
        bool(np.allclose(trial_verts, verts[ids], equal_nan=True))


def _is_shipped(file) -> bool:
    """Whether ``file`` is one of the networks shipped with the package."""
    from ..pretrained import HERE

    return Path(file).resolve().parent == HERE.resolve()


@torch.no_grad()
def _run_network(network, batch, chunk: int = 250, *, progress: bool = False):
    """The network on a TrialBatch, in the recording's layout: (h (B*T, H) float32,
    xy (T, B, 2) float64, class probabilities (B*T, C) float32 or None).

    ``h`` and the probabilities are stacked trial after trial (the order of
    :func:`~hippo_probe.recording.layout.stack_trials`). The network runs on ``chunk``
    trials at a time (bounds memory; the result does not depend on it) and each chunk's
    trials are copied straight into their place: a 1,000-trial recording's 0.5 GB of
    units is allocated once, not again for a concatenation, a transposition and a
    type conversion. ``progress`` shows a bar over the trials.
    """
    from tqdm.auto import tqdm

    network.eval()
    T, B = batch.inputs.shape[:2]
    h_out = prob_out = None            # (B, T, ...): trial-major, reshaped at the end
    xys = []
    # each chunk's h is copied out before the next: their buffers are used again
    with tqdm(total=B, desc=f"record {batch.task}", unit="trial",
              disable=not progress) as bar, reused_buffers():
        for lo in range(0, B, chunk):
            xy, logits, h = network(torch.from_numpy(batch.inputs[:, lo:lo + chunk]))
            hi = lo + h.shape[1]
            if h_out is None:
                h_out = np.empty((B, T, h.shape[2]), np.float32)
            h_out[lo:hi] = np.swapaxes(h.numpy(), 0, 1)
            xys.append(xy.numpy())
            if logits is not None:
                prob = torch.softmax(logits, dim=-1).numpy()
                if prob_out is None:
                    prob_out = np.empty((B, T, prob.shape[2]), np.float32)
                prob_out[lo:hi] = np.swapaxes(prob, 0, 1)
            bar.update(h.shape[1])
    xy = np.concatenate(xys, axis=1).astype(np.float64)
    return (h_out.reshape(B * T, h_out.shape[2]), xy,
            None if prob_out is None else prob_out.reshape(B * T, prob_out.shape[2]))


def record(network, batch, *, baselines: dict | None = None, session_id: str | None = None,
           checkpoint: str | None = None, config=None, chunk: int = 250,
           progress: bool = False):
    """Run ``network`` on ``batch`` and return its recording.

    Parameters
    ----------
    network : Navigator
        E.g. ``hippo_probe.load_pretrained("generalized")``.
    batch : TrialBatch
        Trials to run (any task: a network can be recorded in another task's arenas).
    baselines : dict, optional
        Arrays (T, B, ...) in the arena frame to add, named as in
        :data:`BASELINE_VARIABLES` (e.g. ``{"estimate_pf": ..., "pf_cov": ...}``).
    session_id, checkpoint : str, optional
        Dataset attrs (defaults: ``"<task>-<split>-seed<seed>"`` and the network's file:
        its path, or its name alone for a shipped network, e.g. ``"generalized.pt"``).
    config : TaskConfig, optional
        Must be the batch's own configuration (``batch.config``, the default) if given.
    chunk : int
        Trials run through the network at once (bounds memory; results do not depend on
        it).
    progress : bool
        Show a progress bar over the trials (``hippo-probe record`` does).

    Returns
    -------
    xarray.Dataset
        ``activity`` (time, unit) = LSTM h (float32); ``position``, ``head_direction``,
        ``contact``, ``speed``; ``estimate`` (time, space): the network's estimate in the
        arena frame (the start position added back for start-relative tasks); if the
        network classifies: ``class_probability`` (time, environment_id) and
        ``readout_weight`` (environment_id, unit); ``position_readout_weight`` (space,
        unit); ``arena_vertices`` (environment_id, vertex, space).

    Examples
    --------
    >>> import hippo_probe as hp
    >>> net = hp.load_pretrained("specialized")                       # doctest: +SKIP
    >>> batch = hp.tasks.make_trials("specialized", 20, "test")       # doctest: +SKIP
    >>> rec = hp.record(net, batch)                                   # doctest: +SKIP
    >>> hp.ratemaps(rec)                                              # doctest: +SKIP
    """
    if batch.inputs.shape[1] == 0:
        raise ValueError("`batch` holds 0 trials: nothing to record (make at least one "
                         "trial, e.g. --trials 1)")
    task = batch.checked_config(config)
    net_world = (getattr(network, "info", None) or {}).get("world")
    if net_world is not None and net_world != task.world.name:
        warnings.warn(f"`network` was trained in the {net_world!r} world but `batch` holds "
                      f"{task.world.name!r} trials: its units are recorded outside the "
                      f"world they learned (the recording's attrs say both)", UserWarning,
                      stacklevel=2)
    h, xy, prob = _run_network(network, batch, chunk, progress=progress)
    T, B, H = xy.shape[0], xy.shape[1], h.shape[1]
    net_task = getattr(network, "task", None) or batch.task
    # the position readout speaks in the frame of the task it was trained on (a fitted
    # arena readout's network keeps its base network's position readout)
    if task_config(getattr(network, "position_task", None) or net_task).target \
            == "start_relative":
        estimate = xy + batch.start[None]
    else:
        estimate = xy
    net_file = (getattr(network, "info", None) or {}).get("file")
    if net_file and _is_shipped(net_file):
        net_file = Path(net_file).name  # the same on every machine, as the study's recordings
    rec = trial_layout(
        T, B, batch.dt, trial_id=batch.trial_index, environment=batch.environment,
        start_position=batch.start, task=batch.task, split=batch.split,
        seed=int(batch.seed), network_task=str(net_task),
        checkpoint=str(checkpoint or net_file or net_task),
        session_id=session_id or f"{batch.task}-{task.world.name}-{batch.split}-seed{batch.seed}",
        subject=f"navigator-{net_task}", species="artificial (peephole LSTM)",
        world=task.world.name, heading_drift_rad_per_sqrt_s=float(task.world.noise.heading_drift),
        network_world=str((getattr(network, "info", None) or {}).get("world", "unknown")))

    # environment table: the classifier's classes (all arenas of its task) when the trials
    # are in them, else every arena of the batch's task (fixed arenas) or of its trials
    # (novel arenas)
    if prob is not None:
        classes = task_config(net_task if task_config(net_task).classify else "specialized")
        class_verts = np.asarray(fixed_arenas(classes.name, classes))
        if not _in_arenas(batch, class_verts):
            warnings.warn(f"`network` names the {len(class_verts)} arenas of the "
                          f"{classes.name!r} task, and `batch` holds {batch.task!r} trials "
                          f"in other arenas: its class probabilities and arena readout are "
                          f"left out of the recording (they would be scored against "
                          f"unrelated labels)", UserWarning, stacklevel=2)
            prob = None
    if prob is not None:
        env_ids = np.arange(classes.n_arenas)
        verts = class_verts
    elif task.arenas == "fixed":
        env_ids = np.arange(task.n_arenas)
        verts = np.asarray(fixed_arenas(batch.task, task))
    else:
        env_ids, first = np.unique(batch.environment, return_index=True)
        verts = batch.arena_vertices[first]
    if prob is not None and prob.shape[-1] != len(env_ids):
        raise ValueError(f"`network` classifies {prob.shape[-1]} arenas; expected "
                         f"{len(env_ids)} (the specialized task's arenas)")
    unknown = np.setdiff1d(batch.environment, env_ids)
    if unknown.size:
        raise ValueError(f"`batch` has arenas {unknown[:5].tolist()} outside the "
                         f"environment table (ids 0..{len(env_ids) - 1})")
    rec = rec.assign_coords(environment_id=env_ids, unit=np.arange(H))
    step = np.linalg.norm(np.diff(np.concatenate([batch.start[None], batch.position]),
                                  axis=0), axis=-1)
    data = {
        "activity": (("time", "unit"), h),
        "position": (("time", "space"), stack_trials(batch.position)),
        "head_direction": ("time", stack_trials(batch.head_direction)),
        "heading_drift": ("time", stack_trials(batch.heading_drift)),
        "contact": ("time", stack_trials(batch.contact)),
        "speed": ("time", stack_trials(step / batch.dt)),
        "estimate": (("time", "space"), stack_trials(estimate)),
        "arena_vertices": (("environment_id", "vertex", "space"), verts),
    }
    readout = network.position.weight.detach().numpy().copy()
    if readout.shape[0] == 2:
        data["position_readout_weight"] = (("space", "unit"), readout)
    else:                   # the "placecells" variant: a population of place cells
        data["place_cell_readout_weight"] = (("place_cell", "unit"), readout)
    if prob is not None:
        data["class_probability"] = (("time", "environment_id"), prob)
        data["readout_weight"] = (("environment_id", "unit"),
                                  network.classifier.weight.detach().numpy().copy())
    for name, values in (baselines or {}).items():
        if name not in BASELINE_VARIABLES:
            raise ValueError(f"`baselines` keys must be among {sorted(BASELINE_VARIABLES)}; "
                             f"got {name!r}")
        values = np.asarray(values)
        if values.shape[:2] != (T, B):
            raise ValueError(f"`baselines[{name!r}]` must have shape ({T}, {B}, ...); "
                             f"got {values.shape}")
        data[name] = (BASELINE_VARIABLES[name], stack_trials(values))
    rec = rec.assign(data)
    if "pf_cov" in rec:
        from ..recording.schema import COV
        rec = rec.assign_coords(cov=("cov", np.array(COV, dtype=object)))
    if "position_readout_weight" in rec:
        rec["position_readout_weight"].attrs.update(
            units="m", long_name="weight of the (x, y) position readout")
    else:
        rec["place_cell_readout_weight"].attrs.update(
            units="1", long_name="weight of the place-cell readout (logits)")
        rec["place_cell_centre"] = (("place_cell", "space"),
                                    network.position.centres.numpy().copy(),
                                    {"units": "m", "long_name": "place cell centre"})
        rec["place_cell"] = ("place_cell", np.arange(readout.shape[0]),
                             {"units": "1", "long_name": "place cell"})
    rec["vertex"] = ("vertex", np.arange(verts.shape[1]),
                     {"units": "1", "long_name": "polygon vertex index"})
    rec = annotate(rec)
    validate(rec)
    return rec
