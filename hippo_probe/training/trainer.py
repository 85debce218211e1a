"""The training loop: Adam, clipped gradients, validation, atomic checkpoints, resume, DDP.

Loss (per step, averaged over steps and trials)::

    L = mean ||xy_hat - target||^2 / 2  +  lambda * CE(logits, arena)

The squared error is averaged over the two coordinates. ``lambda`` is fixed for the run
(:func:`class_weight_rule`) and logged.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import os
import sys
import time
import warnings
from pathlib import Path
from typing import NamedTuple

import numpy as np
import torch
import torch.nn.functional as F
from tqdm.auto import tqdm

from .._atomic import exclusive_lock, write_text
from .._validators import check_bool
from .._version import __version__
from ..errors import RunInUseError
from ..model.config import ModelConfig, input_scale_for, native_bf16, resolve_precision
from ..model.load import READOUT_OF, network_parameters
from ..model.navigator import Navigator
from ..tasks import make_trials, task_config
from ..model.checkpoint import load, load_into, require, save_atomic
from .config import TrainConfig
from .data import TrainingTrials
from .memory import reuse_freed_memory


def class_weight_rule(position_cost: float, n_classes: int) -> float:
    """lambda such that the weighted cross-entropy is half the position cost at chance.

    At chance (predicting the mean position, 0, and a uniform class posterior) the squared
    error is the target's mean square and the cross-entropy ``ln C``; so ``lambda = 0.5 *
    position_cost / ln C`` makes ``lambda * CE`` about half of the localization cost, the
    balance prescribed by the project's design. ``position_cost`` is what
    :func:`_position_cost_at_chance` returns for the network's position output.
    """
    return 0.5 * position_cost / math.log(n_classes)


def _position_cost_at_chance(net, target) -> float:
    """The position term's excess over its minimum at chance, on targets (T, B, 2).

    The (x, y) readout's squared error at the mean position 0 is the targets' mean square;
    the place-cell output's cross-entropy at a uniform population is ``ln n``, of which
    the targets' own entropy ``H(q)`` is out of reach: its excess is ``ln n - H(q)``.
    """
    target = np.asarray(target, np.float32)
    if net.config.variant != "placecells":
        return float(np.mean(target ** 2))
    with torch.no_grad():
        q = net.position.targets(torch.from_numpy(target))
        entropy = -(q * torch.log(q.clamp_min(1e-30))).sum(-1).mean()
    return float(math.log(q.shape[-1]) - entropy)


def build_network(config: TrainConfig) -> Navigator:
    task = task_config(config.task, config.world)
    n_classes = task.n_classes if (task.classify or config.train_only == "classifier") else 0
    if config.train_only == "classifier":
        n_classes = task_config("specialized").n_arenas
    model_config = ModelConfig(hidden_size=config.hidden_size, n_classes=n_classes,
                               input_scale=input_scale_for(task.world),
                               precision=config.precision, variant=config.variant)
    torch.manual_seed(config.init_seed)
    net = Navigator(model_config)
    net.base_network = None
    if config.init_from:
        from ..pretrained import checkpoint_world, resolve_network_file
        path = resolve_network_file(config.init_from)
        obj = load(path)
        base_world = checkpoint_world(obj)
        if base_world != config.world:
            raise ValueError(f"`init_from` {config.init_from!r} was trained in the "
                             f"{base_world!r} world; this run is of the {config.world!r} "
                             f"world (`world`)")
        state = network_parameters(obj, path)
        own = net.state_dict()
        wrong = {k: (tuple(v.shape), tuple(own[k].shape)) for k, v in state.items()
                 if k in own and v.shape != own[k].shape}
        if wrong:
            raise ValueError(f"`init_from` {config.init_from!r} has parameters of other "
                             f"shapes (got, expected): {wrong}")
        # a retrained readout starts fresh; every other parameter must come from the file
        fresh = ("classifier.",) if config.train_only == "classifier" else ()
        missing = [k for k in own if k not in state and not k.startswith(fresh)]
        if missing:
            raise ValueError(f"`init_from` {config.init_from!r} lacks parameters {missing}")
        own.update({k: v for k, v in state.items()
                    if k in own and not k.startswith(fresh)})
        net.load_state_dict(own)
        # the name as given and the file's name: an absolute path would leak the trainer's
        # machine into shipped logs; the sha1 identifies the file
        net.base_network = {"init_from": config.init_from, "file": path.name,
                            "sha1": _sha1(path),
                            "steps_done": obj.get("steps_done", obj.get("step")),
                            "finished": obj.get("finished")}
        if READOUT_OF in obj:           # a readout file: the network it reads, pinned too
            net.base_network[READOUT_OF] = obj[READOUT_OF]
    if config.train_only == "classifier":
        for name, p in net.named_parameters():
            p.requires_grad_(name.startswith("classifier."))
    return net


def _plain(model_config) -> dict:
    """A ModelConfig as plain values (what checkpoints store)."""
    return vars(model_config) | {"input_scale": list(model_config.input_scale)}


def _command_line() -> str:
    """The command as typed: the program's name, not its path on the trainer's machine."""
    return " ".join([Path(sys.argv[0]).name, *sys.argv[1:]])


def _sha1(path) -> str:
    import hashlib
    return hashlib.sha1(Path(path).read_bytes()).hexdigest()


class Losses(NamedTuple):
    """The terms of one batch's objective, and the network's outputs."""

    total: torch.Tensor        # what is minimized
    mse: torch.Tensor          # squared error of the decoded position
    ce: torch.Tensor           # arena cross-entropy (0 when not classifying)
    position: torch.Tensor     # the position term trained on
    xy: torch.Tensor
    logits: torch.Tensor | None


def losses(net, inputs, target, environment, class_weight, *, classifier_only=False,
           classify=True, activity_l1=0.0) -> Losses:
    """The objective's terms on one batch of numpy arrays.

    ``total = position + class_weight * ce + activity_l1 * mean |h|``; the position term
    is the squared error of the (x, y) readout (the place cells' cross-entropy for that
    variant), ``mse`` always that of the decoded position.
    """
    xy, logits, h = net(torch.from_numpy(inputs))
    target = torch.from_numpy(np.asarray(target, dtype=np.float32)).to(xy.device)
    mse = ((xy - target) ** 2).mean()
    module = getattr(net, "module", net)            # under DDP, the wrapped Navigator
    position_term = mse if module.config.variant != "placecells" else \
        module.position_loss(h, target)
    ce = torch.zeros((), device=xy.device)
    if not classify:
        logits = None
    if logits is not None:
        labels = torch.from_numpy(np.asarray(environment)).long().to(xy.device)
        ce = F.cross_entropy(logits.reshape(-1, logits.shape[-1]),
                             labels.repeat(logits.shape[0]))
    total = class_weight * ce if classifier_only else position_term + class_weight * ce
    if activity_l1 and not classifier_only:
        total = total + activity_l1 * h.abs().mean()
    return Losses(total, mse, ce, position_term, xy, logits)


@torch.no_grad()
def evaluate_network(net, batch, class_weight: float = 0.0, chunk: int = 250, *,
                     target=None, progress: bool = False) -> dict:
    """Errors of ``net`` on a TrialBatch: per-step curves and summaries.

    ``target`` (T, B, 2) defaults to ``batch.target``; pass the batch's positions in the
    network's own frame to evaluate it on another task's trials. Classification is scored
    only on trials of the specialized task (whose arena ids are the classes). ``progress``
    shows a bar over the trials.

    Returns a dict with ``error_m`` (T,) mean Euclidean error vs time, ``accuracy`` (T,)
    (if the network classifies), overall means and the loss.
    """
    target = batch.target if target is None else target
    classify = net.classifier is not None and batch.task == "specialized"
    net.eval()
    err_sum = np.zeros(batch.n_steps)
    acc_sum = np.zeros(batch.n_steps)
    mse_sum = ce_sum = position_sum = 0.0
    bar = tqdm(total=len(batch), desc=f"evaluate {batch.task}", unit="trial",
               disable=not progress)
    for lo in range(0, len(batch), chunk):
        sl = slice(lo, lo + chunk)
        _, mse, ce, position, xy, logits = losses(net, batch.inputs[:, sl], target[:, sl],
                                                  batch.environment[sl], class_weight,
                                                  classify=classify)
        n = xy.shape[1]
        mse_sum += float(mse) * n
        ce_sum += float(ce) * n
        position_sum += float(position) * n
        truth = torch.from_numpy(np.asarray(target[:, sl], dtype=np.float32))
        err = torch.linalg.norm(xy.cpu() - truth, dim=-1)
        err_sum += err.sum(1).numpy()
        if logits is not None:
            hit = logits.argmax(-1).cpu() == torch.from_numpy(batch.environment[sl])
            acc_sum += hit.float().sum(1).numpy()
        bar.update(xy.shape[1])
    bar.close()
    net.train()
    n = len(batch)
    out = {"error_m": err_sum / n, "mean_error_m": float(err_sum.sum() / n / batch.n_steps),
           "mse": mse_sum / n, "ce": ce_sum / n,
           # the trained objective less its activity cost: for the place-cell output its
           # cross-entropy, for the others the squared error
           "loss": position_sum / n + class_weight * ce_sum / n}
    if classify:
        out["accuracy"] = acc_sum / n
        out["mean_accuracy"] = float(acc_sum.sum() / n / batch.n_steps)
    return out


def summarize(metrics: dict, dt: float, times=(50.0, 100.0, 200.0)) -> dict:
    """Metrics at given times in the trial (s), JSON-ready."""
    out = {k: v for k, v in metrics.items() if not isinstance(v, np.ndarray)}
    for t in times:
        k = int(round(t / dt)) - 1
        if not 0 <= k < len(metrics["error_m"]):
            continue
        out[f"error_{int(t)}s_m"] = float(metrics["error_m"][k])
        if "accuracy" in metrics:
            out[f"accuracy_{int(t)}s"] = float(metrics["accuracy"][k])
    return out


#: the stopping rule is not applied before this many steps (early curves are noisy and the
#: "last fifth" of a few hundred steps is a handful of validations) ...
MIN_STEPS_BEFORE_STOPPING = 2000
#: ... nor before this share of the step budget: the study's tasks have long early
#: plateaus. The darkness world's seed-0 specialized network sat at chance accuracy, its
#: validation loss 0.0168 -> 0.0152 over steps 250-8,000, before falling to 0.0033 by
#: 40,000; from 2,000 steps on, the rule would have ended it (and seed-0 generalized) at
#: 2,000, and it did end localization_s1 at 2,500 and specialized_s1 at 2,000. From a
#: quarter of 40,000 steps, seed 0 ends where it ended (localization at 11,750; the other
#: two ran their budget).
MIN_SHARE_BEFORE_STOPPING = 0.25


def first_step_of_stopping_rule(config: TrainConfig) -> int:
    """The step from which the 1% rule is checked: 2,000 or a quarter of the budget."""
    return max(MIN_STEPS_BEFORE_STOPPING, math.ceil(MIN_SHARE_BEFORE_STOPPING * config.steps))


def stop_reason(config: TrainConfig, validation: list, step: int,
                wall_time_s: float) -> str | None:
    """Why training should end before its budget, or None to go on.

    Two rules (the training issue's): the run has used ``config.max_hours`` of wall time,
    or its validation loss improved by less than ``config.stop_improvement`` over the last
    fifth of its steps::

        1 - min(loss_v : v) / min(loss_v : step_v <= 0.8 step) < stop_improvement

    Parameters
    ----------
    validation : list of dict
        The log's validations (``step`` and ``loss`` of each).
    step : int
        Steps done.
    wall_time_s : float
        Wall time of the run so far, summed over resumes.
    """
    if config.max_hours is not None and wall_time_s >= 3600 * config.max_hours:
        return f"max_hours: {wall_time_s / 3600:.2f} h of wall time >= {config.max_hours} h"
    if config.stop_improvement is None or step < first_step_of_stopping_rule(config):
        return None
    before = [v["loss"] for v in validation if v["step"] <= 0.8 * step]
    if not before or len(before) == len(validation):
        return None
    improvement = 1 - min(v["loss"] for v in validation) / min(before)
    if improvement < config.stop_improvement:
        return (f"stop_improvement: validation loss improved by {100 * improvement:.2f}% "
                f"over steps {int(0.8 * step)}-{step} (< {100 * config.stop_improvement:g}%)")
    return None


def _lr_at(config: TrainConfig, step: int) -> float:
    frac = min(step / max(config.steps, 1), 1.0)
    return config.lr_final + 0.5 * (config.lr - config.lr_final) * (1 + math.cos(math.pi * frac))


def _distributed(device: str = "cpu"):
    """(rank, world_size), initialising the process group under torchrun."""
    world_size = int(os.environ.get("WORLD_SIZE", "1"))
    if world_size <= 1:
        return 0, 1
    import torch.distributed as dist
    if not dist.is_initialized():
        dist.init_process_group("nccl" if device == "cuda" else "gloo")
    return dist.get_rank(), world_size


def fit(config: TrainConfig, run_dir, *, progress: bool = True, cache_dir=None,
        stop_after: int | None = None, overwrite: bool = False,
        stop_requested=None) -> dict:
    """Train (or resume training) a network; returns the training log.

    The process's torch and numba threads are pinned to ``config.threads`` for the run, and
    malloc keeps freed activations for the next step (:func:`.memory.reuse_freed_memory`).

    Files in ``run_dir``: ``checkpoint.pt`` (everything needed to resume; written
    atomically every ``checkpoint_minutes`` and at the end), ``network.pt`` (the best
    parameters by validation loss, loadable by :func:`hippo_probe.load_pretrained`) and
    ``log.json`` (curves, config, seeds, versions, wall time, command line, test metrics).

    Parameters
    ----------
    config : TrainConfig
    run_dir : path
        Created if needed; if it holds a checkpoint of the same config, training resumes.
    progress : bool
        Show a tqdm progress bar (loss and validation error).
    stop_after : int, optional
        Stop (with a checkpoint) after this many optimizer steps of *this* call — to
        simulate an interruption in tests.
    overwrite : bool
        Start afresh in a folder that holds a finished run's ``network.pt`` or
        ``log.json`` but no checkpoint to resume from (default: refuse, so a pruned
        run's network is not replaced by a new run by mistake).
    stop_requested : callable, optional
        Asked before every optimizer step; once it returns True the run checkpoints that
        step and raises KeyboardInterrupt, as Ctrl-C does, but at a step boundary, where
        the parameters, the optimizer, the step and the log agree (``hippo-probe train``
        answers it from SIGINT and SIGTERM).
    """
    overwrite = check_bool("overwrite", overwrite)
    run_dir = Path(run_dir)
    # the lock first, before anything slow (process group, threads, trial cache): a second
    # trainer started on the same folder while the first is starting is refused at once
    lead = int(os.environ.get("RANK", "0")) == 0
    with _sole_trainer(run_dir) if lead else contextlib.nullcontext():
        if lead and not overwrite and not (run_dir / "checkpoint.pt").exists():
            found = [n for n in ("network.pt", "log.json") if (run_dir / n).exists()]
            if found:
                raise FileExistsError(
                    f"`run_dir` {str(run_dir)!r} holds {found} of a run but no "
                    f"checkpoint.pt to resume from; starting afresh would replace "
                    f"them: pass overwrite=True (--overwrite) or use a new folder")
        return _fit_pinned(config, run_dir, progress, cache_dir, stop_after, stop_requested)


def _fit_pinned(config, run_dir, progress, cache_dir, stop_after, stop_requested):
    """``_fit`` with the precision resolved and the process's threads pinned."""
    precision = resolve_precision(config.precision)
    if precision == "bf16" and config.device == "cpu" and not native_bf16():
        warnings.warn("`precision` 'bf16' on a CPU without AVX512-BF16 or AMX: oneDNN "
                      "emulates it, ~20x slower than fp32 here; use precision='auto'",
                      RuntimeWarning, stacklevel=3)
    config = dataclasses.replace(config, precision=precision)
    rank, world_size = _distributed(config.device)
    threads_before = torch.get_num_threads()
    torch.set_num_threads(config.threads)
    try:
        import numba
        numba.set_num_threads(min(config.threads, numba.config.NUMBA_NUM_THREADS))
    except Exception:  # numba threading layer not initialisable: serial is fine
        pass
    reuse_freed_memory()    # each step's activations, reused instead of page-faulted anew
    try:
        return _fit(config, run_dir, rank, world_size, progress, cache_dir, stop_after,
                    stop_requested)
    finally:
        torch.set_num_threads(threads_before)   # don't leave a Jupyter kernel pinned


def _sole_trainer(run_dir: Path):
    """Hold an exclusive lock on ``run_dir`` (its file ``.lock``) while training in it: a
    second process started on the same run (the same command twice) would checkpoint over
    the first one's progress, so it is refused."""
    def refuse(holder):
        raise RunInUseError(f"the run folder {str(run_dir)!r} is being trained by another "
                            f"process (pid {holder}); wait for it, or stop it and resume "
                            f"with the same command") from None

    return exclusive_lock(run_dir / ".lock", refuse)


def _fit(config, run_dir, rank, world_size, progress, cache_dir, stop_after, stop_requested):
    run_dir.mkdir(parents=True, exist_ok=True)
    task = task_config(config.task, config.world)
    n_trials = config.n_trials or task.train_trials
    if config.batch_size % world_size:
        raise ValueError(f"`batch_size` must be divisible by the world size ({world_size}); "
                         f"got {config.batch_size}")
    device = torch.device(config.device)
    net = build_network(config).to(device)
    params = [p for p in net.parameters() if p.requires_grad]
    opt = torch.optim.Adam(params, lr=config.lr)
    validation = make_trials(config.task, config.n_validation, "validation", config.seed,
                             world=config.world) if rank == 0 else None
    classifier_only = config.train_only == "classifier"
    class_weight = _class_weight(config, net, validation)

    ckpt_path = run_dir / "checkpoint.pt"
    log = {"config": config.to_dict(), "n_trials": n_trials, "class_weight": class_weight,
           "model_config": _plain(net.config),
           "base_network": net.base_network,
           "package_version": __version__, "torch_version": str(torch.__version__),
           "command": _command_line(), "world_size": world_size, "train": [],
           "validation": [], "wall_time_s": 0.0}
    step, best_loss, best_state = 0, math.inf, None
    if ckpt_path.exists():
        step, best_loss, best_state, log = _resume(ckpt_path, config, net, opt)
    # the precision of each stretch of trained steps; a stretch starts at its first
    # trained step, so a finished run re-tested on other hardware gains none
    segments = log.setdefault("precision_from_step",
                              [[0, log["config"].get("precision", "fp32")]])

    train_net = net
    if world_size > 1:
        train_net = torch.nn.parallel.DistributedDataParallel(net)
    data = TrainingTrials(config.task, n_trials, config.batch_size, world=config.world,
                          seed=config.seed,
                          init_seed=config.init_seed, cache_dir=cache_dir)

    model_config = _plain(net.config)      # plain values: loadable with weights_only

    def trained_config():
        """``config`` with the precision of the last stretch trained, not of the machine
        that saves: a finished run re-tested elsewhere keeps its own."""
        return dataclasses.replace(config, precision=segments[-1][1])

    def checkpoint(model_state=None):
        if rank == 0:
            save_atomic({"model": model_state or net.state_dict(),
                         "optimizer": opt.state_dict(), "step": step,
                         "best_loss": best_loss, "best_model": best_state,
                         "config": trained_config().to_dict(),
                         "model_config": model_config, "task": config.task, "log": log},
                        ckpt_path)

    def validate():
        nonlocal best_loss, best_state
        m = evaluate_network(net, validation, class_weight)
        entry = {"step": step, "loss": m["loss"], "mean_error_m": m["mean_error_m"],
                 "mse": m["mse"], "ce": m["ce"]}
        if "mean_accuracy" in m:
            entry["mean_accuracy"] = m["mean_accuracy"]
        log["validation"].append(entry)
        if m["loss"] < best_loss:
            best_loss = m["loss"]
            best_state = {k: v.detach().cpu().clone() for k, v in net.state_dict().items()}
        return entry

    t_start, t_ckpt = time.time(), time.time()
    wall0 = log["wall_time_s"]
    bar = tqdm(total=config.steps, initial=step, disable=not progress or rank != 0,
               desc=f"train {config.task}", unit="step", dynamic_ncols=True)
    last_val = log["validation"][-1] if log["validation"] else None
    done_here = 0
    try:
        while step < config.steps:
            if stop_requested is not None and _agreed(stop_requested(), world_size, device):
                raise KeyboardInterrupt     # a step boundary: the checkpoint below is whole
            if step % config.validate_every == 0:
                if rank == 0 and (not log["validation"] or
                                  log["validation"][-1]["step"] != step):
                    last_val = validate()
                # checked even when the step was validated before a resume: a stopped run
                # resumed with the same rules stops again here, without training on
                reason = stop_reason(config, log["validation"], step,
                                     wall0 + time.time() - t_start)
                if world_size > 1:         # every rank stops at the same step
                    flag = torch.tensor([reason is not None], dtype=torch.int32,
                                        device=device)
                    torch.distributed.broadcast(flag, 0)
                    if rank != 0:
                        reason = "the stopping rule on rank 0" if flag.item() else None
                if reason is not None:
                    log["stopped"] = {"step": step, "reason": reason}
                    break
            if segments[-1][1] != config.precision:
                segments.append([step, config.precision])   # resumed on other hardware
            idx = data.indices(step)
            per_rank = config.batch_size // world_size
            idx = idx[rank * per_rank:(rank + 1) * per_rank]
            inputs, target, env = data.batch(idx)
            for group in opt.param_groups:
                group["lr"] = _lr_at(config, step)
            total, mse, ce, *_ = losses(train_net, inputs, target, env, class_weight,
                                        classifier_only=classifier_only,
                                        activity_l1=config.activity_l1)
            opt.zero_grad(set_to_none=True)
            total.backward()
            grad_norm = torch.nn.utils.clip_grad_norm_(params, config.clip_norm)
            opt.step()
            step += 1
            done_here += 1
            values = torch.stack([total.detach(), mse.detach(), ce.detach()])
            if world_size > 1:             # log the global batch's loss, not rank 0's half
                torch.distributed.all_reduce(values)
                values /= world_size
            log["wall_time_s"] = wall0 + time.time() - t_start
            loss_v, mse_v, ce_v = values.tolist()
            log["train"].append({"step": step, "loss": loss_v, "mse": mse_v, "ce": ce_v,
                                 "grad_norm": grad_norm.item(),
                                 "lr": opt.param_groups[0]["lr"],
                                 "time_s": round(log["wall_time_s"], 2)})
            post = {"loss": f"{loss_v:.4g}"}
            if last_val:
                post["val_err_m"] = f"{last_val['mean_error_m']:.3f}"
                if "mean_accuracy" in last_val:
                    post["val_acc"] = f"{last_val['mean_accuracy']:.2f}"
            bar.set_postfix(post, refresh=False)
            bar.update(1)
            if rank == 0 and config.snapshot_every and step % config.snapshot_every == 0:
                save_network(net, trained_config(), log,
                             run_dir / "snapshots" / f"step_{step:06d}.pt")
            if time.time() - t_ckpt > 60 * config.checkpoint_minutes:
                checkpoint()
                t_ckpt = time.time()
            if stop_after is not None and done_here >= stop_after and step < config.steps:
                checkpoint()
                return log
    except KeyboardInterrupt:
        checkpoint()                  # Ctrl-C in Jupyter loses no work
        raise
    finally:
        bar.close()
    if rank == 0:
        if not log["validation"] or log["validation"][-1]["step"] != step:
            validate()
        last_state = {k: v.detach().cpu().clone() for k, v in net.state_dict().items()}
        net.load_state_dict(best_state)
        _test(net, config, class_weight, log)
        log["best_validation_loss"] = best_loss
        checkpoint(last_state)        # the checkpoint keeps the last parameters
        save_network(net, trained_config(), log, run_dir / "network.pt")
        write_text(run_dir / "log.json", json.dumps(log, indent=1), what="out")
    if world_size > 1:
        torch.distributed.barrier()
    return log


def _agreed(flag: bool, world_size: int, device) -> bool:
    """``flag`` of any rank, on every rank (all stop at the same step or none does)."""
    if world_size == 1:
        return bool(flag)
    value = torch.tensor([int(flag)], dtype=torch.int32, device=device)
    torch.distributed.all_reduce(value, op=torch.distributed.ReduceOp.MAX)
    return bool(value.item())


def _class_weight(config, net, validation) -> float:
    """The arena cross-entropy's weight in the loss: 1 when only the classifier trains,
    the configured one, or :func:`class_weight_rule`'s (0 without a classifier)."""
    if config.train_only == "classifier":
        return 1.0                    # the loss is the cross-entropy alone
    if config.class_weight is not None:
        return config.class_weight
    if net.classifier is None:
        return 0.0
    target = validation.target if validation is not None else make_trials(
        config.task, config.n_validation, "validation", config.seed,
        world=config.world).target
    return class_weight_rule(_position_cost_at_chance(net, target), net.config.n_classes)


def _resume(ckpt_path, config, net, opt):
    """Load a run's checkpoint into ``net`` and ``opt``; return (step, best loss, best
    parameters, log). Refused if it is of another configuration."""
    ckpt = require(load(ckpt_path), ("config", "model", "optimizer", "step", "best_loss",
                                     "best_model", "log"), ckpt_path, "resume training")
    diff = TrainConfig.from_dict(ckpt["config"]).differences(config)
    if diff:
        def shown(value):                  # None is an option left at its default
            return "not set" if value is None else repr(value)

        listed = "; ".join(f"{k}: checkpoint {shown(a)}, got {shown(b)}" for k, a, b in
                           ((k, *v) for k, v in diff.items()))
        raise ValueError(f"`run_dir` {str(ckpt_path.parent)!r} holds a checkpoint of another "
                         f"configuration ({listed}); use a new directory")
    load_into(net, ckpt["model"], ckpt_path)
    load_into(opt, ckpt["optimizer"], ckpt_path)
    log = ckpt["log"]
    log.setdefault("resumed_at", []).append(ckpt["step"])
    # the log describes the run as it is trained now: a resume may change a setting that
    # leaves the result's meaning intact (a stopping rule, threads, ...), and the log must
    # not keep the first start's value of it; each resume's command line and changes are
    # kept beside it
    log.setdefault("precision_from_step", [[0, log["config"].get("precision", "fp32")]])
    before = TrainConfig.from_dict(log["config"]).to_dict()
    now = config.to_dict()
    log.setdefault("resumes", []).append({
        "step": ckpt["step"], "command": _command_line(),
        "changed": {k: [before[k], now[k]] for k in config.RESUMABLE_CHANGES
                    if before[k] != now[k]}})
    log["config"] = now
    # a run resumed after it ended (by a stopping rule) is tested and stopped anew; the
    # old verdict and test results must not outlive the training they describe
    for key in ("stopped", "test", "test_curves", "best_validation_loss"):
        log.pop(key, None)
    return ckpt["step"], ckpt["best_loss"], ckpt["best_model"], log


def _test(net, config, class_weight, log) -> None:
    """The test split's errors (and accuracy) of ``net`` into ``log``."""
    test = make_trials(config.task, config.n_test, "test", config.seed, world=config.world)
    metrics = evaluate_network(net, test, class_weight)
    log["test"] = summarize(metrics, test.dt)
    log["test_curves"] = {k: v.tolist() for k, v in metrics.items()
                          if isinstance(v, np.ndarray)}


def save_network(net, config: TrainConfig, log: dict, path) -> None:
    """Save a trained network (parameters, architecture, task, world) for
    ``load_pretrained``."""
    save_atomic({"model": {k: v.detach().cpu() for k, v in net.state_dict().items()},
                 "model_config": _plain(net.config), "task": config.task,
                 "world": config.world,
                 "config": config.to_dict(), "class_weight": log.get("class_weight"),
                 "test": log.get("test"), "base_network": log.get("base_network")}, path)
