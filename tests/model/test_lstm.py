import pytest
import torch

from hippo_probe.model.lstm import (
    PeepholeLSTM,
    _FusedPeepholeLSTMFunction,
    _PeepholeLSTMFunction,
    _plain_inference,
    peephole_step,
    reference_peephole_lstm,
    reused_buffers,
)


def _args(T=6, B=3, F=4, H=5, seed=0, dtype=torch.float64):
    g = torch.Generator().manual_seed(seed)
    shapes = [(T, B, F), (B, H), (B, H), (4 * H, F), (4 * H, H), (4 * H,), (3, H)]
    return [torch.randn(*s, generator=g, dtype=dtype).requires_grad_() for s in shapes]


def test_gradcheck_against_finite_differences():
    assert torch.autograd.gradcheck(_PeepholeLSTMFunction.apply, _args())


def test_forward_and_gradients_match_plain_autograd_reference():
    args = _args(T=20, B=4, F=3, H=7, seed=1)
    fast = _PeepholeLSTMFunction.apply(*args)
    ref = reference_peephole_lstm(*args)
    for a, b in zip(fast, ref):
        torch.testing.assert_close(a, b, rtol=1e-12, atol=1e-12)
    # gradient of a loss touching every output (sequence, final h and c)
    w = [torch.randn_like(o) for o in fast]
    grads_fast = torch.autograd.grad(sum((o * wi).sum() for o, wi in zip(fast, w)), args)
    grads_ref = torch.autograd.grad(sum((o * wi).sum() for o, wi in zip(ref, w)), args)
    for a, b in zip(grads_fast, grads_ref):
        torch.testing.assert_close(a, b, rtol=1e-10, atol=1e-10)


def _fused(*args, kernels="torch"):
    """The fused training path with matmuls in the inputs' dtype."""
    return _FusedPeepholeLSTMFunction.apply(*args, False, kernels)


def _outputs_and_grads(fn, args):
    out = fn(*args)
    g = torch.Generator().manual_seed(99)
    # drawn in float64 whatever the outputs' dtype, so both precisions get the same loss
    w = [torch.randn(o.shape, generator=g, dtype=torch.float64).to(o.dtype) for o in out]
    grads = torch.autograd.grad(sum((o * wi).sum() for o, wi in zip(out, w)), args)
    return [o.detach() for o in out] + list(grads)


def _rel(a, b):
    return float((a.double() - b.double()).norm() / b.double().norm())


def test_fused_path_gradcheck_against_finite_differences():
    # the fused layout's math (batch-major, one matmul a step), in float64 via its torch
    # kernels; the numba kernels are float32 and checked against it below
    assert torch.autograd.gradcheck(_fused, _args())


def test_fused_float32_kernels_match_the_plain_path():
    """The training path's numba kernels against the plain Function in float64: the same
    math up to float32 rounding and the kernels' rational tanh (3.4e-7)."""
    args64 = _args(T=40, B=4, F=3, H=16, seed=3)
    with torch.no_grad():
        for w in args64[3:]:
            w.mul_(16 ** -0.5)                       # the module's initialisation scale
    args32 = [a.detach().float().requires_grad_() for a in args64]
    ref = _outputs_and_grads(_PeepholeLSTMFunction.apply, args64)
    numba = _outputs_and_grads(lambda *a: _fused(*a, kernels="numba"), args32)
    torch_kernels = _outputs_and_grads(_fused, args32)
    for a, b, r in zip(numba, torch_kernels, ref):
        assert _rel(a, r) < 2e-6 and _rel(b, r) < 2e-6     # measured <= 3.4e-7


def test_module_trains_through_the_fused_path_and_infers_through_the_plain_one():
    torch.manual_seed(0)
    lstm = PeepholeLSTM(9, hidden_size=16)
    x = torch.randn(15, 3, 9)
    zeros = torch.zeros(3, 16)
    params = (lstm.weight_x, lstm.weight_h, lstm.bias, lstm.weight_peephole)
    h = lstm(x)[0]
    fused = _fused(x, zeros, zeros, *params, kernels="numba")[0]
    torch.testing.assert_close(h, fused, rtol=0, atol=0)
    with torch.no_grad():
        plain = _PeepholeLSTMFunction.apply(x, zeros, zeros, *params)[0]
        torch.testing.assert_close(lstm(x)[0], plain, rtol=0, atol=0)
    assert not torch.equal(h.detach(), plain)      # two paths, differing in rounding only
    assert _rel(h.detach(), plain) < 1e-6


