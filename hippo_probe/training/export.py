"""Ship a training run's best network as a pretrained network."""

from __future__ import annotations

import json
import re
from pathlib import Path

from .._atomic import write_text
from ..model.checkpoint import load, require, save_atomic


#: Names a shipped network may have: a plain file name, never a path or a hidden file.
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")

#: At most this many per-step entries go into a shipped training log (a 40,000-step run
#: would otherwise ship 7 MB of JSON); the run's checkpoint keeps every step.
MAX_TRAIN_ENTRIES = 500


def _thin(train: list) -> tuple[list, int]:
    """Every k-th step of the training log (the first and last always kept), and k."""
    # with the last step appended, ceil((n - 1) / (MAX - 1)) keeps the count within MAX
    every = max(1, -(-(len(train) - 1) // (MAX_TRAIN_ENTRIES - 1)))
    kept = train[::every]
    if train and kept[-1] is not train[-1]:
        kept.append(train[-1])
    return kept, every


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if hasattr(obj, "__dataclass_fields__"):
        return _jsonable(vars(obj))
    return obj


def _readout_if_shipped_base(network: dict, init_from, dest, name: str) -> dict:
    """A retrained readout's file holds its classifier alone when the network it reads is
    a shipped one or sits in ``dest`` (:func:`~hippo_probe.model.load.as_readout`), so
    its 256-unit LSTM is not shipped twice; otherwise (a base elsewhere, a base that is
    itself a readout or has changed since, or the file about to be written) the whole
    network."""
    from ..model.load import as_readout
    from ..pretrained import HERE, resolve_network_file

    if not init_from:
        return network
    try:
        base_path = resolve_network_file(init_from)
    except (TypeError, ValueError):
        return network
    if base_path.parent.resolve() not in (HERE.resolve(), Path(dest).resolve()) \
            or base_path.resolve() == (Path(dest) / f"{name}.pt").resolve():
        return network
    try:
        return as_readout(network, load(base_path), base_path)
    except ValueError:
        return network


def export_network(run_dir, name: str, dest, *, overwrite: bool = False) -> list:
    """Write ``<dest>/<name>.pt`` (best parameters so far, architecture, task, test
    metrics if the run finished) and ``<dest>/<name>.log.json`` (the training log; its
    per-step entries thinned to every ``train_every``-th step, at most
    :data:`MAX_TRAIN_ENTRIES`, with the first and last kept).

    Works on a finished run (``network.pt``) or on a run in progress (its last
    checkpoint's best parameters); the log says which (``finished``, ``steps_done``).
    A network already under ``name`` in ``dest`` is replaced only with
    ``overwrite=True``: in the repository's ``hippo_probe/pretrained`` it is a shipped
    network that the figures and RESULTS.md were made from.
    """
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise ValueError(f"`name` must be letters, digits, '_' or '-' (a file name inside "
                         f"the destination, e.g. 'generalized_s1'); got {name!r}")
    run_dir = Path(run_dir)
    # the destination is always the caller's: the package never writes into its own folder
    dest = Path(dest)                # made (with its parents) by the first write into it
    existing = [str(p) for p in (dest / f"{name}.pt", dest / f"{name}.log.json") if p.exists()]
    if existing and not overwrite:
        raise FileExistsError(f"`name` {name!r}: {', '.join(existing)} exist(s); pass "
                              f"overwrite=True (--overwrite) to replace, or choose another "
                              f"name (a readout shipped against a replaced network no "
                              f"longer loads)")
    ckpt = require(load(run_dir / "checkpoint.pt"),
                   ("log", "step", "config", "model", "best_model", "best_loss",
                    "model_config", "task"), run_dir / "checkpoint.pt", "export a network")
    log = dict(ckpt["log"])
    # the budget is spent, or a stopping rule ended the run (log["stopped"]); either way
    # the run was tested
    finished = "test" in log and (ckpt["step"] >= ckpt["config"]["steps"] or "stopped" in log)
    state = ckpt["best_model"] or ckpt["model"]
    state = {k: v.detach().clone().contiguous() for k, v in state.items()}
    # plain dicts and tensors only: a shipped file must not depend on class names
    network = {"model": state, "model_config": _jsonable(ckpt["model_config"]),
               "task": ckpt["task"], "world": ckpt["config"].get("world", "compass"),
               "config": ckpt["config"], "class_weight": log.get("class_weight"),
               "test": log.get("test"), "steps_done": ckpt["step"], "finished": finished,
               "base_network": log.get("base_network")}
    if ckpt["config"].get("train_only") == "classifier":
        network = _readout_if_shipped_base(network, ckpt["config"].get("init_from"), dest,
                                           name)
    pt = dest / f"{name}.pt"
    save_atomic(network, pt)
    log.update(steps_done=ckpt["step"], finished=finished,
               best_validation_loss=ckpt["best_loss"])
    log["train"], log["train_every"] = _thin(log.get("train", []))
    if isinstance(log.get("command"), str):       # logs written before _command_line
        program, *rest = log["command"].split(" ")
        log["command"] = " ".join([Path(program).name, *rest])
    js = dest / f"{name}.log.json"
    write_text(js, json.dumps(_jsonable(log), indent=0), what="dest")
    return [pt, js]
