"""Border score in polygon arenas: border cells along one wall, place and random units,
walls estimated from occupancy, and agreement with opexebo on square arenas."""

import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.analysis.border_score import (
    distance_to_walls,
    inradius,
    inside_polygon,
    polygon_walls,
)
from hippo_probe.analysis.place_fields import detect_fields

from .cell_fixtures import PENTAGON, gaussian, ou, polygon_walk, square_walk, wall_rate
from .conftest import SQUARE, make_recording


@pytest.fixture(scope="module")
def pentagon_rec():
    rng = np.random.default_rng(2)
    pos, heading = polygon_walk(30000, rng, PENTAGON)
    units = [wall_rate(pos, PENTAGON[k], PENTAGON[(k + 1) % 5]) for k in (0, 2)]
    units += [gaussian(pos, (0.0, 0.0), 0.1), gaussian(pos, (0.3, -0.35), 0.07)]
    units += list(0.5 + 0.1 * ou(30000, rng, 8).T)
    return make_recording(pos, np.stack(units, 1), head_direction=heading,
                          arena_vertices=PENTAGON)


def test_geometry_of_a_polygon():
    assert inside_polygon(np.array([[0, 0], [0.6, 0.6], [0.49, 0.49]]), SQUARE).tolist() \
        == [True, False, True]
    np.testing.assert_allclose(distance_to_walls(np.array([[0.0, 0.0], [0.4, 0.1]]), SQUARE),
                               [0.5, 0.1])
    assert inradius(SQUARE) == pytest.approx(0.5, abs=1e-6)
    assert inradius(np.array([[0, 0], [2.0, 0], [2.0, 1.0], [0, 1.0]])) == \
        pytest.approx(0.5, abs=1e-6)
    assert len(polygon_walls(SQUARE, np.radians(30))) == 4
    # a nearly straight run of edges is one wall
    bent = np.array([[0, 0], [1, 0], [2, 0.1], [2, 2], [0, 2]], float)
    walls = polygon_walls(bent, np.radians(30))
    assert sorted(map(sorted, walls)) == [[0, 1], [2], [3], [4]]


def test_border_cells_along_one_wall_of_a_polygon_arena_score_high(pentagon_rec):
    res = hp.border_score(pentagon_rec, n_shuffles=50)
    score = res.border_score.values
    assert (score[:2] > 0.7).all(), score
    assert (score[:2] > res.border_score_threshold.values[:2]).all()
    assert (res.border_coverage.values[:2] > 0.9).all()
    # the wall found is the one the cell fires along
    walls = res.attrs["walls_used"][0]
    for unit, edge in ((0, 0), (1, 2)):
        assert edge in walls[int(res.border_wall.values[unit])]
    assert res.attrs["walls_source"] == ["arena_vertices"]
    assert score[2] < 0.0                          # a central place field
    assert score[2] < res.border_score_threshold.values[2]


def test_random_units_score_near_their_shuffles(pentagon_rec):
    res = hp.border_score(pentagon_rec, n_shuffles=100, seed=3)
    rand = slice(4, None)
    score = res.border_score.values[rand]
    mean = res.border_score_shuffle_mean.values[rand]
    std = res.border_score_shuffle_std.values[rand]
    assert (np.abs(score - mean) < 4 * std + 1e-9).all(), (score, mean, std)
    assert (res.border_score_p_value.values[rand] < 0.01).sum() <= 1


def test_walls_are_estimated_from_occupancy_when_unknown():
    rng = np.random.default_rng(4)
    pos, heading, _ = square_walk(30000, rng)
    units = [wall_rate(pos, SQUARE[0], SQUARE[1]), gaussian(pos, (0.1, 0.1), 0.1)]
    rec = make_recording(pos, np.stack(units, 1), head_direction=heading)  # no arena
    res = hp.border_score(rec, n_shuffles=0)
    assert "estimated from occupancy" in res.attrs["walls_source"][0]
    assert res.border_score.values[0] > 0.7 and res.border_score.values[1] < 0.0
    known = hp.border_score(rec, n_shuffles=0, walls=SQUARE)
    assert abs(known.border_score.values[0] - res.border_score.values[0]) < 0.05


def test_lazy_recording_gives_the_same_scores(pentagon_rec):
    eager = hp.border_score(pentagon_rec, n_shuffles=5)
    lazy = hp.border_score(pentagon_rec.chunk({"time": 4000}), n_shuffles=5)
    xr.testing.assert_allclose(eager, lazy)


def test_arguments_are_checked(pentagon_rec):
    maps = hp.ratemaps(pentagon_rec)
    with pytest.raises(ValueError, match="`n_shuffles` needs a recording"):
        hp.border_score(maps, n_shuffles=3)
    with pytest.raises(ValueError, match="`walls` must be one of 'occupancy'"):
        hp.border_score(maps, walls="square")
    with pytest.raises(ValueError, match="`walls` must have shape"):
        hp.border_score(maps, walls=np.zeros((4, 3)))
    with pytest.raises(ValueError, match="`field_threshold` must be < 1"):
        hp.border_score(maps, field_threshold=1.0)


