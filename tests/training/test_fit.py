import json
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings

import numpy as np
import pytest
import torch

import hippo_probe as hp
from hippo_probe.errors import CheckpointError
from hippo_probe.training import TrainConfig, class_weight_rule, fit
from hippo_probe.training.data import TrainingTrials

# float32 named explicitly: these tests stay float32 whichever precision is the default
TINY = dict(task="specialized", n_trials=48, steps=6, batch_size=8, hidden_size=8,
            validate_every=3, n_validation=8, n_test=8, threads=1, precision="fp32")


def _params(path):
    return torch.load(path, weights_only=False)["model"]


def _assert_same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        torch.testing.assert_close(a[k], b[k], rtol=0, atol=0)


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory):
    d = tmp_path_factory.mktemp("run")
    log = fit(TrainConfig(**TINY), d / "run", cache_dir=d / "cache", progress=False)
    return d, log


def test_training_log_and_files(uninterrupted):
    d, log = uninterrupted
    run = d / "run"
    assert {"checkpoint.pt", "network.pt", "log.json"} <= {p.name for p in run.iterdir()}
    saved = json.loads((run / "log.json").read_text())
    assert saved["config"]["steps"] == 6 and len(saved["train"]) == 6
    assert [v["step"] for v in saved["validation"]] == [0, 3, 6]
    for key in ("package_version", "torch_version", "command", "wall_time_s", "test",
                "class_weight"):
        assert key in saved
    assert "/" not in saved["command"].split(" ")[0]  # no path of the trainer's machine
    assert all(e["grad_norm"] >= 0 for e in saved["train"])
    # the class weight follows the rule: half the squared error at chance
    val = hp.tasks.make_trials("specialized", 8, "validation", 0)
    assert saved["class_weight"] == pytest.approx(
        class_weight_rule(float(np.mean(val.target ** 2)), 100))
    net = hp.load_pretrained(run / "network.pt")
    assert net.task == "specialized" and net.classifier.out_features == 100


def test_resume_after_interruption_gives_identical_parameters(uninterrupted, tmp_path):
    d, _ = uninterrupted
    config = TrainConfig(**TINY)
    fit(config, tmp_path / "run", cache_dir=d / "cache", progress=False, stop_after=4)
    assert torch.load(tmp_path / "run" / "checkpoint.pt", weights_only=False)["step"] == 4
    log = fit(config, tmp_path / "run", cache_dir=d / "cache", progress=False)
    assert log["resumed_at"] == [4]
    _assert_same(_params(tmp_path / "run" / "network.pt"), _params(d / "run" / "network.pt"))
    # the checkpoint keeps the LAST parameters: they too must be identical
    _assert_same(_params(tmp_path / "run" / "checkpoint.pt"),
                 _params(d / "run" / "checkpoint.pt"))
    ref = json.loads((d / "run" / "log.json").read_text())
    assert [e["loss"] for e in log["train"]] == [e["loss"] for e in ref["train"]]


@pytest.fixture(scope="module")
def uninterrupted_bf16(tmp_path_factory):
    d = tmp_path_factory.mktemp("run_bf16")
    log = fit(TrainConfig(**{**TINY, "precision": "bf16"}), d / "run",
              cache_dir=d / "cache", progress=False)
    return d, log


