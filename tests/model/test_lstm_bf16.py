"""The bf16 training path of PeepholeLSTM against the float32 path.

Tolerances. bf16 keeps 8 significant bits: rounding an operand or a result costs a
relative error up to 2^-9 (2^-8 is the spacing). A step's pre-activations carry a few
such roundings (x, h and W rounded, the product rounded once after float32 accumulation),
so h_t is off by a relative ~2^-8 per step; the recurrence carries earlier errors forward,
which at most grows that like sqrt(T) (random-walk accumulation) and does not grow it at
all while the recurrence contracts, as it does at the initialisation scale used here
(measured: 0.0025-0.0031 at T = 5, 20, 80 and 320 alike). Gradients add the backward
recurrent product and the rounding of the weight-gradient product: measured 0.0014-0.005
over six seeds at T = 20 (norm-relative), h and c 0.002-0.004. Bounds: 2^-6 (0.016) for
outputs and 2^-5 (0.031) for gradients -- bf16 rounding with a 4-6x margin, so a real error
(one wrong term, as a double-counted dh at the last step was) fails them -- and a floor of
2^-12, so that the test fails if the bf16 path silently ran in float32 (error ~1e-7).
"""

import numpy as np
import pytest
import torch

from hippo_probe.model import ModelConfig, Navigator
from hippo_probe.model.lstm import (
    PeepholeLSTM,
    _FusedPeepholeLSTMFunction,
    _narrow,
    _PeepholeLSTMFunction,
    _tanh,
    _widen,
)

OUT_TOL, GRAD_TOL, FLOOR = 2.0 ** -6, 2.0 ** -5, 2.0 ** -12
NAMES = ("x", "h0", "c0", "weight_x", "weight_h", "bias", "weight_peephole")


def _args(T=20, B=4, F=9, H=16, seed=0):
    """Inputs of unit scale, weights at the module's initialisation scale 1/sqrt(H)."""
    g = torch.Generator().manual_seed(seed)
    shapes = [(T, B, F), (B, H), (B, H), (4 * H, F), (4 * H, H), (4 * H,), (3, H)]
    scales = [1, 0.5, 0.5] + [H ** -0.5] * 4
    return [(s * torch.randn(*shape, generator=g)).requires_grad_()
            for s, shape in zip(scales, shapes)]


def _outputs_and_grads(fn, args, *extra):
    out = fn.apply(*args, *extra)
    g = torch.Generator().manual_seed(99)
    w = [torch.randn(o.shape, generator=g) for o in out]   # a loss touching every output
    grads = torch.autograd.grad(sum((o * wi).sum() for o, wi in zip(out, w)), args)
    return [o.detach() for o in out], list(grads)


def _rel(a, b):
    return float((a - b).norm() / b.norm())


def test_bit_conversions_are_torchs_round_to_nearest_even():
    g = torch.Generator().manual_seed(0)
    v = torch.randn(200_000, generator=g) * torch.logspace(-40, 38, 200_000)
    # exact ties (the low 16 bits 0x8000) must round to even, as torch's cast does
    ties = (torch.arange(1000, dtype=torch.int32) << 16 | 0x8000) + (0x3F80 << 16)
    v = torch.cat([v, ties.view(torch.float32), torch.tensor([0.0, -0.0, 1e-45, -3e38])])
    bits = np.empty(v.numel(), np.int16)
    _narrow(v.numpy().view(np.uint32), bits)
    np.testing.assert_array_equal(bits, v.to(torch.bfloat16).view(torch.int16).numpy())
    wide = np.empty(v.numel(), np.uint32)
    _widen(bits, wide)
    np.testing.assert_array_equal(wide.view(np.float32),
                                  v.to(torch.bfloat16).float().numpy())


def test_rational_tanh_is_float32_accurate():
    x = np.linspace(-20, 20, 400_001).astype(np.float32)
    approx = np.array([_tanh(v) for v in x[::50]])
    assert np.abs(approx - np.tanh(x[::50].astype(np.float64))).max() < 5e-7


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_bf16_matches_fp32_within_bf16_tolerance(seed):
    args = _args(seed=seed)
    ref_out, ref_grads = _outputs_and_grads(_PeepholeLSTMFunction, args)
    out, grads = _outputs_and_grads(_FusedPeepholeLSTMFunction, args, True, "numba")
    for name, a, b in zip(("h_seq", "h_n", "c_n"), out, ref_out):
        assert FLOOR < _rel(a, b) < OUT_TOL, name
    for name, a, b in zip(NAMES, grads, ref_grads):
        assert FLOOR < _rel(a, b) < GRAD_TOL, name


def test_numba_kernels_match_the_torch_kernels():
    """The fused CPU kernels compute what the plain torch version (the GPU path) does.
    Not bit-equal: the kernels' rational tanh and fused multiply-adds differ from torch's
    in the last float32 bits, which can flip a bf16 rounding now and then."""
    args = _args(T=12, seed=3)
    out_n, grads_n = _outputs_and_grads(_FusedPeepholeLSTMFunction, args, True, "numba")
    out_t, grads_t = _outputs_and_grads(_FusedPeepholeLSTMFunction, args, True, "torch")
    for a, b in zip(out_n + grads_n, out_t + grads_t):
        assert _rel(a, b) < 2.0 ** -12          # measured <= 2.5e-7


def test_bf16_path_without_input_gradient_and_single_step():
    x, *rest = _args(T=1, seed=4)
    x = x.detach()
    out = torch.autograd.grad(_FusedPeepholeLSTMFunction.apply(x, *rest, True, "numba")[0].sum(),
                              rest)
    ref = torch.autograd.grad(_PeepholeLSTMFunction.apply(x, *rest)[0].sum(), rest)
    for a, b in zip(out, ref):
        assert _rel(a, b) < GRAD_TOL


def test_module_runs_bf16_only_when_autograd_records():
    torch.manual_seed(0)
    fp32 = PeepholeLSTM(9, hidden_size=16)
    bf16 = PeepholeLSTM(9, hidden_size=16, precision="bf16")
    bf16.load_state_dict(fp32.state_dict())
    x = torch.randn(15, 3, 9)
    with torch.no_grad():                 # evaluation / record: float32, bit for bit
        plain = fp32(x)[0]
        torch.testing.assert_close(bf16(x)[0], plain, rtol=0, atol=0)
    h_fp32, h_bf16 = fp32(x)[0].detach(), bf16(x)[0]
    assert h_bf16.requires_grad and FLOOR < _rel(h_bf16.detach(), h_fp32) < OUT_TOL
    h_bf16.sum().backward()               # parameters and their gradients stay float32
    assert all(p.dtype == p.grad.dtype == torch.float32 for p in bf16.parameters())
    for p in bf16.parameters():           # nothing to differentiate: plain float32 again
        p.requires_grad_(False)
    torch.testing.assert_close(bf16(x)[0], plain, rtol=0, atol=0)


def test_precision_is_checked_and_plumbed():
    with pytest.raises(ValueError, match="`precision` must be one of 'fp32', 'bf16'"):
        PeepholeLSTM(9, 4, precision="fp16")
    with pytest.raises(ValueError, match="`precision`"):
        ModelConfig(precision="half")
    lstm = PeepholeLSTM(9, 4)
    with pytest.raises(ValueError, match="`precision`"):
        lstm.precision = "bfloat16"
    net = Navigator(ModelConfig(hidden_size=8, precision="bf16"))
    assert net.lstm.precision == "bf16" and "precision='bf16'" in repr(net)
    assert all(v.dtype == torch.float32 for v in net.state_dict().values())
