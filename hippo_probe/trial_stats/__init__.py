"""Statistics of each task's trials (speed, contacts, path-integration error, heading
drift) and a picture of example trials: ``hippo-probe world-stats``.

Above :mod:`hippo_probe.tasks` (it makes trials), below everything that uses them.
"""

from .stats import format_stats, plot_example_trials, world_stats

__all__ = ["format_stats", "plot_example_trials", "world_stats"]