def test_resumed_bf16_run_equals_an_uninterrupted_one(uninterrupted, uninterrupted_bf16,
                                                      tmp_path):
    d, log_bf16 = uninterrupted_bf16
    config = TrainConfig(**{**TINY, "precision": "bf16"})
    fit(config, tmp_path / "run", cache_dir=d / "cache", progress=False, stop_after=4)
    log = fit(config, tmp_path / "run", cache_dir=d / "cache", progress=False)
    assert log["resumed_at"] == [4]
    for name in ("network.pt", "checkpoint.pt"):
        _assert_same(_params(tmp_path / "run" / name), _params(d / "run" / name))
    assert [e["loss"] for e in log["train"]] == [e["loss"] for e in log_bf16["train"]]
    # the precision is in the log and the checkpoint; parameters are float32 regardless
    saved = json.loads((d / "run" / "log.json").read_text())
    assert saved["config"]["precision"] == saved["model_config"]["precision"] == "bf16"
    ckpt = torch.load(d / "run" / "checkpoint.pt", weights_only=False)
    assert ckpt["config"]["precision"] == "bf16"
    assert all(v.dtype == torch.float32 for v in ckpt["model"].values())
    # bf16 training really ran (its losses differ from float32's) but validation and test
    # are float32 evaluations: the shipped network behaves the same whatever trained it
    fp32_log = uninterrupted[1]
    assert [e["loss"] for e in log_bf16["train"]] != [e["loss"] for e in fp32_log["train"]]
    assert log_bf16["train"][0]["loss"] == pytest.approx(fp32_log["train"][0]["loss"],
                                                         rel=2.0 ** -6)
    net = hp.load_pretrained(d / "run" / "network.pt")
    assert net.lstm.precision == "fp32" and net.info["config"]["precision"] == "bf16"


