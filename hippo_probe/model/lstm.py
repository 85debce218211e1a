"""A peephole LSTM (Graves 2013) with a hand-written backward pass.

For input ``x_t`` and previous state ``(h_{t-1}, c_{t-1})``::

    i_t = sigma(W_xi x_t + W_hi h_{t-1} + w_ci * c_{t-1} + b_i)     input gate
    f_t = sigma(W_xf x_t + W_hf h_{t-1} + w_cf * c_{t-1} + b_f)     forget gate
    g_t = tanh (W_xg x_t + W_hg h_{t-1} + b_g)                      cell input
    c_t = f_t * c_{t-1} + i_t * g_t
    o_t = sigma(W_xo x_t + W_ho h_{t-1} + w_co * c_t + b_o)         output gate
    h_t = o_t * tanh(c_t)

(``*`` is elementwise; the peephole weights ``w_c.`` are diagonal.)

Why a custom autograd Function: a per-step Python loop under autograd records ~15 graph
nodes per step, and ``torch.nn.LSTM`` has no peepholes. Here the forward pass writes the
gate activations into one preallocated (T, B, 4, H) buffer (the input projection of all
steps is one matmul); the backward pass precomputes every elementwise derivative factor
for all steps at once, so its sequential loop is five kernels per step; the weight
gradients are then one large matmul each. See ``benchmarks/bench_lstm.py``.

References
----------
Graves, A. (2013). Generating sequences with recurrent neural networks. arXiv:1308.0850.
Gers, F. A., Schraudolph, N. N., & Schmidhuber, J. (2002). Learning precise timing with
LSTM recurrent networks. JMLR 3, 115-143.
"""

from __future__ import annotations

import math

import numba
import torch
from torch import nn
from torch.autograd.function import once_differentiable


@numba.njit(fastmath=True, cache=True)
def _derivative_factors(gates, cells, tanh_cells, w_peep, a_o, b_c, k, k_c):
    """Elementwise derivative factors of every step, in one fused pass (see backward).

    Serial on purpose: a numba thread pool spinning beside torch's OpenMP pool made the
    next forward pass several times slower on a 2-core machine.
    """
    T, _, B, H = gates.shape
    for t in range(T):
        for b in range(B):
            for j in range(H):
                i = gates[t, 0, b, j]
                f = gates[t, 1, b, j]
                g = gates[t, 2, b, j]
                o = gates[t, 3, b, j]
                tc = tanh_cells[t, b, j]
                ao = tc * o * (1 - o)
                a_o[t, b, j] = ao
                b_c[t, b, j] = o * (1 - tc * tc) + ao * w_peep[2, j]
                ki = g * i * (1 - i)
                kf = cells[t, b, j] * f * (1 - f)      # cells[t] is c_{t-1}
                k[t, 0, b, j] = ki
                k[t, 1, b, j] = kf
                k[t, 2, b, j] = i * (1 - g * g)
                k_c[t, b, j] = f + ki * w_peep[0, j] + kf * w_peep[1, j]


