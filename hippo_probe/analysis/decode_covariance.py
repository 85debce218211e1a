"""Decode a per-sample target (the particle filter's covariance) from activity by ridge
regression, cross-validated with folds by trial."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_number, check_seed
from . import _common
from .config import COMPUTE, DECODING


def _fold_stats(x, y, fold, n_folds):
    """Per-fold sufficient statistics of one block: n, sum x, sum y, sum y^2, X'X, X'y."""
    x = np.asarray(x, np.float64)
    n_units, n_out = x.shape[1], y.shape[1]
    out = (np.zeros(n_folds), np.zeros((n_folds, n_units)), np.zeros((n_folds, n_out)),
           np.zeros((n_folds, n_out)), np.zeros((n_folds, n_units, n_units)),
           np.zeros((n_folds, n_units, n_out)))
    for f in range(n_folds):
        sel = fold == f
        if not sel.any():
            continue
        xf, yf = x[sel], y[sel]
        out[0][f] = sel.sum()
        out[1][f] = xf.sum(axis=0)
        out[2][f] = yf.sum(axis=0)
        out[3][f] = (yf**2).sum(axis=0)
        out[4][f] = xf.T @ xf
        out[5][f] = xf.T @ yf
    return out


def _add(parts):
    return tuple(sum(p[i] for p in parts) for i in range(6))


def _stats(act, y, fold, n_folds):
    """Sufficient statistics over all samples, one block at a time (lazy if dask)."""
    data = act.data
    if not hasattr(data, "dask"):
        return _fold_stats(data, y, fold, n_folds)
    import dask

    data = data.rechunk({1: -1})
    starts = np.concatenate([[0], np.cumsum(data.chunks[0])])
    blocks = data.to_delayed()[:, 0]
    stat = dask.delayed(_fold_stats, pure=True)
    parts = [stat(b, y[s:e], fold[s:e], n_folds)
             for b, s, e in zip(blocks, starts[:-1], starts[1:])]
    while len(parts) > 1:
        step = COMPUTE.split_every
        parts = [dask.delayed(_add)(parts[i:i + step]) for i in range(0, len(parts), step)]
    return dask.compute(parts[0])[0]


def _fit(stats, keep, alphas):
    """Ridge weights (n_alphas, U, C) and intercepts (n_alphas, C) on the folds ``keep``.

    Centred ridge, intercept unpenalised (as scikit-learn's ``Ridge``):
    ``w = (S_xx + alpha I)^-1 S_xy``, ``b = mean(y) - mean(x) w``.
    """
    n, sx, sy, _, xx, xy = (s[keep].sum(axis=0) for s in stats)
    mx, my = sx / n, sy / n
    sxx = xx - n * np.outer(mx, mx)
    sxy = xy - n * np.outer(mx, my)
    lam, vec = np.linalg.eigh(sxx)
    proj = vec.T @ sxy
    w = np.stack([vec @ (proj / (lam + a)[:, None]) for a in alphas])
    b = my[None] - np.einsum("u,auc->ac", mx, w)
    return w, b


def _sse(stats, f, w, b):
    """Sum of squared errors on fold ``f`` of predictions x'w + b, per alpha and output."""
    n, sx, sy, syy, xx, xy = (s[f] for s in stats)
    cross = np.einsum("uc,auc->ac", xy, w) + b * sy
    quad = np.einsum("auc,uv,avc->ac", w, xx, w) + 2 * b * np.einsum("u,auc->ac", sx, w) \
        + n * b**2
    return syy - 2 * cross + quad


def decode_covariance(rec, target="pf_cov", *, n_folds=None, alphas=None, seed=0):
    """Ridge regression from activity to a per-sample target, cross-validated by trial.

    .. math:: \\hat y_t = W_{f(t)}^\\top a_t + b_{f(t)},\\qquad
              R^2_c = 1 - \\frac{\\sum_t (y_{tc} - \\hat y_{tc})^2}
                                {\\sum_t (y_{tc} - \\bar y_c)^2}

    Trials are dealt into ``n_folds`` folds; each fold is predicted by a ridge model
    fitted on the others, whose penalty (per output component) is chosen by an inner
    cross-validation over the remaining folds. Everything is computed from per-fold
    sufficient statistics (:math:`X^\\top X`, :math:`X^\\top y`, sums), accumulated in one
    pass over the samples, so a dask-backed recording streams and the activity is never
    loaded whole; ``prediction`` is lazy when the recording is.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity`` and the target (time, k), e.g. ``pf_cov``
        (time, cov) from the particle filter. Samples where the target is NaN are left out.
    target : str
        Target variable (default ``"pf_cov"``).
    n_folds : int, optional
        Folds by trial (default 5; at most the number of trials).
    alphas : sequence of float, optional
        Ridge penalties searched (scikit-learn's convention ``||y - Xw||^2 + alpha ||w||^2``).
    seed : int
        Seed of the assignment of trials to folds.

    Returns
    -------
    xarray.Dataset
        ``r2`` (component), ``prediction`` (time, component), ``alpha`` (fold, component).

    References
    ----------
    Hoerl & Kennard (1970), Ridge regression, Technometrics 12:55-67. Kanitscheider &
    Fiete (2017), NIPS 30 (Fig. 5A: the LSTM's units encode the posterior covariance).

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> rng = np.random.default_rng(0)
    >>> trial = np.arange(8000) // 1000
    >>> t = (np.arange(8000) + trial) * 0.1
    >>> act = rng.normal(size=(8000, 3))
    >>> rec = from_arrays(t, np.zeros((8000, 2)), activity=act, trial=trial,
    ...                   activity_kind="lstm_hidden")
    >>> cov = np.c_[act @ [1.0, 2.0, 0.0], rng.normal(size=8000)]
    >>> rec["pf_cov"] = (("time", "cov"), cov, {"units": "m2", "long_name": "covariance"})
    >>> res = decode_covariance(rec.assign_coords(cov=["xx", "yy"]))
    >>> res.r2.values.round(2)
    array([ 1., -0.])
    """
    rec = _common.check_recording(rec, ["activity", target, "trial"], why="decoding")
    tgt = rec[target]
    if tgt.dims[0] != "time":
        tgt = tgt.transpose("time", ...)
    if tgt.ndim == 1:
        tgt = tgt.expand_dims("component", axis=1)
    comp_dim = tgt.dims[1]
    y = _common.values(tgt).astype(float)
    alphas = np.asarray(DECODING.alphas if alphas is None else alphas, float)
    if alphas.ndim != 1 or alphas.size == 0 or not (alphas > 0).all():
        raise ValueError(f"`alphas` must be a non-empty 1-D sequence of numbers > 0; got "
                         f"{alphas.tolist()}")
    valid = np.isfinite(y).all(axis=1)
    trial = _common.values(rec["trial"])
    trials = np.unique(trial[valid])
    n_folds = DECODING.n_folds if n_folds is None else n_folds
    if isinstance(n_folds, (int, np.integer)) and not isinstance(n_folds, bool) \
            and n_folds == 2:
        raise ValueError("`n_folds` must be >= 3: one fold is held out for the score and "
                         "the ridge strength is chosen by cross-validation among the "
                         "others, which needs at least two; got 2")
    n_folds = check_number("n_folds", n_folds, low=3, low_inclusive=True, integer=True)
    if len(trials) < n_folds:
        raise ValueError(f"`n_folds` must be <= the number of trials with a finite "
                         f"`{target}` ({len(trials)}); got {n_folds}")
    order = np.random.default_rng(check_seed("seed", seed)).permutation(len(trials))
    trial_fold = np.empty(len(trials), np.int64)
    trial_fold[order] = np.arange(len(trials)) % n_folds
    sample_fold = np.full(len(trial), -1, np.int64)
    has = np.isin(trial, trials)
    sample_fold[has] = trial_fold[np.searchsorted(trials, trial[has])]
    fit_fold = np.where(valid, sample_fold, -1)
    act = _common.activity(rec)
    stats = _stats(act, np.where(valid[:, None], y, 0.0), fit_fold, n_folds)
    if not all(np.isfinite(s).all() for s in stats):
        raise ValueError("`rec.activity` holds NaN or inf on samples with a finite target: "
                         "the regression cannot be fitted")

    folds = np.arange(n_folds)
    n_out = y.shape[1]
    chosen = np.empty((n_folds, n_out))
    weights, intercepts = [], []
    sse = np.zeros(n_out)
    for f in folds:
        inner = folds[folds != f]
        inner_sse = np.zeros((len(alphas), n_out))
        for g in inner:
            w, b = _fit(stats, inner[inner != g], alphas)
            inner_sse += _sse(stats, g, w, b)
        best = inner_sse.argmin(axis=0)
        chosen[f] = alphas[best]
        w, b = _fit(stats, inner, alphas)
        w, b = w[best, :, np.arange(n_out)].T, b[best, np.arange(n_out)]
        weights.append(w)
        intercepts.append(b)
        sse += _sse(stats, f, w[None], b[None])[0]
    n_total = stats[0].sum()
    sst = stats[3].sum(axis=0) - stats[2].sum(axis=0) ** 2 / n_total
    with np.errstate(invalid="ignore", divide="ignore"):
        r2 = np.where(sst > 0, 1 - sse / sst, np.nan)

    weights, intercepts = np.stack(weights), np.stack(intercepts)

    def predict(block, fold):
        block, fold = np.asarray(block, np.float64), np.asarray(fold).ravel()
        out = np.full((len(block), n_out), np.nan)
        for f in range(n_folds):
            sel = fold == f
            out[sel] = block[sel] @ weights[f] + intercepts[f]
        return out

    if hasattr(act.data, "dask"):
        import dask.array as da

        data = act.data.rechunk({1: -1})
        fold_d = da.from_array(sample_fold, chunks=(data.chunks[0],))
        prediction = da.map_blocks(predict, data, fold_d[:, None], dtype=float,
                                   chunks=(data.chunks[0], (n_out,)))
    else:
        prediction = predict(act.data, sample_fold)
    coords = {comp_dim: tgt[comp_dim].values} if comp_dim in tgt.coords else {}
    out = xr.Dataset(coords={"time": rec["time"], **coords, "fold": folds})
    units = tgt.attrs.get("units", "")
    out["r2"] = (comp_dim, r2, {"units": "1",
                                "long_name": f"cross-validated R^2 of {target}"})
    out["prediction"] = (("time", comp_dim), prediction, {
        "units": units, "long_name": f"decoded {tgt.attrs.get('long_name', target)}"})
    out["alpha"] = (("fold", comp_dim), chosen, {"units": "1",
                                                 "long_name": "ridge penalty chosen"})
    reasons = [f"`{target}` is constant over the samples" if not np.isfinite(v) else ""
               for v in r2]
    attrs = _common.provenance(
        "decode_covariance", rec, target=target, n_folds=n_folds, alphas=alphas.tolist(),
        seed=seed, folds="by trial", n_samples=int(n_total), n_trials=len(trials),
        model="ridge regression with intercept; penalty per component by inner "
              "cross-validation over the training folds")
    out.attrs = _common.report_nan(attrs, [str(c) for c in out[comp_dim].values]
                                   if comp_dim in out.coords else list(range(n_out)),
                                   reasons, "R^2")
    return out