def test_a_run_resumed_in_another_precision_logs_each_stretch(uninterrupted, tmp_path):
    """bf16 and fp32 differ only in rounding, so a run may move between machines with and
    without bf16 units; the log says which precision made which steps."""
    d, _ = uninterrupted
    fit(TrainConfig(**TINY), tmp_path / "run", cache_dir=d / "cache", progress=False,
        stop_after=3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # bf16 emulated on this CPU
        log = fit(TrainConfig(**{**TINY, "precision": "bf16"}), tmp_path / "run",
                  cache_dir=d / "cache", progress=False)
    assert log["precision_from_step"] == [[0, "fp32"], [3, "bf16"]]
    assert log["train"][-1]["step"] == TINY["steps"]
    # a finished run started again (the training queue re-tests it) on the other kind of
    # machine trains no step: it gains no empty stretch
    log = fit(TrainConfig(**TINY), tmp_path / "run", cache_dir=d / "cache", progress=False)
    assert log["precision_from_step"] == [[0, "fp32"], [3, "bf16"]]
    # and the network and checkpoint it saves name the precision that trained its last
    # steps, not the re-testing machine's
    net = hp.load_pretrained(tmp_path / "run" / "network.pt")
    assert net.info["config"]["precision"] == "bf16"
    ckpt = torch.load(tmp_path / "run" / "checkpoint.pt", weights_only=False)
    assert ckpt["config"]["precision"] == "bf16"
    # a checkpoint written before `precision` existed was trained in float32
    old = TrainConfig(**TINY).to_dict()
    del old["precision"]
    assert TrainConfig.from_dict(old).precision == "fp32"
    with pytest.raises(ValueError, match="`precision` must be one of"):
        TrainConfig(precision="fp16")


def test_auto_precision_is_bf16_exactly_where_the_cpu_has_bf16_units(tmp_path):
    from hippo_probe.model.config import native_bf16, resolve_precision

    assert TrainConfig().precision == "auto"
    assert resolve_precision("auto") == ("bf16" if native_bf16() else "fp32")
    assert resolve_precision("fp32") == "fp32"
    log = fit(TrainConfig(**{**TINY, "precision": "auto", "steps": 1}), tmp_path / "run",
              cache_dir=tmp_path / "cache", progress=False)
    assert log["config"]["precision"] == resolve_precision("auto")


def test_train_command_takes_precision(uninterrupted, tmp_path):
    from hippo_probe.cli import build_parser, main
    d, _ = uninterrupted
    args = ["train", "--task", "specialized", "--trials", "16", "--steps", "2",
            "--batch-size", "8", "--hidden-size", "8", "--validate-every", "2",
            "--validation-trials", "8", "--test-trials", "8", "--no-progress",
            "--cache-dir", str(d / "cache"), "--out", str(tmp_path / "run")]
    assert build_parser().parse_args(args).precision == TrainConfig().precision
    assert main([*args, "--precision", "bf16"]) == 0
    saved = json.loads((tmp_path / "run" / "log.json").read_text())
    assert saved["config"]["precision"] == "bf16"


def test_kill_and_resume(uninterrupted, tmp_path):
    """A training process killed with SIGKILL resumes from its last atomic checkpoint and
    finishes with the same parameters as a run that was never interrupted."""
    d, _ = uninterrupted
    run = tmp_path / "run"
    code = textwrap.dedent(f"""
        from hippo_probe.training import TrainConfig, fit
        cfg = TrainConfig(**{dict(TINY, steps=12, checkpoint_minutes=1e-9)!r})
        fit(cfg, {str(run)!r}, cache_dir={str(d / 'cache')!r}, progress=False)
    """)
    proc = subprocess.Popen([sys.executable, "-c", code])
    ckpt = run / "checkpoint.pt"
    deadline = time.time() + 120
    while time.time() < deadline:
        if ckpt.exists():
            try:
                if torch.load(ckpt, weights_only=False)["step"] >= 3:
                    break
            except Exception:
                pass
        time.sleep(0.05)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    killed_at = torch.load(ckpt, weights_only=False)["step"]
    assert 3 <= killed_at < 12
    # the 0-byte temporary torch.save leaves when killed before writing (planted, as the
    # kill may land between writes): removed by the resumed run's first checkpoint
    from hippo_probe import _atomic
    (run / f".checkpoint.pt{_atomic.PARTIAL}{_atomic._HOST}-{proc.pid}-0.pt").touch()
    cfg = TrainConfig(**dict(TINY, steps=12, checkpoint_minutes=1e-9))
    log = fit(cfg, run, cache_dir=d / "cache", progress=False)
    assert log["resumed_at"][0] == killed_at
    # no temporaries left; .lock is the run folder's lock file, kept on purpose (removing
    # it on release would let two trainers lock two different files)
    assert not [p.name for p in run.iterdir() if p.name.startswith(".") and p.name != ".lock"]
    reference = fit(cfg, tmp_path / "ref", cache_dir=d / "cache", progress=False)
    _assert_same(_params(run / "network.pt"), _params(tmp_path / "ref" / "network.pt"))
    _assert_same(_params(run / "checkpoint.pt"), _params(tmp_path / "ref" / "checkpoint.pt"))
    assert reference["test"] == log["test"]
    assert [e["loss"] for e in log["train"]] == [e["loss"] for e in reference["train"]]


def test_train_command_stopped_by_sigterm_checkpoints_and_resumes(uninterrupted, tmp_path):
    """`kill` (SIGTERM) stops a `hippo-probe train` job at a step boundary with a
    checkpoint of that step, though no periodic checkpoint was due, and the job ends as
    killed; resumed, the run is the run that was never stopped."""
    d, _ = uninterrupted
    run = tmp_path / "run"
    command = [sys.executable, "-m", "hippo_probe.cli", "train", "--task", "specialized",
               "--out", str(run), "--cache-dir", str(d / "cache"), "--trials", "48",
               "--steps", "100000", "--batch-size", "8", "--hidden-size", "8",
               "--validate-every", "1000", "--validation-trials", "8", "--test-trials", "8",
               "--threads", "1", "--precision", "fp32", "--checkpoint-minutes", "600",
               "--snapshot-every", "2", "--no-progress"]
    with open(tmp_path / "stderr.txt", "w") as stderr:
        proc = subprocess.Popen(command, stderr=stderr)
        first = run / "snapshots" / "step_000002.pt"      # it is training
        deadline = time.time() + 120
        while not first.exists() and proc.poll() is None and time.time() < deadline:
            time.sleep(0.05)
        assert first.exists(), "no training step"
        assert not (run / "checkpoint.pt").exists()
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=120)
    err = (tmp_path / "stderr.txt").read_text()
    assert proc.returncode == -signal.SIGTERM, err
    assert "resumes from" in err and "Traceback" not in err
    stopped_at = torch.load(run / "checkpoint.pt", weights_only=False)["step"]
    assert stopped_at >= 2
    assert not [p.name for p in run.rglob(".*") if p.name != ".lock"]
    # the command's configuration, resumed for two more steps, against a run never stopped
    cfg = TrainConfig(**dict(TINY, steps=100000, validate_every=1000, checkpoint_minutes=600,
                             snapshot_every=2))
    log = fit(cfg, run, cache_dir=d / "cache", progress=False, stop_after=2)
    assert log["resumed_at"] == [stopped_at]
    reference = fit(cfg, tmp_path / "ref", cache_dir=d / "cache", progress=False,
                    stop_after=stopped_at + 2)
    _assert_same(_params(run / "checkpoint.pt"), _params(tmp_path / "ref" / "checkpoint.pt"))
    assert [e["loss"] for e in log["train"]] == [e["loss"] for e in reference["train"]]


