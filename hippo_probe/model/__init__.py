"""The network: peephole LSTM, Navigator, and ``record`` (network -> recording)."""

from .config import ModelConfig, input_scale_for
from .lstm import PeepholeLSTM, reference_peephole_lstm
from .navigator import Navigator

__all__ = ["ModelConfig", "Navigator", "PeepholeLSTM", "input_scale_for",
           "reference_peephole_lstm", "record"]


def __getattr__(name):
    if name == "record":
        from .record import record
        return record
    raise AttributeError(name)
