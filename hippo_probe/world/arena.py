"""Star-shaped random polygon arenas and their geometry, vectorized.

Every function takes ``vertices`` of shape ``(..., V, 2)`` (counter-clockwise, the arena's
centre at the origin) and ``points`` of shape ``(..., N, 2)``; leading dims broadcast, so
one call handles many points in many arenas.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validators import check_nonnegative_int, check_number, check_positive
from .config import ArenaConfig


@dataclass(frozen=True)
class Arena:
    """A polygon arena; ``vertices`` (V, 2) counter-clockwise around the origin (m)."""

    vertices: np.ndarray

    def __post_init__(self):
        v = np.asarray(self.vertices, dtype=float)
        if v.ndim != 2 or v.shape[1] != 2 or v.shape[0] < 3:
            raise ValueError(f"`vertices` must have shape (V>=3, 2); got {v.shape}")
        object.__setattr__(self, "vertices", v)

    @property
    def area(self) -> float:
        return float(polygon_area(self.vertices))

    @property
    def mean_radius(self) -> float:
        return float(np.linalg.norm(self.vertices, axis=-1).mean())

    def contains(self, points) -> np.ndarray:
        return contains(self.vertices, points)

    def wall_distance(self, points):
        return wall_distance(self.vertices, points)

    def sample_uniform(self, rng, n: int) -> np.ndarray:
        return sample_uniform(self.vertices, rng, n)


def random_arena(rng, n_vertices: int = 10, mean_radius: float = 1.0, *,
                 config: ArenaConfig | None = None) -> Arena:
    """Draw a random star-shaped polygon around the origin.

    Parameters
    ----------
    rng : numpy.random.Generator or int
    n_vertices : int
        Number of vertices (>= 3).
    mean_radius : float
        Mean centre-to-vertex length in metres (exact, after rescaling).
    config : ArenaConfig, optional
        Overrides ``n_vertices`` and ``mean_radius`` and sets the spreads.

    Examples
    --------
    >>> import numpy as np
    >>> arena = random_arena(np.random.default_rng(0), n_vertices=10, mean_radius=0.33)
    >>> arena.vertices.shape
    (10, 2)
    """
    if config is None:
        config = ArenaConfig(n_vertices=n_vertices, mean_radius=mean_radius)
    rng = np.random.default_rng(rng)
    return Arena(random_vertices(rng, config))


def random_vertices(rng: np.random.Generator, config: ArenaConfig) -> np.ndarray:
    """Vertices (V, 2) of one random arena, see :class:`ArenaConfig`."""
    v = config.n_vertices
    spacing = 2 * np.pi / v
    # consecutive vertices must stay less than pi apart, else the polygon misses its
    # centre; only binds for V < 5 (10 vertices: 1.98 > 0.3, draws unchanged)
    jitter = min(config.angle_jitter, 0.99 * (v / 2 - 1) / 2)
    angles = (np.arange(v) * spacing + rng.uniform(0, 2 * np.pi)
              + rng.uniform(-jitter, jitter, v) * spacing)
    radii = rng.uniform(1 - config.radius_spread, 1 + config.radius_spread, v)
    radii *= config.mean_radius / radii.mean()
    return np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=-1)


def regular_polygon(n_vertices: int, radius: float, rotation: float = 0.0) -> Arena:
    """A regular polygon (maximally symmetric arena), e.g. to test ambiguity."""
    check_number("n_vertices", n_vertices, low=3, low_inclusive=True, integer=True)
    check_positive("radius", radius)
    a = rotation + 2 * np.pi * np.arange(n_vertices) / n_vertices
    return Arena(radius * np.stack([np.cos(a), np.sin(a)], axis=-1))


def polygon_area(vertices) -> np.ndarray:
    """Shoelace area of polygons (..., V, 2) -> (...)."""
    v = np.asarray(vertices, dtype=float)
    x, y = v[..., 0], v[..., 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y, axis=-1)


def edges(vertices):
    """Start points ``a`` and edge vectors ``e`` (..., V, 2) of each wall."""
    a = np.asarray(vertices, dtype=float)
    return a, np.roll(a, -1, axis=-2) - a


def inward_normals(vertices) -> np.ndarray:
    """Unit inward normal of each wall (..., V, 2), for counter-clockwise polygons."""
    _, e = edges(vertices)
    n = np.stack([-e[..., 1], e[..., 0]], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def contains(vertices, points) -> np.ndarray:
    """Even-odd inside test: points (..., N, 2) in polygons (..., V, 2) -> bool (..., N)."""
    a, e = edges(vertices)
    p = np.asarray(points, dtype=float)[..., :, None, :]          # (..., N, 1, 2)
    ax, ay = a[..., None, :, 0], a[..., None, :, 1]                 # (..., 1, V)
    bx, by = ax + e[..., None, :, 0], ay + e[..., None, :, 1]
    px, py = p[..., 0], p[..., 1]
    straddles = (ay > py) != (by > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = ax + (py - ay) * (bx - ax) / (by - ay)
    return np.sum(straddles & (px < x_cross), axis=-1) % 2 == 1


def wall_distance(vertices, points):
    """Distance from points to the nearest wall, which wall, and its inward normal.

    Parameters
    ----------
    vertices : array (..., V, 2)
    points : array (..., N, 2)

    Returns
    -------
    distance : array (..., N)
        Euclidean distance to the nearest point of the polygon's boundary (m).
    wall : int array (..., N)
        Index k of that wall (from vertex k to vertex k+1).
    normal : array (..., N, 2)
        Unit inward normal of that wall.
    """
    a, e = edges(vertices)
    p = np.asarray(points, dtype=float)[..., :, None, :]           # (..., N, 1, 2)
    a_ = a[..., None, :, :]                                          # (..., 1, V, 2)
    e_ = e[..., None, :, :]
    t = np.clip(np.sum((p - a_) * e_, axis=-1) / np.sum(e_ * e_, axis=-1), 0.0, 1.0)
    d = np.linalg.norm(p - (a_ + t[..., None] * e_), axis=-1)       # (..., N, V)
    wall = np.argmin(d, axis=-1)
    distance = np.take_along_axis(d, wall[..., None], axis=-1)[..., 0]
    normals = np.broadcast_to(inward_normals(vertices)[..., None, :, :], d.shape + (2,))
    normal = np.take_along_axis(normals, wall[..., None, None], axis=-2)[..., 0, :]
    return distance, wall, normal


def sample_uniform(vertices, rng, n: int) -> np.ndarray:
    """``n`` points uniform in a star-shaped polygon (V, 2) -> (n, 2).

    The polygon is the union of the triangles (origin, v_k, v_k+1); a triangle is picked
    with probability proportional to its area and a point drawn uniformly inside it.
    """
    n = check_nonnegative_int("n", n)
    v = np.asarray(vertices, dtype=float)
    k = rng.choice(len(v), size=n, p=fan_weights(v))
    u1, u2 = rng.random(n), rng.random(n)
    return fan_points(v, k, u1, u2)


def fan_weights(vertices) -> np.ndarray:
    """Area share (..., V) of each triangle (origin, v_k, v_k+1) of polygons (..., V, 2)."""
    v = np.asarray(vertices, dtype=float)
    w = np.roll(v, -1, axis=-2)
    tri_area = 0.5 * (v[..., 0] * w[..., 1] - w[..., 0] * v[..., 1])
    return tri_area / tri_area.sum(axis=-1, keepdims=True)


def fan_points(vertices, k, u1, u2) -> np.ndarray:
    """Points (..., n, 2) in triangles ``k`` (..., n) of polygons (..., V, 2), from uniform
    numbers ``u1``, ``u2`` (..., n): ``u1 v_k + u2 v_k+1``, reflected into the triangle
    when ``u1 + u2 > 1`` (the vectorized second half of :func:`sample_uniform`)."""
    v = np.asarray(vertices, dtype=float)
    w = np.roll(v, -1, axis=-2)
    flip = u1 + u2 > 1
    u1, u2 = np.where(flip, 1 - u1, u1), np.where(flip, 1 - u2, u2)
    k = np.asarray(k)[..., None]
    vk = np.take_along_axis(v, k, axis=-2)
    wk = np.take_along_axis(w, k, axis=-2)
    return u1[..., None] * vk + u2[..., None] * wk