def test_a_stop_requested_ends_the_run_at_a_step_boundary(uninterrupted, tmp_path):
    """What Ctrl-C and `kill` ask through `stop_requested`: the run stops before a step,
    with a checkpoint of the steps it trained, and resumes to the run never stopped."""
    d, _ = uninterrupted
    asked = iter([False, False, False, True])
    with pytest.raises(KeyboardInterrupt):
        fit(TrainConfig(**TINY), tmp_path / "run", cache_dir=d / "cache", progress=False,
            stop_requested=lambda: next(asked))
    ckpt = torch.load(tmp_path / "run" / "checkpoint.pt", weights_only=False)
    assert ckpt["step"] == 3 and len(ckpt["log"]["train"]) == 3
    log = fit(TrainConfig(**TINY), tmp_path / "run", cache_dir=d / "cache", progress=False)
    _assert_same(_params(tmp_path / "run" / "network.pt"),
                 _params(d / "run" / "network.pt"))
    assert [e["loss"] for e in log["train"]] == [e["loss"] for e in uninterrupted[1]["train"]]


def test_resume_refuses_another_configuration(uninterrupted):
    d, _ = uninterrupted
    with pytest.raises(ValueError, match=r"another configuration \(lr: checkpoint 0.001"):
        fit(TrainConfig(**dict(TINY, lr=0.5)), d / "run", cache_dir=d / "cache",
            progress=False)
    # an option left at its default (None) reads as such, not as Python's None
    with pytest.raises(ValueError, match=r"class_weight: checkpoint not set, got 2\.0\)"):
        fit(TrainConfig(**dict(TINY, class_weight=2.0)), d / "run", cache_dir=d / "cache",
            progress=False)


def test_training_moves_the_parameters(uninterrupted):
    d, log = uninterrupted
    ckpt = torch.load(d / "run" / "checkpoint.pt", weights_only=False)
    torch.manual_seed(TINY.get("init_seed", 0))
    from hippo_probe.training import build_network
    init = build_network(TrainConfig(**TINY)).state_dict()
    moved = max((ckpt["model"][k] - init[k]).abs().max().item() for k in init)
    assert moved > 1e-4


