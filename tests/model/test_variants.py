"""The model variants beyond the study: each option changes only what it says."""

import numpy as np
import pytest
import torch

import hippo_probe as hp
from hippo_probe.model import ModelConfig, Navigator
from hippo_probe.model.variants import PlaceCellReadout, VariantLSTM
from hippo_probe.training import TrainConfig, fit


def _net(variant, hidden=16):
    torch.manual_seed(0)
    return Navigator(ModelConfig(hidden_size=hidden, variant=variant))


@pytest.mark.parametrize("variant", ["nonneg", "dale"])
def test_non_negative_outputs_are_non_negative_and_otherwise_the_same_cell(variant):
    net = _net(variant)
    x = torch.randn(30, 4, 9)
    _, _, h = net(x)
    assert (h >= 0).all() and (h > 0).any()
    # the same parameters as a faithful cell: where tanh(c) > 0 the outputs agree step 1
    faithful = _net("faithful")
    faithful.load_state_dict({k: v for k, v in net.state_dict().items()
                              if not k.endswith("sign")}, strict=False)
    if variant == "nonneg":
        _, _, h_f = faithful(x[:1])
        np.testing.assert_allclose(h[:1].detach(), torch.relu(h_f).detach(), atol=1e-6)


@pytest.mark.parametrize("variant", ["nonneg", "dale"])
def test_variants_train_through_the_fused_kernels_and_infer_through_the_plain_step(variant):
    """Training (autograd recording) takes the fused kernels, with Dale's weights as the
    recurrent weights; inference the plain step: the same cell up to rounding."""
    net = _net(variant)
    x = torch.randn(25, 3, 9)
    h_train = net.lstm(x)[0]
    with torch.no_grad():
        h_infer = net.lstm(x)[0]
    assert not torch.equal(h_train.detach(), h_infer)         # two paths
    torch.testing.assert_close(h_train.detach(), h_infer, rtol=0, atol=2e-6)
    # gradients reach the recurrent parameter through the sign mask as by plain autograd
    h_train.sum().backward()
    fused_grad = net.lstm.weight_h.grad.clone()
    net.zero_grad()
    from hippo_probe.model.lstm import peephole_step
    h, c, w_h = torch.zeros(3, 16), torch.zeros(3, 16), net.lstm.recurrent_weight()
    total = 0
    for t in range(25):
        h, c = peephole_step(x[t] @ net.lstm.weight_x.t(), h, c, w_h, net.lstm.bias,
                             net.lstm.weight_peephole, nonneg=True)
        total = total + h.sum()
    total.backward()
    torch.testing.assert_close(fused_grad, net.lstm.weight_h.grad, rtol=1e-4, atol=1e-5)


def test_the_dale_mask_keeps_every_units_outgoing_signs_through_an_optimizer_step():
    net = _net("dale")
    sign = net.lstm.sign
    assert (sign < 0).sum() == round(0.2 * 16)
    opt = torch.optim.Adam(net.parameters(), lr=0.5)      # a large step
    for _ in range(3):
        xy, _, h = net(torch.randn(20, 4, 9))
        (xy.square().mean() + h.mean()).backward()
        opt.step()
        opt.zero_grad()
    w = net.lstm.recurrent_weight().detach()
    # column j holds unit j's outgoing weights: one sign per column, the mask's
    assert ((w * sign[None, :]) >= 0).all()


def test_place_cell_targets_sum_to_one_and_decode_to_the_position():
    readout = PlaceCellReadout(8, n=2000, width=0.05, extent=0.66, seed=0)
    xy = torch.tensor([[0.0, 0.0], [0.2, -0.1], [-0.3, 0.25]])
    q = readout.targets(xy)
    torch.testing.assert_close(q.sum(-1), torch.ones(3))
    # the target population, read as a softmax, decodes back to the position (inside the
    # centres' disk, where the cells are dense)
    decoded = q @ readout.centres
    torch.testing.assert_close(decoded, xy, atol=0.01, rtol=0)
    assert readout.loss(torch.zeros(3, 8), xy) > 0


def test_a_variant_trains_saves_and_records_under_its_name(tmp_path):
    config = TrainConfig(task="generalized", variant="placecells", n_trials=16, steps=2,
                         batch_size=4, hidden_size=8, validate_every=2, n_validation=4,
                         n_test=4, precision="fp32")
    fit(config, tmp_path / "run", cache_dir=tmp_path / "cache", progress=False)
    net = hp.load_pretrained(tmp_path / "run" / "network.pt")
    assert net.config.variant == "placecells"
    assert isinstance(net.position, PlaceCellReadout)
    rec = hp.record(net, hp.tasks.make_trials("generalized", 2, "test", 0))
    assert rec.place_cell_readout_weight.dims == ("place_cell", "unit")
    l1 = TrainConfig(task="generalized", variant="nonneg", activity_l1=0.1, n_trials=16,
                     steps=2, batch_size=4, hidden_size=8, validate_every=2,
                     n_validation=4, n_test=4)
    log = fit(l1, tmp_path / "nonneg", cache_dir=tmp_path / "cache", progress=False)
    assert log["config"]["variant"] == "nonneg" and log["config"]["activity_l1"] == 0.1
    assert isinstance(hp.load_pretrained(tmp_path / "nonneg" / "network.pt").lstm,
                      VariantLSTM)
    with pytest.raises(ValueError, match="`variant` must be one of"):
        TrainConfig(variant="grid")


