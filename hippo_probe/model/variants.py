"""Model variants beyond the study: which ingredient makes place fields emerge?

The study's network (``variant="faithful"``) is a peephole LSTM with a linear (x, y)
readout; its units come out as smooth planar gradients. Published models that did grow
place fields or global remapping had one of a few ingredients; each is a named variant
here, recorded in the network's :class:`~hippo_probe.model.config.ModelConfig` and always
labelled as a departure from the study:

``nonneg``
    Non-negative unit output, ``h = o * relu(tanh(c))``: the cell's output gate and
    squashing are kept, only negative outputs are cut, so a unit is silent (0) or active
    like a firing rate (Sorscher et al. 2019/2023; Pettersen et al., eLife RP 99302, use
    ReLU units). Trained with an L1 activity cost (``TrainConfig.activity_l1``).
``dale``
    As ``nonneg``, and Dale's law on the recurrent weights: each unit's outgoing
    recurrent weights share one sign, 80% of the units excitatory and 20% inhibitory, by a
    fixed sign mask on non-negative magnitudes, ``W_h = |V| * s`` (Song, Yang & Wang 2016).
    Inhibitory magnitudes start 4x larger so that excitation and inhibition balance on
    average (0.8 * 1 = 0.2 * 4).
``placecells``
    A population output instead of (x, y): a softmax over 256 place cells with Gaussian
    tuning in the task's target frame, trained by cross-entropy to the place cells'
    activity at the true position; the position estimate is the decoded centre
    ``sum_i p_i mu_i`` (Banino et al. 2018), so its error compares with the others'.

The ``nonneg`` and ``dale`` variants train on the faithful network's fused kernels (its
``nonneg`` option; Dale's weights ``|V| * s`` enter them as the recurrent weights, with
autograd through the sign mask), in the same precision; a forward pass autograd does not
record runs the plain step (:func:`~hippo_probe.model.lstm.peephole_step`).

References
----------
Banino, A. et al. (2018). Vector-based navigation using grid-like representations in
artificial agents. Nature 557, 429-433. Sorscher, B., Mel, G. C., Ocko, S. A., Giocomo,
L. M. & Ganguli, S. (2023). A unified theory for the computational and mechanistic
origins of grid cells. Neuron 111, 121-137. Song, H. F., Yang, G. R. & Wang, X.-J. (2016).
Training excitatory-inhibitory recurrent neural networks for cognitive tasks. PLoS Comput
Biol 12, e1004792.
"""

from __future__ import annotations

import math

import numpy as np
import torch
from torch import nn

from .config import VARIANTS  # noqa: F401  (the names, defined without torch)
from .lstm import PeepholeLSTM, _FusedPeepholeLSTMFunction, peephole_step

#: Fraction of excitatory units under Dale's law (cortex: about 80%).
EXCITATORY_FRACTION = 0.8


