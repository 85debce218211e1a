"""The shipped networks' table (hippo_probe.pretrained.summary, `hippo-probe networks`):
read from the training logs, spread over seeds as mean (min–max)."""

import json

import numpy as np
import pytest

from hippo_probe.pretrained.summary import (
    markdown,
    per_seed_text,
    seed_spread,
    shipped_table,
    training_log,
)


def _ship(folder, name, seed, errors, accuracy=None, stopped=None, steps=40000,
          variant=None):
    stem = name if seed == 0 else f"{name}_seed{seed}"
    (folder / f"{stem}.pt").write_bytes(b"")          # only its presence is read here
    test = {f"error_{t}s_m": e for t, e in zip((50, 100, 200), errors)}
    if accuracy:
        test |= {f"accuracy_{t}s": a for t, a in zip((50, 100, 200), accuracy)}
    (folder / f"{stem}.log.json").write_text(json.dumps({
        "config": {"steps": steps, "world": "darkness", "variant": variant}, "test": test,
        "validation": [{"step": 250}, {"step": stopped or steps}],
        "stopped": {"step": stopped, "reason": "stop_improvement"} if stopped else None,
        "wall_time_s": 7200.0}))


def test_spread_over_seeds(tmp_path):
    _ship(tmp_path, "specialized", 0, (0.06, 0.05, 0.04), (0.5, 0.7, 0.9))
    _ship(tmp_path, "specialized", 2, (0.08, 0.07, 0.06), (0.7, 0.9, 1.0), stopped=12000)
    _ship(tmp_path, "localization", 0, (0.2, 0.1, 0.1))
    table = shipped_table(["localization", "specialized", "generalized"], folder=tmp_path)
    assert list(table.index) == [("localization", 0), ("specialized", 0), ("specialized", 2)]
    assert table.loc[("specialized", 2), "steps"] == 12000
    assert table.loc[("specialized", 2), "stopped_early"]
    assert not table.loc[("specialized", 0), "stopped_early"]
    assert table.loc[("specialized", 0), "hours"] == pytest.approx(2.0)
    assert np.isnan(table.loc[("localization", 0), "accuracy_200s"])

    spread = seed_spread(table)
    assert spread.loc["specialized", "seeds"] == "0, 2"
    assert spread.loc["specialized", "error_200s_m"] == "0.050 (0.040–0.060)"
    assert spread.loc["specialized", "accuracy_200s"] == "0.95 (0.90–1.00)"
    assert spread.loc["localization", "error_50s_m"] == "0.200"     # one seed: no range
    text = markdown(spread)
    assert "| localization | darkness | 0 | 0.200 / 0.100 / 0.100 | — |" in text


def test_per_seed_rows_print_each_value_to_its_precision_and_a_dash_for_none(tmp_path):
    _ship(tmp_path, "specialized", 0, (0.0612, 0.05, 0.04), (0.5, 0.7, 0.912))
    _ship(tmp_path, "localization", 0, (0.2, 0.1, 0.1))
    log = tmp_path / "localization.log.json"     # as a readout fitted without a budget
    log.write_text(log.read_text().replace('"steps": 40000', '"steps": null'))
    lines = per_seed_text(shipped_table(["localization", "specialized"],
                                        folder=tmp_path)).splitlines()
    localization, specialized = lines[2].split(), lines[3].split()
    # seed, world, variant, steps, budget, stopped_early, hours, 3 errors, 3 accuracies
    assert specialized[1:] == ["0", "darkness", "faithful", "40000", "40000", "False",
                               "2.0", "0.061", "0.050", "0.040", "0.50", "0.70", "0.91"]
    assert localization[5] == "—" and localization[-3:] == ["—", "—", "—"]


def test_a_variant_is_labelled_a_departure_and_the_study_s_network_is_not(tmp_path):
    _ship(tmp_path, "generalized", 0, (0.08, 0.08, 0.09))           # a log before variants
    _ship(tmp_path, "generalized_nonneg", 0, (0.12, 0.13, 0.15), steps=20000,
          variant="nonneg")
    table = shipped_table(["generalized", "generalized_nonneg"], folder=tmp_path)
    assert table["variant"].tolist() == ["faithful", "nonneg"]
    text = markdown(seed_spread(table))
    assert "| generalized | darkness |" in text
    assert "| generalized_nonneg (nonneg variant, a departure) | darkness |" in text


def test_the_shipped_logs_are_readable():
    """Every shipped network's log gives its test errors (what `hippo-probe networks`
    prints), and the darkness world's localization network ships at least seed 0."""
    table = shipped_table()
    assert ("localization", 0) in table.index
    assert table.loc[("localization", 0), "world"] == "darkness"
    assert table[["error_50s_m", "error_100s_m", "error_200s_m"]].notna().all().all()


def test_unreadable_log_is_a_clear_error(tmp_path):
    _ship(tmp_path, "generalized", 0, (0.1, 0.1, 0.1))
    (tmp_path / "generalized.log.json").write_text("{not json")
    with pytest.raises(ValueError, match="training log of 'generalized' seed 0"):
        shipped_table(["generalized"], folder=tmp_path)


def test_a_training_log_is_read_by_name_and_seed(tmp_path):
    _ship(tmp_path, "generalized", 0, (0.1, 0.1, 0.1))
    _ship(tmp_path, "generalized", 2, (0.2, 0.2, 0.2))
    assert training_log("generalized", 2, folder=tmp_path)["test"]["error_50s_m"] == 0.2
    with pytest.raises(ValueError, match=r"`seed` 1 of 'generalized' is not shipped; "
                                         r"shipped seeds: \[0, 2\]"):
        training_log("generalized", 1, folder=tmp_path)
    with pytest.raises(ValueError, match="shipped seeds: none"):
        training_log("specialized", 0, folder=tmp_path)
    with pytest.raises(ValueError, match="`name` must be a shipped network's name"):
        training_log("../generalized", 0, folder=tmp_path)
    with pytest.raises(TypeError, match="`seed` must be an integer; got True"):
        training_log("generalized", True, folder=tmp_path)
