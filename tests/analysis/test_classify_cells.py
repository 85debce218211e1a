"""classify_cells: one table of scores, shuffle thresholds and classes."""

import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.config import CellClassConfig

from .cell_fixtures import NAMES, mixed_population
from .conftest import SQUARE, make_recording


@pytest.fixture(scope="module")
def population():
    return mixed_population()


@pytest.fixture(scope="module")
def table(population):
    return hp.classify_cells(population, n_shuffles=100, seed=0)


def test_every_unit_gets_its_class(table):
    # 0 grid, 1 border, 2 place, 3 head direction, 4 speed, 5 conjunctive, 6.. random
    assert table.cell_class.values[:6].tolist() == NAMES
    for unit, name in enumerate(NAMES):
        assert table[f"is_{name}"].values[unit], (unit, name)
    # random units: each per-unit test lets through its nominal 1-5% of them
    assert (table.cell_class.values[6:] != "unclassified").sum() <= 1
    # memberships overlap where they should: a grid cell also has place fields
    assert table.is_place.values[0] and table.is_head_direction.values[5]
    assert not table.is_grid.values[1:].any() and not table.is_border.values[[0, 2, 3]].any()


def test_the_table_holds_scores_thresholds_and_rules(table, population):
    for score in ("grid_score", "border_score", "spatial_information",
                  "hd_mean_vector_length", "speed_score", "pxd_direction_length",
                  "pxd_position_information"):
        assert table[f"{score}_threshold"].dims == ("unit",)
        assert table[f"{score}_p_value"].dims == ("unit",)
    assert table.grid_score_threshold.attrs["percentile"] == 95
    assert table.border_score_threshold.attrs["percentile"] == 99
    assert "Solstad" in table.is_border.attrs["source"]
    assert "0.5" in table.attrs["rules"]["border"]
    assert abs(table.grid_spacing.values[0] - 0.4) < 1 / 32
    assert table.n_fields.values[2] == 1
    df = table.to_dataframe()
    assert len(df) == population.sizes["unit"] and "cell_class" in df
    # the same numbers as the single analyses
    info = hp.spatial_information(population)
    np.testing.assert_allclose(table.spatial_information, info.information, rtol=1e-9)
    grid = hp.grid_score(population, n_shuffles=100, seed=0)
    np.testing.assert_allclose(table.grid_score, grid.grid_score, rtol=1e-9)
    np.testing.assert_allclose(table.grid_score_threshold, grid.grid_score_threshold,
                               rtol=1e-9)


def test_lazy_recording_gives_the_same_table(population):
    eager = hp.classify_cells(population, n_shuffles=5)
    lazy = hp.classify_cells(population.chunk({"time": 8000}), n_shuffles=5)
    xr.testing.assert_allclose(eager.drop_vars("cell_class"), lazy.drop_vars("cell_class"))
    assert (eager.cell_class.values == lazy.cell_class.values).all()


def test_signed_lstm_activity_is_classified_the_same(population):
    signed = population.copy()
    signed["activity"] = np.tanh(2 * population.activity - 1).astype(np.float32)
    signed.attrs["activity_kind"] = "lstm_hidden"
    # a network's units have no counting noise: said, with the way to compare with cells
    with pytest.warns(AnalysisWarning, match=r"no counting noise.*poisson_spikes"):
        table = hp.classify_cells(signed, n_shuffles=50)
    assert table.cell_class.values[:6].tolist() == NAMES
    assert "minimum over the recording" in table.attrs["rate_offset"]


def test_pooled_thresholds_and_a_stricter_config(population):
    pooled = hp.classify_cells(population, n_shuffles=30, threshold="pooled")
    assert np.unique(pooled.grid_score_threshold.values).size == 1
    strict = hp.classify_cells(population, n_shuffles=30,
                               config=CellClassConfig(grid_percentile=99.9,
                                                      border_min_score=0.99))
    assert not strict.is_border.any()
    assert strict.grid_score_threshold.attrs["percentile"] == 99.9


def test_several_environments_use_the_most_visited_one():
    rec = mixed_population(n=12000, seed=1)
    env = np.r_[np.zeros(8000, int), np.ones(4000, int)]
    trial = env.copy()
    two = make_recording(rec.position.values, rec.activity.values, trial=trial,
                         environment=env, head_direction=rec.head_direction.values,
                         arena_vertices=SQUARE)
    with pytest.warns(AnalysisWarning, match="most visited one, 0"):
        table = hp.classify_cells(two, n_shuffles=5)
    assert table.attrs["environment"] == 0
    with pytest.raises(ValueError, match="`environment` must be one of"):
        hp.classify_cells(two, n_shuffles=5, environment=7)


def test_arguments_are_checked(population):
    with pytest.raises(TypeError, match="`config` must be a CellClassConfig"):
        hp.classify_cells(population, config={"grid_percentile": 90})
    with pytest.raises(ValueError, match="`threshold` must be one of 'unit', 'pooled'"):
        hp.classify_cells(population, threshold="all")


def test_without_head_direction_place_cells_are_still_found(population):
    """No head direction: the head-direction and conjunctive classes are NaN-scored and
    empty, and the place class is decided without the factorial gate."""
    table = hp.classify_cells(population.drop_vars("head_direction"), n_shuffles=50, seed=0)
    assert table.cell_class.values[2] == "place"
    assert not table.is_head_direction.values.any() and not table.is_conjunctive.values.any()
    assert np.isnan(table.hd_mean_vector_length.values).all()


def test_no_shuffles_is_refused_not_silently_unclassified(population):
    with pytest.raises(ValueError, match="`n_shuffles` must be >= 1"):
        hp.classify_cells(population, n_shuffles=0)
