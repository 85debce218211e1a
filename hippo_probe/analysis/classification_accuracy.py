"""Accuracy of environment classification vs time in trial."""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import _common
from .config import CONVENTIONS
from .localization_error import trial_time_average


def classification_accuracy(rec, probability="class_probability"):
    """Fraction of trials whose most probable environment is the true one, vs time in trial.

    .. math:: \\mathrm{acc}(t) = \\langle [\\arg\\max_e P_j(e, t) = e_j] \\rangle_j

    also the mean probability given to the true environment, :math:`\\langle P_j(e_j, t)
    \\rangle_j`. Samples whose probabilities are all NaN are skipped.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``environment``, ``trial_time`` and the class probabilities
        (time, environment_id).
    probability : str
        Variable holding the probabilities: ``"class_probability"`` (network) or
        ``"class_probability_pfslam"``.

    Returns
    -------
    xarray.Dataset
        ``accuracy``, ``true_class_probability`` and ``n_trials`` over ``trial_time``;
        attrs ``chance`` = 1 / number of environments.

    References
    ----------
    Kanitscheider & Fiete (2017), NIPS 30 (Fig. 3C: classification of the arena).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> p = np.array([[0.6, 0.4], [0.2, 0.8], [0.9, 0.1], [0.3, 0.7]])
    >>> rec = xr.Dataset(
    ...     {"class_probability": (("time", "environment_id"), p)},
    ...     coords={"time": np.arange(4.0), "trial_time": ("time", [0.0, 1, 0, 1]),
    ...             "environment": ("time", [1, 1, 0, 0]), "environment_id": [0, 1]},
    ...     attrs={"dt": 1.0})
    >>> classification_accuracy(rec).accuracy.values
    array([0.5, 0.5])
    """
    rec = _common.check_recording(rec, [probability, "environment", "trial_time"],
                            why="classification accuracy")
    prob = rec[probability]
    if "environment_id" not in prob.dims:
        raise ValueError(f"`rec.{probability}` must have dims ('time', 'environment_id'); "
                         f"got {prob.dims}")
    prob = _common.values(prob.transpose("time", "environment_id")).astype(float)
    ids = _common.values(rec["environment_id"])
    env = _common.values(rec["environment"])
    known = np.isin(env, ids)
    if not known.all():
        missing = np.unique(env[~known])[:5]
        raise ValueError(f"`rec.environment` holds ids {list(missing)} that are not in "
                         f"`environment_id` {list(ids[:10])}: accuracy is undefined")
    valid = np.isfinite(prob).any(axis=1)
    if not valid.any():
        raise ValueError(f"`rec.{probability}` is all NaN: accuracy cannot be computed")
    # a posterior over the environments: >= 0 and summing to 1 (float32 rounding aside);
    # anything else (all zeros, logits, percentages) would give a plausible wrong argmax
    total = np.nansum(prob, axis=1)
    off = valid & ((np.abs(total - 1) > CONVENTIONS.probability_tolerance)
                   | (np.nanmin(np.where(valid[:, None], prob, 0.0), axis=1) < 0))
    if off.any():
        i = int(np.flatnonzero(off)[0])
        raise ValueError(f"`rec.{probability}` must hold probabilities (>= 0, summing to 1 "
                         f"over `environment_id` at each sample); at index {i} they sum to "
                         f"{total[i]:.6g} (min {np.nanmin(prob[i]):.6g})")
    best = ids[np.argmax(np.where(np.isfinite(prob), prob, -np.inf), axis=1)]
    sorter = np.argsort(ids, kind="stable")          # ids may be integers or text
    true_col = sorter[np.searchsorted(ids, env, sorter=sorter)]
    p_true = prob[np.arange(len(env)), true_col]
    correct = np.where(valid, (best == env).astype(float), np.nan)
    tt, mean, sem, count = trial_time_average(np.c_[correct, np.where(valid, p_true, np.nan)],
                                              rec)
    out = xr.Dataset(coords={"trial_time": ("trial_time", tt,
                                            {"units": "s", "long_name": "time in trial"})})
    out["accuracy"] = ("trial_time", mean[:, 0], {"units": "1",
                                                  "long_name": "classification accuracy"})
    out["accuracy_sem"] = ("trial_time", sem[:, 0], {"units": "1",
                                                     "long_name": "s.e.m. of accuracy"})
    out["true_class_probability"] = ("trial_time", mean[:, 1], {
        "units": "1", "long_name": "probability of the true environment"})
    out["n_trials"] = ("trial_time", count[:, 0], {"units": "1", "long_name": "trials averaged"})
    out.attrs = _common.provenance("classification_accuracy", rec, probability=probability,
                                   chance=1.0 / len(ids),
                                   sem="NaN where fewer than 2 trials contribute")
    return out
