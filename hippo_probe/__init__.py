"""hippo_probe: recurrent networks that navigate like rats, recorded like real cells.

Reproduces and extends Kanitscheider & Fiete, "Training recurrent networks to generate
hypotheses about how the brain solves hard navigation problems" (NIPS 2017,
arXiv:1609.09059).

Importing this package is cheap: it never loads torch. The parts that need torch
(``model``, ``training``, ``record``, ``load_pretrained``) and the heavier subpackages are
imported on first attribute access.

Examples
--------
>>> import hippo_probe as hp
>>> batch = hp.tasks.make_trials("generalized", n_trials=4, split="train", seed=0)
>>> batch.inputs.shape[1]
4
"""

from __future__ import annotations

import importlib

from ._version import __version__
from .errors import HippoProbeError, RecordingError

# name -> module that defines it; resolved lazily so ``import hippo_probe`` stays light
# (no torch, no pynwb, no dask.distributed) and cannot fail on a machine without torch.
_LAZY_ATTRS = {
    # recording I/O (no torch)
    "open_recording": "hippo_probe.recording",
    "save_recording": "hippo_probe.recording",
    "validate": "hippo_probe.recording",
    "from_arrays": "hippo_probe.recording",
    "from_nwb": "hippo_probe.recording",
    "to_nwb": "hippo_probe.recording",
    "select_trials": "hippo_probe.recording",
    "poisson_spikes": "hippo_probe.recording",
    # pynapple bridge (pynapple is imported when called)
    "to_pynapple": "hippo_probe.recording",
    "from_pynapple": "hippo_probe.recording",
    # analyses (no torch)
    "ratemaps": "hippo_probe.analysis",
    "spatial_information": "hippo_probe.analysis",
    "spatial_selectivity": "hippo_probe.analysis",
    "place_field_stability": "hippo_probe.analysis",
    "head_direction_tuning": "hippo_probe.analysis",
    "remapping_similarity": "hippo_probe.analysis",
    "context_cells": "hippo_probe.analysis",
    "decode_covariance": "hippo_probe.analysis",
    "decode_environment": "hippo_probe.analysis",
    "correlation_dimension": "hippo_probe.analysis",
    "intrinsic_dimension": "hippo_probe.analysis",
    "localization_error": "hippo_probe.analysis",
    "map_scorecard": "hippo_probe.analysis",
    "classification_accuracy": "hippo_probe.analysis",
    "AnalysisWarning": "hippo_probe.analysis",
    # cell classes
    "place_fields": "hippo_probe.analysis",
    "spatial_autocorrelation": "hippo_probe.analysis",
    "grid_score": "hippo_probe.analysis",
    "border_score": "hippo_probe.analysis",
    "speed_score": "hippo_probe.analysis",
    "conjunctive_tuning": "hippo_probe.analysis",
    "classify_cells": "hippo_probe.analysis",
    # torch-backed
    # from its own module: importing the submodule hippo_probe.model.record (as the
    # `record` command does) rebinds the package attribute `record` to the module
    "record": "hippo_probe.model.record",
    "load_pretrained": "hippo_probe.model.load",
}
_SUBMODULES = {
    "world", "tasks", "model", "training", "baselines", "recording", "analysis", "plot",
    "pretrained", "cli",
}

__all__ = sorted(
    ["__version__", "HippoProbeError", "RecordingError", *_LAZY_ATTRS, *_SUBMODULES]
)


def __getattr__(name: str):
    if name not in _SUBMODULES and name not in _LAZY_ATTRS:
        raise AttributeError(f"module 'hippo_probe' has no attribute {name!r}")
    try:
        if name in _SUBMODULES:
            module = importlib.import_module(f"hippo_probe.{name}")
        else:
            module = getattr(importlib.import_module(_LAZY_ATTRS[name]), name)
    except ModuleNotFoundError as err:
        from ._optional import EXTRAS, missing

        if err.name in EXTRAS:
            raise missing(err.name, f"hippo_probe.{name}") from None
        raise
    globals()[name] = module  # cache: later look-ups skip __getattr__
    return module


def __dir__():
    return __all__
