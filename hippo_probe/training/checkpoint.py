"""Atomic checkpoints: written beside, then renamed into place; loaded without running code.

Files are read with ``torch.load(weights_only=True)``: tensors, containers and plain
Python values only, plus the allow-list :data:`SAFE_GLOBALS` (the project's own
architecture dataclass and torch's version string, which files written before the
allow-list hold). A file that names any other global (a crafted pickle would name e.g.
``os.system``) is refused before anything in it runs.
"""

from __future__ import annotations

import os
import pickle
from pathlib import Path

import torch

from ..errors import CheckpointError


def save_atomic(obj, path) -> None:
    """``torch.save`` to ``path`` so that a crash leaves the previous file or the new one."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    torch.save(obj, tmp)
    with open(tmp, "rb") as f:
        os.fsync(f.fileno())
    os.replace(tmp, path)


def load(path) -> dict:
    """Load a checkpoint (or a shipped network file), with a clear error if unusable."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"`checkpoint` must be an existing file; got {str(path)!r}")
    try:
        with torch.serialization.safe_globals(_safe_globals()):
            obj = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as err:
        if "GLOBAL" not in str(err):           # not a refused object: a corrupt file
            raise CheckpointError(f"`checkpoint` {str(path)!r} is not a readable torch "
                                  f"checkpoint ({_first_line(err)})") from None
        raise CheckpointError(
            f"`checkpoint` {str(path)!r} holds objects other than tensors and plain values "
            f"and was refused without running anything in it ({_first_line(err)}); load "
            f"only networks and checkpoints written by hippo_probe") from None
    except Exception as err:  # torch raises many types for a corrupt file
        raise CheckpointError(f"`checkpoint` {str(path)!r} is not a readable torch "
                              f"checkpoint ({type(err).__name__}: {err})") from None
    if not isinstance(obj, dict) or "model" not in obj or "model_config" not in obj:
        raise CheckpointError(f"`checkpoint` {str(path)!r} has no network in it "
                              f"(expected keys 'model' and 'model_config')")
    return obj


def _safe_globals() -> list:
    """Classes a checkpoint may name besides tensors and plain values (module docstring)."""
    from torch.torch_version import TorchVersion

    from ..model.config import ModelConfig

    return [ModelConfig, TorchVersion]


def _first_line(err) -> str:
    """The line of torch's weights-only error that names the refused global."""
    lines = [line.strip() for line in str(err).splitlines()]
    named = [line for line in lines if "Unsupported global" in line or "GLOBAL" in line]
    return (named or lines or [type(err).__name__])[0][:200]
