"""Figure 3: novel arenas, the arena classifier, PF-SLAM and readout retraining.

A generalized network (a new arena every trial) vs the oracular particle filter, path
integration and naive Bayes; B specialized network (100 familiar arenas) vs the oracular
particle filter; C its classification accuracy vs time; D-E PF-SLAM with 100 to 10,000
particles vs the network (localization error and classification accuracy); F
classification by the generalized network after retraining only its arena readout.

The builder of ``hippo-probe figures --only fig3`` and of the script
``paper_figures/fig3.py``; contract in :mod:`hippo_probe.paper`.
"""

import matplotlib.pyplot as plt

import hippo_probe as hp
from hippo_probe.tasks import make_trials

from . import config as C


def _curves(ax, err, names, numbers, key):
    """Euclidean error of each estimate (mean +- s.e.m.) into ``ax``; the curves into
    ``numbers[key]``."""
    numbers["trial_time_s"] = err.trial_time.values
    hp.plot.error_curves(err, variables=("euclidean",), colors=C.COLORS, labels=C.LABELS,
                         axes=[ax])
    for name in names:
        numbers.setdefault(key, {})[C.LABELS[name]] = err.euclidean.sel(estimate=name).values


def _slam(cfg):
    """PF-SLAM's mean error (m) and accuracy vs time, at each of ``cfg.slam_particles``."""
    from hippo_probe.baselines import localization_errors, run_baselines

    batch = make_trials("specialized", cfg.slam_trials, "test", cfg.seed, world=cfg.world)

    def run():
        out = {}
        for n in cfg.slam_particles:
            ds = run_baselines(batch, slam_particles=n, methods=["pfslam"])
            out[f"error_{n}"] = localization_errors(ds).sel(baseline="pfslam").values
            guess = ds.class_probability_pfslam.argmax("environment_id")
            out[f"accuracy_{n}"] = (guess == ds.trial_environment).mean("trial_id").values
        return out
    return C.shared_arrays("pf_slam", cfg, run, C.batch_digest(batch), cfg.slam_particles)


def make(cfg, out):
    """Draw the figure into ``out``; returns the numbers written to its JSON."""
    cfg = C.cached_under(cfg, out)
    numbers = {}
    gen = C.recording("generalized", cfg)
    spec = C.recording("specialized", cfg)
    readout = C.recording("readout", cfg)
    fig, ax = plt.subplots(2, 3, figsize=(13, 7.5), constrained_layout=True)
    ax = ax.ravel()

    names = ["estimate", "estimate_pf", "estimate_nb", "estimate_pi"]
    err_g = hp.localization_error(gen, estimate=names)
    _curves(ax[0], err_g, names, numbers, "A_generalized_error")
    ax[0].set_title("A  generalized network, novel arenas")
    late = err_g.trial_time.values > 100
    numbers["A_ratio_network_to_pf_t_gt_100s"] = float(
        err_g.euclidean.sel(estimate="estimate")[late].mean()
        / err_g.euclidean.sel(estimate="estimate_pf")[late].mean())

    names = ["estimate", "estimate_pf", "estimate_sh", "estimate_pi"]
    err_s = hp.localization_error(spec, estimate=names)
    _curves(ax[1], err_s, names, numbers, "B_specialized_error")
    ax[1].set_title("B  specialized network, 100 familiar arenas")

    acc = hp.classification_accuracy(spec)
    t = acc.trial_time.values
    ax[2].plot(t, acc.accuracy, color="k", label="network")
    ax[2].axhline(acc.attrs.get("chance", 0.01), color="gray", ls=":", label="chance")
    ax[2].set_title("C  arena classification (specialized network)")
    numbers["C_accuracy"] = acc.accuracy.values
    numbers["C_accuracy_at"] = C.at_times(t, acc.accuracy.values)

    slam = _slam(cfg)
    sub = hp.select_trials(spec, trials=spec.trial_id.values[:cfg.slam_trials])
    net_err = hp.localization_error(sub).euclidean.values
    net_acc = hp.classification_accuracy(sub).accuracy.values
    ts = C.step_times(spec)
    ax[3].plot(t, net_err, color="k", lw=1.6, label="network")
    cmap = plt.get_cmap("Purples")
    for k, n in enumerate(cfg.slam_particles):
        c = cmap(0.4 + 0.6 * k / max(len(cfg.slam_particles) - 1, 1))
        ax[3].plot(ts, slam[f"error_{n}"], color=c, label=f"PF-SLAM {n:,} particles")
        ax[4].plot(ts, slam[f"accuracy_{n}"], color=c, label=f"PF-SLAM {n:,} particles")
        numbers[f"D_pfslam_{n}_error_at"] = C.at_times(ts, slam[f"error_{n}"])
        numbers[f"E_pfslam_{n}_accuracy_at"] = C.at_times(ts, slam[f"accuracy_{n}"])
        numbers[f"last20s_pfslam_{n}"] = {
            "error": C.window_mean(ts, slam[f"error_{n}"]),
            "accuracy": C.window_mean(ts, slam[f"accuracy_{n}"])}
    ax[4].plot(t, net_acc, color="k", lw=1.6, label="network")
    numbers["D_network_error_at"] = C.at_times(t, net_err)
    numbers["E_network_accuracy_at"] = C.at_times(t, net_acc)
    numbers["last20s_network_on_slam_trials"] = {"error": C.window_mean(t, net_err),
                                                 "accuracy": C.window_mean(t, net_acc)}
    ax[3].set_ylabel("Euclidean error (m)")
    ax[3].set_title(f"D  PF-SLAM vs network ({cfg.slam_trials} trials)")
    ax[4].set_title(f"E  PF-SLAM vs network ({cfg.slam_trials} trials)")

    acc_r = hp.classification_accuracy(readout)
    ax[5].plot(t, acc_r.accuracy, color="tab:green", label="generalized net, new readout")
    ax[5].plot(t, acc.accuracy, color="k", alpha=0.5, label="specialized net")
    ax[5].axhline(1 / readout.sizes["environment_id"], color="gray", ls=":", label="chance")
    ax[5].set_title("F  readout retraining")
    numbers["F_readout_accuracy_at"] = C.at_times(t, acc_r.accuracy.values)
    for a in (ax[2], ax[4], ax[5]):
        a.set_ylabel("classification accuracy")
        a.set_ylim(0, 1.02)
    for a in ax[2:]:
        a.set_xlabel("time in trial (s)")
        a.set_xlim(0, t[-1])
        a.legend(frameon=False, fontsize=7)
    # below the PF-SLAM curves' plateau, above the 100-particle line
    ax[4].legend(frameon=False, fontsize=7, loc="lower right", bbox_to_anchor=(1, 0.2))
    # the accuracy curve rises early and stays high: the middle right is below it and
    # above chance
    ax[2].legend(frameon=False, fontsize=7, loc="center right")
    # the retrained readout lies anywhere from chance to the specialized network's curve
    # (0.04 to 0.42 at 200 s over the shipped runs): matplotlib finds the emptiest place
    ax[5].legend(frameon=False, fontsize=7, loc="best")
    ax[3].set_ylim(bottom=0)
    fig.suptitle(f"Fig. 3 — {gen.sizes['trial_id']} test trials per panel (A-C, F)")
    C.save(fig, "fig3", numbers, cfg, out)
    return numbers

