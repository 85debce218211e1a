"""``hippo-probe train`` and ``hippo-probe evaluate``."""

from ..tasks import TASKS
from ..world.config import WORLDS


def add_commands(sub):
    from ..model.config import PRECISIONS
    from .config import TrainConfig
    d = TrainConfig()
    p = sub.add_parser("train", help="train (or resume) a network; see TrainConfig")
    p.add_argument("--task", required=True, choices=TASKS)
    p.add_argument("--world", choices=WORLDS, default=d.world,
                   help=f"world of the trials (default {d.world}, the study's; compass: "
                        f"no heading drift)")
    p.add_argument("--trials", type=int, default=None,
                   help="training-set size (default: the study's, 5k/300k/250k)")
    p.add_argument("--steps", type=int, default=d.steps, help="optimizer steps (budget)")
    p.add_argument("--batch-size", type=int, default=d.batch_size)
    p.add_argument("--lr", type=float, default=d.lr)
    p.add_argument("--lr-final", type=float, default=d.lr_final)
    p.add_argument("--hidden-size", type=int, default=d.hidden_size)
    p.add_argument("--validate-every", type=int, default=d.validate_every)
    p.add_argument("--validation-trials", type=int, default=d.n_validation)
    p.add_argument("--test-trials", type=int, default=d.n_test)
    p.add_argument("--checkpoint-minutes", type=float, default=d.checkpoint_minutes)
    p.add_argument("--threads", type=int, default=d.threads)
    p.add_argument("--precision", choices=("auto", *PRECISIONS), default=d.precision,
                   help="matmul precision of training: bf16 (AMX matmuls, float32 state "
                        "and optimizer), fp32, or auto = bf16 where the CPU has bf16 "
                        f"hardware, else fp32 (default {d.precision})")
    p.add_argument("--seed", type=int, default=d.seed, help="seed of the task's splits")
    p.add_argument("--init-seed", type=int, default=d.init_seed)
    p.add_argument("--class-weight", type=float, default=None)
    p.add_argument("--init-from", default=None,
                   help="initialise from a checkpoint / pretrained name")
    p.add_argument("--train-only", choices=["classifier"], default=None,
                   help="freeze all but the arena readout (readout retraining)")
    p.add_argument("--cache-dir", default=None, help="trial cache (default ~/.cache/...)")
    p.add_argument("--out", required=True, help="run directory (resumes if it exists)")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(run=_train)

    e = sub.add_parser("evaluate", help="errors / accuracy of a network on a split")
    e.add_argument("checkpoint", help="a .pt file (run checkpoint, network.pt) or a "
                                      "pretrained name")
    e.add_argument("--split", default="test", choices=["train", "validation", "test"])
    e.add_argument("--trials", type=int, default=1000)
    e.add_argument("--seed", type=int, default=0)
    e.add_argument("--task", default=None, choices=TASKS,
                   help="evaluate on another task than the network's own")
    e.add_argument("--world", default=None, choices=WORLDS,
                   help="evaluate in another world than the network's own")
    e.set_defaults(run=_evaluate)


def _train(a):
    import json
    import os
    import sys

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
                         precision=a.precision)
    log = fit(config, a.out, progress=not a.no_progress, cache_dir=a.cache_dir)
    if "test" in log:
        print(json.dumps(log["test"], indent=1))


def _evaluate(a):
    import json
    import math

    from ..pretrained import load_pretrained
    from ..tasks import make_trials
    from .trainer import evaluate_network, summarize

    from ..tasks import task_config

    if a.trials < 1:
        raise ValueError(f"`--trials` must be >= 1; got {a.trials}")
    net = load_pretrained(a.checkpoint)
    task = a.task or net.task
    world = a.world or net.world
    batch = make_trials(task, a.trials, a.split, a.seed, world=world)
    weight = (net.info.get("class_weight") or 0.0)
    # score the readout in the frame of the task the network was trained on
    start_relative = task_config(net.task).target == "start_relative"
    target = batch.position - batch.start[None] if start_relative else batch.position
    metrics = summarize(evaluate_network(net, batch, weight, target=target), batch.dt)
    broken = sorted(k for k, v in metrics.items()
                    if isinstance(v, float) and not math.isfinite(v))
    if broken:
        raise ValueError(f"the network {str(a.checkpoint)!r} gives non-finite results "
                         f"({', '.join(broken)}): its parameters are broken")
    print(json.dumps({"network": str(a.checkpoint), "task": task, "world": world,
                      "network_world": net.world, "split": a.split,
                      "trials": a.trials, **metrics}, indent=1))
