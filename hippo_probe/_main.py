"""``hippo-probe main``: the README's main job."""

from pathlib import Path


def add_commands(sub):
    p = sub.add_parser("main", help="the README's main job (world statistics, figures)")
    p.add_argument("--out", default="figures", help="output folder (default: figures/)")
    p.set_defaults(run=_main)


def _main(args):
    from .world.stats import format_stats, plot_example_trials, world_stats

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print("== World statistics (500 test trials per task) ==")
    print(format_stats(world_stats(n_trials=500)))
    fig = plot_example_trials()
    fig.savefig(out / "example_trials.png", dpi=120)
    print(f"saved {out / 'example_trials.png'}")
