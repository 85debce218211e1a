"""The options that choose a command's trials, one voice for every command that runs
trials (``record``, ``evaluate``, ``baselines``, ``world-stats``): ``--task``,
``--world``, ``--split``, ``--seed`` and ``--trials``."""

from __future__ import annotations

from ._cli_common import count, one_of
from .tasks import SPLITS, TASKS
from .world.config import WORLDS

#: The default of ``--task`` / ``--world`` that means "the network's own".
NETWORKS_OWN = None


def add_trial_options(p, *, task=NETWORKS_OWN, world=NETWORKS_OWN, trials=1000,
                      trials_help="number of trials", task_help=None):
    """Add the trial options to the subcommand parser ``p``.

    Parameters
    ----------
    task : str, None or False
        Default of ``--task``: a task's name, :data:`NETWORKS_OWN` (the network's own),
        ``"required"``, or False for a command without the option.
    world : str or None
        Default of ``--world``: a world's name or :data:`NETWORKS_OWN`.
    trials : int or None
        Default of ``--trials`` (None: the whole split).
    trials_help, task_help : str
        Their help texts, where the command says more.
    """
    if task is not False:
        required = task == "required"
        own = task is NETWORKS_OWN
        p.add_argument("--task", required=required, default=None if required else task,
                       choices=TASKS, type=one_of("task", TASKS),
                       help=task_help or ("task whose trials to run"
                                          + (" (default: the network's own)" if own else "")))
    p.add_argument("--world", default=world, choices=WORLDS, type=one_of("world", WORLDS),
                   help="world of the trials: darkness (the study's: the sensed heading "
                        "drifts) or compass (no drift)"
                        + ("; default: the network's own" if world is NETWORKS_OWN else ""))
    p.add_argument("--split", default="test", choices=SPLITS, type=one_of("split", SPLITS),
                   help="split of the trials")
    p.add_argument("--seed", type=int, default=0, help="seed of the split")
    p.add_argument("--trials", type=count(), default=trials, metavar="N", help=trials_help)
