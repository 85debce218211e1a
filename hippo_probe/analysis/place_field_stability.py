"""Place-field stability: rate-map correlation between disjoint parts of a session."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_number, check_option
from . import _common
from .._docs import fill_doc
from .config import STABILITY
from .ratemaps import _ratemap_parts


def pearson_masked(a, b, min_n):
    """Pearson r along the last axis over entries finite in both; NaN below ``min_n``.

    Returns ``(r, n)``.
    """
    ok = np.isfinite(a) & np.isfinite(b)
    n = ok.sum(axis=-1)
    a0, b0 = np.where(ok, a, 0.0), np.where(ok, b, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ma, mb = a0.sum(-1, keepdims=True) / n[..., None], b0.sum(-1, keepdims=True) / n[..., None]
        da, db = np.where(ok, a0 - ma, 0.0), np.where(ok, b0 - mb, 0.0)
        r = (da * db).sum(-1) / np.sqrt((da**2).sum(-1) * (db**2).sum(-1))
    return np.where(n >= min_n, r, np.nan), n


def _split_codes(rec, split):
    """Sample -> (environment, part) code; part 0/1 by trials or by time."""
    env = _common.values(rec["environment"]) if "environment" in rec.coords or \
        "environment" in rec else np.zeros(rec.sizes["time"], np.int64)
    trial = _common.values(rec["trial"]) if "trial" in rec.coords or "trial" in rec \
        else np.zeros(rec.sizes["time"], np.int64)
    envs, env_code = np.unique(env, return_inverse=True)
    part = np.zeros(len(env), np.int64)
    how = {}
    for e in range(len(envs)):
        idx = np.flatnonzero(env_code == e)
        trials = list(dict.fromkeys(trial[idx]))  # in order of appearance
        if len(trials) >= 2:
            if split == "odd_even":
                second = trials[1::2]
            else:
                second = trials[len(trials) // 2:]
            part[idx] = np.isin(trial[idx], second)
            how[str(envs[e])] = f"{split} of {len(trials)} trials"
        else:
            # a single trial (e.g. one rodent session): its first vs second half in time
            part[idx[len(idx) // 2:]] = 1
            how[str(envs[e])] = "first vs second half of the samples (one trial)"
    return env_code * 2 + part, envs, how


@fill_doc
def place_field_stability(rec, *, split="halves", bin_size=None, sigma=None, min_speed=None,
                          extent=None, min_bins=None):
    """Correlation of each unit's rate maps from two disjoint parts of a session.

    .. math:: s = \\mathrm{corr}_i\\bigl(\\lambda^{A}_i, \\lambda^{B}_i\\bigr)

    Pearson correlation over the bins visited in both parts A and B, computed in each
    environment separately. The parts are disjoint sets of trials of that environment:
    the first and second half of its trials (``split="halves"``) or alternating trials
    (``"odd_even"``); an environment with a single trial (a rodent session) is split into
    the first and second half of its samples.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and ``position``; may be dask-backed.
    split : {'halves', 'odd_even'}
        How trials are divided.
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    %(extent)s
    min_bins : int, optional
        Fewer common visited bins give NaN (default 5).

    Returns
    -------
    xarray.Dataset
        ``stability`` (unit, environment) and ``n_bins`` (environment) common bins.

    References
    ----------
    Muller & Kubie (1987), The effects of changes in the environment on the spatial firing
    of hippocampal complex-spike cells, J. Neurosci. 7:1951-1968. Thompson & Best (1990),
    Long-term stability of the place-field activity of single units recorded from the
    dorsal hippocampus of freely behaving rats, Brain Res. 509:299-308.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(6000) * 0.1
    >>> xy = 0.5 * np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> field = np.exp(-((xy - 0.2) ** 2).sum(1, keepdims=True) / 0.02)
    >>> rec = from_arrays(t, xy, activity=field, activity_kind="rate")
    >>> bool(place_field_stability(rec, bin_size=0.2).stability[0, 0] > 0.99)
    True
    """
    rec = _common.check_recording(rec, ["activity", "position"], why="place-field stability")
    check_option("split", split, ("halves", "odd_even"))
    # a correlation needs at least 2 bins visited in both halves
    min_bins = check_number("min_bins", STABILITY.min_bins if min_bins is None else min_bins,
                            low=2, low_inclusive=True, integer=True)
    codes, envs, how = _split_codes(rec, split)
    labels = np.arange(2 * len(envs))
    parts = _ratemap_parts(rec, bin_size=bin_size, sigma=sigma, min_occupancy=None,
                           min_speed=min_speed, by=None, extent=extent,
                           groups=(codes, labels, "part"))
    maps = parts["maps"][0]  # (U, 2E, ny, nx)
    n_units = maps.shape[0]
    maps = maps.reshape(n_units, len(envs), 2, -1)
    r, n = pearson_masked(maps[:, :, 0], maps[:, :, 1], min_bins)
    coords = {name: c for name, c in rec["activity"].coords.items() if c.dims == ("unit",)}
    env_attrs = rec["environment"].attrs if "environment" in rec.coords else {}
    coords["environment"] = ("environment", envs, env_attrs)
    out = xr.Dataset(coords=coords)
    out["stability"] = (("unit", "environment"), r, {
        "units": "1", "long_name": "rate-map correlation between session parts"})
    out["n_bins"] = ("environment", n[0], {"units": "1",
                                           "long_name": "bins visited in both parts"})
    attrs = _common.provenance(
        "place_field_stability", rec, split=split, split_used=str(how),
        bin_size=parts["grid"].bin_size, sigma=parts["sigma"], sigma_units="bins",
        min_speed=min_speed, min_bins=min_bins)
    flat = maps.reshape(n_units, len(envs), -1)
    reasons = []
    for (u, e), value in np.ndenumerate(r):
        if np.isfinite(value):
            reasons.append("")
        elif n[u, e] < min_bins:
            reasons.append(f"only {n[u, e]} bins visited in both parts (< {min_bins})")
        elif not np.isfinite(flat[u, e]).any() or np.nanstd(flat[u, e]) == 0:
            reasons.append("rate map is constant: correlation undefined")
        else:
            reasons.append("rate map is constant in one part: correlation undefined")
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["stability"]), reasons,
                                   "place-field stability")
    return out
