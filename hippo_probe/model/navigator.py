"""The Navigator: a peephole LSTM with a linear position readout (and an arena classifier)."""

from __future__ import annotations

import torch
from torch import nn

from .config import ModelConfig
from .lstm import PeepholeLSTM
from .variants import PlaceCellReadout, VariantLSTM


class Navigator(nn.Module):
    """LSTM + linear (x, y) readout [+ softmax readout over arenas].

    ``Navigator(inputs) -> (xy, logits or None, h)`` with ``inputs`` (T, B, F) in physical
    units (the network scales them by ``config.input_scale``), ``xy`` (T, B, 2) in the
    task's target frame (m), ``logits`` (T, B, n_classes) and ``h`` (T, B, H) the hidden
    state sequence (the "recorded" activity).

    Attributes
    ----------
    config : ModelConfig
        The architecture: sizes, variant, precision.
    lstm : PeepholeLSTM or VariantLSTM
        The recurrent layer.
    position : torch.nn.Linear or PlaceCellReadout
        The (x, y) readout.
    classifier : torch.nn.Linear or None
        The arena readout (tasks with arenas to name).
    task, world, info
        Set by :func:`~hippo_probe.load_pretrained` from the network's file (see there).

    Examples
    --------
    >>> import torch
    >>> net = Navigator(ModelConfig(hidden_size=8, n_classes=3))
    >>> xy, logits, h = net(torch.zeros(4, 2, 9))
    >>> xy.shape, logits.shape, h.shape
    (torch.Size([4, 2, 2]), torch.Size([4, 2, 3]), torch.Size([4, 2, 8]))
    """

    def __init__(self, config: ModelConfig = ModelConfig()):
        super().__init__()
        self.config = config
        self.register_buffer("input_scale",
                             torch.tensor(config.input_scale, dtype=torch.float32))
        if config.variant in ("nonneg", "dale"):
            self.lstm = VariantLSTM(config.input_size, config.hidden_size, config.forget_bias,
                                    precision=config.precision, nonneg=True,
                                    dale=config.variant == "dale")
        else:
            self.lstm = PeepholeLSTM(config.input_size, config.hidden_size,
                                     config.forget_bias, precision=config.precision)
        if config.variant == "placecells":
            self.position = PlaceCellReadout(config.hidden_size, config.n_place_cells,
                                             config.place_cell_width,
                                             config.place_cell_extent)
        else:
            self.position = nn.Linear(config.hidden_size, 2)
        self.classifier = nn.Linear(config.hidden_size, config.n_classes) \
            if config.n_classes else None

    def position_loss(self, h, target):
        """The position term of the loss: the mean squared error of the (x, y) readout,
        or the place cells' cross-entropy for the "placecells" variant."""
        if isinstance(self.position, PlaceCellReadout):
            return self.position.loss(h, target)
        return ((self.position(h) - target) ** 2).mean()

    def forward(self, inputs):
        inputs = torch.as_tensor(inputs, dtype=self.input_scale.dtype,
                                 device=self.input_scale.device)
        h, _ = self.lstm(inputs / self.input_scale)
        xy = self.position(h)
        logits = self.classifier(h) if self.classifier is not None else None
        return xy, logits, h
