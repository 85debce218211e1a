"""The arena readout fitted as a convex problem (hippo_probe.paper.readout)."""

from dataclasses import replace

import numpy as np
import pytest

from hippo_probe.analysis.decode_environment import decoder_weights, fit_linear_decoder
from hippo_probe.paper import readout as R


def test_the_fit_recovers_a_known_separating_direction():
    rng = np.random.default_rng(0)
    direction = rng.normal(size=12)
    direction /= np.linalg.norm(direction)
    y = rng.integers(0, 2, 4000)
    # the classes differ along `direction` only; every unit has its own offset and scale
    x = rng.normal(size=(4000, 12)) + 1.5 * (2 * y[:, None] - 1) * direction
    scales = rng.uniform(0.5, 3, 12)
    x = x * scales + rng.normal(0, 5, 12)
    dec = fit_linear_decoder(x, y, c=1.0)
    assert dec.converged
    w, b = decoder_weights(dec)
    # on the raw features the folded weights give the pipeline's own decision
    logits = x @ w.T + b
    raw_pred = (logits[:, 0] > 0) if w.shape[0] == 1 else logits.argmax(1)
    assert np.array_equal(raw_pred.astype(int), dec.predict(x))
    # x = g * scale + offset with g the generating features: a readout of x with weights
    # w reads g with weights w * scale, which must point along the known direction
    back = w[0] * scales
    cos = abs(np.dot(back, direction)) / np.linalg.norm(back)
    assert cos > 0.95
    assert np.mean(dec.predict(x) == y) > 0.9


def test_a_warm_started_fit_reaches_the_same_optimum():
    rng = np.random.default_rng(1)
    y = rng.integers(0, 4, 600)
    x = rng.normal(size=(600, 6)) + np.eye(4, 6)[y] * 2
    cold = fit_linear_decoder(x, y, c=1.0, tol=1e-8)
    warm = fit_linear_decoder(x, y, c=1.0, tol=1e-8,
                              warm_from=fit_linear_decoder(x, y, c=0.1, tol=1e-8))
    np.testing.assert_allclose(decoder_weights(warm)[0], decoder_weights(cold)[0],
                               rtol=1e-3, atol=1e-3)


def test_the_leaky_average_is_a_normalized_exponential_mean():
    rng = np.random.default_rng(2)
    h = rng.normal(size=(30, 2, 3)).astype(np.float32)
    a = R.leaky_average(h, 0.4, 2.0)
    w = np.exp(-0.4 * np.arange(30) / 2.0)
    t = 17
    expect = (w[:t + 1][::-1, None, None] * h[:t + 1]).sum(0) / w[:t + 1].sum()
    np.testing.assert_allclose(a[t], expect, rtol=1e-5)
    np.testing.assert_allclose(a[0], h[0])
    const = np.full((10, 1, 1), 0.3, np.float32)
    np.testing.assert_allclose(R.leaky_average(const, 0.4, 50.0), const, rtol=1e-6)
    running = R.leaky_average(h, 0.4, np.inf)
    np.testing.assert_allclose(running[t], h[:t + 1].mean(0), rtol=1e-5)
    with pytest.raises(ValueError, match="`tau` must be > 0"):
        R.leaky_average(h, 0.4, 0.0)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    import torch

    from hippo_probe.model import ModelConfig, Navigator

    torch.manual_seed(0)
    net = Navigator(ModelConfig(hidden_size=8)).eval()
    cfg = replace(R.READOUT, block=20, sizes=(20, 40), n_validation=20, n_test=20,
                  c_grid=(0.1, 1.0), taus=(10.0,), curve_times=(40.0, 100.0, 200.0))
    folder = tmp_path_factory.mktemp("features")
    for split, n in (("validation", 20), ("test", 20), ("train", 40)):
        keys = R.extract_features({"tiny": net}, split, n, folder, world="darkness",
                                  cfg=cfg, progress=False)
    return net, cfg, folder, keys["tiny"]


def test_features_are_stored_by_block_and_not_recomputed(tiny):
    net, cfg, folder, key = tiny
    x, y, times = R.load_features(folder, key, "train", 40, "h", cfg)
    assert x.shape == (40, len(cfg.fit_times), 8) and y.shape == (40,)
    assert list(times) == list(cfg.fit_times) and y.max() < 100
    stamp = (folder / key / "train" / "block_00001.npz").stat().st_mtime_ns
    R.extract_features({"tiny": net}, "train", 40, folder, world="darkness", cfg=cfg,
                       progress=False)
    assert (folder / key / "train" / "block_00001.npz").stat().st_mtime_ns == stamp
    with pytest.raises(FileNotFoundError, match="extract them first"):
        R.load_features(folder, key, "train", 60, "h", cfg)


