"""``hippo-probe record``, ``hippo-probe export-network`` and ``hippo-probe networks``."""

from .._cli_common import check_output
from .._cli_trials import add_trial_options
from ..world.config import MotionConfig


def add_commands(sub):
    motion = MotionConfig()
    p = sub.add_parser("record", help="record a network's hidden units on a split "
                                      "(a recording, schema v1, as zarr)")
    p.add_argument("--network", required=True,
                   help="pretrained name (e.g. generalized, generalized_compass; see "
                        "hippo_probe.pretrained) or a .pt file")
    add_trial_options(p, trials_help=f"number of trials (each {motion.n_steps} steps of "
                                     f"{motion.network_dt:g} s: "
                                     f"{motion.n_steps * motion.network_dt:g} s)")
    p.add_argument("--baselines", default=None, metavar="FILE",
                   help="add the estimates of a `hippo-probe baselines` output store (made "
                        "on the same task, world, split and seed; default: none)")
    p.add_argument("--out", required=True, metavar="STORE",
                   help="destination zarr store (e.g. recordings/NAME.zarr)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.set_defaults(run=_record)

    n = sub.add_parser("networks", help="the shipped networks, their training seeds and "
                                        "test errors as mean (min-max) over seeds")
    n.add_argument("--per-seed", action="store_true",
                   help="one row per network and seed, with its training steps and hours")
    n.set_defaults(run=_networks)


def _record(a):
    from pathlib import Path

    from .._validators import check_positive

    # refuse bad arguments before loading torch and making the trials
    check_positive("--trials", a.trials, integer=True)
    check_output("--out", a.out, overwrite=a.overwrite)
    if a.baselines and not Path(a.baselines).exists():
        raise FileNotFoundError(f"--baselines {a.baselines} does not exist")

    from ..model.load import load_pretrained
    from ..recording import save_recording
    from ..tasks import make_trials
    from .record import record

    net = load_pretrained(a.network)
    task = a.task or net.task
    batch = make_trials(task, a.trials, a.split, a.seed, world=a.world or net.world)
    baselines = None
    if a.baselines:
        from ..baselines.results import open_baselines
        from .record import baselines_from_dataset
        baselines = baselines_from_dataset(open_baselines(a.baselines), batch)
    rec = record(net, batch, baselines=baselines, checkpoint=str(a.network),
                 progress=not a.no_progress)
    save_recording(rec, a.out, overwrite=a.overwrite)
    print(f"saved {a.out}: {rec.sizes['time']} samples x {rec.sizes['unit']} units")


def _networks(a):
    from ..pretrained.summary import markdown, per_seed_text, seed_spread, shipped_table

    table = shipped_table()
    if table.empty:
        raise FileNotFoundError("no shipped networks in this installation "
                                "(hippo_probe/pretrained)")
    print(per_seed_text(table) if a.per_seed else markdown(seed_spread(table)))