def test_export_and_readout_retraining(uninterrupted, tmp_path):
    d, _ = uninterrupted
    from hippo_probe.training import export_network
    pt, js = export_network(d / "run", "tiny_spec", dest=tmp_path)
    net = hp.load_pretrained(pt)
    assert net.info["finished"] and net.info["steps_done"] == TINY["steps"]
    assert json.loads(js.read_text())["steps_done"] == TINY["steps"]
    # readout retraining: only the classifier changes
    cfg = TrainConfig(**dict(TINY, init_from=str(pt), train_only="classifier", steps=2))
    fit(cfg, tmp_path / "readout", cache_dir=d / "cache", progress=False)
    new = torch.load(tmp_path / "readout" / "checkpoint.pt", weights_only=False)["model"]
    old = torch.load(pt, weights_only=False)["model"]
    for k in old:
        if k.startswith("classifier."):
            assert not torch.equal(new[k], old[k])
        else:
            torch.testing.assert_close(new[k], old[k], rtol=0, atol=0)
    log = json.loads((tmp_path / "readout" / "log.json").read_text())
    assert log["base_network"]["file"] == pt.name and log["class_weight"] == 1.0
    assert log["base_network"]["init_from"] == str(pt)
    # shipped beside the network it reads, the readout holds its classifier alone
    from hippo_probe.model.load import READOUT_OF
    ro, _ = export_network(tmp_path / "readout", "tiny_spec_readout", dest=tmp_path)
    saved = torch.load(ro, weights_only=False)
    assert set(saved["model"]) == {"classifier.weight", "classifier.bias"}
    assert saved[READOUT_OF]["name"] == "tiny_spec" and ro.stat().st_size < pt.stat().st_size
    loaded = hp.load_pretrained(ro).state_dict()
    for k, v in new.items():
        torch.testing.assert_close(loaded[k], v, rtol=0, atol=0)


@pytest.mark.parametrize("steps,every", [(6, 1), (500, 1), (501, 2), (40_000, 81)])
def test_a_shipped_training_log_is_thinned_keeping_first_and_last(steps, every):
    from hippo_probe.training import export
    train = [{"step": s} for s in range(1, steps + 1)]
    kept, k = export._thin(train)
    assert k == every and len(kept) <= export.MAX_TRAIN_ENTRIES
    assert kept[0]["step"] == 1 and kept[-1]["step"] == steps
    assert all(b["step"] - a["step"] <= every for a, b in zip(kept, kept[1:]))


def test_readout_retraining_needs_the_specialized_task():
    with pytest.raises(ValueError, match="specialized task"):
        TrainConfig(task="generalized", train_only="classifier", init_from="x")
    with pytest.raises(ValueError, match="needs `init_from`"):
        TrainConfig(task="specialized", train_only="classifier")


def test_training_order_is_a_function_of_the_step_only():
    a = TrainingTrials("specialized", 2500, 64, init_seed=3)
    b = TrainingTrials("specialized", 2500, 64, init_seed=3)
    steps = [0, 5, 38, 39, 40, 77]
    got = [a.indices(s) for s in steps]
    for s, idx in zip(reversed(steps), reversed(got)):
        np.testing.assert_array_equal(b.indices(s), idx)
    # an epoch visits every trial once (up to the last partial batch)
    epoch = np.concatenate([a.indices(s) for s in range(a.batches_per_epoch)])
    assert len(np.unique(epoch)) == len(epoch) == 2500 // 64 * 64


def test_bad_configs_and_checkpoints(tmp_path):
    with pytest.raises(ValueError, match="`task` must be one of"):
        TrainConfig(task="flying")
    with pytest.raises(ValueError, match="`steps` must be > 0"):
        TrainConfig(steps=0)
    with pytest.raises(CheckpointError, match="existing file"):
        hp.load_pretrained(tmp_path / "missing.pt")
    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"not a checkpoint")
    with pytest.raises(CheckpointError, match="not a readable"):
        hp.load_pretrained(bad)
    with pytest.raises(ValueError, match="shipped networks"):
        hp.load_pretrained("no-such-network")


def test_a_network_knows_its_world(uninterrupted, tmp_path):
    """A run trains in its world (darkness by default) and ships it with the network;
    shipped networks made before the darkness world are the compass world's; a readout
    retrained in one world refuses a base network of the other."""
    d, _ = uninterrupted
    from hippo_probe.training import export_network
    pt, _ = export_network(d / "run", "tiny_world", dest=tmp_path)
    assert hp.load_pretrained(pt).world == "darkness"
    assert hp.load_pretrained(d / "run" / "checkpoint.pt").world == "darkness"
    assert hp.load_pretrained("generalized_compass").world == "compass"
    cfg = TrainConfig(**dict(TINY, world="compass", init_from=str(pt),
                             train_only="classifier", steps=1))
    with pytest.raises(ValueError, match="trained in the 'darkness' world; this run is of "
                                         "the 'compass' world"):
        fit(cfg, tmp_path / "readout", cache_dir=d / "cache", progress=False)
    with pytest.raises(ValueError, match="`world` must be one of"):
        TrainConfig(world="moon")
    # logs of runs from before the world existed read as compass runs
    assert TrainConfig.from_dict({"task": "generalized"}).world == "compass"