@pytest.mark.parametrize("B", [250, 37])
def test_inference_path_is_the_plain_path_bit_for_bit(B):
    """A recording's forward pass (no autograd: no per-step cells, two (B, H) cell
    buffers taking turns) gives the whole-sequence Function's h, h_T and c_T exactly, at
    the study's width and a recording's batch of trials (and an odd one)."""
    torch.manual_seed(1)
    lstm = PeepholeLSTM(9, hidden_size=256)
    x = torch.randn(40, B, 9)
    h0, c0 = 0.1 * torch.randn(B, 256), 0.1 * torch.randn(B, 256)
    params = (lstm.weight_x, lstm.weight_h, lstm.bias, lstm.weight_peephole)
    with torch.no_grad():
        whole = _PeepholeLSTMFunction.apply(x, h0, c0, *params)
        stepped = _plain_inference(x, h0, c0, *params)
    for a, b in zip(stepped, whole):
        assert torch.equal(a, b)


def test_reused_buffers_hold_h_until_the_next_pass_only_inside_the_block():
    torch.manual_seed(2)
    lstm = PeepholeLSTM(9, hidden_size=32)
    x1, x2 = torch.randn(20, 5, 9), torch.randn(20, 5, 9)
    with torch.no_grad():
        alone = [lstm(x) for x in (x1, x2)]
        apart = [lstm(x)[0] for x in (x1, x2)]
        with reused_buffers():
            first, (first_h, first_c) = lstm(x1)
            kept = first.clone()
            second = lstm(x2)[0]
            third = lstm(torch.randn(20, 4, 9))[0]        # another shape: new buffers
        after = lstm(x1)[0]
    assert apart[0].data_ptr() != apart[1].data_ptr()
    assert second.data_ptr() == first.data_ptr() != third.data_ptr()
    assert after.data_ptr() not in (first.data_ptr(), third.data_ptr())
    assert torch.equal(kept, alone[0][0]) and torch.equal(second, alone[1][0])
    assert not torch.equal(first, kept)           # the first h, overwritten by the second
    # the final state is not reused: still the first pass's
    assert torch.equal(first_h, alone[0][1][0]) and torch.equal(first_c, alone[0][1][1])


def _nonneg_reference(x, h, c, w_x, w_h, bias, w_peep):
    """Plain autograd of the non-negative cell, ``h = o * relu(tanh c)``."""
    out = []
    for t in range(x.shape[0]):
        h, c = peephole_step(x[t] @ w_x.t(), h, c, w_h, bias, w_peep, nonneg=True)
        out.append(h)
    return torch.stack(out), h, c


def test_the_non_negative_fused_path_is_the_non_negative_cell():
    """``nonneg`` in the fused training path: finite differences in float64 (its torch
    kernels), and the numba kernels in float32 against plain autograd of the same cell."""
    nonneg = (False, "torch", True)
    assert torch.autograd.gradcheck(
        lambda *a: _FusedPeepholeLSTMFunction.apply(*a, *nonneg), _args(seed=5))
    args64 = _args(T=40, B=4, F=3, H=16, seed=3)
    with torch.no_grad():
        for w in args64[3:]:
            w.mul_(16 ** -0.5)
    args32 = [a.detach().float().requires_grad_() for a in args64]
    ref = _outputs_and_grads(_nonneg_reference, args64)
    numba = _outputs_and_grads(
        lambda *a: _FusedPeepholeLSTMFunction.apply(*a, False, "numba", True), args32)
    assert (ref[0] == 0).float().mean() > 0.2        # the cut is exercised
    for a, r in zip(numba, ref):
        assert _rel(a, r) < 2e-6
    # and it is not the faithful cell
    faithful = _outputs_and_grads(lambda *a: _fused(*a, kernels="numba"), args32)
    assert _rel(faithful[0], ref[0]) > 0.1


def test_peepholes_matter():
    args = _args(seed=2)
    out1 = _PeepholeLSTMFunction.apply(*args)[0]
    args[-1] = torch.zeros_like(args[-1])
    out2 = _PeepholeLSTMFunction.apply(*args)[0]
    assert (out1 - out2).abs().max() > 1e-3


def test_module_shapes_state_and_forget_bias():
    lstm = PeepholeLSTM(9, hidden_size=16)
    assert torch.all(lstm.bias[16:32] == 1.0) and torch.all(lstm.bias[:16] == 0.0)
    x = torch.randn(7, 2, 9)
    h_seq, (h, c) = lstm(x)
    assert h_seq.shape == (7, 2, 16) and h.shape == c.shape == (2, 16)
    torch.testing.assert_close(h, h_seq[-1])
    # continuing from the final state equals running the whole sequence at once
    first, state = lstm(x[:4])
    second, _ = lstm(x[4:], state)
    torch.testing.assert_close(torch.cat([first, second]), h_seq)
    assert h_seq.abs().max() < 1


@pytest.mark.parametrize("bad", [(7, 2, 8), (7, 9)])
def test_bad_input_shape(bad):
    with pytest.raises(ValueError, match="`x` must have shape"):
        PeepholeLSTM(9, 4)(torch.zeros(bad))


def test_bad_sizes():
    with pytest.raises(ValueError, match="hidden_size"):
        PeepholeLSTM(9, 0)
