"""The network: peephole LSTM, Navigator, and ``record`` (network -> recording).

Attributes are imported lazily so that ``hippo-probe --help`` (which reads this package's
``_cli``) does not load torch.
"""

import importlib

_ATTRS = {"ModelConfig": ".config", "input_scale_for": ".config",
          "PeepholeLSTM": ".lstm", "reference_peephole_lstm": ".lstm",
          "Navigator": ".navigator", "record": ".record", "load_pretrained": ".load"}
__all__ = sorted(_ATTRS)


def __getattr__(name):
    if name not in _ATTRS:
        raise AttributeError(f"module 'hippo_probe.model' has no attribute {name!r}")
    return getattr(importlib.import_module(_ATTRS[name], __name__), name)
