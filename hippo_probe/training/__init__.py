"""Training of Navigator networks: fit loop, checkpoints, resume, DDP, readout retraining."""

from .config import TrainConfig
from .fit import (build_network, class_weight_rule, evaluate_network, fit, save_network,
                  summarize)

__all__ = ["TrainConfig", "build_network", "class_weight_rule", "evaluate_network", "fit",
           "save_network", "summarize"]
