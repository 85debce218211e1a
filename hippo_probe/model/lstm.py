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
gate activations into one preallocated (T, 4, B, H) buffer (the input projection of all
steps is one matmul); the backward pass precomputes every elementwise derivative factor
for all steps at once, so its sequential loop is five kernels per step; the weight
gradients are then one large matmul each. See ``benchmarks/bench_lstm.py``.

A second Function, the fused training path (:class:`_FusedPeepholeLSTMFunction`), runs the
same math with each step's elementwise work in one numba kernel, for training on the CPU:
in float32, or with its matmuls in bfloat16 on the CPU's AMX units and the rest in float32
(``PeepholeLSTM(precision="bf16")``). A forward pass that autograd does not record
(evaluation, ``record``) always runs the first Function's forward steps
(:func:`_plain_inference`: the same numbers, without the per-step cells that only the
backward pass needs; :func:`reused_buffers` lets a caller that runs many batches, as
``record`` does, write each into the previous one's memory).

References
----------
Graves, A. (2013). Generating sequences with recurrent neural networks. arXiv:1308.0850.
Gers, F. A., Schraudolph, N. N., & Schmidhuber, J. (2002). Learning precise timing with
LSTM recurrent networks. JMLR 3, 115-143.
"""

from __future__ import annotations

import contextvars
import math
from contextlib import contextmanager

import numba
import numpy as np
import torch
from torch import nn
from torch.autograd.function import once_differentiable

from .._validators import check_option
from .config import PRECISIONS


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


def _input_gates(x, w_x, bias, out=None):
    """The input projection of every step at once plus the bias, (T, 4, B, H) (into
    ``out`` if given): the start of the gates of both plain paths."""
    F = x.shape[2]
    H = w_x.shape[0] // 4
    gates = torch.matmul(x.unsqueeze(1), w_x.view(4, H, F).transpose(1, 2), out=out)
    gates += bias.view(4, 1, H)
    return gates


def _plain_step(g, c, h, w_h4_t, w_peep, c_new, tanh_c, h_new):
    """One step of the plain float32 forward, in place: ``g`` (4, B, H) holds the step's
    input projection plus bias and becomes the gates (post-activation); ``c_new``,
    ``tanh_c`` and ``h_new`` (B, H) receive ``c_t``, ``tanh(c_t)`` and ``h_t`` from
    ``c = c_{t-1}`` and ``h = h_{t-1}``. The training path and the inference path
    (:func:`_plain_inference`) both step through it, so they compute the same numbers."""
    B, H = h.shape
    g.baddbmm_(h.expand(4, B, H), w_h4_t)
    g[:2].addcmul_(c, w_peep[:2, None, :]).sigmoid_()     # peepholes of i and f
    g[2].tanh_()
    torch.mul(g[1], c, out=c_new)
    c_new.addcmul_(g[0], g[2])
    g[3].addcmul_(c_new, w_peep[2]).sigmoid_()
    torch.mul(g[3], torch.tanh(c_new, out=tanh_c), out=h_new)


#: Buffers that the inference path uses again from one call to the next while
#: :func:`reused_buffers` is active (None otherwise): name -> the buffer of that name from
#: the latest call (made anew when the shape, dtype or device changes). Each thread
#: starts with None; threads started inside the block must not run the network.
_REUSED = contextvars.ContextVar("reused_lstm_buffers", default=None)


@contextmanager
def reused_buffers():
    """Within the block, the forward passes of :class:`PeepholeLSTM` that autograd does
    not record, in this thread, use their large buffers again instead of allocating
    them anew: the ``h_seq`` each returns is valid only until the next such pass
    (``h_T`` and ``c_T`` are not reused).

    For a caller that runs a network on many batches of trials and copies each
    ``h_seq`` out (:func:`hippo_probe.model.record.record`): a 250-trial batch of 500
    steps needs 0.64 GB of gates and ``h``, which the operating system would otherwise
    zero page by page for every batch (about a tenth of a recording's time on a 2-core
    machine).
    """
    token = _REUSED.set({})
    try:
        yield
    finally:
        _REUSED.reset(token)


def _buffer(name, shape, like):
    """An uninitialized tensor of ``shape`` like ``like``: the one of the same name and
    shape from the previous call inside :func:`reused_buffers`, else a new one."""
    reused = _REUSED.get()
    if reused is None:
        return like.new_empty(shape)
    held = reused.get(name)
    if held is None or held.shape != shape or held.dtype != like.dtype \
            or held.device != like.device:
        reused.pop(name, None)                 # freed before its successor is made
        held = reused[name] = like.new_empty(shape)
    return held


@torch.no_grad()
def _plain_inference(x, h0, c0, w_x, w_h, bias, w_peep):
    """The plain forward pass without what its backward needs: the same operations as
    :class:`_PeepholeLSTMFunction`'s forward, hence h bit for bit (tested), returned as
    ``(h_seq, h_T, c_T)``.

    The cell and ``tanh(c)`` of every step are not kept: (B, H) buffers, the cell's two
    taking turns, instead of two (T, B, H) arrays. The gates (T, 4, B, H) and ``h`` come from
    :func:`_buffer`, so that inside :func:`reused_buffers` a recording's batches of
    trials write into the same memory.
    """
    T, B, _ = x.shape
    H = w_h.shape[1]
    gates = _input_gates(x, w_x, bias, out=_buffer("gates", (T, 4, B, H), x))
    hidden = _buffer("hidden", (T + 1, B, H), x)       # hidden[t] = h_{t-1}
    hidden[0] = h0
    w_h4_t = w_h.view(4, H, H).transpose(1, 2)
    c, c_new, tanh_c = c0.clone(), x.new_empty(B, H), x.new_empty(B, H)
    for t in range(T):
        _plain_step(gates[t], c, hidden[t], w_h4_t, w_peep, c_new, tanh_c, hidden[t + 1])
        c, c_new = c_new, c
    return hidden[1:], hidden[-1].clone(), c


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
        T, B, _ = x.shape
        H = w_h.shape[1]
        w_h4 = w_h.view(4, H, H)
        gates = _input_gates(x, w_x, bias)                 # (T, 4, B, H)
        cells = x.new_empty(T + 1, B, H)           # cells[t] = c_{t-1}; cells[0] = c0
        hidden = x.new_empty(T + 1, B, H)          # hidden[t] = h_{t-1}
        tanh_cells = x.new_empty(T, B, H)
        cells[0] = c0
        hidden[0] = h0
        w_h4_t = w_h4.transpose(1, 2)
        for t in range(T):
            _plain_step(gates[t], cells[t], hidden[t], w_h4_t, w_peep,
                        cells[t + 1], tanh_cells[t], hidden[t + 1])
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


# --- the fused training path -----------------------------------------------------------
#
# For training on the CPU the elementwise work of a step is ONE fused numba kernel
# (forward) and ONE (backward) instead of ~12 and ~5 torch kernels, in a batch-major layout
# where a step's input projection and recurrence are ONE matmul. Two flavours share the
# per-row math (``_forward_row``, ``_backward_row``):
#
# * bf16 (``PeepholeLSTM(precision="bf16")``): matmuls in bfloat16 on the CPU's AMX units,
#   everything else float32. torch's CPU matmuls cannot write a float32 result from bf16
#   operands, so each product comes back rounded to bf16 (after float32 accumulation inside
#   oneDNN) and is widened before it touches the state. bf16 values cross into numba as
#   int16 bit patterns (numba has no bfloat16): widening is a 16-bit shift, narrowing rounds
#   to nearest even, as torch's own cast does.
# * float32 (the default precision's training path on the CPU): the same with float32
#   matmuls. On an AVX2 machine (no AVX-512) its training step took 1.3x less time than
#   the gate-major Function above, whose ~17 elementwise torch kernels a step were a third
#   of it (``benchmarks/bench_lstm.py``, "fp32 unfused"); it differs from that Function
#   only in rounding (the rational tanh below, the order of sums), ~3e-7 relative.
#
# The gate-major Function above stays the inference path (record, evaluation: bit for bit
# what it always computed) and the float64 / GPU path.

#: Coefficients of the [13/6] rational approximation of tanh on [-7.9988, 7.9988] used by
#: Eigen (``generic_fast_tanh_float``): max abs error 3.4e-7 against float64 tanh, relative
#: error < 3e-7 near 0 -- a thousand times below a bf16 rounding. numba has no vectorised
#: exp/tanh (no SVML here): libm's scalar tanh was ~40x slower than this polynomial.
#: float32 constants throughout: a float64 literal would make numba compute the whole
#: expression in float64, at half the vector width.
_TANH_CLAMP = np.float32(7.99881172180175781)
_TANH_P = tuple(np.float32(c) for c in (
    4.89352455891786e-03, 6.37261928875436e-04, 1.48572235717979e-05,
    5.12229709037114e-08, -8.60467152213735e-11, 2.00018790482477e-13,
    -2.76076847742355e-16))
_TANH_Q = tuple(np.float32(c) for c in (
    4.89352518554385e-03, 2.26843463243900e-03, 1.18534705686654e-04,
    1.19825839466702e-06))
_HALF, _ONE = np.float32(0.5), np.float32(1.0)


@numba.njit(fastmath=True, cache=True, inline="always", error_model="numpy")
def _tanh(x):
    x = min(max(x, -_TANH_CLAMP), _TANH_CLAMP)
    x2 = x * x
    p = x2 * _TANH_P[6] + _TANH_P[5]
    p = x2 * p + _TANH_P[4]
    p = x2 * p + _TANH_P[3]
    p = x2 * p + _TANH_P[2]
    p = x2 * p + _TANH_P[1]
    p = x2 * p + _TANH_P[0]
    q = x2 * _TANH_Q[3] + _TANH_Q[2]
    q = x2 * q + _TANH_Q[1]
    q = x2 * q + _TANH_Q[0]
    return x * p / q


@numba.njit(fastmath=True, cache=True, inline="always", error_model="numpy")
def _sigmoid(x):
    return _HALF + _HALF * _tanh(_HALF * x)


@numba.njit(cache=True)
def _widen(bits, out_u32):
    """bf16 bit patterns (int16) -> their float32 values' bit patterns."""
    for j in range(bits.shape[0]):
        out_u32[j] = (np.uint32(bits[j]) & 0xFFFF) << 16


@numba.njit(cache=True)
def _narrow(u32, out_bits):
    """float32 bit patterns -> bf16 bit patterns (int16), rounding to nearest even."""
    for j in range(u32.shape[0]):
        u = u32[j]
        out_bits[j] = (u + 0x7FFF + ((u >> 16) & 1)) >> 16


@numba.njit(fastmath=True, cache=True, inline="always", error_model="numpy")
def _forward_row(z, bias, w_peep, c, gates_tb, c_new, tc, h, nonneg):
    """One sequence's step: gates, cell and h from its pre-activation product row z (4H,).
    With ``nonneg``, ``tc`` is ``relu(tanh c)`` and ``h = o * relu(tanh c)``.

    One short loop per quantity over the H units, on purpose: LLVM vectorises a loop only
    when it can check cheaply that its arrays don't overlap, and one loop writing all seven
    outputs stayed scalar (4.7x slower).
    """
    H = c.shape[0]
    zi, zf, zg, zo = z[:H], z[H:2 * H], z[2 * H:3 * H], z[3 * H:]
    b_i, b_f, b_g, b_o = bias[0], bias[1], bias[2], bias[3]
    w_i, w_f, w_o = w_peep[0], w_peep[1], w_peep[2]
    i, f, g, o = gates_tb[0], gates_tb[1], gates_tb[2], gates_tb[3]
    for j in range(H):
        i[j] = _sigmoid(zi[j] + b_i[j] + w_i[j] * c[j])
    for j in range(H):
        f[j] = _sigmoid(zf[j] + b_f[j] + w_f[j] * c[j])
    for j in range(H):
        g[j] = _tanh(zg[j] + b_g[j])
    for j in range(H):
        c_new[j] = f[j] * c[j] + i[j] * g[j]
    for j in range(H):
        o[j] = _sigmoid(zo[j] + b_o[j] + w_o[j] * c_new[j])
    for j in range(H):
        tc[j] = _tanh(c_new[j])
    if nonneg:
        for j in range(H):
            tc[j] = max(tc[j], np.float32(0.0))
    for j in range(H):
        h[j] = o[j] * tc[j]


@numba.njit(fastmath=True, cache=True, inline="always", error_model="numpy")
def _backward_row(dh, gates_tb, tc, c_prev, c, dc, w_peep, dz, dct, d_bias, d_peep,
                  nonneg):
    """One sequence's backward step: pre-activation gradients dz (4H,: i, f, g, o) from
    ``dh``; ``dc`` goes from dc_t to dc_{t-1} in place; dz is added into the bias and
    peephole gradients. ``dct`` is scratch (H,). Short loops, as in :func:`_forward_row`.
    With ``nonneg`` (``tc = relu(tanh c)``) no gradient reaches a cell through a unit
    whose output is cut to 0.
    """
    H = c.shape[0]
    di, df, dg, do = dz[:H], dz[H:2 * H], dz[2 * H:3 * H], dz[3 * H:]
    i, f, g, o = gates_tb[0], gates_tb[1], gates_tb[2], gates_tb[3]
    w_i, w_f, w_o = w_peep[0], w_peep[1], w_peep[2]
    p_i, p_f, p_o = d_peep[0], d_peep[1], d_peep[2]
    for j in range(H):
        do[j] = dh[j] * tc[j] * o[j] * (_ONE - o[j])
    if nonneg:
        for j in range(H):
            slope = _ONE - tc[j] * tc[j] if tc[j] > 0 else np.float32(0.0)
            dct[j] = dc[j] + dh[j] * o[j] * slope + do[j] * w_o[j]
    else:
        for j in range(H):
            dct[j] = dc[j] + dh[j] * o[j] * (_ONE - tc[j] * tc[j]) + do[j] * w_o[j]
    for j in range(H):
        di[j] = dct[j] * g[j] * i[j] * (_ONE - i[j])
    for j in range(H):
        df[j] = dct[j] * c_prev[j] * f[j] * (_ONE - f[j])
    for j in range(H):
        dg[j] = dct[j] * i[j] * (_ONE - g[j] * g[j])
    for j in range(H):
        dc[j] = dct[j] * f[j] + di[j] * w_i[j] + df[j] * w_f[j]
    for j in range(4 * H):
        d_bias[j] += dz[j]
    for j in range(H):
        p_i[j] += di[j] * c_prev[j]
    for j in range(H):
        p_f[j] += df[j] * c_prev[j]
    for j in range(H):
        p_o[j] += do[j] * c[j]


@numba.njit(fastmath=True, cache=True, error_model="numpy")
def _bf16_forward_step(t, z_bits, bias, w_peep, gates, cells, tanh_cells, hidden, xh_bits,
                       nonneg):
    """Step t's gates and state from its pre-activation product ``z`` (bf16, (B, 4H)).

    Writes gates[t] (post-activation, (B, 4, H)), cells[t + 1], tanh_cells[t],
    hidden[t + 1] (float32) and, if another step follows, h_t's bf16 bits into
    ``xh_bits[t + 1, :, F:]`` (the next product's operand).
    """
    _, B, _, H = gates.shape
    F = xh_bits.shape[2] - H
    z_u = np.empty(4 * H, np.uint32)
    h_u = np.empty(H, np.uint32)
    h_f = h_u.view(np.float32)
    for b in range(B):
        _widen(z_bits[b], z_u)
        h = hidden[t + 1, b]
        _forward_row(z_u.view(np.float32), bias, w_peep, cells[t, b], gates[t, b],
                     cells[t + 1, b], tanh_cells[t, b], h, nonneg)
        if t + 1 < xh_bits.shape[0]:
            h_f[:] = h
            _narrow(h_u, xh_bits[t + 1, b, F:])


@numba.njit(fastmath=True, cache=True, error_model="numpy")
def _fp32_forward_step(t, z, bias, w_peep, gates, cells, tanh_cells, hidden, xh, nonneg):
    """:func:`_bf16_forward_step` with a float32 product ``z`` and operand buffer ``xh``."""
    _, B, _, H = gates.shape
    F = xh.shape[2] - H
    for b in range(B):
        h = hidden[t + 1, b]
        _forward_row(z[b], bias, w_peep, cells[t, b], gates[t, b], cells[t + 1, b],
                     tanh_cells[t, b], h, nonneg)
        if t + 1 < xh.shape[0]:
            xh[t + 1, b, F:] = h


@numba.njit(fastmath=True, cache=True, error_model="numpy")
def _bf16_backward_step(t, gates, cells, tanh_cells, w_peep, d_hidden, d_hn, rec_bits,
                        nonneg, use_rec, dc, dg_bits, d_bias, d_peep):
    """Step t of the backward recurrence, fused.

    ``dh = d_hidden[t] + rec``; rec is the bf16 product dg_{t+1} W_h, or at the last step
    (``use_rec`` False) ``d_hn``, the gradient of the returned final h (float32). Updates
    ``dc`` from dc_t to dc_{t-1} in place, writes the pre-activation gradients' bf16 bits
    to ``dg_bits[t]`` ((B, 4H), gates i, f, g, o) and adds their float32 values into the
    bias and peephole gradients.
    """
    _, B, _, H = gates.shape
    rec_u = np.empty(H, np.uint32)
    rec = rec_u.view(np.float32)
    dz_u = np.empty(4 * H, np.uint32)
    dz = dz_u.view(np.float32)
    dh = np.empty(H, np.float32)
    dct = np.empty(H, np.float32)
    d_bias = d_bias.reshape(4 * H)
    for b in range(B):
        if use_rec:
            _widen(rec_bits[b], rec_u)
        else:
            rec[:] = d_hn[b]
        dhb = d_hidden[t, b]
        for j in range(H):
            dh[j] = dhb[j] + rec[j]
        _backward_row(dh, gates[t, b], tanh_cells[t, b], cells[t, b], cells[t + 1, b], dc[b],
                      w_peep, dz, dct, d_bias, d_peep, nonneg)
        _narrow(dz_u, dg_bits[t, b])


@numba.njit(fastmath=True, cache=True, error_model="numpy")
def _fp32_backward_step(t, gates, cells, tanh_cells, w_peep, d_hidden, d_hn, rec, nonneg,
                        use_rec, dc, d_gates, d_bias, d_peep):
    """:func:`_bf16_backward_step` with a float32 product ``rec``, writing float32
    pre-activation gradients into ``d_gates[t]``."""
    _, B, _, H = gates.shape
    dh = np.empty(H, np.float32)
    dct = np.empty(H, np.float32)
    d_bias = d_bias.reshape(4 * H)
    for b in range(B):
        r = rec[b] if use_rec else d_hn[b]
        dhb = d_hidden[t, b]
        for j in range(H):
            dh[j] = dhb[j] + r[j]
        _backward_row(dh, gates[t, b], tanh_cells[t, b], cells[t, b], cells[t + 1, b], dc[b],
                      w_peep, d_gates[t, b], dct, d_bias, d_peep, nonneg)


def _forward_step_torch(t, z, bias, w_peep, gates, cells, tanh_cells, hidden, xh, nonneg):
    """The forward step kernels' math with torch ops, any dtype and device (the GPU path;
    the reference the numba kernels are tested against)."""
    B, H = cells.shape[1:]
    zf = z.view(B, 4, H).to(cells.dtype) + bias.view(4, H)
    c = cells[t]
    i_f = torch.sigmoid(zf[:, :2] + w_peep[:2] * c.unsqueeze(1))
    g = torch.tanh(zf[:, 2])
    c_new = i_f[:, 1] * c + i_f[:, 0] * g
    o = torch.sigmoid(zf[:, 3] + w_peep[2] * c_new)
    tc = torch.tanh(c_new)
    if nonneg:
        tc = torch.relu(tc)
    gates[t, :, :2] = i_f
    gates[t, :, 2] = g
    gates[t, :, 3] = o
    cells[t + 1] = c_new
    tanh_cells[t] = tc
    torch.mul(o, tc, out=hidden[t + 1])
    if t + 1 < xh.shape[0]:
        xh[t + 1, :, xh.shape[2] - H:] = hidden[t + 1]


def _backward_step_torch(t, gates, cells, tanh_cells, w_peep, d_hidden, d_hn, rec, nonneg,
                         use_rec, dc, dg_out, d_bias, d_peep):
    """The backward step kernels' math with torch ops, any dtype and device."""
    i, f, g, o = gates[t].unbind(1)
    tc, c_prev = tanh_cells[t], cells[t]
    dh = d_hidden[t] + (rec.to(d_hn.dtype) if use_rec else d_hn)
    do = dh * tc * o * (1 - o)
    slope = (1 - tc * tc) * (tc > 0) if nonneg else 1 - tc * tc
    dc += dh * o * slope + do * w_peep[2]
    di = dc * g * i * (1 - i)
    df = dc * c_prev * f * (1 - f)
    dg = dc * i * (1 - g * g)
    dc.mul_(f).add_(di * w_peep[0] + df * w_peep[1])
    dz = torch.stack([di, df, dg, do], 1)
    dg_out[t] = dz.view(dz.shape[0], -1)
    d_bias += dz.sum(0)
    d_peep += torch.stack([(di * c_prev).sum(0), (df * c_prev).sum(0),
                           (do * cells[t + 1]).sum(0)])


def _as_numpy(tensor):
    """A CPU tensor as numpy, bf16 as its int16 bit patterns (numba has no bfloat16)."""
    if tensor.dtype == torch.bfloat16:
        return tensor.view(torch.int16).numpy()
    return tensor.numpy()


class _FusedPeepholeLSTMFunction(torch.autograd.Function):
    """The training path: :class:`_PeepholeLSTMFunction`'s math, fused per step.

    ``apply(x, h0, c0, w_x, w_h, bias, w_peep, bf16, kernels, nonneg)``. Layout is batch-major,
    (T, B, 4, H) with gates i, f, g, o: one step's pre-activations are ONE (B, F+H) x
    (F+H, 4H) product of ``[x_t, h_{t-1}]`` (kept as a buffer ``xh`` in the matmul dtype)
    with ``[W_x, W_h]^T`` -- input projection and recurrence together -- and every weight
    gradient is one (4H, T B) x (T B, F+H) product after the loop, instead of T small
    ones. ``bf16``: the matmuls in bfloat16 (accumulated in float32 inside oneDNN, one
    rounding at the end), else in the inputs' dtype. The saved gates, cell states and h,
    the cell-gradient recurrence and the bias and peephole gradients stay in the inputs'
    dtype. ``kernels`` is "numba" (CPU, float32) or "torch" (any device and dtype; also
    the reference the numba kernels are tested against). ``nonneg``: ``h = o * relu(tanh
    c)`` (the non-negative variants of :mod:`.variants`).
    """

    @staticmethod
    def forward(ctx, x, h0, c0, w_x, w_h, bias, w_peep, bf16=False, kernels="numba",
                nonneg=False):
        T, B, F = x.shape
        H = w_h.shape[1]
        mm_dtype = torch.bfloat16 if bf16 else x.dtype
        w_cat = torch.cat([w_x, w_h], 1).to(mm_dtype)              # (4H, F+H)
        xh = x.new_empty(T, B, F + H, dtype=mm_dtype)              # [x_t, h_{t-1}]
        xh[:, :, :F] = x
        xh[0, :, F:] = h0
        gates = x.new_empty(T, B, 4, H)
        cells = x.new_empty(T + 1, B, H)       # cells[t] = c_{t-1}
        hidden = x.new_empty(T + 1, B, H)      # hidden[t] = h_{t-1}
        tanh_cells = x.new_empty(T, B, H)
        cells[0] = c0
        hidden[0] = h0
        z = x.new_empty(B, 4 * H, dtype=mm_dtype)
        w_t = w_cat.t().contiguous()         # a transposed view was 1.4x slower per step
        bias4, w_peep = bias.detach().view(4, H), w_peep.detach()
        arrays = (z, bias4, w_peep, gates, cells, tanh_cells, hidden, xh)
        nonneg = bool(nonneg)
        if kernels == "numba":
            step = _bf16_forward_step if bf16 else _fp32_forward_step
            arrays = tuple(_as_numpy(a) for a in arrays)
        else:
            step = _forward_step_torch
        for t in range(T):
            torch.mm(xh[t], w_t, out=z)
            step(t, *arrays, nonneg)
        ctx.save_for_backward(xh, w_x, w_h, w_peep, gates, cells, tanh_cells)
        ctx.bf16, ctx.kernels, ctx.nonneg = bf16, kernels, nonneg
        h_seq = hidden[1:]
        return h_seq, h_seq[-1].clone(), cells[-1].clone()

    @staticmethod
    @once_differentiable
    def backward(ctx, d_hidden, d_hn, d_cn):
        xh, w_x, w_h, w_peep, gates, cells, tanh_cells = ctx.saved_tensors
        T, B, _, H = gates.shape
        F = w_x.shape[1]
        mm_dtype = xh.dtype
        d_hidden = torch.zeros_like(tanh_cells) if d_hidden is None else d_hidden.contiguous()
        d_hn = torch.zeros_like(cells[0]) if d_hn is None else d_hn.contiguous()
        dc = d_cn.clone().contiguous() if d_cn is not None else torch.zeros_like(cells[0])
        w_h_mm = w_h.detach().to(mm_dtype).contiguous()               # (4H, H)
        d_gates = gates.new_empty(T, B, 4 * H, dtype=mm_dtype)
        rec = gates.new_zeros(B, H, dtype=mm_dtype)                 # dg_{t+1} W_h
        d_bias = gates.new_zeros(4, H)
        d_peep = gates.new_zeros(3, H)
        arrays = (gates, cells, tanh_cells, w_peep.detach(), d_hidden, d_hn, rec, ctx.nonneg)
        state = (dc, d_gates, d_bias, d_peep)
        if ctx.kernels == "numba":
            step = _bf16_backward_step if ctx.bf16 else _fp32_backward_step
            arrays = (*(_as_numpy(a) for a in arrays[:-1]), arrays[-1])
            state = tuple(_as_numpy(a) for a in state)
        else:
            step = _backward_step_torch
        for t in range(T - 1, -1, -1):
            step(t, *arrays, t < T - 1, *state)
            torch.mm(d_gates[t], w_h_mm, out=rec)
        dtype = gates.dtype
        dh0 = rec.to(dtype)
        dg_all = d_gates.view(T * B, 4 * H)
        d_w = torch.mm(dg_all.t(), xh.view(T * B, F + H)).to(dtype)   # [dW_x, dW_h]
        d_x = None
        if ctx.needs_input_grad[0]:
            d_x = torch.mm(dg_all, w_x.detach().to(mm_dtype)).to(dtype).view(T, B, F)
        return (d_x, dh0, dc, d_w[:, :F].contiguous(), d_w[:, F:].contiguous(),
                d_bias.view(4 * H), d_peep, None, None, None)


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
    precision : {"fp32", "bf16"}, default "fp32"
        Matmul precision of the training path. With "bf16", a forward pass that autograd
        records (and its backward) runs every matmul in bfloat16 -- on the CPU's AMX
        units -- while the cell state, the gate nonlinearities, h, the losses and all
        gradient accumulation stay float32; the parameters themselves stay float32 (Adam's
        master weights). With "fp32", such a pass on the CPU in float32 takes the fused
        float32 kernels (equal to the plain path up to rounding, ~1e-6 relative). A
        forward pass autograd does not record (under ``torch.no_grad()``: evaluation,
        validation, ``record``) always runs the plain float32 path, so a network behaves
        the same however it was trained.

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

    def __init__(self, input_size: int, hidden_size: int = 256, forget_bias: float = 1.0,
                 precision: str = "fp32"):
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
        self.precision = precision
        self.reset_parameters()

    @property
    def precision(self) -> str:
        """"fp32" or "bf16": the matmul precision of the training path (see class doc)."""
        return self._precision

    @precision.setter
    def precision(self, value: str):
        self._precision = check_option("precision", value, PRECISIONS)

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
        args = (x, h0, c0, self.weight_x, self.weight_h, self.bias, self.weight_peephole)
        recorded = torch.is_grad_enabled() and any(a.requires_grad for a in args)
        on_cpu = x.device.type == "cpu"
        if recorded and self.precision == "bf16":
            kernels = "numba" if on_cpu else "torch"
            h_seq, h_n, c_n = _FusedPeepholeLSTMFunction.apply(*args, True, kernels)
        elif recorded and on_cpu and x.dtype == torch.float32:
            h_seq, h_n, c_n = _FusedPeepholeLSTMFunction.apply(*args, False, "numba")
        elif recorded:
            h_seq, h_n, c_n = _PeepholeLSTMFunction.apply(*args)
        else:
            h_seq, h_n, c_n = _plain_inference(*args)
        return h_seq, (h_n, c_n)

    def extra_repr(self) -> str:
        return (f"{self.input_size}, hidden_size={self.hidden_size}, peepholes=True, "
                f"precision={self.precision!r}")


def peephole_step(xw_t, h, c, weight_h, bias, weight_peephole, nonneg: bool = False):
    """One step of the peephole LSTM (the equations above) by plain autograd, given the
    step's input projection ``x_t W_x^T``; with ``nonneg`` the output is ``o * relu(tanh
    c)`` (the non-negative variants of :mod:`.variants`)."""
    H = weight_h.shape[1]
    z = xw_t + h @ weight_h.t() + bias
    zi, zf, zg, zo = z.split(H, dim=1)
    i = torch.sigmoid(zi + weight_peephole[0] * c)
    f = torch.sigmoid(zf + weight_peephole[1] * c)
    c = f * c + i * torch.tanh(zg)
    o = torch.sigmoid(zo + weight_peephole[2] * c)
    squashed = torch.tanh(c)
    return o * (torch.relu(squashed) if nonneg else squashed), c


def reference_peephole_lstm(x, h0, c0, weight_x, weight_h, bias, weight_peephole):
    """Plain-autograd peephole LSTM (slow, obviously correct), for gradient checks."""
    h, c, out = h0, c0, []
    for t in range(x.shape[0]):
        h, c = peephole_step(x[t] @ weight_x.t(), h, c, weight_h, bias, weight_peephole)
        out.append(h)
    return torch.stack(out), h, c
