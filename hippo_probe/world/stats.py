"""Summary statistics of the tasks' trials, and a picture of example trials."""

from __future__ import annotations

import numpy as np

from .. import tasks as _tasks

#: Times (s) at which the path-integration error is reported.
PI_REPORT_TIMES = (50.0, 100.0, 200.0)


def path_integration_error(batch) -> np.ndarray:
    """Euclidean error (T, B) of integrating the noisy displacement inputs from the
    true start: the drift that boundary contacts must correct."""
    disp = batch.inputs[..., [batch.features.index("dx"), batch.features.index("dy")]]
    estimate = batch.start[None] + np.cumsum(disp.astype(np.float64), axis=0)
    return np.linalg.norm(estimate - batch.position, axis=-1)


def trial_statistics(batch) -> dict:
    """Mean speed, contact statistics and PI error of one batch."""
    step = np.linalg.norm(np.diff(batch.position, axis=0), axis=-1)
    pi_error = path_integration_error(batch).mean(axis=1)
    contacts_per_trial = batch.contact.sum(axis=0)
    duration = batch.n_steps * batch.dt
    out = {
        "task": batch.task,
        "n_trials": len(batch),
        "mean_speed_m_per_s": float(step.mean() / batch.dt),
        "contacts_per_trial": float(contacts_per_trial.mean()),
        "mean_time_between_contacts_s": float(duration / max(contacts_per_trial.mean(), 1e-12)),
        "arena_mean_radius_m": float(np.linalg.norm(batch.arena_vertices, axis=-1).mean()),
    }
    for t in PI_REPORT_TIMES:
        k = int(round(t / batch.dt)) - 1
        if 0 <= k < batch.n_steps:
            out[f"pi_error_{int(t)}s_m"] = float(pi_error[k])
    return out


def world_stats(n_trials: int = 500, split: str = "test", seed: int = 0) -> dict:
    """:func:`trial_statistics` of every task."""
    return {task: trial_statistics(_tasks.make_trials(task, n_trials, split, seed))
            for task in _tasks.TASKS}


def format_stats(stats: dict) -> str:
    """A plain-text table of :func:`world_stats`."""
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
    return "\n".join(rows)


def plot_example_trials(seed: int = 0, n_examples: int = 3, split: str = "test"):
    """A figure: for each task, example arenas with the trajectory and contact points."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(_tasks.TASKS), n_examples,
                             figsize=(3.2 * n_examples, 3.2 * len(_tasks.TASKS)),
                             squeeze=False, constrained_layout=True)
    for row, task in enumerate(_tasks.TASKS):
        batch = _tasks.make_trials(task, n_examples, split, seed)
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
