"""Training of Navigator networks: fit loop, checkpoints, resume, DDP, readout retraining.

Attributes are imported lazily so that ``hippo-probe --help`` (which reads this package's
``_cli``) does not load torch.
"""

import importlib

_ATTRS = {"TrainConfig": ".config", "build_network": ".trainer", "class_weight_rule": ".trainer",
          "evaluate_network": ".trainer", "fit": ".trainer", "save_network": ".trainer",
          "summarize": ".trainer", "export_network": ".export"}
__all__ = sorted(_ATTRS)


def __getattr__(name):
    if name not in _ATTRS:
        raise AttributeError(f"module 'hippo_probe.training' has no attribute {name!r}")
    return getattr(importlib.import_module(_ATTRS[name], __name__), name)
