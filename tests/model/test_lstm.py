import pytest
import torch

from hippo_probe.model.lstm import PeepholeLSTM, _PeepholeLSTMFunction, reference_peephole_lstm


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
