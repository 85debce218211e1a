"""``hippo-probe train`` and ``hippo-probe evaluate``."""

import contextlib
import os
import signal
import sys
import threading

from .._cli_common import check_output, count, one_of
from .._cli_trials import add_trial_options
from ..tasks import TASKS
from ..world.config import WORLDS


def add_commands(sub):
    from ..model.config import PRECISIONS, VARIANTS
    from .config import TrainConfig
    d = TrainConfig()
    p = sub.add_parser("train", help="train (or resume) a network; see TrainConfig")
    p.add_argument("--task", required=True, choices=TASKS, type=one_of("task", TASKS),
                   help="the task to learn (see hippo_probe.tasks)")
    p.add_argument("--world", choices=WORLDS, type=one_of("world", WORLDS), default=d.world,
                   help="world of every trial of the run: darkness (the study's: the sensed "
                        "heading drifts) or compass (no drift)")
    p.add_argument("--trials", type=count(), default=None, metavar="N",
                   help="training-set size, trials 0..N-1 of the train split (default: the "
                        "study's, 5,000 / 300,000 / 250,000 for localization / generalized / "
                        "specialized)")
    p.add_argument("--steps", type=count(), default=d.steps,
                   help="budget in optimizer (Adam) steps")
    p.add_argument("--batch-size", type=count(), default=d.batch_size,
                   help="trials (sequences of 500 time steps) per optimizer step")
    p.add_argument("--lr", type=float, default=d.lr,
                   help="initial Adam learning rate, cosine-decayed to --lr-final")
    p.add_argument("--lr-final", type=float, default=d.lr_final,
                   help="learning rate at the end of the budget")
    p.add_argument("--hidden-size", type=count(), default=d.hidden_size,
                   help="LSTM units (the recorded cells)")
    p.add_argument("--validate-every", type=count(), default=d.validate_every, metavar="STEPS",
                   help="optimizer steps between validations (the best network by "
                        "validation loss is kept)")
    p.add_argument("--validation-trials", type=count(), default=d.n_validation, metavar="N",
                   help="trials of the validation split used at each validation")
    p.add_argument("--test-trials", type=count(), default=d.n_test, metavar="N",
                   help="trials of the test split scored at the end")
    p.add_argument("--checkpoint-minutes", type=float, default=d.checkpoint_minutes,
                   metavar="MIN", help="wall time between checkpoints (min)")
    p.add_argument("--threads", type=count(), default=d.threads, metavar="N",
                   help="CPU threads of torch and numba in this process")
    p.add_argument("--precision", choices=("auto", *PRECISIONS), default=d.precision,
                   type=one_of("precision", ("auto", *PRECISIONS)),
                   help="matmul precision of training: bf16 (AMX matmuls, float32 state "
                        "and optimizer), fp32, or auto = bf16 where the CPU has bf16 "
                        "hardware, else fp32")
    p.add_argument("--stop-improvement", type=float, default=d.stop_improvement,
                   metavar="FRACTION",
                   help="stop before --steps once the validation loss improved by less than "
                        "this fraction over the last fifth of the steps done, checked from a "
                        "quarter of --steps (0 = never)")
    p.add_argument("--max-hours", type=float, default=d.max_hours, metavar="H",
                   help="stop before --steps once the run's wall time, summed over resumes, "
                        "passes H hours (default: no cap but the step budget)")
    p.add_argument("--variant", default=d.variant, choices=VARIANTS,
                   type=one_of("variant", VARIANTS),
                   help="the study's network (faithful, default) or a labelled departure: "
                        "nonneg, dale, placecells (hippo_probe.model.variants)")
    p.add_argument("--activity-l1", type=float, default=d.activity_l1, metavar="WEIGHT",
                   help="L1 cost on the units' activity, WEIGHT * mean |h|")
    p.add_argument("--snapshot-every", type=count(), default=None, metavar="STEPS",
                   help="save the current parameters every STEPS steps as "
                        "FOLDER/snapshots/step_NNNNNN.pt (default: no snapshots)")
    p.add_argument("--seed", type=int, default=d.seed,
                   help="seed of the task's splits (which trials exist)")
    p.add_argument("--init-seed", type=int, default=d.init_seed,
                   help="seed of the initial parameters and of the order of training trials")
    p.add_argument("--class-weight", type=float, default=None, metavar="LAMBDA",
                   help="weight of the arena classification (cross-entropy) term of the "
                        "loss (default: half the squared position error at chance, "
                        "0.5 var(target) / ln(number of arenas))")
    p.add_argument("--init-from", default=None, metavar="NETWORK",
                   help="initialise from a checkpoint (.pt) or a pretrained name (default: "
                        "random initial parameters)")
    p.add_argument("--train-only", choices=["classifier"], default=None,
                   type=one_of("train_only", ("classifier",)),
                   help="classifier: freeze all but the arena readout and retrain it "
                        "(specialized task, needs --init-from; default: train everything)")
    p.add_argument("--cache-dir", default=None, metavar="FOLDER",
                   help="cache of generated trials (default: $HIPPO_PROBE_CACHE or "
                        "~/.cache/hippo_probe/trials)")
    p.add_argument("--out", required=True, metavar="FOLDER",
                   help="run directory: checkpoint.pt, network.pt, log.json (resumes the "
                        "run if it exists)")
    p.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    p.add_argument("--overwrite", action="store_true",
                   help="start afresh in a FOLDER holding a finished run's network.pt or "
                        "log.json without a checkpoint (default: refuse)")
    p.set_defaults(run=_train)

    e = sub.add_parser("evaluate", help="errors / accuracy of a network on a split")
    e.add_argument("checkpoint", metavar="NETWORK",
                   help="a .pt file (run checkpoint, network.pt) or a pretrained name (e.g. "
                        "generalized)")
    add_trial_options(e)
    e.add_argument("--no-progress", action="store_true", help="do not show a progress bar")
    e.set_defaults(run=_evaluate)

    x = sub.add_parser("export-network", help="ship a run's best network as pretrained "
                                              "(network .pt + training log .json)")
    x.add_argument("run_dir", metavar="RUN_DIR",
                   help="run directory of `hippo-probe train` (holds network.pt and log.json)")
    x.add_argument("name", metavar="NAME",
                   help="pretrained name to ship it under (e.g. generalized)")
    x.add_argument("--dest", required=True, metavar="FOLDER",
                   help="folder to write into (the repository's shipped networks: "
                        "hippo_probe/pretrained)")
    x.add_argument("--overwrite", action="store_true",
                   help="replace a network already exported under NAME in FOLDER")
    x.set_defaults(run=_export)


