"""Atomic checkpoints: written beside, then renamed into place; loaded without running code.

Files are read with ``torch.load(weights_only=True)``: tensors, containers and plain
Python values only, plus the allow-list :data:`SAFE_GLOBALS` (the project's own
architecture dataclass and torch's version string, which files written before the
allow-list hold). A file that names any other global (a crafted pickle would name e.g.
``os.system``) is refused before anything in it runs.

Every file carries :data:`DIGEST_KEY`, the sha256 of its content (each tensor's dtype,
shape and bytes, every plain value's repr, in key order), checked on load: a flipped
byte in a tensor is refused rather than resumed from. Files written before the digest
existed have none and load unchecked.
"""

from __future__ import annotations

import hashlib
import pickle
import warnings
from pathlib import Path

import torch

from .._atomic import atomic_path
from ..errors import CheckpointError


DIGEST_KEY = "content_sha256"


def content_digest(obj) -> str:
    """sha256 of a checkpoint's content: tensors by dtype, shape and bytes, plain values
    by repr, dicts in key order (so it does not depend on how the file was zipped)."""
    h = hashlib.sha256()

    def visit(value):
        if isinstance(value, torch.Tensor):
            t = value.detach().cpu().contiguous()
            h.update(f"T{t.dtype}{tuple(t.shape)}".encode())
            # flattened first: a 0-d tensor (Adam's step count) cannot be viewed as bytes
            h.update(t.reshape(-1).view(torch.uint8).numpy().tobytes() if t.numel() else b"")
        elif isinstance(value, dict):
            h.update(b"D%d" % len(value))
            for key in sorted(value, key=repr):
                h.update(repr(key).encode())
                visit(value[key])
        elif isinstance(value, (list, tuple)):
            h.update(b"L%d" % len(value))
            for item in value:
                visit(item)
        else:
            h.update(f"V{type(value).__name__}:{value!r}".encode())

    visit({k: v for k, v in obj.items() if k != DIGEST_KEY})
    return h.hexdigest()


def save_atomic(obj: dict, path) -> None:
    """``torch.save`` ``obj`` with its :func:`content_digest` to ``path``, atomically (a
    crash leaves the previous file or the new one)."""
    obj = {**obj, DIGEST_KEY: content_digest(obj)}
    with atomic_path(path, overwrite=True, what="checkpoint") as tmp:
        torch.save(obj, tmp)


def load(path) -> dict:
    """Load a checkpoint (or a shipped network file), with a clear error if unusable."""
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"`checkpoint` must be an existing file; got {str(path)!r}")
    try:
        with torch.serialization.safe_globals(_safe_globals()), warnings.catch_warnings():
            # a pickle of another protocol is refused below, not warned about first
            warnings.filterwarnings("ignore", message="Detected pickle protocol")
            obj = torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as err:
        if "GLOBAL" not in str(err) and not _plain_pickle(path):
            # not an object or a pickle refused by the safe loader: a corrupt file
            raise CheckpointError(f"`checkpoint` {str(path)!r} is not a readable torch "
                                  f"checkpoint ({_first_line(err)})") from None
        raise CheckpointError(
            f"`checkpoint` {str(path)!r} holds objects other than tensors and plain values "
            f"(or pickle instructions torch does not write) "
            f"and was refused without running anything in it ({_first_line(err)}); load "
            f"only networks and checkpoints written by hippo_probe") from None
    except Exception as err:  # torch raises many types for a corrupt file
        raise CheckpointError(f"`checkpoint` {str(path)!r} is not a readable torch "
                              f"checkpoint ({type(err).__name__}: {err})") from None
    if not isinstance(obj, dict) or "model" not in obj or "model_config" not in obj:
        raise CheckpointError(f"`checkpoint` {str(path)!r} has no network in it "
                              f"(expected keys 'model' and 'model_config')")
    stored = obj.pop(DIGEST_KEY, None)
    if stored is not None and stored != content_digest(obj):
        raise CheckpointError(f"`checkpoint` {str(path)!r} is corrupt: its content does "
                              f"not match the sha256 written with it (a damaged copy?); "
                              f"use an intact copy or an earlier checkpoint")
    return obj


def require(obj: dict, keys, path, purpose: str) -> dict:
    """``obj`` if it holds every key in ``keys``; otherwise a CheckpointError saying which
    are missing and what they were needed for."""
    missing = [k for k in keys if k not in obj]
    if missing:
        raise CheckpointError(f"`checkpoint` {str(path)!r} lacks {missing}, needed to "
                              f"{purpose} (is it a shipped network rather than a training "
                              f"checkpoint, or from an older version?)")
    return obj


def load_into(module, state, path) -> None:
    """``module.load_state_dict(state)`` (a network or an optimizer), as a CheckpointError
    naming the file when the parameters do not fit (other shapes, missing keys)."""
    try:
        module.load_state_dict(state)
    except (RuntimeError, KeyError, ValueError, TypeError) as err:
        lines = [line.strip() for line in str(err).strip().splitlines() if line.strip()]
        detail = "; ".join(lines[:3])[:400]
        raise CheckpointError(f"`checkpoint` {str(path)!r} does not fit this "
                              f"{type(module).__name__} ({type(err).__name__}: {detail})"
                              ) from None


def _safe_globals() -> list:
    """Classes a checkpoint may name besides tensors and plain values (module docstring)."""
    from torch.torch_version import TorchVersion

    from .config import ModelConfig

    return [ModelConfig, TorchVersion]


def _plain_pickle(path) -> bool:
    """Whether ``path`` starts as a pickle of protocol 2 or later does (its PROTO
    opcode), rather than as a torch zip file or bytes of no format."""
    with open(path, "rb") as f:
        head = f.read(2)
    return len(head) == 2 and head[0] == 0x80 and 2 <= head[1] <= 5


def _first_line(err) -> str:
    """The line of torch's weights-only error that says what was refused (a global, an
    opcode), not its advice to load the file unsafely."""
    lines = [line.strip() for line in str(err).splitlines() if line.strip()]
    named = [line for line in lines if "Unsupported global" in line or "GLOBAL" in line
             or line.startswith("Unsupported operand")]
    return (named or lines[:1] or [type(err).__name__])[0][:200]
