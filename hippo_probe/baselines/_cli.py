"""``hippo-probe baselines``."""


def add_commands(sub):
    p = sub.add_parser(
        "baselines",
        help="run PI, SH, NB, the particle filter (and PF-SLAM) on a task's trials")
    p.add_argument("--task", required=True,
                   help="localization, generalized or specialized")
    p.add_argument("--world", default="darkness",
                   help="the world of the trials: darkness (the default, the study's) or compass")
    p.add_argument("--split", default="test", help="train, validation or test (default test)")
    p.add_argument("--seed", type=int, default=0, help="seed of the split (default 0)")
    p.add_argument("--out", required=True, metavar="FILE",
                   help="zarr store to write (estimates in the arena frame, PF covariances, "
                        "PF-SLAM class posteriors; layout: hippo_probe.baselines.results)")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="also save the localization error vs time of every baseline here")
    p.add_argument("--trials", type=int, default=None,
                   help="number of trials (default: the whole split)")
    p.add_argument("--first", type=int, default=0, help="index of the first trial (default 0)")
    p.add_argument("--particles", type=int, default=None,
                   help="particles of the oracular PF per trial (default 1000 with a known "
                        "start, 2000 with an unknown one)")
    p.add_argument("--slam-particles", type=int, default=None,
                   help="particles of PF-SLAM per trial, specialized task (default 10000)")
    p.add_argument("--prior-trials", type=int, default=None,
                   help="training trials of the naive-Bayes prior (default 2000)")
    p.add_argument("--threads", type=int, default=None,
                   help="threads of the particle filters (default: all cores)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing FILE")
    p.set_defaults(run=_baselines)


def _baselines(args):
    import time
    from pathlib import Path

    from .._atomic import save_figure
    from .._validators import check_option
    from ..tasks import SPLITS, TASKS, make_trials, task_config
    from .config import BaselineConfig, NaiveBayesConfig
    from .results import error_table, plot_errors, run_baselines, save_baselines

    check_option("task", args.task, TASKS)
    check_option("split", args.split, SPLITS)
    out = Path(args.out)
    if out.exists() and not args.overwrite:
        raise FileExistsError(f"`--out` {str(out)!r} exists; pass --overwrite to replace it")
    n_trials = args.trials if args.trials is not None else \
        task_config(args.task, args.world).split_size(args.split)
    began = time.perf_counter()
    batch = make_trials(args.task, n_trials, args.split, args.seed, first=args.first,
                        world=args.world)
    baseline = BaselineConfig() if args.prior_trials is None else \
        BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=args.prior_trials))
    ds = run_baselines(batch, n_particles=args.particles, slam_particles=args.slam_particles,
                       threads=args.threads, progress=True, baseline=baseline)
    save_baselines(ds, out, overwrite=args.overwrite)
    print(error_table(ds))
    print(f"saved {out} ({time.perf_counter() - began:.0f} s)")
    if args.plot:
        plot = save_figure(plot_errors(ds), args.plot, dpi=150)
        print(f"saved {plot}")
