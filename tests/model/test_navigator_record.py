import numpy as np
import pytest
import torch

import hippo_probe as hp
from hippo_probe.model import ModelConfig, Navigator, input_scale_for
from hippo_probe.tasks import task_config


@pytest.fixture(scope="module")
def specialized_batch():
    return hp.tasks.make_trials("specialized", 3, "test", 0)


def test_input_scale_makes_inputs_order_one(specialized_batch):
    scale = np.array(input_scale_for(task_config("specialized").world))
    scaled = specialized_batch.inputs / scale
    rms = np.sqrt((scaled ** 2).mean(axis=(0, 1)))
    dx = specialized_batch.features.index("dx")
    assert 0.3 < rms[dx] < 3


def test_record_network_recording(specialized_batch):
    torch.manual_seed(0)
    net = Navigator(ModelConfig(hidden_size=8, n_classes=100))
    net.task = "specialized"
    rec = hp.record(net, specialized_batch)
    hp.validate(rec)
    T, B = specialized_batch.n_steps, len(specialized_batch)
    assert rec.sizes["time"] == T * B and rec.sizes["unit"] == 8
    assert rec.activity.dtype == np.float32
    # class probabilities sum to one; readout weights are the classifier's
    np.testing.assert_allclose(rec.class_probability.sum("environment_id"), 1, atol=1e-5)
    np.testing.assert_array_equal(rec.readout_weight.values,
                                  net.classifier.weight.detach().numpy())
    # activity of trial 1 equals running the network on that trial alone
    _, _, h = net(torch.from_numpy(specialized_batch.inputs[:, 1:2]))
    trial1 = rec.activity.where(rec.trial == specialized_batch.trial_index[1], drop=True)
    np.testing.assert_allclose(trial1.values, h[:, 0].detach().numpy(), atol=1e-6)
    np.testing.assert_array_equal(rec.environment_id.values, np.arange(100))


@pytest.mark.parametrize("n_classes", [100, 0])
@pytest.mark.parametrize("chunk", [1, 2, 250])
def test_a_recording_made_in_chunks_stacks_each_chunks_output(specialized_batch, chunk,
                                                             n_classes):
    """Chunks of trials copied into their rows: the arrays of the network run on each
    chunk, concatenated over trials and stacked trial after trial, in float32 (with and
    without an arena classifier)."""
    from hippo_probe.recording.layout import stack_trials
    torch.manual_seed(0)
    net = Navigator(ModelConfig(hidden_size=8, n_classes=n_classes))
    net.task = "specialized" if n_classes else "generalized"
    rec = hp.record(net, specialized_batch, chunk=chunk)
    inputs = specialized_batch.inputs
    with torch.no_grad():
        parts = [net(torch.from_numpy(inputs[:, lo:lo + chunk]))
                 for lo in range(0, inputs.shape[1], chunk)]
    h = torch.cat([part[2] for part in parts], dim=1).numpy()
    assert rec.activity.dtype == np.float32
    np.testing.assert_array_equal(rec.activity.values, stack_trials(h))
    if not n_classes:
        assert "class_probability" not in rec
        return
    logits = torch.cat([part[1] for part in parts], dim=1)
    assert rec.class_probability.dtype == np.float32
    np.testing.assert_array_equal(rec.class_probability.values,
                                  stack_trials(torch.softmax(logits, -1).numpy()))


def test_record_generalized_estimate_in_arena_frame():
    batch = hp.tasks.make_trials("generalized", 2, "test", 0)
    net = Navigator(ModelConfig(hidden_size=8))
    rec = hp.record(net, batch)
    xy, _, _ = net(torch.from_numpy(batch.inputs))
    expected = xy[:, 0].detach().numpy() + batch.start[0]
    got = rec.estimate.values[: batch.n_steps]
    np.testing.assert_allclose(got, expected, atol=1e-5)
    assert "class_probability" not in rec


def test_record_rejects_bad_baselines(specialized_batch):
    net = Navigator(ModelConfig(hidden_size=4))
    with pytest.raises(ValueError, match="baselines"):
        hp.record(net, specialized_batch, baselines={"estimate_xyz": np.zeros((500, 3, 2))})
    with pytest.raises(ValueError, match=r"must have shape \(500, 3"):
        hp.record(net, specialized_batch, baselines={"estimate_pf": np.zeros((10, 3, 2))})


