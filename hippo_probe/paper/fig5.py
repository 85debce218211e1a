"""Figure 5: what the population encodes beyond position.

A1-A3 the particle filter's posterior covariance (Cxx, Cyy, Cxy) decoded linearly from
the localization network's hidden units (cross-validated by trial); B1 the specialized
network's posterior over the 100 arenas at a few moments early in a trial, B2 the mean
probability it gives the true arena vs time; C1-C3 the correlation dimension of each
network's hidden-state trajectories (Grassberger-Procaccia, with the local slope of C(r)),
beside two nearest-neighbour estimators on the same states (TwoNN and MLE,
scikit-dimension). Panel letters follow the study's (its 5A, 5B, 5C) with a number each.

The builder of ``hippo-probe figures --only fig5`` and of the script
``paper_figures/fig5.py``; contract in :mod:`hippo_probe.paper`.
"""

import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp

from . import config as C

SNAPSHOTS_S = (2.0, 10.0, 30.0, 80.0)


def _r2_time_alone(truth, trial_time):
    """Leave-one-trial-out R² of a predictor that knows only the time in trial (the mean
    of the other trials at that time): the control for decoding, since the posterior
    shrinks predictably as a trial goes on."""
    ok = np.isfinite(truth)
    truth, trial_time = truth[ok], trial_time[ok]
    _, group = np.unique(trial_time, return_inverse=True)
    n = np.bincount(group)
    total = np.bincount(group, truth)
    keep = n[group] > 1
    others = (total[group] - truth)[keep] / (n[group] - 1)[keep]
    truth = truth[keep]
    return float(1 - np.sum((truth - others) ** 2) / np.sum((truth - truth.mean()) ** 2))


