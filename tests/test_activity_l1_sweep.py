"""The L1 sweep's summary (analyses/activity_l1_sweep.py): the weight-choosing rule, and
the script end to end on two tiny runs."""

import json

import pytest


@pytest.fixture(scope="module")
def sweep(analysis_script):
    return analysis_script("activity_l1_sweep")


def test_the_largest_weight_within_the_tolerance_is_kept(sweep):
    rows = [{"weight": w, "best_validation_error_m": e}
            for w, e in ((0, 0.100), (0.01, 0.104), (0.1, 0.109), (1, 0.150))]
    assert sweep.choose(rows, 0.10) == 0.1
    assert sweep.choose(rows, 0.05) == 0.01
    assert sweep.choose(rows[1:], 0.10) is None           # no unpenalised run to compare


def test_the_sweep_summarises_finished_runs(sweep, tmp_path, monkeypatch):
    from hippo_probe.training import TrainConfig, fit

    for weight in (0.0, 0.5):
        config = TrainConfig(task="generalized", variant="nonneg", activity_l1=weight,
                             n_trials=16, steps=2, batch_size=4, hidden_size=8,
                             validate_every=2, n_validation=4, n_test=4)
        fit(config, tmp_path / f"l1_{weight}", cache_dir=tmp_path / "cache", progress=False)
    (tmp_path / "unfinished").mkdir()
    out = tmp_path / "out"
    monkeypatch.setattr("sys.argv", ["activity_l1_sweep.py", str(tmp_path / "l1_0.0"),
                                     str(tmp_path / "l1_0.5"), str(tmp_path / "unfinished"),
                                     "--trials", "2", "--out", str(out)])
    sweep.main()
    result = json.loads((out / "sweep.json").read_text())
    assert [r["weight"] for r in result["rows"]] == [0.0, 0.5]
    for row in result["rows"]:
        assert 0 <= row["fraction_silent"] <= 1 and row["mean_activity"] >= 0
        assert 0 < row["population_sparseness"] <= 1
    assert result["kept"] in (0.0, 0.5)
    assert "(kept)" in (out / "sweep.md").read_text()
    assert (out / "sweep.png").stat().st_size > 1000
