"""``hippo-probe world-stats``."""


def add_commands(sub):
    p = sub.add_parser("world-stats", help="statistics of each task's trials, and a picture")
    p.add_argument("--trials", type=int, default=500, help="trials per task (default 500)")
    p.add_argument("--world", default="darkness",
                   help="the world: darkness (the default, the study's) or compass (no drift)")
    p.add_argument("--split", default="test",
                   help="split of the trials: train, validation or test (default test)")
    p.add_argument("--seed", type=int, default=0, help="seed of the split (default 0)")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="save example arenas with trajectories and contacts here")
    p.add_argument("--json", default=None, metavar="FILE", help="also write the numbers here")
    p.set_defaults(run=_world_stats)


def _world_stats(args):
    import json

    from .._atomic import save_figure, write_text
    from .stats import format_stats, plot_example_trials, world_stats

    stats = world_stats(n_trials=args.trials, split=args.split, seed=args.seed,
                        world=args.world)
    print(format_stats(stats))
    if args.json:
        write_text(args.json, json.dumps(stats, indent=2))
    if args.plot:
        fig = plot_example_trials(seed=args.seed, world=args.world)
        save_figure(fig, args.plot, dpi=120)
        print(f"saved {args.plot}")
