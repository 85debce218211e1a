"""Shipped pretrained networks and ``load_pretrained``.

Files here: ``<name>.pt`` (parameters, architecture, task, world, test metrics) and
``<name>.log.json`` (the full training log: curves, config, seeds, versions, wall time,
command line). Names: the darkness world's networks (the study's world) under the task's
name, ``localization``, ``generalized``, ``specialized`` and ``generalized_readout`` (the
generalized network with a retrained arena readout); the compass world's as
``localization_compass``, ``generalized_compass``, ``specialized_compass`` and
``generalized_compass_readout``, kept for the ablation (what the compass takes away).
Variants that depart from the study's network, each trained 20,000 steps on the
generalized task of the darkness world (``docs/guides/results.md``, "The map-ingredient
scorecard: the study's network and its variants"): ``generalized_nonneg`` (non-negative
units, h = o * relu(tanh c), with an L1 activity cost of weight 1),
``generalized_dale`` (the same, with each unit's outgoing recurrent weights of one fixed
sign: 80% of the units excitatory, 20% inhibitory) and ``generalized_placecells`` (the
study's units with a population output: a softmax over 256 Gaussian place cells,
cross-entropy loss, the position decoded as their centre); their reference at the same
budget, ``generalized_faithful``, is the study's network trained the same 20,000 steps.
A network knows its world (``net.world``): record it, evaluate it and compare it with
baselines on trials of that world. Each name may ship several training seeds:
``<name>.pt`` is the seed reported first (``seed=0``), ``<name>_seed<k>.pt`` seed ``k``.
"""

from __future__ import annotations

from pathlib import Path

HERE = Path(__file__).parent
NAMES = ("localization", "generalized", "specialized", "generalized_readout",
         "localization_compass", "generalized_compass", "specialized_compass",
         "generalized_compass_readout", "generalized_faithful", "generalized_nonneg",
         "generalized_dale", "generalized_placecells")

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
            where = ("the compass-world ablation networks come with a clone of the "
                     "repository, not with the installed wheel"
                     if "_compass" in str(name_or_path) else "its training has not finished")
            raise ValueError(f"the network {name_or_path!r} is not in this installation "
                             f"({where}); shipped: {available()}")
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
