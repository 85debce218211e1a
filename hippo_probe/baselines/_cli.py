"""``hippo-probe baselines``."""

from .._cli_common import check_output, count
from .._cli_trials import add_trial_options


def add_commands(sub):
    from .config import BaselineConfig

    d = BaselineConfig()
    p = sub.add_parser(
        "baselines",
        help="run PI, SH, NB, the particle filter (and PF-SLAM) on a task's trials")
    add_trial_options(p, task="required", world="darkness", trials=None,
                      trials_help="number of trials (default: the whole split)",
                      task_help="task whose trials to run (PF-SLAM on the specialized task "
                                "only)")
    p.add_argument("--out", required=True, metavar="STORE",
                   help="zarr store to write (estimates in the arena frame, PF covariances, "
                        "PF-SLAM class posteriors; layout: hippo_probe.baselines.results)")
    p.add_argument("--plot", default=None, metavar="PNG",
                   help="also save the localization error (m) vs time of every baseline "
                        "here (default: no plot)")
    p.add_argument("--first", type=count(0), default=0, metavar="INDEX",
                   help="index of the first trial in the split")
    p.add_argument("--particles", type=count(), default=None, metavar="N",
                   help=f"particles of the oracular particle filter per trial (default: "
                        f"{d.particle_filter.n_particles} with a known start, "
                        f"{d.particle_filter.unknown_start_particles} with an unknown one)")
    p.add_argument("--slam-particles", type=count(), default=None, metavar="N",
                   help=f"particles of PF-SLAM per trial, specialized task (default: "
                        f"{d.particle_filter.slam_particles})")
    p.add_argument("--prior-trials", type=count(), default=None, metavar="N",
                   help=f"training trials behind the naive-Bayes prior over positions "
                        f"(default: {d.naive_bayes.prior_trials})")
    p.add_argument("--threads", type=count(), default=None, metavar="N",
                   help="CPU threads of the particle filters (default: all cores)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(run=_baselines)


def _baselines(args):
    # refuse the outputs before making a single trial (the run takes minutes)
    out = check_output("--out", args.out, overwrite=args.overwrite)
    if args.plot:
        check_output("--plot", args.plot, kind="file", overwrite=args.overwrite,
                     example="errors.png")

    import time

    from .._atomic import save_figure
    from ..tasks import make_trials, task_config
    from .config import BaselineConfig, NaiveBayesConfig
    from .results import error_table, plot_errors, run_baselines, save_baselines

    size = task_config(args.task, args.world).split_size(args.split)
    n_trials = args.trials if args.trials is not None else size - args.first
    if args.first >= size or args.first + n_trials > size:
        asked = f"--first {args.first}" + (f" --trials {n_trials}" if args.trials else "")
        raise ValueError(f"{asked}: the {args.split} split of the {args.task} task holds "
                         f"trials 0 to {size - 1}")
    began = time.perf_counter()
    batch = make_trials(args.task, n_trials, args.split, args.seed, first=args.first,
                        world=args.world)
    baseline = BaselineConfig() if args.prior_trials is None else \
        BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=args.prior_trials))
    ds = run_baselines(batch, n_particles=args.particles, slam_particles=args.slam_particles,
                       threads=args.threads, progress=not args.no_progress,
                       baseline=baseline)
    save_baselines(ds, out, overwrite=args.overwrite)
    print(error_table(ds))
    print(f"saved {out} ({time.perf_counter() - began:.0f} s)")
    if args.plot:
        plot = save_figure(plot_errors(ds), args.plot, dpi=150)
        print(f"saved {plot}")