class VariantLSTM(PeepholeLSTM):
    """The peephole LSTM with a non-negative output and, optionally, Dale's law.

    Parameters
    ----------
    input_size, hidden_size, forget_bias, precision
        As :class:`~hippo_probe.model.lstm.PeepholeLSTM`.
    nonneg : bool
        ``h = o * relu(tanh(c))`` instead of ``o * tanh(c)``.
    dale : bool
        Sign-constrained outgoing recurrent weights (80% excitatory units).

    Which units are inhibitory is drawn from torch's random generator, like the initial
    weights (so the network's ``init_seed`` sets both), and saved with the network as the
    buffer ``sign``.
    """

    def __init__(self, input_size: int, hidden_size: int = 256, forget_bias: float = 1.0,
                 precision: str = "fp32", *, nonneg: bool = True, dale: bool = False):
        super().__init__(input_size, hidden_size, forget_bias, precision=precision)
        self.nonneg, self.dale = bool(nonneg), bool(dale)
        sign = torch.ones(hidden_size)
        if self.dale:
            n_inhibitory = hidden_size - int(round(EXCITATORY_FRACTION * hidden_size))
            sign[torch.randperm(hidden_size)[:n_inhibitory]] = -1.0
            with torch.no_grad():   # balanced on average: 0.8 * 1 = 0.2 * 4
                self.weight_h.abs_()
                self.weight_h[:, sign < 0] *= EXCITATORY_FRACTION / (1 - EXCITATORY_FRACTION)
        self.register_buffer("sign", sign)

    def recurrent_weight(self):
        """The recurrent weights used: ``|V| * s`` (column j = unit j's outgoing weights,
        of sign ``s_j``) under Dale's law, else the parameter itself."""
        return self.weight_h.abs() * self.sign[None, :] if self.dale else self.weight_h

    def forward(self, x, state=None):
        if x.dim() != 3 or x.shape[-1] != self.input_size or x.shape[0] == 0:
            raise ValueError(f"`x` must have shape (T >= 1, B, {self.input_size}); "
                             f"got {tuple(x.shape)}")
        B = x.shape[1]
        h, c = state if state is not None else (x.new_zeros(B, self.hidden_size),
                                                x.new_zeros(B, self.hidden_size))
        w_h = self.recurrent_weight()
        args = (x, h, c, self.weight_x, w_h, self.bias, self.weight_peephole)
        recorded = torch.is_grad_enabled() and any(a.requires_grad for a in args)
        on_cpu = x.device.type == "cpu"
        if recorded and (self.precision == "bf16" or (on_cpu and x.dtype == torch.float32)):
            bf16 = self.precision == "bf16"
            h_seq, h, c = _FusedPeepholeLSTMFunction.apply(
                *args, bf16, "numba" if on_cpu else "torch", self.nonneg)
            return h_seq, (h, c)
        xw = x @ self.weight_x.t()          # the input projection of every step at once
        out = []
        for t in range(x.shape[0]):
            h, c = peephole_step(xw[t], h, c, w_h, self.bias, self.weight_peephole,
                                 self.nonneg)
            out.append(h)
        return torch.stack(out), (h, c)

    def extra_repr(self) -> str:
        return (f"{self.input_size}, hidden_size={self.hidden_size}, peepholes=True, "
                f"nonneg={self.nonneg}, dale={self.dale}")


class PlaceCellReadout(nn.Module):
    """A softmax population of place cells read from the units, decoded to a position.

    ``n`` centres ``mu_i`` uniform in a disk of radius ``extent`` (fixed by ``seed``,
    saved with the network), each with Gaussian tuning of width ``width``. The target
    activity at position ``x`` is ``q_i(x) = exp(-|x - mu_i|^2 / 2 width^2) / sum_k
    exp(-|x - mu_k|^2 / 2 width^2)`` (sums to 1); the readout's softmax ``p = softmax(W h
    + b)`` is trained by the cross-entropy ``-sum_i q_i log p_i``, and decodes to ``sum_i
    p_i mu_i``.
    """

    def __init__(self, hidden_size: int, n: int, width: float, extent: float,
                 seed: int = 0):
        super().__init__()
        rng = np.random.default_rng(seed)
        radius = extent * np.sqrt(rng.uniform(size=n))        # uniform in the disk
        angle = rng.uniform(0, 2 * math.pi, n)
        centres = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
        self.register_buffer("centres", torch.from_numpy(centres.astype(np.float32)))
        self.width = float(width)
        self.linear = nn.Linear(hidden_size, n)

    @property
    def weight(self):          # the readout's weights, as a linear (x, y) readout's
        return self.linear.weight

    def logits(self, h):
        return self.linear(h)

    def targets(self, xy):
        """The place cells' activity ``q(x)`` at positions ``xy`` (..., 2): sums to 1."""
        d2 = ((xy[..., None, :] - self.centres) ** 2).sum(-1)
        return torch.softmax(-d2 / (2 * self.width ** 2), dim=-1)

    def decode(self, logits):
        """The decoded centre ``sum_i p_i mu_i`` of each softmax population."""
        return torch.softmax(logits, dim=-1) @ self.centres

    def forward(self, h):
        return self.decode(self.logits(h))

    def loss(self, h, target):
        """Cross-entropy of the readout's softmax to the target population activity."""
        q = self.targets(target)
        return -(q * torch.log_softmax(self.logits(h), dim=-1)).sum(-1).mean()
