"""Loading a network file (a shipped network, a training checkpoint or a run) as a
:class:`~hippo_probe.model.navigator.Navigator`: the file is checked before anything is
built from it."""

from __future__ import annotations

import re
from pathlib import Path

from ..pretrained import checkpoint_world, resolve_network_file

#: The key of a readout file: an arena classifier alone, fitted on the frozen network it
#: names (``{"name", "seed", "parameters_sha256"}``). The network's parameters are not
#: copied into it; they are read from that network's file when the readout is loaded.
READOUT_OF = "readout_of"
_PLAIN_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_-]*")


def parameters_digest(obj: dict) -> str:
    """sha256 of a network file's parameters (its best ones if it has both), whatever
    else the file holds: what a readout was fitted on."""
    from .checkpoint import content_digest

    return content_digest({"model": obj.get("best_model") or obj["model"]})


def as_readout(network: dict, base: dict, base_file) -> dict:
    """A network file's content as a readout file: its classifier alone, naming its
    network ``base_file`` (``<name>[_seed<k>].pt``, whose loaded content is ``base``) by
    name, seed and parameters' digest (:data:`READOUT_OF`).

    Raises
    ------
    ValueError
        ``network``'s other parameters are not ``base``'s: it is not a readout of it.
    """
    import torch

    state = network.get("best_model") or network["model"]
    # the network read may have a classifier of its own (a specialized network): the
    # readout's replaces it
    base_state = {k: v for k, v in (base.get("best_model") or base["model"]).items()
                  if not k.startswith("classifier.")}
    head = {k: v for k, v in state.items() if k.startswith("classifier.")}
    rest = {k: v for k, v in state.items() if not k.startswith("classifier.")}
    if set(head) != {"classifier.weight", "classifier.bias"} or set(rest) != set(base_state) \
            or not all(torch.equal(v, base_state[k]) for k, v in rest.items()):
        raise ValueError(f"`network` is not a readout of {Path(base_file).name}: its "
                         f"parameters other than the classifier differ from that network's")
    name, seed = _name_and_seed(Path(base_file).stem)
    if not _PLAIN_NAME.fullmatch(name):
        raise ValueError(f"a readout names its network by a plain file name; "
                         f"{Path(base_file).name!r} is not one")
    out = {key: value for key, value in network.items() if key != "best_model"}
    out["model"] = head
    out[READOUT_OF] = {"name": name, "seed": seed,
                       "parameters_sha256": parameters_digest(base)}
    return out


def _name_and_seed(stem: str) -> tuple[str, int]:
    """``"generalized_seed2"`` -> ("generalized", 2); a seed-0 network has no suffix, so
    ``"x_seed0"`` is the name ``"x_seed0"`` itself."""
    head, _, k = stem.rpartition("_seed")
    return (head, int(k)) if head and k.isdigit() and int(k) > 0 else (stem, 0)


def base_files(readout_path, name: str, seed: int) -> list[Path]:
    """Where the network a readout reads may be: ``<name>[_seed<k>].pt`` beside the
    readout file, then the shipped network of that name and seed. Only these two places:
    a name never reaches another folder."""
    from ..pretrained import HERE, NAMES

    file = f"{name}.pt" if not seed else f"{name}_seed{seed}.pt"
    places = [Path(readout_path).parent / file]
    if name in NAMES:
        places.append(HERE / file)
    return [p for p in dict.fromkeys(places) if p.is_file()]


def network_parameters(obj: dict, path, base: dict | None = None) -> dict:
    """The parameters a loaded network file ``obj`` (read from ``path``) stands for: its
    best ones if it has both, and for a readout file (:data:`READOUT_OF`) its network's
    (``base``, if already loaded by :func:`readout_base`) with the readout's classifier."""
    if READOUT_OF in obj:
        return _readout_parameters(obj, path, base or readout_base(obj, path))
    return obj.get("best_model") or obj["model"]


def _readout_parameters(obj: dict, path, base: dict) -> dict:
    """A readout file's parameters: its base network's, with the readout's classifier."""
    from ..errors import CheckpointError

    head = obj["model"]
    if set(head) != {"classifier.weight", "classifier.bias"}:
        raise CheckpointError(f"`checkpoint` {str(path)!r} is a readout and must hold only "
                              f"the classifier; got {sorted(head)}")
    return {**(base.get("best_model") or base["model"]), **head}