def test_a_partial_request_still_stores_whole_blocks(tiny, tmp_path):
    net, cfg, _, key = tiny
    R.extract_features({"tiny": net}, "train", 25, tmp_path, world="darkness", cfg=cfg,
                       progress=False)
    x, _, _ = R.load_features(tmp_path, key, "train", 25, "h", cfg)
    assert x.shape[0] == 25
    # the second block holds all its 20 trials, so 40 trials need nothing new
    whole, _, _ = R.load_features(tmp_path, key, "train", 40, "h", cfg)
    ref, _, _ = R.load_features(tiny[2], key, "train", 40, "h", cfg)
    np.testing.assert_array_equal(whole, ref)


def test_the_cache_key_changes_with_the_network_and_the_protocol(tiny):
    import torch

    net, cfg, _, key = tiny
    assert R.feature_key("tiny", net, "darkness", cfg) == key
    assert R.feature_key("tiny", net, "compass", cfg) != key
    assert R.feature_key("tiny", net, "darkness", replace(cfg, taus=(20.0,))) != key
    other = type(net)(net.config)
    with torch.no_grad():
        other.load_state_dict(net.state_dict())
        other.position.bias.add_(1e-3)
    assert R.feature_key("tiny", other, "darkness", cfg) != key


def test_times_off_the_step_grid_are_refused():
    with pytest.raises(ValueError, match="multiples of dt"):
        R._steps([10.0, 10.3], 0.4, 500)
    with pytest.raises(ValueError, match="within"):
        R._steps([400.0], 0.4, 500)
    assert list(R._steps([0.4, 200.0], 0.4, 500)) == [0, 499]


def test_the_learning_curve_on_a_tiny_recording(tiny):
    _, cfg, folder, key = tiny
    res = R.learning_curve(folder, key, ["h", "leaky_10"], cfg, progress=False)
    assert set(res["decoders"]) == {"h", "leaky_10"}
    for kind in ("h", "leaky_10"):
        rows = res["kinds"][kind]["rows"]
        assert [r["train_trials"] for r in rows] == [20, 40]
        for r in rows:
            assert r["c"] in cfg.c_grid and 1 <= len(r["path"]) <= 2
            assert len(r["test_accuracy"]) == len(cfg.curve_times)
            assert all(0 <= a <= 1 for a in r["test_accuracy"])


def test_the_exported_readout_gives_the_decoders_logits(tiny, tmp_path):
    import torch

    import hippo_probe as hp
    from hippo_probe.model.checkpoint import save_atomic
    from hippo_probe.training.trainer import save_network
    from hippo_probe.training import TrainConfig

    net, cfg, folder, key = tiny
    base = tmp_path / "base.pt"
    save_network(net, TrainConfig(task="generalized", hidden_size=8), {}, base)
    res = R.learning_curve(folder, key, ["h"], cfg, progress=False)
    dec = res["decoders"]["h"]
    save_atomic(R.readout_network(base, dec, description={"readout": "convex"}),
                tmp_path / "readout.pt")
    out = hp.load_pretrained(tmp_path / "readout.pt")
    x, _, _ = R.load_features(folder, key, "test", 20, "h", cfg)
    flat = x.reshape(-1, 8)
    with torch.no_grad():
        logits = out.classifier(torch.from_numpy(flat)).numpy()
    # rows are arena ids, whichever arenas the few training trials happened to visit
    assert logits.shape[1] == 100 and len(dec.classes_) < 100
    assert np.array_equal(logits.argmax(1), dec.predict(flat))
    np.testing.assert_allclose(logits[:, dec.classes_], dec.decision_function(flat),
                               atol=1e-4)


def test_a_readout_file_holds_its_classifier_and_refuses_another_network(tiny, tmp_path):
    import torch

    import hippo_probe as hp
    from hippo_probe.errors import CheckpointError
    from hippo_probe.model.checkpoint import load, save_atomic
    from hippo_probe.model.load import READOUT_OF
    from hippo_probe.training import TrainConfig
    from hippo_probe.training.trainer import save_network

    net, cfg, folder, key = tiny
    base = tmp_path / "tinynet_seed3.pt"
    save_network(net, TrainConfig(task="generalized", hidden_size=8), {}, base)
    dec = R.learning_curve(folder, key, ["h"], cfg, progress=False)["decoders"]["h"]
    readout = R.readout_network(base, dec, description={})
    assert set(readout["model"]) == {"classifier.weight", "classifier.bias"}
    assert readout[READOUT_OF]["name"] == "tinynet" and readout[READOUT_OF]["seed"] == 3
    save_atomic(readout, tmp_path / "readout.pt")
    loaded = hp.load_pretrained(tmp_path / "readout.pt")
    for k, v in net.state_dict().items():
        torch.testing.assert_close(loaded.state_dict()[k], v)
    # the network it was fitted on, changed: refused rather than read with other units
    changed = load(base)
    changed["model"] = {k: v + 1e-3 if k == "lstm.bias" else v
                        for k, v in changed["model"].items()}
    save_atomic(changed, base)
    with pytest.raises(CheckpointError, match="holds other parameters than those it was "
                                              "fitted on"):
        hp.load_pretrained(tmp_path / "readout.pt")
    # a network named by a path is not looked up
    save_atomic({**readout, READOUT_OF: {**readout[READOUT_OF], "name": "../tinynet"}},
                tmp_path / "escape.pt")
    with pytest.raises(CheckpointError, match="not named by a plain name"):
        hp.load_pretrained(tmp_path / "escape.pt")