def test_the_dale_mask_follows_the_networks_init_seed():
    masks = []
    for seed in (0, 0, 1):
        torch.manual_seed(seed)
        masks.append(VariantLSTM(9, 64, dale=True).sign.clone())
    assert torch.equal(masks[0], masks[1]) and not torch.equal(masks[0], masks[2])
    assert all((m < 0).sum() == round(0.2 * 64) for m in masks)


def test_the_place_cell_outputs_validation_loss_is_its_training_objective():
    from hippo_probe.tasks import make_trials
    from hippo_probe.training.trainer import (_position_cost_at_chance, evaluate_network,
                                              losses)

    net = _net("placecells")
    batch = make_trials("generalized", 3, "validation", 0)
    m = evaluate_network(net, batch)
    with torch.no_grad():
        terms = losses(net, batch.inputs, batch.target, batch.environment, 0.0)
    # what the best network is chosen by is the cross-entropy trained on, not the
    # decoded position's squared error
    assert m["loss"] == pytest.approx(float(terms.position), rel=1e-5)
    assert m["mse"] == pytest.approx(float(terms.mse), rel=1e-5)
    assert m["loss"] != pytest.approx(m["mse"], rel=0.1)
    # at chance the cross-entropy's reachable part is ln n - H(q), between 0 and ln n
    cost = _position_cost_at_chance(net, batch.target)
    assert 0 < cost < np.log(net.config.n_place_cells)
    faithful = _net("faithful")
    assert _position_cost_at_chance(faithful, batch.target) == pytest.approx(
        float(np.mean(batch.target.astype(np.float32) ** 2)), rel=1e-6)


def test_the_place_cell_decoding_floor_is_the_one_documented():
    """Noise-free targets decode about 2.5 cm off (ModelConfig.place_cell_width)."""
    from hippo_probe.model import ModelConfig

    c = ModelConfig(variant="placecells")
    readout = PlaceCellReadout(8, c.n_place_cells, c.place_cell_width,
                               c.place_cell_extent, seed=0)
    xy = torch.from_numpy(np.random.default_rng(0).uniform(-0.5, 0.5, (20000, 2))
                          .astype(np.float32))
    off = (readout.targets(xy) @ readout.centres - xy).norm(dim=-1)
    assert 0.02 < float(off.mean()) < 0.03 and float(off.quantile(0.95)) < 0.06


def test_the_shipped_non_negative_variant_records_non_negative_sparse_units():
    net = hp.load_pretrained("generalized_nonneg")
    assert (net.config.variant, net.world) == ("nonneg", "darkness")
    assert net.info["config"]["activity_l1"] == 1.0
    rec = hp.record(net, hp.tasks.make_trials("generalized", 2, "test", 0))
    rates = rec.activity.values
    assert rates.min() >= 0.0
    # the L1 cost leaves most units silent and the rest sparse
    assert np.mean(rates.max(axis=0) < 1e-3) > 0.3


def test_the_variants_reference_is_the_studys_network_at_their_budget():
    from hippo_probe.pretrained.summary import shipped_table

    table = shipped_table(["generalized_faithful", "generalized_nonneg", "generalized_dale",
                           "generalized_placecells"])
    assert table.loc[("generalized_faithful", 0), "variant"] == "faithful"
    # one budget for the reference and every variant, trained to its end
    assert set(table["budget"]) == {20000} and set(table["steps"]) == {20000}
    assert not table["stopped_early"].any()
    net = hp.load_pretrained("generalized_faithful")
    assert (net.config.variant, net.world) == ("faithful", "darkness")


def test_the_shipped_dale_variant_keeps_its_signs_and_non_negative_units():
    net = hp.load_pretrained("generalized_dale")
    assert (net.config.variant, net.world) == ("dale", "darkness")
    assert net.info["config"]["activity_l1"] == 1.0
    sign = net.lstm.sign
    # 80% of the units excitatory, 20% inhibitory, and every unit's outgoing weights of
    # its own sign after 20,000 steps of training
    assert int((sign < 0).sum()) == round(0.2 * sign.numel())
    w = net.lstm.recurrent_weight().detach()
    assert ((w * sign[None, :]) >= 0).all()
    rec = hp.record(net, hp.tasks.make_trials("generalized", 2, "test", 0))
    assert rec.activity.values.min() >= 0.0


def test_the_shipped_place_cell_variant_decodes_positions_from_its_place_cells():
    net = hp.load_pretrained("generalized_placecells")
    assert (net.config.variant, net.world) == ("placecells", "darkness")
    assert isinstance(net.position, PlaceCellReadout)
    rec = hp.record(net, hp.tasks.make_trials("generalized", 2, "test", 0))
    assert rec.place_cell_readout_weight.dims == ("place_cell", "unit")
    # the place cells' decoded centre localizes: a median error of centimetres (the test
    # split's mean is 0.09 m), far below the arena's size
    error = np.hypot(*(rec.estimate - rec.position).values.T)
    assert np.median(error) < 0.2
