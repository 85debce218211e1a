"""analyses/map_ingredients.py: a network named at several seeds is summarised across them."""


import numpy as np
import pytest


@pytest.fixture(scope="module")
def script(analysis_script):
    return analysis_script("map_ingredients")


def row(script, network, place, ratio, readout, fields):
    out = {key: 0.5 for _, key, _ in script.SCORE_LINES}
    out.update(network=network, variant="nonneg", steps=20000, fraction_place_like=place,
               error_over_pf_after_100s=ratio, arena_readout_accuracy_200s=readout,
               median_field_area=np.nan, place_fields=fields, global_remapping=False)
    return out


def test_seeds_of_a_network_are_summarised_and_single_networks_are_not(script):
    rows = [row(script, "generalized_nonneg", 0.66, 3.26, 0.025, True),
            row(script, "generalized_nonneg@1", 0.40, 3.00, None, False),
            row(script, "generalized_nonneg@2", 0.52, 3.50, 0.031, True),
            row(script, "generalized", 0.05, 2.02, 0.127, False)]
    summary = script.across_seeds(rows)
    assert list(summary) == ["generalized_nonneg"]
    s = summary["generalized_nonneg"]
    assert s["seeds"] == ["generalized_nonneg", "generalized_nonneg@1", "generalized_nonneg@2"]
    assert s["fraction_place_like"]["mean"] == pytest.approx(0.52666, abs=1e-4)
    assert (s["fraction_place_like"]["min"], s["fraction_place_like"]["max"]) == (0.40, 0.66)
    # an unmeasured readout is left out of its mean, not counted as 0
    assert s["arena_readout_accuracy_200s"]["n"] == 2
    assert s["arena_readout_accuracy_200s"]["mean"] == pytest.approx(0.028)
    assert s["median_field_area"] is None                # NaN at every seed
    assert s["place_fields"] == {"yes": 2, "of": 3}
    table = script.seeds_table(summary).splitlines()
    assert len(table) == 3 and table[0].count("|") == table[2].count("|")
    assert "| `generalized_nonneg` | 3 | 20,000 | 3.25 (3.00–3.50) |" in table[2]
    assert table[2].endswith("| 2 of 3 | 0 of 3 |")


def test_a_network_named_twice_is_refused(script):
    script.check_distinct(["generalized", "generalized@1", "generalized_nonneg"])
    with pytest.raises(SystemExit, match="names one network twice: 'generalized' and "
                                         "'generalized@0'"):
        script.check_distinct(["generalized", "generalized@0"])


def test_cache_files_of_two_networks_never_collide(script, tmp_path):
    names = ["runs/a", "runs_a", "x" * 300 + "/net", "generalized@1", "generalized_1"]
    files = {script.cache_file(tmp_path, n, "d" * 64, "t1") for n in names}
    assert len(files) == len(names)
    assert all(len(f.name) < 100 for f in files)
    assert script.cache_file(tmp_path, "a", "d" * 64, "t1") != \
        script.cache_file(tmp_path, "a", "e" * 64, "t1")


def test_a_damaged_cache_file_is_computed_again(script, tmp_path):
    path = tmp_path / "row.npz"
    path.write_bytes(b"not a zip file")
    with pytest.warns(UserWarning, match="cannot be read .* computing it again"):
        assert script.read_cached(path, "generalized") is None
    np.savez(path, row=np.array('{"network": "elsewhere", "x": NaN}'), units=np.arange(2),
             maps=np.zeros((2, 2, 3, 3)), rules=np.array("r"))
    row, units, maps, rules = script.read_cached(path, "generalized")
    assert row["network"] == "generalized" and np.isnan(row["x"]) and rules == "r"
    assert units.tolist() == [0, 1] and maps.shape == (2, 2, 3, 3)
