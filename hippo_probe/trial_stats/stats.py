"""Summary statistics of the tasks' trials, and a picture of example trials."""

from __future__ import annotations

import numpy as np

from .. import tasks as _tasks

#: Times (s) at which the path-integration error is reported.
PI_REPORT_TIMES = (50.0, 100.0, 200.0)

#: Drift rates of head-direction cells recorded without vision, deg/min (19 cells), the
#: range Cheung et al. (2012, PLoS Comput Biol 8:e1002651) compare their drift model with.
CHEUNG_DRIFT_RANGE_DEG_PER_MIN = (5.1, 26.6)

#: Window (s) over which drift rates are measured.
DRIFT_WINDOW_S = 60.0


def drift_rates(batch, window: float = DRIFT_WINDOW_S) -> np.ndarray:
    """Absolute heading-drift rates, deg/min, over consecutive non-overlapping windows of
    ``window`` seconds from each trial's start: ``|eta(t + w) - eta(t)| / w`` (one value per
    window and trial; the first window starts at ``eta = 0``)."""
    per_window = int(round(window / batch.dt))
    drift = np.concatenate([np.zeros((1, len(batch))), batch.heading_drift])   # eta_0 = 0
    ends = np.arange(0, batch.n_steps + 1, per_window)
    change = np.abs(np.diff(drift[ends], axis=0))
    return np.degrees(change).ravel() * (60.0 / window)


def path_integration_error(batch) -> np.ndarray:
    """Euclidean error (T, B) of integrating the noisy displacement inputs from the
    true start: the drift that boundary contacts must correct."""
    disp = batch.inputs[..., [batch.features.index("dx"), batch.features.index("dy")]]
    estimate = batch.start[None] + np.cumsum(disp.astype(np.float64), axis=0)
    return np.linalg.norm(estimate - batch.position, axis=-1)


def trial_statistics(batch) -> dict:
    """Mean speed, contact statistics, heading-drift rates and PI error of one batch."""
    step = np.linalg.norm(np.diff(batch.position, axis=0), axis=-1)
    pi_error = path_integration_error(batch).mean(axis=1)
    contacts_per_trial = batch.contact.sum(axis=0)
    duration = batch.n_steps * batch.dt
    rates = drift_rates(batch)
    lo, hi = CHEUNG_DRIFT_RANGE_DEG_PER_MIN
    out = {
        "task": batch.task,
        "world": batch.world.name,
        "n_trials": len(batch),
        "mean_speed_m_per_s": float(step.mean() / batch.dt),
        "contacts_per_trial": float(contacts_per_trial.mean()),
        "mean_time_between_contacts_s": float(duration / max(contacts_per_trial.mean(), 1e-12)),
        "arena_mean_radius_m": float(np.linalg.norm(batch.arena_vertices, axis=-1).mean()),
        "drift_rate_median_deg_per_min": float(np.median(rates)),
        "drift_rate_q25_deg_per_min": float(np.quantile(rates, 0.25)),
        "drift_rate_q75_deg_per_min": float(np.quantile(rates, 0.75)),
        "drift_rate_fraction_in_cheung_range": float(np.mean((rates >= lo) & (rates <= hi))),
    }
    for t in PI_REPORT_TIMES:
        k = int(round(t / batch.dt)) - 1
        if 0 <= k < batch.n_steps:
            out[f"pi_error_{int(t)}s_m"] = float(pi_error[k])
    return out


def world_stats(n_trials: int = 500, split: str = "test", seed: int = 0,
                world="darkness") -> dict:
    """:func:`trial_statistics` of every task in ``world``."""
    if n_trials < 1:
        raise ValueError(f"`n_trials` must be >= 1; got {n_trials}")
    return {task: trial_statistics(_tasks.make_trials(task, n_trials, split, seed,
                                                      world=world))
            for task in _tasks.TASKS}


def format_stats(stats: dict) -> str:
    """A plain-text table of :func:`world_stats`, with the drift rates beside Cheung et
    al.'s range."""
    cols = [("mean speed (m/s)", "mean_speed_m_per_s"),
            ("s between contacts", "mean_time_between_contacts_s"),
            ("PI err 50 s (m)", "pi_error_50s_m"),
            ("PI err 100 s (m)", "pi_error_100s_m"),
            ("PI err 200 s (m)", "pi_error_200s_m"),
            ("arena radius (m)", "arena_mean_radius_m")]
    head = f"{'task':<14}" + "".join(f"{c:>20}" for c, _ in cols)
    rows = [head, "-" * len(head)]
    for task, s in stats.items():
        rows.append(f"{task:<14}" + "".join(f"{s.get(k, float('nan')):>20.3f}" for _, k in cols))
    if all(s["drift_rate_median_deg_per_min"] == 0 for s in stats.values()):
        return "\n".join(rows)        # the compass world: no drift, the table as it was
    lo, hi = CHEUNG_DRIFT_RANGE_DEG_PER_MIN
    rows += ["", f"heading drift over {DRIFT_WINDOW_S:.0f} s windows, deg/min (Cheung et al. "
             f"2012: head-direction cells in darkness, {lo}-{hi} deg/min over 19 cells)",
             f"{'task':<14}{'median':>12}{'quartiles':>18}{'in their range':>18}"]
    for task, s in stats.items():
        quartiles = (f"{s['drift_rate_q25_deg_per_min']:.1f}-"
                     f"{s['drift_rate_q75_deg_per_min']:.1f}")
        rows.append(f"{task:<14}{s['drift_rate_median_deg_per_min']:>12.1f}{quartiles:>18}"
                    f"{s['drift_rate_fraction_in_cheung_range']:>18.0%}")
    return "\n".join(rows)


def plot_example_trials(seed: int = 0, n_examples: int = 3, split: str = "test",
                        world="darkness"):
    """A figure: for each task, example arenas with the trajectory and contact points."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(_tasks.TASKS), n_examples,
                             figsize=(3.2 * n_examples, 3.2 * len(_tasks.TASKS)),
                             squeeze=False, constrained_layout=True)
    for row, task in enumerate(_tasks.TASKS):
        batch = _tasks.make_trials(task, n_examples, split, seed, world=world)
        for col in range(n_examples):
            ax = axes[row, col]
            v = batch.arena_vertices[col]
            closed = np.vstack([v, v[:1]])
            ax.plot(closed[:, 0], closed[:, 1], color="k", lw=1.5)
            pos = batch.position[:, col]
            ax.plot(pos[:, 0], pos[:, 1], lw=0.6, color="tab:blue", label="trajectory")
            touched = batch.contact[:, col]
            ax.scatter(pos[touched, 0], pos[touched, 1], s=8, color="tab:red", zorder=3,
                       label="contact")
            ax.scatter(*batch.start[col], marker="*", s=80, color="tab:green", zorder=4,
                       label="start")
            ax.set_aspect("equal")
            ax.set_title(f"{task} · env {batch.environment[col]}", fontsize=9)
            ax.set_xlabel("x (m)")
            ax.set_ylabel("y (m)")
    axes[0, 0].legend(fontsize=7, loc="lower left")
    fig.suptitle("Example trials: 200 s of foraging; red = boundary contacts")
    return fig