class _PeepholeLSTMFunction(torch.autograd.Function):
    """Forward and backward of the whole sequence.

    Internal layout is gate-major, (T, 4, B, H): each gate of a step is one contiguous
    (B, H) block, so every elementwise kernel runs on contiguous memory (strided gate
    slices of a (B, 4H) layout were 2-4x slower per kernel). The recurrent products are
    batched over the four gates: ``baddbmm`` forward, ``addbmm`` (which also sums the four
    gates' contributions) backward.
    """

    @staticmethod
    def forward(ctx, x, h0, c0, w_x, w_h, bias, w_peep):
        T, B, F = x.shape
        H = w_h.shape[1]
        w_h4 = w_h.view(4, H, H)
        # input projection of every step at once, straight into (T, 4, B, H)
        gates = torch.matmul(x.unsqueeze(1), w_x.view(4, H, F).transpose(1, 2))
        gates += bias.view(4, 1, H)
        cells = x.new_empty(T + 1, B, H)           # cells[t] = c_{t-1}; cells[0] = c0
        hidden = x.new_empty(T + 1, B, H)          # hidden[t] = h_{t-1}
        tanh_cells = x.new_empty(T, B, H)
        cells[0] = c0
        hidden[0] = h0
        w_if = w_peep[:2, None, :]                 # (2, 1, H) peepholes of i and f
        w_o = w_peep[2]
        w_h4_t = w_h4.transpose(1, 2)
        for t in range(T):
            g = gates[t]
            c = cells[t]
            g.baddbmm_(hidden[t].expand(4, B, H), w_h4_t)
            g[:2].addcmul_(c, w_if).sigmoid_()
            g[2].tanh_()
            c_new = torch.mul(g[1], c, out=cells[t + 1])
            c_new.addcmul_(g[0], g[2])
            g[3].addcmul_(c_new, w_o).sigmoid_()
            torch.mul(g[3], torch.tanh(c_new, out=tanh_cells[t]), out=hidden[t + 1])
        ctx.save_for_backward(x, w_x, w_h, w_peep, gates, cells, tanh_cells, hidden)
        h_seq = hidden[1:]
        return h_seq, h_seq[-1].clone(), cells[-1].clone()

    @staticmethod
    @once_differentiable
    def backward(ctx, d_hidden, d_hn, d_cn):
        x, w_x, w_h, w_peep, gates, cells, tanh_cells, hidden = ctx.saved_tensors
        T, _, B, H = gates.shape
        F = x.shape[-1]
        # do = dh * a_o ; dc = dc_next + dh * b_c ; (di, df, dg) = dc * k ; dc_prev = dc * k_c
        if gates.device.type == "cpu":
            a_o = torch.empty_like(tanh_cells)
            b_c = torch.empty_like(tanh_cells)
            k_c = torch.empty_like(tanh_cells)
            k = gates.new_empty(T, 3, B, H)
            _derivative_factors(gates.detach().numpy(), cells.detach().numpy(),
                                tanh_cells.detach().numpy(), w_peep.detach().numpy(),
                                a_o.numpy(), b_c.numpy(), k.numpy(), k_c.numpy())
        else:   # the same factors with torch ops (GPU)
            i, f, g, o = gates.unbind(1)
            a_o = tanh_cells * o * (1 - o)
            b_c = o * (1 - tanh_cells * tanh_cells) + a_o * w_peep[2]
            k = torch.stack([g * i * (1 - i), cells[:-1] * f * (1 - f), i * (1 - g * g)], 1)
            k_c = f + k[:, 0] * w_peep[0] + k[:, 1] * w_peep[1]
        dh_all = torch.zeros_like(tanh_cells) if d_hidden is None else d_hidden.clone()
        if d_hn is not None:
            dh_all[-1] += d_hn
        dc = d_cn.clone() if d_cn is not None else torch.zeros_like(tanh_cells[0])
        dh0 = torch.zeros_like(dc)
        d_gates = torch.empty_like(gates)
        w_h4 = w_h.view(4, H, H)
        d_w_h4 = torch.zeros_like(w_h4)
        d_w_x4 = x.new_zeros(4, H, F)
        for t in range(T - 1, -1, -1):
            dh = dh_all[t]
            dg = d_gates[t]
            torch.mul(dh, a_o[t], out=dg[3])
            dc.addcmul_(dh, b_c[t])
            torch.mul(dc, k[t], out=dg[:3])
            dc.mul_(k_c[t])
            (dh_all[t - 1] if t > 0 else dh0).addbmm_(dg, w_h4)
            d_w_h4.baddbmm_(dg.transpose(1, 2), hidden[t].expand(4, B, H))
            # per step while dg is in cache: one (T, 4, B, H) x (T, B, F) product after the
            # loop was a 2,000-batch bmm, 6x slower
            d_w_x4.baddbmm_(dg.transpose(1, 2), x[t].expand(4, B, F))
        d_w_x = d_w_x4.view(4 * H, F)
        # reduce over the contiguous leading dim first: a sum over dims (0, 2) at once
        # took a strided path ~10x slower
        d_bias = d_gates.sum(0).sum(1).view(4 * H)
        d_w_peep = torch.stack([
            (d_gates[:, 0] * cells[:-1]).sum((0, 1)),
            (d_gates[:, 1] * cells[:-1]).sum((0, 1)),
            (d_gates[:, 3] * cells[1:]).sum((0, 1)),
        ])
        d_x = None
        if ctx.needs_input_grad[0]:
            d_x = torch.matmul(d_gates, w_x.view(4, H, F)).sum(1)
        return d_x, dh0, dc, d_w_x, d_w_h4.view(4 * H, H), d_bias, d_w_peep


