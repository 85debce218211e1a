"""Shipped pretrained networks and ``load_pretrained``.

Files here: ``<name>.pt`` (parameters, architecture, task, world, test metrics) and
``<name>.log.json`` (the full training log: curves, config, seeds, versions, wall time,
command line). Names: the darkness world's networks (the study's world) under the task's
name, ``localization``, ``generalized``, ``specialized`` and ``generalized_readout`` (the
generalized network with a retrained arena readout); the compass world's as
``localization_compass``, ``generalized_compass``, ``specialized_compass`` and
``generalized_compass_readout``, kept for the ablation (what the compass takes away).
A network knows its world (``net.world``): record it, evaluate it and compare it with
baselines on trials of that world. Each name may ship several training seeds:
``<name>.pt`` is the seed reported first (``seed=0``), ``<name>_seed<k>.pt`` seed ``k``.
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).parent
NAMES = ("localization", "generalized", "specialized", "generalized_readout",
         "localization_compass", "generalized_compass", "specialized_compass",
         "generalized_compass_readout")

#: The world of a checkpoint that does not name one: every such file was made before the
#: darkness world existed.
LEGACY_WORLD = "compass"


def checkpoint_world(obj: dict) -> str:
    """The world a loaded network or checkpoint was trained in (:data:`LEGACY_WORLD` for
    files that do not say)."""
    return obj.get("world") or (obj.get("config") or {}).get("world") or LEGACY_WORLD


def available() -> list:
    """Names of the shipped networks present in this installation."""
    return sorted(p.stem for p in HERE.glob("*.pt"))


def shipped_seeds(name: str, *, folder=None) -> list[int]:
    """Training seeds shipped for the network ``name`` (e.g. ``[0, 1, 2]``), in ``folder``
    (default: the package's)."""
    folder = HERE if folder is None else Path(folder)
    seeds = [0] if (folder / f"{name}.pt").exists() else []
    seeds += sorted(int(p.stem.rpartition("_seed")[2]) for p in folder.glob(f"{name}_seed*.pt")
                    if p.stem.rpartition("_seed")[2].isdigit())
    return seeds


def resolve_network_file(name_or_path, seed=None) -> Path:
    """A shipped network's file by name (and training ``seed``, default 0), or a path to a
    network/checkpoint file."""
    import os

    from .._validators import check_nonnegative_int

    if not isinstance(name_or_path, (str, os.PathLike)) or not str(name_or_path):
        raise TypeError(f"`name` must be a shipped network's name (one of {list(NAMES)}) or "
                        f"a path to a .pt file; got {name_or_path!r}")
    seed = None if seed is None else check_nonnegative_int("seed", seed)
    if str(name_or_path) in NAMES:
        candidate = HERE / (f"{name_or_path}.pt" if not seed
                            else f"{name_or_path}_seed{seed}.pt")
        if candidate.exists():
            return candidate    # a shipped name wins over a same-named local folder
        if seed and shipped_seeds(str(name_or_path)):
            raise ValueError(f"`seed` {seed} of the network {name_or_path!r} is not shipped; "
                             f"shipped seeds: {shipped_seeds(str(name_or_path))}")
        if not Path(name_or_path).exists():
            raise ValueError(f"the network {name_or_path!r} is not shipped in this version "
                             f"(its training has not finished); shipped: {available()}")
    elif seed is not None:
        raise ValueError(f"`seed` selects among the shipped networks' training seeds; "
                         f"{name_or_path!r} is a file, so seed must be None; got {seed}")
    candidate = HERE / f"{name_or_path}.pt"
    path = Path(name_or_path)
    if path.is_dir() and (path / "network.pt").exists():
        return path / "network.pt"      # a training run's directory
    if path.suffix == ".pt" or path.exists():
        return path
    if not candidate.exists():
        raise ValueError(f"`name` must be one of the shipped networks {available()} or a "
                         f"path to a .pt file; got {name_or_path!r}")
    return candidate


def _check_declared_shapes(config, state, path) -> None:
    """The architecture a file declares must be the one its parameters have, checked
    before the network is built: a crafted ``hidden_size`` cannot make us allocate more
    than the file holds."""
    from ..errors import CheckpointError

    h, f = config.hidden_size, config.input_size
    expected = {"lstm.weight_h": (4 * h, h), "lstm.weight_x": (4 * h, f)}
    if getattr(config, "variant", "faithful") == "placecells":
        expected["position.linear.weight"] = (config.n_place_cells, h)
    else:
        expected["position.weight"] = (2, h)
    if config.n_classes:
        expected["classifier.weight"] = (config.n_classes, h)
    for key, shape in expected.items():
        got = tuple(state[key].shape) if key in state and hasattr(state[key], "shape") \
            else None
        if got != shape:
            raise CheckpointError(f"`checkpoint` {str(path)!r} declares hidden_size={h}, "
                                  f"n_classes={config.n_classes} but its `{key}` has shape "
                                  f"{got} (expected {shape}): refused before building it")


def load_pretrained(name: str, seed: int | None = None):
    """Load a shipped network (or a network/checkpoint file) as a Navigator in eval mode.

    The network runs float32 whatever precision trained it (``net.info["config"]`` names
    that of its last trained stretch; the training log's ``precision_from_step``, every
    stretch), so its outputs, and gradients taken through it, are the same everywhere.

    Parameters
    ----------
    name : str or os.PathLike
        A shipped network's name (:data:`NAMES`) or the path of a ``.pt`` file (a
        shipped-network file, a training checkpoint or a run directory).
    seed : int, optional
        The training seed of a shipped network (default: the one reported first, 0);
        :func:`shipped_seeds` lists them.

    Examples
    --------
    >>> import hippo_probe as hp
    >>> net = hp.load_pretrained("generalized")            # doctest: +SKIP
    >>> net.task                                            # doctest: +SKIP
    'generalized'
    """
    import dataclasses

    try:
        import torch  # noqa: F401
    except ModuleNotFoundError:
        from .._optional import missing
        raise missing("torch", "load_pretrained") from None

    from ..model.config import ModelConfig
    from ..model.navigator import Navigator
    from ..training.checkpoint import load, load_into

    from ..errors import CheckpointError

    path = resolve_network_file(name, seed)
    obj = load(path)
    config = obj["model_config"]
    try:
        if isinstance(config, dict):
            config = ModelConfig(**{**config, "input_scale": tuple(config["input_scale"])})
        state = obj.get("best_model") or obj["model"]
        _check_declared_shapes(config, state, path)
        net = Navigator(dataclasses.replace(config, precision="fp32"))
    except CheckpointError:
        raise
    except (TypeError, KeyError, ValueError) as err:
        raise CheckpointError(f"`checkpoint` {str(path)!r} holds an architecture this "
                              f"version cannot build ({type(err).__name__}: {err})") from None
    load_into(net, state, path)
    net.task = obj.get("task")
    net.world = checkpoint_world(obj)
    net.info = {k: obj.get(k) for k in ("task", "config", "class_weight", "test",
                                        "steps_done", "finished", "base_network")}
    net.info["world"] = net.world
    net.info["file"] = str(path)
    return net.eval()