def _train(a):
    import json

    check_output("--out", a.out, kind="folder")     # a run folder, not a file: refused now

    if "torch" not in sys.modules:
        # OpenMP workers that torch starts before `set_num_threads` takes effect keep
        # spin-waiting at barriers; with two or three runs sharing the cores that made every
        # run ~10x slower (12 s instead of 1.1 s per step here). Size the pool, and let idle
        # workers sleep, before libgomp loads.
        os.environ.setdefault("OMP_NUM_THREADS", str(a.threads))
        os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    from .config import TrainConfig
    from .trainer import fit

    config = TrainConfig(task=a.task, world=a.world, n_trials=a.trials, steps=a.steps,
                         batch_size=a.batch_size, lr=a.lr, lr_final=a.lr_final,
                         hidden_size=a.hidden_size, validate_every=a.validate_every,
                         n_validation=a.validation_trials, n_test=a.test_trials,
                         checkpoint_minutes=a.checkpoint_minutes, threads=a.threads,
                         seed=a.seed, init_seed=a.init_seed, class_weight=a.class_weight,
                         init_from=a.init_from, train_only=a.train_only,
                         precision=a.precision,
                         stop_improvement=a.stop_improvement or None,
                         max_hours=a.max_hours or None,
                         snapshot_every=a.snapshot_every, variant=a.variant,
                         activity_l1=a.activity_l1)
    with _stop_at_a_step_boundary() as received:
        try:
            log = fit(config, a.out, progress=not a.no_progress, cache_dir=a.cache_dir,
                      overwrite=a.overwrite, stop_requested=lambda: bool(received))
        except KeyboardInterrupt:
            if not received:
                raise
            # the trainer checkpointed the step boundary it stopped at
            print(f"hippo-probe train: stopped by signal {received[0]}; the same command "
                  f"resumes from {os.path.join(a.out, 'checkpoint.pt')}", file=sys.stderr)
            _end_by(received[0])
    if "test" in log:
        print(json.dumps(log["test"], indent=1))