# --------------------------------------------------------------------- opexebo
def test_border_score_agrees_with_opexebo_on_a_square_arena():
    """Same maps (every bin visited), same fields: the coverage is identical and the
    score differs only by the distance convention, d_m(opexebo) = d_m + 1 / n_bins
    (opexebo counts a bin along a wall as 1 bin away, we measure its centre, 0.5 bin,
    and normalise by the inradius, half the side)."""
    opexebo = pytest.importorskip("opexebo")
    rng = np.random.default_rng(0)
    pos = rng.uniform(-0.5, 0.5, (60000, 2))
    units = [wall_rate(pos, SQUARE[3], SQUARE[0]), wall_rate(pos, SQUARE[2], SQUARE[3], 0.08),
             gaussian(pos, (0.1, 0.0), 0.1), gaussian(pos, (0.4, -0.4), 0.08),
             wall_rate(pos, SQUARE[0], SQUARE[1]) * gaussian(pos, (0.0, -0.5), 0.25)]
    rec = make_recording(pos, np.stack(units, 1), arena_vertices=SQUARE)
    maps = hp.ratemaps(rec, bin_size=0.025, sigma=1.0)
    assert np.isfinite(maps.values).all()
    res = hp.border_score(maps)
    n = maps.sizes["x"]
    min_bins = int(np.ceil(0.02 / 0.025**2))
    for u in range(len(units)):
        m = maps.values[u]
        labels = detect_fields(m[None], threshold=0.3, min_bins=min_bins).labels[0]
        fields = [{"field_map": (labels == k).astype(float)}
                  for k in range(1, labels.max() + 1)]
        score, coverage = opexebo.analysis.border_score(m, labels, fields, "square",
                                                        walls="trbl")
        assert res.border_coverage.values[u] == pytest.approx(coverage, abs=1e-12)
        c, d = res.border_coverage.values[u], res.border_distance.values[u]
        if coverage == 0:
            assert score == -1 and res.border_score.values[u] == -1
            continue
        converted = (c - (d + 1 / n)) / (c + d + 1 / n)
        assert converted == pytest.approx(score, abs=1e-9)
        assert res.border_score.values[u] >= score     # our bins lie 0.5 bin nearer


def test_a_map_without_data_is_nan_and_one_without_a_field_is_minus_one():
    from .cell_fixtures import mixed_population

    rec = mixed_population(n=6000)
    maps = hp.ratemaps(rec, sigma=1).copy()
    maps[1] = np.nan                      # no finite bin: undefined
    maps[2] = 0.0                         # visited but flat: no field, the -1 convention
    walls = rec["arena_vertices"].values[0]
    score = hp.border_score(maps, walls=walls).border_score.values
    assert np.isnan(score[1]) and score[2] == -1.0 and np.isfinite(score[0])


def _walk(inside, n=60_000, seed=0):
    """A random walk at about 0.2 m/s in 20 ms steps kept to the region ``inside``."""
    rng = np.random.default_rng(seed)
    xy = np.zeros((n, 2))
    p = np.array([0.0, 0.0])
    for i in range(n):
        q = p + rng.normal(0, 0.004, 2)
        p = q if inside(q) else p
        xy[i] = p
    return xy


def _session_in(inside):
    xy = _walk(inside)
    t = np.arange(len(xy)) * 0.02
    act = np.exp(-((xy - 0.2) ** 2).sum(1) / 0.02)[:, None]
    return hp.recording.from_arrays(t, xy, activity=act, activity_kind="rate")


def _hull_warnings(rec, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        hp.border_score(rec, n_shuffles=0, **kw)
    return [str(w.message) for w in caught if "convex hull" in str(w.message)]


def test_walls_estimated_around_a_maze_are_warned_about():
    """A Y-shaped track fills a small part of its hull; the open square fills most."""
    def y_maze(q):
        arms = [np.array([np.cos(a), np.sin(a)]) for a in (np.pi / 2, 7 * np.pi / 6,
                                                           11 * np.pi / 6)]
        return any(0 <= q @ u <= 0.6 and abs(q @ np.array([-u[1], u[0]])) <= 0.04
                   for u in arms)

    def square(q):
        return bool(np.all(np.abs(q) <= 0.5))

    said = _hull_warnings(_session_in(y_maze), bin_size=0.05)
    assert len(said) == 1 and "maze or track" in said[0]
    fill = float(said[0].split("fill only ")[1].split("%")[0])
    assert fill < 50
    assert not _hull_warnings(_session_in(square), bin_size=0.05)
    # walls given: nothing estimated, nothing to warn about
    assert not _hull_warnings(_session_in(y_maze), bin_size=0.05,
                              walls=[[-0.6, -0.4], [0.6, -0.4], [0.0, 0.65]])


def test_the_shipped_y_maze_session_is_warned_about():
    pytest.importorskip("pynwb")
    mouse = hp.from_nwb(Path(__file__).parents[1] / "data" / "A2929-200711.nwb",
                        epoch="wake", position_units="m")
    said = _hull_warnings(mouse)
    assert len(said) == 1 and "28%" in said[0]