def test_record_uses_the_frame_of_the_networks_own_task():
    """A localization network (arena-frame readout) recorded on generalized trials must
    not get the start added; a generalized network (start-relative readout) recorded on
    localization trials must."""
    net = Navigator(ModelConfig(hidden_size=4))
    gen = hp.tasks.make_trials("generalized", 2, "test", 0)
    xy, _, _ = net(torch.from_numpy(gen.inputs))
    net.task = "localization"
    rec = hp.record(net, gen)
    np.testing.assert_allclose(rec.estimate.values[:500], xy[:, 0].detach().numpy(),
                               atol=1e-5)
    loc = hp.tasks.make_trials("localization", 2, "test", 0)
    xy, _, _ = net(torch.from_numpy(loc.inputs))
    net.task = "generalized"
    rec = hp.record(net, loc)
    np.testing.assert_allclose(rec.estimate.values[:500],
                               xy[:, 0].detach().numpy() + loc.start[0], atol=1e-5)


def test_baselines_from_dataset_matches_trials(tmp_path):
    from hippo_probe.baselines.results import run_baselines
    from hippo_probe.model.record import baselines_from_dataset
    batch = hp.tasks.make_trials("generalized", 2, "test", 0)
    ds = run_baselines(batch, n_particles=50)
    arrays = baselines_from_dataset(ds, batch)
    assert arrays["estimate_pf"].shape == (500, 2, 2)
    # estimates are in the arena frame: PI from the true start is close early on
    assert np.abs(arrays["estimate_pi"][0] - batch.position[0]).max() < 0.05
    other = hp.tasks.make_trials("generalized", 2, "test", 1)
    with pytest.raises(ValueError, match="other trials"):
        baselines_from_dataset(ds, other)


def test_a_fitted_arena_readout_keeps_its_networks_position_frame():
    """generalized_readout is the generalized network with a classifier fitted on the
    specialized task: its (x, y) readout is still start-relative, so on the same trials
    its estimate is the generalized network's (it was the arena frame's, off by the
    start)."""
    gen = hp.load_pretrained("generalized")
    readout = hp.load_pretrained("generalized_readout")
    assert (readout.task, readout.position_task) == ("specialized", "generalized")
    assert gen.position_task == "generalized"
    batch = hp.tasks.make_trials("generalized", 3, "test", 0, world=gen.world)
    a = hp.record(gen, batch)
    with pytest.warns(UserWarning, match="class probabilities and arena readout"):
        b = hp.record(readout, batch)
    np.testing.assert_array_equal(a.activity.values, b.activity.values)
    # a shipped network is named by its file alone: the same on every machine
    assert (a.attrs["checkpoint"], b.attrs["checkpoint"]) == ("generalized.pt",
                                                              "generalized_readout.pt")
    np.testing.assert_allclose(b.estimate.values, a.estimate.values, atol=1e-6)


def test_a_classifier_recorded_outside_its_arenas_keeps_the_trials_arenas():
    """The specialized network on localization trials: its class probabilities name the
    specialized task's arenas, not the trial's, so they are left out (warned) and the
    environment table is the trials' own arena, whose outline bounds the maps."""
    net = hp.load_pretrained("specialized")
    loc = hp.tasks.make_trials("localization", 2, "test", 0, world=net.world)
    with pytest.warns(UserWarning, match="class probabilities and arena readout are left "
                                         "out"):
        rec = hp.record(net, loc)
    assert "class_probability" not in rec and "readout_weight" not in rec
    np.testing.assert_allclose(rec.arena_vertices.values[0], loc.arena_vertices[0])
    with pytest.raises(ValueError, match="class_probability"):
        hp.classification_accuracy(rec)
    # in its own arenas the classifier's table stays
    spec = hp.record(net, hp.tasks.make_trials("specialized", 2, "test", 0, world=net.world))
    assert spec.sizes["environment_id"] == 100 and "class_probability" in spec


def test_evaluate_scores_a_fitted_readout_in_its_networks_frame(capsys):
    from hippo_probe.cli import main
    errors = []
    for name in ("generalized", "generalized_readout"):
        assert main(["evaluate", name, "--task", "generalized", "--trials", "3",
                     "--no-progress"]) == 0
        out = capsys.readouterr().out
        errors.append(float(out.split('"mean_error_m": ')[1].split(",")[0]))
    assert errors[0] == errors[1]
