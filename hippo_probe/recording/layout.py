"""The time axis and trial table of a recording, and trial-aligned chunks.

``trial_layout`` + ``stack_trials`` turn per-trial arrays (``T`` steps × ``B`` trials, as
a network or a :class:`hippo_probe.tasks.TrialBatch` holds them) into the schema's
concatenated ``time`` axis::

    rec = trial_layout(T, B, dt, environment=batch.environment, start_position=batch.start)
    rec["activity"] = ("time", "unit"), stack_trials(h).astype("float32")
    rec["position"] = ("time", "space"), stack_trials(batch.position)
    rec = annotate(rec.assign_coords(unit=np.arange(h.shape[-1])))
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_number, check_positive, check_shape
from .._version import __version__
from .schema import SCHEMA_VERSION, SPACE, annotate


def trial_blocks(trial):
    """Contiguous runs of equal values of a per-sample ``trial`` array.

    Returns
    -------
    starts, stops : int arrays
        Sample ``starts[k]:stops[k]`` form the k-th run.
    ids : array
        The trial value of each run.

    Examples
    --------
    >>> trial_blocks(np.array([4, 4, 7, 7, 7]))
    (array([0, 2]), array([2, 5]), array([4, 7]))
    """
    trial = np.asarray(trial)
    if trial.size == 0:
        empty = np.zeros(0, dtype=int)
        return empty, empty, trial[:0]
    starts = np.concatenate([[0], np.flatnonzero(trial[1:] != trial[:-1]) + 1])
    stops = np.concatenate([starts[1:], [trial.size]])
    return starts, stops, trial[starts]


def stack_trials(x):
    """Concatenate time-major per-trial arrays along time: ``(T, B, ...) -> (B*T, ...)``.

    Trial ``b`` occupies rows ``b*T`` to ``(b+1)*T - 1``, the order of
    :func:`trial_layout`'s time axis.

    Examples
    --------
    >>> stack_trials(np.array([[1, 10], [2, 20], [3, 30]]))   # T=3 steps, B=2 trials
    array([ 1,  2,  3, 10, 20, 30])
    """
    x = np.asarray(x)
    if x.ndim < 2:
        raise ValueError(f"`x` must have shape (T, B, ...); got {x.shape}")
    return np.swapaxes(x, 0, 1).reshape((x.shape[0] * x.shape[1],) + x.shape[2:])


def trial_layout(n_steps, n_trials, dt, *, trial_id=None, environment=None,
                 start_position=None, t0=0.0, source="network",
                 activity_kind="lstm_hidden", **attrs):
    """The coords and attrs of a recording of ``n_trials`` trials of ``n_steps`` steps.

    Sample ``s`` of trial ``k`` (its state at the *end* of step ``s``) is at
    ``trial_time = (s + 1) dt`` and ``time = trial_start[k] + (s + 1) dt`` with
    ``trial_start[k] = t0 + k (n_steps + 1) dt``: consecutive trials are separated by
    one empty ``dt``, as the schema asks. Add the data variables (flattened with
    :func:`stack_trials`), the ``unit`` coord and any ``environment_id`` table, then
    call :func:`~hippo_probe.recording.schema.annotate` and
    :func:`~hippo_probe.recording.validate`.

    Parameters
    ----------
    n_steps, n_trials : int
        ``T`` and ``B``.
    dt : float
        Step (s).
    trial_id : (B,) int, optional
        Trial ids (default ``0 .. B-1``); e.g. each trial's index within its split.
    environment : int or (B,) int, optional
        Environment (arena) id of each trial (default 0).
    start_position : (B, 2), optional
        Start position of each trial, arena frame (m).
    t0 : float
        Start of the first trial (s).
    source, activity_kind : str
        Dataset attrs (defaults for a network recording).
    **attrs
        More dataset attrs (``task``, ``seed``, ``checkpoint`` …).

    Returns
    -------
    xarray.Dataset
        Coords ``time, trial, trial_time, environment, trial_id, trial_start,
        trial_stop, trial_environment, environment_id, space`` (and ``start_position``),
        with units and long names, and the attrs ``schema_version, source,
        activity_kind, dt, created_by`` plus ``attrs``.

    Examples
    --------
    >>> rec = trial_layout(3, 2, 0.5, environment=[7, 9])
    >>> rec.time.values
    array([0.5, 1. , 1.5, 2.5, 3. , 3.5])
    >>> rec.trial_start.values
    array([0., 2.])
    """
    n_steps = check_positive("n_steps", n_steps, integer=True)
    n_trials = check_positive("n_trials", n_trials, integer=True)
    dt = check_positive("dt", dt)
    t0 = check_number("t0", t0)
    if trial_id is None:
        trial_id = np.arange(n_trials)
    trial_id = check_shape("trial_id", np.asarray(trial_id), (n_trials,))
    environment = np.broadcast_to(np.asarray(0 if environment is None else environment),
                                  (n_trials,))
    step_time = (np.arange(n_steps) + 1) * dt
    trial_start = t0 + np.arange(n_trials) * (n_steps + 1) * dt
    table = {"trial_start": trial_start, "trial_stop": trial_start + n_steps * dt,
             "trial_environment": environment.copy()}
    if start_position is not None:
        table["start_position"] = check_shape("start_position", start_position,
                                              (n_trials, 2)).astype(float)
    return assemble(
        time=np.repeat(trial_start, n_steps) + np.tile(step_time, n_trials),
        trial=np.repeat(trial_id, n_steps), trial_time=np.tile(step_time, n_trials),
        trial_id=trial_id, table=table, dt=dt,
        attrs=dict(source=source, activity_kind=activity_kind, **attrs))


def assemble(*, time, trial, trial_time, trial_id, table, dt, attrs,
             environment_ids=None):
    """The schema's coords and attrs from a time axis and a trial table (internal)."""
    trial_id = np.asarray(trial_id)
    trial_env = np.asarray(table["trial_environment"])
    starts, stops, _ = trial_blocks(trial)
    coords = {
        "time": np.asarray(time, dtype=float),
        "trial": ("time", np.asarray(trial)),
        "trial_time": ("time", np.asarray(trial_time, dtype=float)),
        "environment": ("time", np.repeat(trial_env, stops - starts)),
        "trial_id": trial_id,
        "space": np.array(SPACE, dtype=object),
        "environment_id": (np.unique(trial_env) if environment_ids is None
                           else np.asarray(environment_ids)),
    }
    for name, values in table.items():
        dims = ("trial_id", "space") if name == "start_position" else ("trial_id",)
        coords[name] = (dims, np.asarray(values))
    base = {"schema_version": SCHEMA_VERSION, "dt": float(dt),
            "created_by": f"hippo_probe {__version__}"}
    return annotate(xr.Dataset(coords=coords, attrs={**base, **attrs}))