@contextlib.contextmanager
def _stop_at_a_step_boundary():
    """While training, SIGINT (Ctrl-C) and SIGTERM (``kill``, a scheduler's stop) ask the
    trainer to stop at its next step boundary, with a checkpoint; a second such signal
    ends the process at once (checkpoints are written atomically, so the last one stays
    whole). Yields the list of the signals received. A signal the process was started to
    ignore stays ignored (a job started with ``&`` ignores SIGINT, which is why SIGTERM
    matters), and off the main thread, where Python takes no handlers, nothing changes."""
    received = []

    def request(signum, frame):
        if received:
            _end_by(signum)
        received.append(signum)

    watched = [] if threading.current_thread() is not threading.main_thread() else [
        s for s in (signal.SIGINT, signal.SIGTERM)
        if signal.getsignal(s) is not signal.SIG_IGN]
    previous = {s: signal.signal(s, request) for s in watched}
    try:
        yield received
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


def _end_by(signum):
    """End the process as the signal ``signum`` would have, so that a shell loop or a job
    scheduler sees it stopped, not an ordinary exit status."""
    sys.stdout.flush()
    signal.signal(signum, signal.SIG_DFL)
    os.kill(os.getpid(), signum)


def _evaluate(a):
    import json
    import math

    from ..model.load import load_pretrained
    from ..tasks import make_trials, task_config
    from .trainer import evaluate_network, summarize

    if a.trials < 1:
        raise ValueError(f"`--trials` must be >= 1; got {a.trials}")
    net = load_pretrained(a.checkpoint)
    task = a.task or net.task
    world = a.world or net.world
    batch = make_trials(task, a.trials, a.split, a.seed, world=world)
    weight = (net.info.get("class_weight") or 0.0)
    # score the (x, y) readout in the frame of the task it was trained on
    start_relative = task_config(net.position_task or net.task).target == "start_relative"
    target = batch.position - batch.start[None] if start_relative else batch.position
    metrics = evaluate_network(net, batch, weight, target=target,
                               progress=not a.no_progress)
    metrics = summarize(metrics, batch.dt)
    broken = sorted(k for k, v in metrics.items()
                    if isinstance(v, float) and not math.isfinite(v))
    if broken:
        raise ValueError(f"the network {str(a.checkpoint)!r} gives non-finite results "
                         f"({', '.join(broken)}): its parameters are broken")
    if net.classifier is None or task != "specialized":
        # a network without an arena readout (or scored off its task) has no such term
        for key in ("ce", "loss"):
            metrics.pop(key, None)
    # four significant digits: what the test split's sampling error leaves meaningful
    shown = {k: (float(f"{v:.4g}") if isinstance(v, float) else v) for k, v in metrics.items()}
    print(json.dumps({"network": str(a.checkpoint), "task": task, "world": world,
                      "network_world": net.world, "split": a.split,
                      "trials": a.trials, **shown}, indent=1))


def _export(a):
    from .export import export_network

    check_output("--dest", a.dest, kind="folder")
    paths = export_network(a.run_dir, a.name, a.dest, overwrite=a.overwrite)
    print("\n".join(f"wrote {p}" for p in paths))