def test_a_named_network_not_in_this_installation_is_a_clear_error(tmp_path, monkeypatch):
    import hippo_probe.pretrained as pretrained

    # an installation without networks: a wheel (no compass-world ablation) or a version
    # whose training has not finished
    monkeypatch.setattr(pretrained, "HERE", tmp_path)
    with pytest.raises(ValueError, match="'generalized_compass' is not in this installation "
                                         r"\(the compass-world ablation networks come with "
                                         "a clone"):
        hp.load_pretrained("generalized_compass")
    with pytest.raises(ValueError, match=r"'generalized' is not in this installation \(its "
                                         r"training has not finished\)"):
        hp.load_pretrained("generalized")


@pytest.mark.parametrize("name", ["../outside", "", ".hidden", "a/b", None])
def test_export_refuses_a_name_that_is_not_a_plain_file_name(uninterrupted, tmp_path, name):
    from hippo_probe.training import export_network
    d, _ = uninterrupted
    with pytest.raises(ValueError, match="`name` must be letters"):
        export_network(d / "run", name, dest=tmp_path / "dest")
    assert not (tmp_path / "outside.pt").exists() and not (tmp_path / "dest").exists()


def test_export_replaces_an_exported_network_only_when_told(uninterrupted, tmp_path, capsys):
    from hippo_probe.cli import main
    from hippo_probe.training import export_network
    d, _ = uninterrupted
    pt, js = export_network(d / "run", "tiny_kept", dest=tmp_path)
    before, log = _params(pt), js.read_text()
    pt.write_bytes(b"stands for a shipped network")
    with pytest.raises(FileExistsError, match="`name` 'tiny_kept': .* exist\\(s\\); pass "
                                              r"overwrite=True \(--overwrite\)"):
        export_network(d / "run", "tiny_kept", dest=tmp_path)
    pt.rename(tmp_path / "aside.pt")              # its log alone is refused too
    with pytest.raises(FileExistsError, match="tiny_kept.log.json exist"):
        export_network(d / "run", "tiny_kept", dest=tmp_path)
    (tmp_path / "aside.pt").rename(pt)
    argv = ["export-network", str(d / "run"), "tiny_kept", "--dest", str(tmp_path)]
    assert main(argv) == 2 and "exist(s)" in capsys.readouterr().err
    assert pt.read_bytes() == b"stands for a shipped network"
    assert main([*argv, "--overwrite"]) == 0
    _assert_same(_params(pt), before)
    assert js.read_text() == log


def test_evaluate_refuses_no_trials_and_a_broken_network(uninterrupted, tmp_path, capsys):
    from hippo_probe.cli import main
    from hippo_probe.training import export_network
    from hippo_probe.model.checkpoint import save_atomic
    d, _ = uninterrupted
    pt, _ = export_network(d / "run", "tiny_eval", dest=tmp_path)
    assert main(["evaluate", str(pt), "--trials", "0"]) == 2
    assert "argument --trials: must be a whole number >= 1; got 0" in \
        capsys.readouterr().err
    obj = torch.load(pt, weights_only=True)
    obj["model"] = {k: torch.full_like(v, float("nan")) for k, v in obj["model"].items()}
    save_atomic(obj, tmp_path / "nan.pt")         # a NaN network, intact as a file
    assert main(["evaluate", str(tmp_path / "nan.pt"), "--trials", "2"]) == 2
    assert "non-finite results" in capsys.readouterr().err


