"""Arenas: random star-shaped polygons and their vectorized geometry."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from matplotlib.path import Path

from hippo_probe.world import (Arena, ArenaConfig, contains, inward_normals, polygon_area,
                               random_arena, random_vertices, regular_polygon,
                               sample_uniform, wall_distance)

seeds = st.integers(0, 2**32 - 1)
arena_configs = st.builds(
    ArenaConfig,
    n_vertices=st.integers(4, 24),
    mean_radius=st.floats(0.01, 10.0),
    radius_spread=st.floats(0.0, 0.9),
    angle_jitter=st.floats(0.0, 0.499),
)


def random_arenas(seed, n, config=ArenaConfig(mean_radius=0.33)):
    rng = np.random.default_rng(seed)
    return np.stack([random_vertices(rng, config) for _ in range(n)])


def assert_simple_star_shaped(v, geometry):
    a, b = v, np.roll(v, -1, axis=0)
    n = len(v)
    # simple: no two non-adjacent walls share a point ...
    i, j = np.triu_indices(n, k=2)
    non_adjacent = (j - i) % n != n - 1
    i, j = i[non_adjacent], j[non_adjacent]
    crossing = geometry.cross(a[i], b[i], a[j], b[j])
    assert not crossing.any(), f"walls {i[crossing]} and {j[crossing]} intersect"
    # ... and no wall folds back onto the next one
    e, f = b - a, np.roll(b - a, -1, axis=0)
    folded = (e[:, 0] * f[:, 1] - e[:, 1] * f[:, 0] == 0) & (np.sum(e * f, axis=1) < 0)
    assert not folded.any()
    # star-shaped about the origin: the origin is strictly left of every (CCW) wall, and
    # the boundary winds exactly once around it
    cross = a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    assert (cross > 0).all(), "the origin is not in the polygon's kernel"
    winding = np.sum(np.arctan2(cross, np.sum(a * b, axis=1))) / (2 * np.pi)
    assert winding == pytest.approx(1.0, abs=1e-9)


@settings(max_examples=150, deadline=None)
@given(seed=seeds, config=arena_configs)
def test_random_arena_is_simple_star_shaped_with_the_requested_mean_radius(
        seed, config, geometry):
    v = random_arena(seed, config=config).vertices
    assert v.shape == (config.n_vertices, 2)
    assert np.linalg.norm(v, axis=1).mean() == pytest.approx(config.mean_radius, rel=1e-12)
    assert_simple_star_shaped(v, geometry)
    assert polygon_area(v) > 0  # counter-clockwise


def test_task_sized_arenas_are_simple_and_star_shaped(geometry):
    for mean_radius in (1.0, 0.33):
        for v in random_arenas(7, 500, ArenaConfig(mean_radius=mean_radius)):
            assert_simple_star_shaped(v, geometry)


def test_triangle_arenas_are_star_shaped_about_the_origin(geometry):
    for seed in range(200):
        assert_simple_star_shaped(random_arena(seed, n_vertices=3).vertices, geometry)


def test_random_arena_same_seed_same_arena_different_seed_different_arena():
    a = random_arena(np.random.default_rng(3), mean_radius=0.33).vertices
    b = random_arena(np.random.default_rng(3), mean_radius=0.33).vertices
    c = random_arena(np.random.default_rng(4), mean_radius=0.33).vertices
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)


def test_polygon_area_of_regular_polygons_and_random_arenas():
    for n, r in ((3, 1.0), (4, 2.0), (10, 0.33), (100, 1.0)):
        expected = 0.5 * n * r**2 * np.sin(2 * np.pi / n)
        assert regular_polygon(n, r, rotation=0.3).area == pytest.approx(expected, rel=1e-12)
    # against counting grid cells inside (matplotlib's point-in-polygon)
    verts = random_arenas(11, 5)
    g = np.linspace(-0.7, 0.7, 701)
    cell = (g[1] - g[0]) ** 2
    grid = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    for v in verts:
        grid_area = Path(v).contains_points(grid).sum() * cell
        assert polygon_area(v) == pytest.approx(grid_area, rel=0.01)
    # vectorized over arenas
    np.testing.assert_allclose(polygon_area(verts), [polygon_area(v) for v in verts],
                               rtol=1e-14)


@settings(max_examples=25, deadline=None)
@given(seed=seeds)
def test_contains_matches_matplotlib_over_many_arenas_at_once(seed):
    rng = np.random.default_rng(seed)
    verts = random_arenas(rng, 20)                                     # (20, V, 2)
    points = rng.uniform(-0.7, 0.7, (20, 300, 2))                      # (20, N, 2)
    inside = contains(verts, points)
    assert inside.shape == (20, 300)
    distance, _, _ = wall_distance(verts, points)
    clear = distance > 1e-9          # matplotlib and we may disagree on the boundary itself
    for v, p, ins, ok in zip(verts, points, inside, clear):
        np.testing.assert_array_equal(ins[ok], Path(v).contains_points(p[ok]))
    # the origin (the arena's centre) is always inside
    assert contains(verts, np.zeros((20, 1, 2))).all()
    # one set of points broadcast against many arenas
    shared = contains(verts, points[0])
    np.testing.assert_array_equal(shared[0], inside[0])


def test_wall_distance_matches_dense_boundary_sampling(geometry):
    rng = np.random.default_rng(5)
    per_edge = 1001
    for config in (ArenaConfig(mean_radius=0.33), ArenaConfig(mean_radius=1.0)):
        verts = random_arenas(rng, 8, config)
        r = config.mean_radius
        points = rng.uniform(-1.6 * r, 1.6 * r, (8, 100, 2))          # inside and outside
        distance, wall, normal = wall_distance(verts, points)
        for v, p, d, k in zip(verts, points, distance, wall):
            samples = geometry.boundary(v, per_edge)                   # (V * S, 2)
            gap = np.linalg.norm(np.roll(v, -1, 0) - v, axis=1).max() / (per_edge - 1)
            brute = np.linalg.norm(p[:, None] - samples[None], axis=-1)
            nearest = brute.min(axis=1)
            # the true distance is at most the sampled one, and at most half a gap less
            assert (d <= nearest + 1e-12).all()
            assert (nearest - d <= gap / 2 + 1e-12).all()
            # the reported wall is one at that distance
            own = brute.reshape(len(p), len(v), per_edge)[np.arange(len(p)), k].min(axis=1)
            assert (own - d <= gap / 2 + 1e-12).all()
        # the reported normal is the unit inward normal of the reported wall
        np.testing.assert_allclose(np.linalg.norm(normal, axis=-1), 1.0, rtol=1e-12)
        edge = np.take_along_axis(np.roll(verts, -1, 1) - verts, wall[..., None], axis=1)
        np.testing.assert_allclose(np.sum(edge * normal, axis=-1), 0.0, atol=1e-12)


def test_inward_normals_point_into_the_arena():
    verts = random_arenas(8, 200)
    normals = inward_normals(verts)                                      # (A, V, 2)
    midpoints = 0.5 * (verts + np.roll(verts, -1, axis=1))
    np.testing.assert_allclose(np.linalg.norm(normals, axis=-1), 1.0, rtol=1e-12)
    assert contains(verts, midpoints + 1e-6 * normals).all()
    assert not contains(verts, midpoints - 1e-6 * normals).any()


@settings(max_examples=100, deadline=None)
@given(seed=seeds, config=arena_configs)
def test_sample_uniform_stays_inside(seed, config):
    rng = np.random.default_rng(seed)
    v = random_vertices(rng, config)
    points = sample_uniform(v, rng, 500)
    assert points.shape == (500, 2)
    assert contains(v, points).all()


def _clip_area(v, normal, offset):
    """Area of polygon v cut to the half-plane normal . x <= offset (Sutherland-Hodgman)."""
    out = []
    for a, b in zip(v, np.roll(v, -1, axis=0)):
        sa, sb = normal @ a - offset, normal @ b - offset
        if sa <= 0:
            out.append(a)
        if sa * sb < 0:
            out.append(a + (b - a) * sa / (sa - sb))
    return polygon_area(np.array(out)) if len(out) >= 3 else 0.0


def test_sample_uniform_is_uniform():
    """The fraction of samples in a random half-plane equals its share of the area."""
    rng = np.random.default_rng(12)
    n = 40_000
    for v in random_arenas(rng, 4, ArenaConfig(mean_radius=1.0, radius_spread=0.8)):
        points = sample_uniform(v, rng, n)
        for _ in range(8):
            phi = rng.uniform(0, 2 * np.pi)
            normal = np.array([np.cos(phi), np.sin(phi)])
            offset = rng.uniform(-0.6, 0.6)
            share = _clip_area(v, normal, offset) / polygon_area(v)
            observed = np.mean(points @ normal <= offset)
            sd = np.sqrt(share * (1 - share) / n)
            assert abs(observed - share) < 5 * sd + 1e-12, (observed, share)


def test_arena_methods_agree_with_the_functions():
    rng = np.random.default_rng(2)
    arena = random_arena(rng, n_vertices=10, mean_radius=0.33)
    points = rng.uniform(-0.5, 0.5, (100, 2))
    np.testing.assert_array_equal(arena.contains(points), contains(arena.vertices, points))
    for got, want in zip(arena.wall_distance(points), wall_distance(arena.vertices, points)):
        np.testing.assert_array_equal(got, want)
    assert arena.area == polygon_area(arena.vertices)
    assert arena.mean_radius == pytest.approx(0.33, rel=1e-12)
    samples = arena.sample_uniform(np.random.default_rng(0), 10)
    np.testing.assert_array_equal(
        samples, sample_uniform(arena.vertices, np.random.default_rng(0), 10))


@pytest.mark.parametrize("make, name, value", [
    (lambda: random_arena(0, n_vertices=2), "n_vertices", "2"),
    (lambda: random_arena(0, n_vertices=0), "n_vertices", "0"),
    (lambda: random_arena(0, mean_radius=0.0), "mean_radius", "0.0"),
    (lambda: random_arena(0, mean_radius=-0.33), "mean_radius", "-0.33"),
    (lambda: ArenaConfig(radius_spread=-0.1), "radius_spread", "-0.1"),
    (lambda: ArenaConfig(angle_jitter=0.5), "angle_jitter", "0.5"),
    (lambda: regular_polygon(2, 1.0), "n_vertices", "2"),
    (lambda: regular_polygon(6, -1.0), "radius", "-1.0"),
    (lambda: Arena(np.zeros((2, 2))), "vertices", r"\(2, 2\)"),
])
def test_bad_arena_parameters_raise_naming_parameter_and_value(make, name, value):
    with pytest.raises(ValueError, match=rf"`{name}`.*{value}"):
        make()


def test_sample_uniform_negative_count_names_the_parameter():
    with pytest.raises(ValueError, match=r"`n`.*-1"):
        sample_uniform(regular_polygon(6, 1.0).vertices, np.random.default_rng(0), -1)


def test_the_reference_segment_test_itself(geometry):
    p = np.array
    assert geometry.cross(p([0., 0]), p([1., 1]), p([0., 1]), p([1., 0]))      # X
    assert geometry.cross(p([0., 0]), p([1., 0]), p([1., 0]), p([1., 1]))      # touch at end
    assert geometry.cross(p([0., 0]), p([2., 0]), p([1., 0]), p([3., 0]))      # overlap
    assert not geometry.cross(p([0., 0]), p([1., 0]), p([2., 0]), p([3., 0]))  # in line
    assert not geometry.cross(p([0., 0]), p([1., 0]), p([0., 1]), p([1., 1]))  # parallel
    assert geometry.cross(p([.5, 0]), p([.5, 0]), p([0., 0]), p([1., 0]))      # point on
    assert not geometry.cross(p([.5, .1]), p([.5, .1]), p([0., 0]), p([1., 0]))
