"""``hippo-probe world-stats``."""

from ..cli import check_output, count, one_of
from ..tasks import SPLITS
from ..world.config import WORLDS


def add_commands(sub):
    p = sub.add_parser("world-stats", help="statistics of each task's trials, and a picture")
    p.add_argument("--trials", type=count(), default=500, metavar="N",
                   help="trials per task")
    p.add_argument("--world", default="darkness", choices=WORLDS, type=one_of("world", WORLDS),
                   help="the world: darkness (the study's: the sensed heading drifts) or "
                        "compass (no drift)")
    p.add_argument("--split", default="test", choices=SPLITS, type=one_of("split", SPLITS),
                   help="split of the trials")
    p.add_argument("--seed", type=int, default=0, help="seed of the split")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="save example arenas with trajectories and wall contacts here "
                        "(default: no picture)")
    p.add_argument("--json", default=None, metavar="FILE",
                   help="also write the numbers here, as JSON (default: only printed)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing --json or --plot file of another kind")
    p.set_defaults(run=_world_stats)


def _world_stats(args):
    import json

    from .._atomic import save_figure, write_text
    from .stats import format_stats, plot_example_trials, world_stats

    # refused before the trials are simulated
    if args.json:
        check_output("--json", args.json, kind="file", writes="json",
                     overwrite=args.overwrite)
    if args.plot:
        check_output("--plot", args.plot, kind="file", overwrite=args.overwrite)

    stats = world_stats(n_trials=args.trials, split=args.split, seed=args.seed,
                        world=args.world)
    print(format_stats(stats))
    if args.json:
        write_text(args.json, json.dumps(stats, indent=2))
    if args.plot:
        fig = plot_example_trials(seed=args.seed, world=args.world)
        save_figure(fig, args.plot, dpi=120)
        print(f"saved {args.plot}")