def _validations(losses, every=500):
    return [{"step": every * i, "loss": v} for i, v in enumerate(losses)]


def test_stop_reason_follows_the_last_fifth_rule():
    from hippo_probe.training.trainer import stop_reason
    config = TrainConfig(**TINY)
    # 5,000 steps; the last fifth is 4,000-5,000: best 1.0 before, 0.995 in it (0.5%)
    flat = _validations([3.0, 2.0, 1.5, 1.2, 1.1, 1.05, 1.02, 1.01, 1.0, 0.999, 0.995])
    assert "0.50%" in stop_reason(config, flat, 5000, 0.0)
    # the same run improving by 2% over its last fifth goes on
    falling = flat[:-2] + [{"step": 4500, "loss": 0.99}, {"step": 5000, "loss": 0.98}]
    assert stop_reason(config, falling, 5000, 0.0) is None
    # too early to judge, or the rule switched off
    assert stop_reason(config, flat[:4], 1500, 0.0) is None
    # an early plateau of a long budget is not judged before a quarter of it
    long_budget = TrainConfig(**{**TINY, "steps": 40000})
    assert stop_reason(long_budget, flat, 5000, 0.0) is None
    plateau_then_flat = flat + _validations([0.995] * 22)[11:]
    assert "0.00%" in stop_reason(long_budget, plateau_then_flat, 10500, 0.0)
    assert stop_reason(TrainConfig(**{**TINY, "stop_improvement": None}), flat, 5000,
                       0.0) is None
    # the wall-time cap, whatever the curve
    assert stop_reason(TrainConfig(**{**TINY, "max_hours": 1}), falling, 5000,
                       3601.0).startswith("max_hours")


def test_a_run_past_its_hour_cap_stops_tested_and_exportable(tmp_path):
    # a cap of ~0 hours: the run stops at its first validation (step 0 is validated, then
    # checked), is tested, and saves its network
    config = TrainConfig(**{**TINY, "max_hours": 1e-9})
    log = fit(config, tmp_path / "run", cache_dir=tmp_path / "cache", progress=False)
    assert log["stopped"]["step"] == 0 and log["stopped"]["reason"].startswith("max_hours")
    assert "test" in log and (tmp_path / "run" / "network.pt").exists()
    from hippo_probe.training.export import export_network
    export_network(tmp_path / "run", "tiny", tmp_path / "shipped")
    shipped = json.loads((tmp_path / "shipped" / "tiny.log.json").read_text())
    assert shipped["finished"] is True and shipped["steps_done"] == 0


def test_the_stopping_rule_may_change_on_resume():
    a = TrainConfig(**TINY)
    b = TrainConfig(**{**TINY, "stop_improvement": None, "max_hours": 3.0})
    assert a.differences(b) == {}
    with pytest.raises(ValueError, match="stop_improvement"):
        TrainConfig(**{**TINY, "stop_improvement": 2.0})


def test_a_stopped_run_resumed_stops_again_or_trains_on_without_its_old_verdict(tmp_path):
    run, cache = tmp_path / "run", tmp_path / "cache"
    capped = TrainConfig(**{**TINY, "max_hours": 1e-9})
    fit(capped, run, cache_dir=cache, progress=False)
    # the same rules: it stops where it stood, without training a step more
    again = fit(capped, run, cache_dir=cache, progress=False)
    assert again["stopped"]["step"] == 0 and len(again["train"]) == 0
    # the cap lifted: it trains to its budget and no longer says it stopped
    done = fit(TrainConfig(**TINY), run, cache_dir=cache, progress=False)
    assert "stopped" not in done and len(done["train"]) == 6 and "test" in done
    # the log describes the rules the run was last trained under, and each resume
    saved = json.loads((run / "log.json").read_text())
    assert saved["config"]["max_hours"] is None
    assert [r["changed"] for r in saved["resumes"]] == [{}, {"max_hours": [1e-9, None]}]
    assert all(r["step"] == 0 and r["command"] for r in saved["resumes"])