def test_the_readout_figure_draws_the_curve_and_the_learning_curve(tiny):
    import matplotlib

    matplotlib.use("Agg")
    _, cfg, folder, key = tiny
    res = R.learning_curve(folder, key, ["h", "leaky_10"], cfg, progress=False)
    res.pop("decoders")
    res.update(network="tiny", leaky_tau_choice={"chosen": "leaky_10"})
    fig = R.plot_readout([res])
    left, right = fig.axes
    assert len(left.lines) >= 2 and right.get_xscale() == "log"
    assert left.get_xlabel() == "time in trial (s)"


def test_a_shipped_readout_finds_its_network_past_a_namesake_and_nowhere_else(tmp_path,
                                                                           monkeypatch):
    import shutil

    import hippo_probe as hp
    from hippo_probe.errors import CheckpointError
    from hippo_probe.model.checkpoint import load, save_atomic
    from hippo_probe.model.load import READOUT_OF
    from hippo_probe.pretrained import HERE

    shutil.copy(HERE / "generalized_readout.pt", tmp_path)
    # a user's own "generalized" beside it: not the network it was fitted on
    other = load(HERE / "generalized.pt")
    other["model"] = {k: v + 1e-3 if k == "lstm.bias" else v
                      for k, v in other["model"].items()}
    save_atomic(other, tmp_path / "generalized.pt")
    shipped = hp.load_pretrained("generalized_readout").state_dict()
    found = hp.load_pretrained(tmp_path / "generalized_readout.pt").state_dict()
    assert all((found[k] == v).all() for k, v in shipped.items())
    # a network that is neither beside it nor shipped is not looked for anywhere else
    readout = load(HERE / "generalized_readout.pt")
    save_atomic({**readout, READOUT_OF: {**readout[READOUT_OF], "name": "mynet"}},
                tmp_path / "mine.pt")
    (tmp_path / "cwd").mkdir()
    save_atomic(load(HERE / "generalized.pt"), tmp_path / "cwd" / "mynet")
    monkeypatch.chdir(tmp_path / "cwd")
    with pytest.raises(CheckpointError, match="found neither beside it nor among the "
                                              "shipped networks"):
        hp.load_pretrained(tmp_path / "mine.pt")


def _result(features, kind, sizes, acc):
    times = [float(t) for t in range(10, 201, 10)]
    rows = [{"train_trials": n, "c": 1.0, "path": [{"c": 1.0}], "test_accuracy": [a] * 20}
            for n, a in zip(sizes, acc)]
    return {"features": features, "network": features.split("-")[0], "sizes": sizes,
            "kinds": {kind: {"rows": rows, "times": times}}, "config": {"sizes": sizes},
            "fit_seconds": 10}


def test_a_later_size_or_kind_extends_the_learning_curve_and_replaces_its_own_size():
    old = _result("net-abc", "h", [4000, 16000], [0.2, 0.25])
    new = _result("net-abc", "h", [16000, 64000], [0.26, 0.3])
    new["kinds"].update(_result("net-abc", "leaky_200", [4000], [0.5])["kinds"])
    merged = R.merge_results(old, new)
    rows = merged["kinds"]["h"]["rows"]
    assert [r["train_trials"] for r in rows] == [4000, 16000, 64000]
    assert [r["test_accuracy"][-1] for r in rows] == [0.2, 0.26, 0.3]
    assert [r["train_trials"] for r in merged["kinds"]["leaky_200"]["rows"]] == [4000]
    assert merged["sizes"] == [4000, 16000, 64000]
    assert len(merged["runs"]) == 2 and merged["fit_seconds"] == 20
    assert [r["train_trials"] for r in old["kinds"]["h"]["rows"]] == [4000, 16000]
    with pytest.raises(ValueError, match="another network or protocol"):
        R.merge_results(old, _result("net-def", "h", [64000], [0.3]))