def is_trial_aligned(trial, chunks) -> bool:
    """True when every chunk along ``time`` holds whole trials or a piece of one trial.

    Examples
    --------
    >>> is_trial_aligned(np.repeat([0, 1], [4, 4]), (2, 2, 4)), is_trial_aligned(
    ...     np.repeat([0, 1], [4, 4]), (3, 5))
    (True, False)
    """
    starts = trial_blocks(trial)[0]
    edges = set(starts.tolist()) | {len(trial)}
    bounds = np.cumsum((0,) + tuple(chunks))
    for a, b in zip(bounds[:-1].tolist(), bounds[1:].tolist()):
        inner = starts[(starts > a) & (starts < b)]
        if inner.size and not (a in edges and b in edges):
            return False
    return True


def trial_aligned_chunks(trial, samples_per_chunk):
    """Chunk sizes along ``time`` that never straddle two trials.

    Consecutive whole trials are grouped while the group holds at most
    ``samples_per_chunk`` samples; a trial longer than that is cut into pieces of
    ``samples_per_chunk`` (the last one shorter), which match regular stored chunks of
    that size when the trial starts on a chunk boundary (e.g. a one-trial session).

    Examples
    --------
    >>> trial_aligned_chunks(np.repeat([0, 1, 2, 3], [3, 3, 3, 10]), 7)
    (6, 3, 7, 3)
    """
    starts, stops, _ = trial_blocks(trial)
    chunks, current = [], 0
    for length in (stops - starts).tolist():
        if current and current + length > samples_per_chunk:
            chunks.append(current)
            current = 0
        if length > samples_per_chunk:
            full, rest = divmod(length, samples_per_chunk)
            chunks.extend([samples_per_chunk] * full + ([rest] if rest else []))
        else:
            current += length
    if current:
        chunks.append(current)
    return tuple(chunks)