def test_a_run_being_trained_by_another_process_is_refused(tmp_path, monkeypatch):
    """The same command started twice would checkpoint over the first one's progress."""
    import fcntl

    from hippo_probe.errors import RunInUseError
    from hippo_probe.training import trainer

    def started(*args):
        raise AssertionError("the second trainer got past the lock")

    run = tmp_path / "run"
    run.mkdir()
    with open(run / ".lock", "a+") as held:        # another trainer's lock
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        held.write("4242")
        held.flush()
        # refused before anything else starts (trial cache, threads, process group), so
        # a second trainer started while the first is still starting cannot slip in
        with monkeypatch.context() as m:
            m.setattr(trainer, "_fit_pinned", started)
            with pytest.raises(RunInUseError, match=r"being trained by another process "
                                                    r"\(pid 4242\)"):
                fit(TrainConfig(**TINY), run, cache_dir=tmp_path / "cache", progress=False)
        assert not (run / "checkpoint.pt").exists()
    # released (as by the holder's death), the run trains
    fit(TrainConfig(**{**TINY, "steps": 1}), run, cache_dir=tmp_path / "cache",
        progress=False)
    assert (run / "checkpoint.pt").exists()


def test_a_resumed_warm_restart_equals_an_uninterrupted_one(uninterrupted, tmp_path):
    """Continuing a trained network with a fresh schedule (``init_from``) resumes exactly,
    and its snapshots are the parameters at their steps."""
    d, _ = uninterrupted
    base = d / "run" / "network.pt"
    warm = dict(TINY, init_from=str(base), lr=3e-4, lr_final=3e-5, snapshot_every=2)
    fit(TrainConfig(**warm), tmp_path / "whole", cache_dir=d / "cache", progress=False)
    fit(TrainConfig(**warm), tmp_path / "parts", cache_dir=d / "cache", progress=False,
        stop_after=3)
    log = fit(TrainConfig(**warm), tmp_path / "parts", cache_dir=d / "cache",
              progress=False)
    assert log["resumed_at"] == [3]
    assert log["base_network"]["file"] == "network.pt"
    for name in ("network.pt", "checkpoint.pt"):
        _assert_same(_params(tmp_path / "parts" / name), _params(tmp_path / "whole" / name))
    snaps = sorted(p.name for p in (tmp_path / "whole" / "snapshots").iterdir())
    assert snaps == ["step_000002.pt", "step_000004.pt", "step_000006.pt"]
    for name in snaps:
        _assert_same(_params(tmp_path / "parts" / "snapshots" / name),
                     _params(tmp_path / "whole" / "snapshots" / name))
    # the last snapshot holds the last parameters; the first differs from the base
    _assert_same(_params(tmp_path / "whole" / "snapshots" / snaps[-1]),
                 _params(tmp_path / "whole" / "checkpoint.pt"))
    first = _params(tmp_path / "whole" / "snapshots" / snaps[0])
    assert not torch.equal(first["lstm.weight_h"], _params(base)["lstm.weight_h"])
    assert hp.load_pretrained(tmp_path / "whole" / "snapshots" / snaps[0]).task == "specialized"


def test_a_finished_run_without_its_checkpoint_is_not_overwritten(uninterrupted, tmp_path):
    import shutil as sh

    d, _ = uninterrupted
    run = tmp_path / "run"
    sh.copytree(d / "run", run)
    (run / "checkpoint.pt").unlink()          # pruned, as the queue does once shipped
    before = (run / "network.pt").read_bytes()
    with pytest.raises(FileExistsError, match=r"holds \['network.pt', 'log.json'\] .* no "
                                              r"checkpoint.pt"):
        fit(TrainConfig(**TINY), run, cache_dir=d / "cache", progress=False)
    assert (run / "network.pt").read_bytes() == before
    fit(TrainConfig(**{**TINY, "steps": 3}), run, cache_dir=d / "cache", progress=False,
        overwrite=True)
    assert (run / "network.pt").read_bytes() != before