def test_the_seed_summary_gives_mean_and_range_per_size():
    results = [dict(_result(f"generalized_seed{k}-x", "h", [4000], [a]), world="darkness")
               for k, a in enumerate((0.1, 0.2, 0.6))]
    results.append(dict(_result("generalized_compass-x", "h", [4000], [0.05]),
                        world="compass"))
    table = R.seed_summary(results)
    assert ("| darkness | units h (the study's readout) | 4,000 | 3 | 0.300 (0.100–0.600) |"
            in table)
    assert "| compass | units h (the study's readout) | 4,000 | 1 | 0.050 (0.050–0.050) |" \
        in table


def test_the_shipped_log_measures_the_exported_weights_and_keeps_the_old_readouts(tiny,
                                                                                tmp_path):
    from hippo_probe.model.checkpoint import save_atomic
    from hippo_probe.training import TrainConfig
    from hippo_probe.training.trainer import save_network

    net, cfg, folder, key = tiny
    base = tmp_path / "base.pt"
    save_network(net, TrainConfig(task="generalized", hidden_size=8), {}, base)
    res = R.learning_curve(folder, key, ["h"], cfg, progress=False)
    save_atomic(R.readout_network(base, res["decoders"]["h"],
                                  description={"readout": "convex", "world": "darkness"}),
                tmp_path / "readout.pt")
    h = res["kinds"]["h"]
    row = h["rows"][-1]
    gradient = {"config": {"steps": 4000}, "steps_done": 2000, "stopped": {"step": 2000},
                "test": {"accuracy_200s": 0.13}}
    log = R.readout_log(tmp_path / "readout.pt", row, h["times"], n_test=cfg.n_test,
                        previous=gradient)
    # the trainer's evaluation of the shipped weights gives the fit's own test accuracy
    for t in (100, 200):
        assert log["test"][f"accuracy_{t}s"] == row["test_accuracy"][h["times"].index(t)]
    assert log["config"]["steps"] is None and log["fit"]["train_trials"] == row["train_trials"]
    assert log["replaces"] == {"readout": "gradient-trained", "steps_done": 2000,
                               "stopped": {"step": 2000}, "test": {"accuracy_200s": 0.13}}
    again = R.readout_log(tmp_path / "readout.pt", row, h["times"], n_test=cfg.n_test,
                          previous=log)
    assert again["replaces"] == log["replaces"]


def test_a_convex_readout_is_described_by_its_fit_not_by_steps(tmp_path):
    import json

    from hippo_probe.paper.results import _trained
    from hippo_probe.pretrained.summary import shipped_table

    assert _trained("generalized_readout", {"fit_trials": 64000, "fit_c": 10.0}) == \
        "generalized_readout fitted to convergence on 64,000 training trials (C = 10)"
    assert _trained("generalized", {"steps_done": 40000, "steps_budget": 40000,
                                    "finished": True}) == "generalized 40000 of 40000 steps"
    (tmp_path / "generalized_readout.pt").write_bytes(b"")
    log = {"config": {"steps": None, "world": "darkness"}, "fit": {"train_trials": 64000},
           "test": {"accuracy_200s": 0.25}, "wall_time_s": 3600.0}
    (tmp_path / "generalized_readout.log.json").write_text(json.dumps(log))
    row = shipped_table(["generalized_readout"], folder=tmp_path).iloc[0]
    assert row["steps"] == 0 and row["budget"] is None and row["accuracy_200s"] == 0.25
    assert row["hours"] == 1.0 and not row["stopped_early"]


def test_a_fit_the_solver_reports_unconverged_is_recorded_and_never_chosen(monkeypatch):
    import warnings

    from sklearn.exceptions import ConvergenceWarning
    from sklearn.linear_model import LogisticRegression

    rng = np.random.default_rng(3)
    y = rng.integers(0, 3, 300)
    x = (rng.normal(size=(300, 4)) + np.eye(3, 4)[y] * 2)[:, None, :].repeat(2, 1)
    fit = LogisticRegression.fit

    def line_search_fails_at_c_10(self, *args, **kwargs):
        out = fit(self, *args, **kwargs)
        if self.C == 10.0:            # as L-BFGS reports a failed line search
            warnings.warn("lbfgs failed to converge (status=2): ABNORMAL_TERMINATION_IN_"
                          "LNSRCH", ConvergenceWarning)
        return out

    monkeypatch.setattr(LogisticRegression, "fit", line_search_fails_at_c_10)
    cfg = replace(R.READOUT, c_grid=(1.0, 10.0), fit_times=(0.4, 0.8))
    best, c, path = R.fit_path(x, y, x, y, [0.4, 0.8], cfg)
    assert c == 1.0 and [p["converged"] for p in path] == [True, False]
    assert "ABNORMAL_TERMINATION_IN_LNSRCH" in path[1]["solver_message"]
    assert "solver_message" not in path[0]
    with pytest.raises(RuntimeError, match="no fit along C"):
        R.fit_path(x, y, x, y, [0.4, 0.8], replace(cfg, c_grid=(10.0,)))