class PeepholeLSTM(nn.Module):
    """Single-layer LSTM with peepholes and forget gates (Graves 2013), time-major.

    Parameters
    ----------
    input_size : int
    hidden_size : int, default 256
        The study's network size.
    forget_bias : float, default 1.0
        Initial forget-gate bias, so memory is kept by default early in training
        (Gers et al. 2000; Jozefowicz et al. 2015).

    Attributes
    ----------
    weight_x : (4H, F)  input weights, gates stacked in the order i, f, g, o
    weight_h : (4H, H)  recurrent weights
    bias : (4H,)
    weight_peephole : (3, H)  diagonal peepholes w_ci, w_cf, w_co

    Examples
    --------
    >>> import torch
    >>> lstm = PeepholeLSTM(9, hidden_size=16)
    >>> h_seq, (h, c) = lstm(torch.zeros(5, 2, 9))
    >>> h_seq.shape
    torch.Size([5, 2, 16])
    """

    def __init__(self, input_size: int, hidden_size: int = 256, forget_bias: float = 1.0):
        super().__init__()
        if int(input_size) < 1:
            raise ValueError(f"`input_size` must be >= 1; got {input_size}")
        if int(hidden_size) < 1:
            raise ValueError(f"`hidden_size` must be >= 1; got {hidden_size}")
        self.input_size, self.hidden_size = int(input_size), int(hidden_size)
        H = self.hidden_size
        self.weight_x = nn.Parameter(torch.empty(4 * H, self.input_size))
        self.weight_h = nn.Parameter(torch.empty(4 * H, H))
        self.bias = nn.Parameter(torch.zeros(4 * H))
        self.weight_peephole = nn.Parameter(torch.zeros(3, H))
        self.forget_bias = float(forget_bias)
        self.reset_parameters()

    def reset_parameters(self):
        """Uniform(-1/sqrt(H), 1/sqrt(H)) weights as torch.nn.LSTM; forget bias set."""
        bound = 1.0 / math.sqrt(self.hidden_size)
        for w in (self.weight_x, self.weight_h, self.weight_peephole):
            nn.init.uniform_(w, -bound, bound)
        with torch.no_grad():
            self.bias.zero_()
            self.bias[self.hidden_size:2 * self.hidden_size] = self.forget_bias

    def forward(self, x, state=None):
        """Run over a sequence.

        Parameters
        ----------
        x : tensor (T, B, input_size)
        state : (h0, c0), each (B, H), optional (zeros)

        Returns
        -------
        h_seq : (T, B, H)
        (h_T, c_T) : final state
        """
        if x.dim() != 3 or x.shape[-1] != self.input_size or x.shape[0] == 0:
            raise ValueError(f"`x` must have shape (T >= 1, B, {self.input_size}); "
                             f"got {tuple(x.shape)}")
        B = x.shape[1]
        if state is None:
            h0 = x.new_zeros(B, self.hidden_size)
            c0 = x.new_zeros(B, self.hidden_size)
        else:
            h0, c0 = state
            for name, v in (("h0", h0), ("c0", c0)):
                if tuple(v.shape) != (B, self.hidden_size):
                    raise ValueError(f"`state` {name} must have shape ({B}, "
                                     f"{self.hidden_size}); got {tuple(v.shape)}")
        h_seq, h_n, c_n = _PeepholeLSTMFunction.apply(
            x, h0, c0, self.weight_x, self.weight_h, self.bias, self.weight_peephole)
        return h_seq, (h_n, c_n)

    def extra_repr(self) -> str:
        return f"{self.input_size}, hidden_size={self.hidden_size}, peepholes=True"


def reference_peephole_lstm(x, h0, c0, weight_x, weight_h, bias, weight_peephole):
    """Plain-autograd peephole LSTM (slow, obviously correct), for gradient checks."""
    H = weight_h.shape[1]
    h, c, out = h0, c0, []
    for t in range(x.shape[0]):
        z = x[t] @ weight_x.t() + h @ weight_h.t() + bias
        zi, zf, zg, zo = z.split(H, dim=1)
        i = torch.sigmoid(zi + weight_peephole[0] * c)
        f = torch.sigmoid(zf + weight_peephole[1] * c)
        c = f * c + i * torch.tanh(zg)
        o = torch.sigmoid(zo + weight_peephole[2] * c)
        h = o * torch.tanh(c)
        out.append(h)
    return torch.stack(out), h, c