def position_task(obj: dict, path, base: dict | None = None) -> str | None:
    """The task whose frame a loaded network file's (x, y) readout speaks: the task it
    was trained on, or, where its training fitted the arena readout alone
    (``train_only = "classifier"``: a readout of a frozen network), its base network's
    (the generalized network's start-relative frame, though the readout was fitted on the
    specialized task; ``base``: a readout file's network, if already loaded). None where
    that base cannot be found."""
    cfg = obj.get("config") or {}
    if not (isinstance(cfg, dict) and cfg.get("train_only") == "classifier"):
        return obj.get("task")
    if READOUT_OF in obj:
        return position_task(base or readout_base(obj, path), path)
    # a readout trained by gradient steps holds all its parameters: its base by name
    from ..pretrained import NAMES, resolve_network_file
    from .checkpoint import load

    base = cfg.get("init_from")
    if isinstance(base, str) and base in NAMES:
        base_path = resolve_network_file(base)
        return position_task(load(base_path), base_path)
    return None


def readout_base(obj: dict, path) -> dict:
    """The loaded network file a readout file reads (by name, seed and parameters'
    digest: beside it, then among the shipped networks)."""
    from ..errors import CheckpointError
    from .checkpoint import load

    ref = obj[READOUT_OF]
    name, seed = (ref.get("name"), ref.get("seed")) if isinstance(ref, dict) else (None, None)
    if not (isinstance(name, str) and _PLAIN_NAME.fullmatch(name)
            and isinstance(seed, int) and not isinstance(seed, bool) and seed >= 0):
        raise CheckpointError(f"`checkpoint` {str(path)!r} is a readout whose network is "
                              f"not named by a plain name and seed: {ref!r}")
    digest = ref.get("parameters_sha256")
    candidates = base_files(path, name, seed)
    for candidate in candidates:          # the first with the parameters it was fitted on
        base = load(candidate)
        if parameters_digest(base) == digest:
            break
    else:
        raise CheckpointError(
            f"`checkpoint` {str(path)!r} reads the network {name!r} (seed {seed}), "
            + ("which was found neither beside it nor among the shipped networks"
               if not candidates else
               f"but {', '.join(str(c) for c in candidates)} holds other parameters than "
               f"those it was fitted on; refit it on that version of the network"))
    return base


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
        A shipped network's name (``hippo_probe.pretrained.NAMES``: "localization",
        "generalized", "specialized", "generalized_readout", their ``*_compass``
        counterparts and the map-ingredient variants) or the path of a ``.pt`` file (a
        shipped-network file, a training checkpoint or a run directory).
    seed : int, optional
        The training seed of a shipped network (default: the one reported first, 0);
        :func:`hippo_probe.pretrained.shipped_seeds` lists them.

    Returns
    -------
    Navigator
        In eval mode, float32, with attributes from its file: ``net.task`` (the task it
        was trained on, e.g. "generalized"), ``net.position_task`` (the task whose frame
        its (x, y) readout speaks: a fitted arena readout keeps its network's),
        ``net.world`` ("darkness" or "compass":
        make its trials with ``world=net.world``) and ``net.info`` (a dict: "task",
        "world", "config" (the training configuration), "class_weight", "test" (its
        test-split errors), "steps_done", "finished", "base_network" and, for a readout,
        under "readout_of" the network it reads).

    Raises
    ------
    ModuleNotFoundError
        torch is not installed (the ``[model]`` extra).
    CheckpointError
        The file is damaged, not a network, or of an architecture this version cannot
        build; nothing in it is run.

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

    from ..errors import CheckpointError
    from .checkpoint import load, load_into
    from .config import ModelConfig
    from .navigator import Navigator

    path = resolve_network_file(name, seed)
    obj = load(path)
    config = obj["model_config"]
    try:
        if isinstance(config, dict):
            config = ModelConfig(**{**config, "input_scale": tuple(config["input_scale"])})
        # a readout's network, read once for its parameters and its frame
        base = readout_base(obj, path) if READOUT_OF in obj else None
        state = network_parameters(obj, path, base)
        _check_declared_shapes(config, state, path)
        net = Navigator(dataclasses.replace(config, precision="fp32"))
    except CheckpointError:
        raise
    except (TypeError, KeyError, ValueError) as err:
        raise CheckpointError(f"`checkpoint` {str(path)!r} holds an architecture this "
                              f"version cannot build ({type(err).__name__}: {err})") from None
    load_into(net, state, path)
    net.task = obj.get("task")
    net.position_task = position_task(obj, path, base)
    net.world = checkpoint_world(obj)
    net.info = {k: obj.get(k) for k in ("task", "config", "class_weight", "test",
                                        "steps_done", "finished", "base_network",
                                        READOUT_OF)}
    net.info["world"] = net.world
    net.info["file"] = str(path)
    return net.eval()
