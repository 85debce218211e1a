"""``hippo-probe record`` and ``hippo-probe export-network``."""

from pathlib import Path

from ..tasks import SPLITS, TASKS


def add_commands(sub):
    p = sub.add_parser("record", help="record a network's hidden units on a split "
                                      "(a recording, schema v1, as zarr)")
    p.add_argument("--network", required=True,
                   help="pretrained name (e.g. generalized, generalized_compass; see "
                        "hippo_probe.pretrained) or a .pt file")
    p.add_argument("--split", default="test", choices=SPLITS,
                   help="split of the trials (default test)")
    p.add_argument("--task", default=None, choices=TASKS,
                   help="task whose trials to run (default: the network's own)")
    p.add_argument("--world", default=None,
                   help="world of the trials, darkness or compass (default: the network's own)")
    p.add_argument("--trials", type=int, default=1000, help="number of trials (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the split (default 0)")
    p.add_argument("--baselines", default=None, metavar="FILE",
                   help="add the estimates of a `hippo-probe baselines` output file")
    p.add_argument("--out", required=True, help="destination zarr store")
    p.add_argument("--overwrite", action="store_true")
    p.set_defaults(run=_record)

    e = sub.add_parser("export-network", help="ship a run's best network as pretrained "
                                              "(network .pt + training log .json)")
    e.add_argument("run_dir")
    e.add_argument("name", help="e.g. generalized")
    e.add_argument("--dest", default=None, help="folder (default: hippo_probe/pretrained)")
    e.set_defaults(run=_export)


def _record(a):
    from ..pretrained import load_pretrained
    from ..recording import save_recording
    from ..tasks import make_trials
    from .record import record

    from .._validators import check_positive

    check_positive("--trials", a.trials, integer=True)
    if (Path(a.out).exists() or Path(a.out).is_symlink()) and not a.overwrite:
        raise FileExistsError(f"--out {a.out} already exists; pass --overwrite to replace it")
    net = load_pretrained(a.network)
    task = a.task or net.task
    batch = make_trials(task, a.trials, a.split, a.seed, world=a.world or net.world)
    baselines = None
    if a.baselines:
        from ..baselines.results import open_baselines
        from .record import baselines_from_dataset
        baselines = baselines_from_dataset(open_baselines(a.baselines), batch)
    rec = record(net, batch, baselines=baselines, checkpoint=str(a.network))
    save_recording(rec, a.out, overwrite=a.overwrite)
    print(f"saved {a.out}: {rec.sizes['time']} samples x {rec.sizes['unit']} units")


def _export(a):
    from ..training.export import export_network

    paths = export_network(a.run_dir, a.name, dest=a.dest)
    print("\n".join(f"wrote {p}" for p in paths))
