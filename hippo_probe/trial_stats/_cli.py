"""``hippo-probe world-stats``."""

from .._cli_common import check_output
from .._cli_trials import add_trial_options


def add_commands(sub):
    p = sub.add_parser("world-stats", help="statistics of each task's trials, and a picture")
    add_trial_options(p, task=False, world="darkness", trials=500,
                      trials_help="trials per task")
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
        check_output("--plot", args.plot, kind="file", overwrite=args.overwrite,
                     example="example_trials.png")

    stats = world_stats(n_trials=args.trials, split=args.split, seed=args.seed,
                        world=args.world)
    print(format_stats(stats))
    if args.json:
        write_text(args.json, json.dumps(stats, indent=2))
    if args.plot:
        fig = plot_example_trials(seed=args.seed, world=args.world)
        save_figure(fig, args.plot, dpi=120)
        print(f"saved {args.plot}")
