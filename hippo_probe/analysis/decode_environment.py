"""Decode the environment (arena) from the population at given times in the trial: a
linear probe of whether the context is linearly present in the units."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validators import check_number
from . import _common
from .config import ENVIRONMENT_DECODING as CFG


def _samples(rec, t, half_width):
    """Indices of each trial's samples within ``half_width`` (s) of time ``t`` in trial."""
    tt = _common.values(rec["trial_time"]).astype(float)
    return np.flatnonzero(np.abs(tt - t) <= half_width)


def fit_linear_decoder(x, y, *, c, max_iter=None, tol=1e-4, warm_from=None):
    """Fit a multinomial logistic regression of labels ``y`` on standardized features ``x``.

    The units are standardized on ``x`` (mean 0, s.d. 1), then the softmax model
    ``p(e | x) = exp(w_e . z + b_e) / sum_k exp(w_k . z + b_k)``, ``z = (x - mu) / sigma``,
    is fitted by L-BFGS (scikit-learn) to the minimum of the convex objective
    ``C * sum_j -log p(e_j | x_j) + |W|^2 / 2``: a unique optimum, reached whatever the
    start, so the fit is a measurement, not a training run.

    Parameters
    ----------
    x : array (n_samples, n_features)
    y : array (n_samples,)
        Integer labels.
    c : float
        Inverse L2 strength (scikit-learn's ``C``), > 0.
    max_iter : int, optional
        Solver iterations (default :attr:`EnvironmentDecodingConfig.max_iter`).
    tol : float
        Solver tolerance on the projected gradient.
    warm_from : sklearn.pipeline.Pipeline, optional
        A decoder fitted on the same features (another ``c``) whose coefficients start the
        solver: the same optimum, fewer iterations along a path of ``c``.

    Returns
    -------
    sklearn.pipeline.Pipeline
        ``StandardScaler`` then ``LogisticRegression``; ``n_iter``, ``converged`` and
        ``solver_message`` are set on it. ``converged`` is False when the iterations ran
        out *or* scikit-learn reported the solver as not converged (e.g. L-BFGS's line
        search failing, which stops it early: a fit that stopped after a few iterations is
        not thereby converged); ``solver_message`` is that report ("" if none).
    """
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    max_iter = CFG.max_iter if max_iter is None else max_iter
    scaler = StandardScaler().fit(x)
    model = LogisticRegression(C=c, max_iter=max_iter, tol=tol,
                               warm_start=warm_from is not None)
    z = scaler.transform(x)
    if warm_from is not None:
        prev = warm_from[-1]
        model.coef_, model.intercept_ = prev.coef_.copy(), prev.intercept_.copy()
        model.classes_ = prev.classes_
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    with warnings.catch_warnings(record=True) as caught:
        # converged or not is returned (``converged``) rather than warned once per fit
        warnings.simplefilter("always", ConvergenceWarning)
        model.fit(z, y)
    failed = [str(w.message) for w in caught if issubclass(w.category, ConvergenceWarning)]
    for w in caught:                       # other warnings reach the caller as usual
        if not issubclass(w.category, ConvergenceWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    pipeline = make_pipeline(scaler, model)
    pipeline.n_iter = int(np.max(model.n_iter_))
    pipeline.converged = pipeline.n_iter < max_iter and not failed
    pipeline.solver_message = " ".join(" ".join(m.split()) for m in failed)[:300]
    return pipeline


def decoder_weights(decoder) -> tuple[np.ndarray, np.ndarray]:
    """(W (n_classes, n_features), b (n_classes,)) of a fitted decoder on the raw features.

    The standardization is folded into the linear map: ``w_e . (x - mu) / sigma + b_e =
    (w_e / sigma) . x + (b_e - (w_e / sigma) . mu)``, so a plain linear layer on the raw
    units gives the decoder's logits.
    """
    scaler, model = decoder[0], decoder[-1]
    w = model.coef_ / scaler.scale_[None, :]
    b = model.intercept_ - w @ scaler.mean_
    return w, b


def _fit(x, y, c, max_iter):
    return fit_linear_decoder(x, y, c=c, max_iter=max_iter)


def _accuracy(model, x, y) -> float:
    return float(np.mean(model.predict(x) == y)) if len(y) else np.nan


def decode_environment(rec, *, test=None, times=None, c=None, window=None, n_folds=None):
    """Accuracy of a linear decoder of the environment from the activity, by time in trial.

    At each time ``t`` a multinomial logistic regression (scikit-learn, units standardized
    on the training samples, L2 strength ``1 / c``) maps the population vector to the
    environment: trained on each trial's samples within ``window`` steps of ``t``, scored
    on each held-out trial's sample nearest ``t``::

        acc(t) = < [argmax_e p(e | x_j(t)) = e_j] >_j   over held-out trials j

    Held out means another recording (``test``: e.g. trials of the test split, the
    decoder trained on the training split's) or, without one, ``n_folds`` folds by trial
    (a trial is never scored by a decoder that saw it). It asks of any recording what
    readout retraining (the study's Fig. 3F) asks of a network, with a convex fit run to
    convergence instead of gradient steps.

    The decoder reads the population at one instant (``window`` steps around it), as a
    network's readout does: on a network's units, or on rates. Spike counts in short bins
    may hold too few spikes at any one instant to name the arena, even where cells remap:
    smooth them over time, or bin them more coarsely, first.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity``, ``environment``, ``trial`` and ``trial_time``.
    test : xarray.Dataset, optional
        A recording to score on (same units); default: cross-validation within ``rec``.
    times : sequence of float, optional
        Times in trial (s); default 50, 100, 200 s.
    c : float, optional
        Inverse L2 strength (default 1).
    window : int, optional
        Training samples per trial at each time: ``t`` and ``window`` steps on each side
        (default 2).
    n_folds : int, optional
        Folds by trial when ``test`` is None (default 5).

    Returns
    -------
    xarray.Dataset
        Over ``trial_time`` (the ``times``): ``accuracy`` (held-out trials),
        ``train_accuracy`` (the training trials' own samples at ``t``: far above
        ``accuracy`` means the decoder memorizes trials), ``n_scored`` (held-out
        samples scored: one per trial where ``t`` falls on a sample, two where it falls
        midway between two) and ``n_unseen`` (held-out samples in an environment the
        decoder was not trained on, e.g. an environment of a single trial: they cannot be
        named, so they are not scored, with a warning); attrs ``chance`` (1 /
        environments) and the parameters.

    References
    ----------
    Kanitscheider & Fiete (2017), NIPS 30 (Fig. 3F: readout retraining). Hastie,
    Tibshirani & Friedman (2009), The Elements of Statistical Learning, 2nd ed., Sect. 4.4
    (multinomial logistic regression) and 7.10 (cross-validation).

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> rng = np.random.default_rng(0)
    >>> env = np.repeat([0, 1], 200)                       # 20 trials of 20 samples
    >>> act = rng.normal(size=(400, 5)) + env[:, None]     # the environment shifts units
    >>> rec = xr.Dataset(
    ...     {"activity": (("time", "unit"), act)},
    ...     coords={"time": np.arange(400.0), "unit": np.arange(5),
    ...             "trial": ("time", np.repeat(np.arange(20), 20)),
    ...             "trial_time": ("time", np.tile(np.arange(1.0, 21.0), 20)),
    ...             "environment": ("time", env)}, attrs={"dt": 1.0})
    >>> res = decode_environment(rec, times=[10.0])
    >>> res.accuracy.item() > 0.8
    True
    """
    need = ["activity", "environment", "trial", "trial_time"]
    rec = _common.check_recording(rec, need, why="environment decoding")
    if test is not None:
        _common.check_recording(test, need, why="environment decoding", name="test")
        if test.sizes["unit"] != rec.sizes["unit"]:
            raise ValueError(f"`test` must have the units of `rec` ({rec.sizes['unit']}); "
                             f"got {test.sizes['unit']}")
    times = [check_number("times", float(t), low=0) for t in
             (CFG.times if times is None else np.atleast_1d(times))]
    c = check_number("c", CFG.c if c is None else c, low=0)
    window = check_number("window", CFG.window if window is None else window, low=0,
                          low_inclusive=True, integer=True)
    n_folds = check_number("n_folds", CFG.n_folds if n_folds is None else n_folds, low=2,
                           low_inclusive=True, integer=True)
    dt = _common.sample_dt(rec)
    act = _common.activity(rec)
    env = _common.values(rec["environment"])
    trial = _common.values(rec["trial"])
    trial_ids = np.unique(trial)
    n_trials = len(trial_ids)
    if test is None and n_trials < n_folds:
        raise ValueError(f"cross-validation by trial needs at least `n_folds` = {n_folds} "
                         f"trials; `rec` has {n_trials}")
    acc, train_acc, scored, unseen, reasons = [], [], [], [], []
    longest = float(np.max(_common.values(rec["trial_time"])))
    for t in times:
        fit_idx = _samples(rec, t, (window + 0.5) * dt)
        at_idx = _samples(rec, t, 0.5 * dt)
        reason = None
        if not len(at_idx):
            reason = (f"no sample at {t:g} s in any trial (the longest trial lasts "
                      f"{longest:g} s)")
        elif len(np.unique(env[fit_idx])) < 2:
            reason = "the training samples at this time come from one environment only"
        if reason:
            acc.append(np.nan)
            train_acc.append(np.nan)
            scored.append(0)
            unseen.append(0)
            reasons.append(reason)
            continue
        reasons.append(None)
        x_fit = np.asarray(act.isel(time=fit_idx).values, np.float64)
        x_at = np.asarray(act.isel(time=at_idx).values, np.float64)
        if test is not None:
            model = _fit(x_fit, env[fit_idx], c, CFG.max_iter)
            test_idx = _samples(test, t, 0.5 * _common.sample_dt(test))
            if not len(test_idx):
                reasons[-1] = f"no sample at {t:g} s in any trial of `test`"
            y_test = _common.values(test["environment"])[test_idx]
            # an environment the decoder never saw cannot be named: not scored
            known = np.isin(y_test, model[-1].classes_)
            x_test = np.asarray(_common.activity(test).isel(time=test_idx[known]).values,
                                np.float64)
            acc.append(_accuracy(model, x_test, y_test[known]))
            train_acc.append(_accuracy(model, x_at, env[at_idx]))
            scored.append(int(known.sum()))
            unseen.append(int((~known).sum()))
            continue
        from sklearn.model_selection import KFold

        hits, n, train_hits, train_n, n_unseen = 0, 0, 0, 0, 0
        # folds of whole trials, shuffled: trials are often stored by environment
        folds = KFold(n_splits=n_folds, shuffle=True, random_state=0)
        for _, held_trials in folds.split(trial_ids):
            held = np.isin(trial, trial_ids[held_trials])
            fit_mask = ~held[fit_idx]
            at_held = held[at_idx]
            if len(np.unique(env[fit_idx][fit_mask])) < 2:
                continue
            model = _fit(x_fit[fit_mask], env[fit_idx][fit_mask], c, CFG.max_iter)
            # a held-out trial in an environment no training trial of its fold visits
            # (an arena of one trial) cannot be named: not scored
            known = np.isin(env[at_idx], model[-1].classes_)
            scorable = at_held & known
            hits += int(np.sum(model.predict(x_at[scorable]) == env[at_idx][scorable]))
            n += int(scorable.sum())
            n_unseen += int((at_held & ~known).sum())
            train_hits += int(np.sum(model.predict(x_at[~at_held]) == env[at_idx][~at_held]))
            train_n += int((~at_held).sum())
        acc.append(hits / n if n else np.nan)
        train_acc.append(train_hits / train_n if train_n else np.nan)
        scored.append(n)
        unseen.append(n_unseen)
    n_env = len(np.unique(env))
    coords = {"trial_time": ("trial_time", np.asarray(times),
                             {"units": "s", "long_name": "time in trial"})}
    out = xr.Dataset({
        "accuracy": ("trial_time", np.asarray(acc, float),
                     {"units": "1", "long_name": "decoding accuracy, held-out trials"}),
        "train_accuracy": ("trial_time", np.asarray(train_acc, float),
                           {"units": "1", "long_name": "decoding accuracy, training trials"}),
        "n_scored": ("trial_time", np.asarray(scored, np.int64),
                     {"units": "1", "long_name": "held-out samples scored"}),
        "n_unseen": ("trial_time", np.asarray(unseen, np.int64),
                     {"units": "1", "long_name": "held-out samples not scored: their "
                                                 "environment is not in the training set"}),
    }, coords=coords)
    if sum(unseen):
        _common.warn(f"{max(unseen)} held-out samples at a time are in environments that no "
                     f"training trial visits (an environment of one trial, or one missing "
                     f"from `rec`): they cannot be named and are left out of `accuracy` "
                     f"(`n_unseen`); chance is still 1 / {len(np.unique(env))} environments")
    out.attrs = _common.provenance(
        "decode_environment", rec, c=c, window=window, chance=1.0 / n_env,
        n_environments=n_env,
        validation=("separate test recording" if test is not None
                    else f"{n_folds}-fold by trial"),
        model="multinomial logistic regression on standardized units (scikit-learn)")
    out.attrs = _common.report_nan(out.attrs, [f"{t:g} s" for t in times], reasons,
                                   "decoding accuracy")
    return out