def make(cfg, out):
    """Draw the figure into ``out``; returns the numbers written to its JSON."""
    cfg = C.cached_under(cfg, out)
    numbers = {}
    loc = C.recording("localization", cfg)
    spec = C.recording("specialized", cfg)
    gen = C.recording("generalized", cfg)
    fig, ax = plt.subplots(2, 4, figsize=(15, 7), constrained_layout=True)

    dec = hp.decode_covariance(loc, n_folds=min(5, loc.sizes["trial_id"]))
    rng = np.random.default_rng(cfg.seed)
    trial_length = float(C.step_times(loc)[-1])
    for k, comp in enumerate(["xx", "yy", "xy"]):
        a = ax[0, k]
        truth = loc.pf_cov.sel(cov=comp).values
        pred = dec.prediction.sel(cov=comp).values
        ok = np.flatnonzero(np.isfinite(truth) & np.isfinite(pred))
        # 4,000 samples drawn uniformly over all trials and times (a stride would hit the
        # same few times in every trial); coloured by time in trial: the prior's broad
        # covariance sits at the trial start
        shown = np.sort(rng.choice(ok, min(4000, ok.size), replace=False))
        # rasterized in the PDF (the PNG is the same): 4,000 vector dots a panel made it
        # slow to write and to open
        dots = a.scatter(truth[shown], pred[shown], s=2, alpha=0.4,
                         c=loc.trial_time.values[shown], cmap="viridis",
                         vmin=0, vmax=trial_length, rasterized=True)
        lim = [np.nanmin(truth), np.nanmax(truth)]
        a.plot(lim, lim, color="tab:red", lw=0.8, label="identity")
        a.legend(frameon=False, fontsize=7, loc="upper left")
        r2 = float(dec.r2.sel(cov=comp))
        r2_time = _r2_time_alone(truth, loc.trial_time.values)
        a.set_title(f"A{k + 1}  C{comp} (localization network): cross-validated R² = {r2:.2f}\n"
                    f"(time in trial alone: R² = {r2_time:.2f})", fontsize=9)
        numbers.setdefault("A_r2_time_in_trial_alone", {})[comp] = r2_time
        a.set_xlabel(f"particle filter C{comp} (m²)")
        a.set_ylabel("decoded from units (m²)")
        numbers.setdefault("A_r2", {})[comp] = r2
    fig.colorbar(dots, ax=ax[0, 2], label="time in trial (s)", shrink=0.8)

    trial = spec.trial_id.values[0]
    one = hp.select_trials(spec, trials=[trial])
    true_env = int(one.trial_environment.values[0])
    a = ax[0, 3]
    for t in SNAPSHOTS_S:
        k = int(round(t / spec.attrs["dt"])) - 1
        p = one.class_probability.isel(time=k).values
        a.plot(one.environment_id.values, p, lw=0.9, label=f"t = {t:g} s")
        numbers.setdefault("B_true_class_probability", {})[f"{t:g}s"] = float(p[true_env])
    a.axvline(true_env, color="k", ls=":", lw=0.8, label="true arena")
    a.set_xlabel("arena id")
    a.set_ylabel("network posterior")
    a.set_title("B1  arena posterior, one trial", fontsize=9)
    a.legend(frameon=False, fontsize=7)

    for k, (name, rec) in enumerate((("localization", loc), ("generalized", gen),
                                     ("specialized", spec))):
        # C(r) of high-dimensional sets rises steeply: see DIMENSION_C_RANGE
        res = hp.correlation_dimension(rec, max_points=cfg.dimension_samples,
                                       c_range=C.DIMENSION_C_RANGE)
        a = ax[1, k]
        a.plot(res.log_r, res.log_c, color="k")
        if np.isfinite(res.attrs["dimension"]):
            a.axvspan(np.log10(res.attrs["r_min"]), np.log10(res.attrs["r_max"]),
                      color="tab:blue", alpha=0.15, label="scaling range")
        a.set_xlabel("log10 r")
        a.set_ylabel("log10 C(r)")
        nn = hp.intrinsic_dimension(rec, max_points=cfg.dimension_samples)
        nn_d = {str(e): float(v) for e, v in zip(nn.estimator.values, nn.dimension.values)}
        d = res.attrs["dimension"]
        d_text = f"D = {d:.2f}" if np.isfinite(d) else "no scaling range"
        a.set_title(f"C{k + 1}  {name}: {d_text} "
                    f"({res.attrs['n_points']:,} states)\n"
                    + ", ".join(f"{e} {v:.1f}" for e, v in nn_d.items())
                    + " (nearest neighbours, same states)", fontsize=9)
        # the local slope: a plateau at D over the scaling range is what makes D a dimension
        slope = a.twinx()
        slope.plot(res.log_r, res.local_slope, color="tab:orange", lw=0.9,
                   label="local slope")
        if np.isfinite(d):
            slope.axhline(d, color="tab:orange", ls=":", lw=0.8)
            slope.set_ylim(0, 1.5 * d if d > 1 else 12)
        else:   # no plateau: show the slope over the searched range of C(r)
            searched = res.log_c.values >= np.log10(C.DIMENSION_C_RANGE[0])
            slope.set_ylim(0, 1.2 * np.nanmax(res.local_slope.values[searched], initial=10))
        slope.set_ylabel("d log C / d log r", color="tab:orange")
        handles = a.get_legend_handles_labels()
        extra = slope.get_legend_handles_labels()
        # below the axes: inside, every corner meets the slope's curve in some run
        a.legend(handles[0] + extra[0], handles[1] + extra[1], frameon=False, fontsize=7,
                 loc="upper center", bbox_to_anchor=(0.5, -0.2), ncols=2)
        numbers.setdefault("C_dimension", {})[name] = float(res.attrs["dimension"])
        numbers.setdefault("C_n_points", {})[name] = int(res.attrs["n_points"])
        for e, v in nn_d.items():
            numbers.setdefault(f"C_dimension_{e}", {})[name] = v
    a = ax[1, 3]
    p_true = hp.classification_accuracy(spec).true_class_probability
    a.plot(p_true.trial_time, p_true, color="k", label="network")
    a.axhline(1 / spec.sizes["environment_id"], color="gray", ls=":", label="chance")
    a.set_xlabel("time in trial (s)")
    a.set_ylabel("posterior of the true arena")
    a.set_title(f"B2  mean over {spec.sizes['trial_id']} trials", fontsize=9)
    a.legend(frameon=False, fontsize=7)
    numbers["B_mean_true_class_probability_end"] = float(p_true[-1])
    fig.suptitle("Fig. 5 — uncertainty, arena identity and dimensionality in the population")
    C.save(fig, "fig5", numbers, cfg, out)
    return numbers

