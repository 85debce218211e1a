"""Localization error of position estimates vs time in trial."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._angles import wrap_angle
from .._validators import check_real, check_shape
from . import _common


def trial_time_average(values, rec):
    """Mean, s.e.m. and count over trials of per-sample ``values`` (time, k) at each
    time in trial that occurs (samples are matched by ``round(trial_time / dt)``); NaN
    values are skipped.

    Returns ``(trial_time, mean, sem, count)``.
    """
    dt = _common.sample_dt(rec)
    step = np.rint(_common.values(rec["trial_time"]) / dt).astype(np.int64)
    steps, index = np.unique(step, return_inverse=True)
    n_steps = len(steps)
    values = np.asarray(values, float).reshape(len(step), -1)
    ok = np.isfinite(values)
    v = np.where(ok, values, 0.0)
    count = np.zeros((n_steps, values.shape[1]))
    total = np.zeros_like(count)
    total2 = np.zeros_like(count)
    for j in range(values.shape[1]):
        count[:, j] = np.bincount(index, weights=ok[:, j], minlength=n_steps)
        total[:, j] = np.bincount(index, weights=v[:, j], minlength=n_steps)
        total2[:, j] = np.bincount(index, weights=v[:, j] ** 2, minlength=n_steps)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = total / count
        var = (total2 - count * mean**2) / (count - 1)
        sem = np.sqrt(np.maximum(var, 0.0) / count)
    return steps * dt, mean, sem, count


def position_errors(estimate, position, centre=(0.0, 0.0)):
    """Euclidean, radial and angular error of ``estimate`` (n, 2) about ``centre``.

    .. math:: e = \\lVert\\hat p - p\\rVert,\\quad
              e_r = \\bigl|\\,\\lVert\\hat p - c\\rVert - \\lVert p - c\\rVert\\,\\bigr|,\\quad
              e_\\theta = \\bigl|\\mathrm{wrap}(\\angle(\\hat p - c) - \\angle(p - c))\\bigr|
    """
    est = np.asarray(estimate, float) - centre
    pos = np.asarray(position, float) - centre
    euclid = np.linalg.norm(est - pos, axis=1)
    radial = np.abs(np.linalg.norm(est, axis=1) - np.linalg.norm(pos, axis=1))
    diff = np.arctan2(est[:, 1], est[:, 0]) - np.arctan2(pos[:, 1], pos[:, 0])
    angular = np.abs(wrap_angle(diff))
    return euclid, radial, angular


def _xy(rec, name):
    da = rec[name]
    if set(da.dims) != {"time", "space"}:
        raise ValueError(f"`rec.{name}` must be a position (dims ('time', 'space')) to be "
                         f"compared with `rec.position`; got dims {da.dims}")
    if "space" in da.coords:
        da = da.sel(space=["x", "y"])
    return _common.values(da.transpose("time", "space"))


def localization_error(rec, estimate="estimate", *, centre=(0.0, 0.0)):
    """Euclidean, radial and angular error of a position estimate vs time in trial.

    .. math:: e(t) = \\langle \\lVert \\hat p_{j}(t) - p_{j}(t) \\rVert \\rangle_j,\\quad
              e_r(t) = \\langle \\bigl|\\lVert \\hat p_j\\rVert - \\lVert p_j\\rVert\\bigr|
              \\rangle_j,\\quad
              e_\\theta(t) = \\langle |\\mathrm{wrap}(\\angle \\hat p_j - \\angle p_j)|
              \\rangle_j

    averaged over trials :math:`j` at each time in trial, with radius and polar angle taken
    about the arena's centre (the origin of the arena frame). Radial and angular errors
    separate a wrong distance from the centre from a wrong bearing (e.g. an estimate
    rotated by an arena symmetry).

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``position``, ``trial_time`` and the estimate(s).
    estimate : str or list of str
        Variable(s) holding estimates (time, space) in the arena frame, e.g.
        ``"estimate"``, ``"estimate_pf"``; several give an ``estimate`` dim.
    centre : (x, y)
        Centre for the radial and angular errors (default: the arena frame's origin).

    Returns
    -------
    xarray.Dataset
        ``euclidean``, ``radial`` (m), ``angular`` (rad), each with ``*_sem``, and
        ``n_trials`` over ``trial_time`` (and ``estimate`` for several).

    References
    ----------
    Kanitscheider & Fiete (2017), Training recurrent networks to generate hypotheses
    about how the brain solves hard navigation problems, NIPS 30 (Fig. 2-3).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> t = np.arange(4) * 0.5
    >>> rec = xr.Dataset(
    ...     {"position": (("time", "space"), np.ones((4, 2))),
    ...      "estimate": (("time", "space"), np.ones((4, 2)) + [0.3, 0.4])},
    ...     coords={"time": t, "trial_time": ("time", t), "space": ["x", "y"]},
    ...     attrs={"dt": 0.5})
    >>> localization_error(rec).euclidean.values
    array([0.5, 0.5, 0.5, 0.5])
    """
    names = [estimate] if isinstance(estimate, str) else list(estimate)
    rec = _common.check_recording(rec, ["position", "trial_time", *names],
                            why="localization error")
    centre = check_shape("centre", check_real("centre", centre).astype(float), (2,))
    pos = _xy(rec, "position")
    results = []
    for name in names:
        est = _xy(rec, name)
        errors = np.stack(position_errors(est, pos, centre), axis=1)
        if not np.isfinite(errors).any():
            raise ValueError(f"`rec.{name}` and `rec.position` have no sample where both are "
                             "finite: localization error cannot be computed")
        tt, mean, sem, count = trial_time_average(errors, rec)
        results.append((mean, sem, count[:, 0]))
    many = not isinstance(estimate, str)
    dims = ("estimate", "trial_time") if many else ("trial_time",)

    def pick(i, j):
        stacked = np.stack([r[i][:, j] if r[i].ndim == 2 else r[i] for r in results])
        return stacked if many else stacked[0]

    coords = {"trial_time": ("trial_time", tt, {"units": "s", "long_name": "time in trial"})}
    if many:
        coords["estimate"] = ("estimate", names)
    out = xr.Dataset(coords=coords)
    for j, (name, units, long) in enumerate([
            ("euclidean", "m", "Euclidean error"), ("radial", "m", "radial error"),
            ("angular", "rad", "angular error")]):
        out[name] = (dims, pick(0, j), {"units": units, "long_name": long})
        out[f"{name}_sem"] = (dims, pick(1, j), {"units": units,
                                                  "long_name": f"s.e.m. of {long.lower()}"})
    out["n_trials"] = (dims, pick(2, 0), {"units": "1", "long_name": "trials averaged"})
    out.attrs = _common.provenance("localization_error", rec, estimate=names,
                                   centre=list(centre),
                                   sem="NaN where fewer than 2 trials contribute")
    return out
