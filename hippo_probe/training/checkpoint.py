"""Atomic checkpoints: written beside, then renamed into place."""

from __future__ import annotations

import os
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
        obj = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as err:  # torch raises many types for a corrupt file
        raise CheckpointError(f"`checkpoint` {str(path)!r} is not a readable torch "
                              f"checkpoint ({type(err).__name__}: {err})") from None
    if not isinstance(obj, dict) or "model" not in obj or "model_config" not in obj:
        raise CheckpointError(f"`checkpoint` {str(path)!r} has no network in it "
                              f"(expected keys 'model' and 'model_config')")
    return obj
