"""Border score (Solstad et al. 2008) for arenas of any polygonal shape."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import optimize

from .._angles import wrap_angle
from .._validators import check_finite, check_number, check_option, check_real, check_shape
from . import _common
from ._common import refuse_map_options
from .._docs import fill_doc
from ._shuffles import MapStack, add_significance, check_percentile
from .config import BORDER, CELL_CLASS
from .place_fields import bin_coords, check_maps, detect_fields


# ------------------------------------------------------------------ polygon geometry
def _edges(vertices):
    v = np.asarray(vertices, float)
    return v, np.roll(v, -1, axis=0)


def signed_area(vertices):
    """Shoelace area: > 0 for counter-clockwise vertices."""
    v = np.asarray(vertices, float)
    x, y = v[:, 0], v[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def inside_polygon(points, vertices):
    """Even-odd rule: whether each point (P, 2) lies inside the polygon (V, 2)."""
    p = np.asarray(points, float)
    a, b = _edges(vertices)
    x, y = p[:, :1], p[:, 1:2]
    crosses = (a[None, :, 1] > y) != (b[None, :, 1] > y)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (y - a[None, :, 1]) / (b[None, :, 1] - a[None, :, 1])
        x_cross = a[None, :, 0] + t * (b[None, :, 0] - a[None, :, 0])
    return (crosses & (x < x_cross)).sum(axis=1) % 2 == 1


def distance_to_walls(points, vertices):
    """Distance (P,) of each point to the nearest edge of the polygon."""
    p = np.asarray(points, float)[:, None, :]
    a, b = _edges(vertices)
    ab = (b - a)[None]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.clip(((p - a[None]) * ab).sum(-1) / (ab * ab).sum(-1), 0.0, 1.0)
    t = np.nan_to_num(t)
    nearest = a[None] + t[..., None] * ab
    return np.sqrt(((p - nearest) ** 2).sum(-1)).min(axis=1)


def inradius(vertices, resolution=64):
    """The largest distance from a point of the polygon to its boundary (the radius of
    the largest inscribed circle): a grid search refined by Nelder-Mead."""
    v = np.asarray(vertices, float)
    lo, hi = v.min(0), v.max(0)
    gx, gy = np.meshgrid(np.linspace(lo[0], hi[0], resolution),
                         np.linspace(lo[1], hi[1], resolution))
    pts = np.c_[gx.ravel(), gy.ravel()]
    pts = pts[inside_polygon(pts, v)]
    if not len(pts):
        return float("nan")
    d = distance_to_walls(pts, v)
    start = pts[np.argmax(d)]

    def neg(q):
        q = np.asarray(q)[None]
        return -distance_to_walls(q, v)[0] if inside_polygon(q, v)[0] else 0.0

    res = optimize.minimize(neg, start, method="Nelder-Mead",
                            options={"xatol": 1e-9 * (hi - lo).max(), "fatol": 1e-12})
    return float(max(-res.fun, d.max()))


def polygon_walls(vertices, merge_angle):
    """Group the polygon's edges into walls: runs of consecutive edges whose direction
    stays within ``merge_angle`` (rad) of the run's length-weighted mean direction.

    Returns a list of walls, each a list of edge indices (in order around the polygon).
    """
    a, b = _edges(vertices)
    d = b - a
    length = np.hypot(d[:, 0], d[:, 1])
    ang = np.arctan2(d[:, 1], d[:, 0])
    n = len(ang)
    turn = np.abs(wrap_angle(ang - np.roll(ang, 1)))
    start = int(np.argmax(turn))  # never split a straight run at the list's start
    walls, current, ref = [], [], 0j
    for k in range(n):
        e = (start + k) % n
        z = length[e] * np.exp(1j * ang[e])
        if current and abs(wrap_angle(ang[e] - np.angle(ref))) >= merge_angle:
            walls.append(current)
            current, ref = [], 0j
        current.append(e)
        ref += z
    walls.append(current)
    return walls


def estimate_arena(occupancy, x, y, bin_size):
    """An arena polygon from the visited bins: the convex hull of their corners.

    Returns vertices (V, 2) counter-clockwise.
    """
    from scipy.spatial import ConvexHull

    iy, ix = np.nonzero(np.asarray(occupancy) > 0)
    if len(iy) == 0:
        raise ValueError("no visited bin: cannot estimate the arena's walls")
    h = bin_size / 2
    cx, cy = x[ix], y[iy]
    corners = np.concatenate([np.c_[cx + sx * h, cy + sy * h]
                              for sx in (-1, 1) for sy in (-1, 1)])
    hull = ConvexHull(corners)
    return corners[hull.vertices]


@dataclass
class Walls:
    """What the border score needs of an arena, on a given bin grid.

    Attributes
    ----------
    vertices : ndarray (V, 2)
    distance : ndarray (ny * nx,)
        Distance of each bin centre to the nearest wall (0 for centres outside).
    d_max : float
        The arena's inradius (the largest possible distance to the perimeter).
    wall_bins : list of ndarray
        For each wall used for coverage, the flat bin adjacent to the wall at each of its
        sample points (-1 where no visited bin lies within ``search_width``).
    wall_edges : list of list
        The polygon edges of each wall used.
    source : str
    """

    vertices: np.ndarray
    distance: np.ndarray
    d_max: float
    wall_bins: list
    wall_edges: list
    source: str


def arena_walls(vertices, x, y, bin_size, visited, *, search_width, merge_angle,
                min_wall_bins, source):
    """Precompute distances and the wall-adjacent bins on a bin grid (see :class:`Walls`).

    Each wall is sampled every bin along its length; from each sample point, bins are
    looked up along the inward normal at 0.5, 1.5, ... bins (at most ``search_width``),
    and the first visited one is the bin adjacent to the wall there (on an axis-aligned
    square arena these are exactly the bins of the first visited row or column, as in
    the BNT and opexebo).
    """
    v = np.asarray(vertices, float)
    if signed_area(v) < 0:
        v = v[::-1]
    nx, ny = len(x), len(y)
    x0, y0 = x[0] - bin_size / 2, y[0] - bin_size / 2
    gx, gy = np.meshgrid(x, y)
    centres = np.c_[gx.ravel(), gy.ravel()]
    dist = np.where(inside_polygon(centres, v), distance_to_walls(centres, v), 0.0)
    visited = np.asarray(visited, bool).ravel()
    a, b = _edges(v)
    walls = polygon_walls(v, merge_angle)
    wall_bins, wall_edges = [], []
    for edges in walls:
        seg_len = np.array([np.hypot(*(b[e] - a[e])) for e in edges])
        total = seg_len.sum()
        if total < min_wall_bins * bin_size:
            continue
        n_pts = max(1, round(total / bin_size))
        s = (np.arange(n_pts) + 0.5) * total / n_pts
        cum = np.r_[0, np.cumsum(seg_len)]
        which = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(edges) - 1)
        bins = np.full(n_pts, -1, np.int64)
        for i, (si, wi) in enumerate(zip(s, which)):
            e = edges[wi]
            direction = (b[e] - a[e]) / seg_len[wi]
            normal = np.array([-direction[1], direction[0]])  # inward (counter-clockwise)
            p = a[e] + (si - cum[wi]) * direction
            for j in range(search_width):
                q = p + (j + 0.5) * bin_size * normal
                ix = int(np.floor((q[0] - x0) / bin_size))
                iy = int(np.floor((q[1] - y0) / bin_size))
                if 0 <= ix < nx and 0 <= iy < ny and visited[iy * nx + ix]:
                    bins[i] = iy * nx + ix
                    break
        wall_bins.append(bins)
        wall_edges.append(list(edges))
    return Walls(vertices=v, distance=dist, d_max=inradius(v), wall_bins=wall_bins,
                 wall_edges=wall_edges, source=source)


# ------------------------------------------------------------------ the score of a stack
def border_stats(maps, weights, walls: Walls, *, threshold, min_bins, connectivity=1):
    """Border score of a stack of maps (N, ny, nx) sharing one arena and bin grid.

    .. math:: b = \\frac{c_M - d_m}{c_M + d_m}

    ``weights`` (N, ny, nx) are the non-negative rates that weight the firing distance.
    Maps without a field score -1 (``c_M = 0``; the BNT/opexebo convention); maps without
    a single finite bin (no visited bin, NaN activity) are undefined: NaN.

    Returns a dict of arrays (N,): ``score``, ``coverage`` (c_M), ``distance`` (d_m),
    ``wall`` (index of the best wall, -1 if none), ``n_fields``.
    """
    n_maps = maps.shape[0]
    f = detect_fields(maps, threshold=threshold, min_bins=min_bins,
                      connectivity=connectivity, describe=False)
    labels = f.labels.reshape(n_maps, -1)
    k = int(labels.max()) + 1 if labels.size else 1
    coverage = np.zeros(n_maps)
    best_wall = np.full(n_maps, -1)
    rows = np.arange(n_maps)[:, None]
    for w, bins in enumerate(walls.wall_bins):
        ok = bins >= 0
        if not ok.any():
            continue
        lab = labels[:, bins[ok]]
        counts = np.zeros((n_maps, k))
        np.add.at(counts, (np.broadcast_to(rows, lab.shape), lab), 1.0)
        counts[:, 0] = 0
        cov = counts.max(axis=1) / ok.sum()
        better = cov > coverage
        coverage = np.where(better, cov, coverage)
        best_wall = np.where(better, w, best_wall)
    in_field = labels > 0
    wts = np.where(in_field, np.nan_to_num(np.asarray(weights, float).reshape(n_maps, -1)),
                   0.0)
    wts = np.maximum(wts, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        dm = (wts * walls.distance[None]).sum(1) / wts.sum(1) / walls.d_max
        score = (coverage - dm) / (coverage + dm)
    has_field = f.count > 0
    # no field: -1 (the BNT/opexebo convention); no finite bin at all: undefined (NaN)
    defined = np.isfinite(np.asarray(maps, float).reshape(n_maps, -1)).any(axis=1)
    score = np.where(has_field, score, np.where(defined, -1.0, np.nan))
    return {"score": score, "coverage": coverage, "distance": np.where(has_field, dm, np.nan),
            "wall": best_wall, "n_fields": f.count}


def field_bins(bin_size, min_area, min_bins):
    """Smallest field in bins: ``min_area`` (m^2) in bins of ``bin_size``, at least
    ``min_bins``."""
    return max(int(min_bins), int(np.ceil(min_area / bin_size**2 - 1e-9)))


def resolve_walls(walls, maps, lead, x, y, size, *, search_width, merge_angle,
                   min_wall_bins):
    """One :class:`Walls` per map group (list over the flattened non-unit lead dims)."""
    group_dims = [d for d in lead if d != "unit"]
    n_groups = int(np.prod([maps.sizes[d] for d in group_dims])) if group_dims else 1
    ny, nx = len(y), len(x)
    if "occupancy" in maps.coords:
        occ = maps["occupancy"]
        o = occ.transpose(*[d for d in group_dims if d in occ.dims], "y", "x").values
        occ_g = np.broadcast_to(o.reshape(-1, ny, nx), (n_groups, ny, nx))
    else:
        occ_g = np.ones((n_groups, ny, nx))
    kw = dict(search_width=search_width, merge_angle=merge_angle,
              min_wall_bins=min_wall_bins)
    known = maps.attrs.get("arena_vertices")
    env_ids = maps.attrs.get("arena_environment")
    out, coverage = [], []
    for g in range(n_groups):
        visited = occ_g[g] > 0
        estimated = False
        if (isinstance(walls, str) and walls == "occupancy") or (walls is None and known is None):
            verts, estimated = estimate_arena(occ_g[g], x, y, size), True
            source = "estimated from occupancy (convex hull of the visited bins)"
        elif walls is not None:
            verts = check_finite("walls", check_shape(
                "walls", check_real("walls", walls).astype(float), (None, 2)))
            if len(verts) < 3:
                raise ValueError(f"`walls` must be a polygon of at least 3 vertices; got "
                                 f"{len(verts)}")
            source = "given"
        else:
            known_v = np.asarray(known, float)
            env = None
            if len(group_dims) == 1 and "environment" in maps.coords and \
                    maps["environment"].dims == (group_dims[0],):
                env = maps["environment"].values[g]     # by environment, or by trial
            ids = np.asarray(env_ids) if env_ids is not None else np.arange(len(known_v))
            if env is not None and env in ids:
                verts, source = known_v[list(ids).index(env)], "arena_vertices"
            elif len(known_v) == 1:
                verts, source = known_v[0], "arena_vertices"
            else:
                verts, source = estimate_arena(occ_g[g], x, y, size), (
                    "estimated from occupancy: the maps pool several arenas")
                estimated = True
        verts = verts[np.isfinite(verts).all(1)]
        out.append(arena_walls(verts, x, y, size, visited, source=source, **kw))
        if estimated:
            coverage.append(hull_coverage(verts, x, y, visited))
    if coverage and min(coverage) < BORDER.min_hull_coverage:
        _common.warn(
            f"the visited bins fill only {min(coverage):.0%} of their convex hull, from "
            f"which the walls were estimated: a maze or track rather than an open field, "
            f"whose hull edges cross space the animal never entered. Border (and grid) "
            f"scores assume an open arena; pass `walls=` with the arena's outline, or "
            f"read them with care")
    return out


def hull_coverage(vertices, x, y, visited) -> float:
    """The fraction of the bins whose centres lie inside the polygon ``vertices`` that
    were visited."""
    gx, gy = np.meshgrid(x, y)
    inside = inside_polygon(np.c_[gx.ravel(), gy.ravel()], np.asarray(vertices, float))
    return float(np.asarray(visited, bool).ravel()[inside].mean()) if inside.any() else 1.0


@fill_doc
def border_score(rec_or_maps, *, walls=None, n_shuffles=None, seed=None, percentile=None,
                 threshold=None, field_threshold=None, min_area=None, search_width=None,
                 bin_size=None, sigma=None, min_speed=None, by=None, extent=None):
    """Border score of every unit's rate map, in a polygonal arena (Solstad et al. 2008).

    .. math:: b = \\frac{c_M - d_m}{c_M + d_m},\\qquad
              d_m = \\frac{1}{d_{max}}\\frac{\\sum_{i \\in F} \\lambda_i d_i}
              {\\sum_{i\\in F} \\lambda_i}

    :math:`c_M` is the largest fraction of any one wall covered by any one field, and
    :math:`d_m` the rate-weighted mean distance to the nearest wall of the bins of all
    fields, over :math:`d_{max}`, the largest distance to the perimeter (half the shorter
    side in a rectangle, the inradius of a polygon). Fields are contiguous bins above 30%
    of the map's range above its minimum (of the peak, for spike maps) covering at least
    200 cm^2. The walls are the sides of the arena polygon: consecutive edges turning by
    less than 30 degrees form one wall, and walls shorter than 4 bins are not used for
    coverage. A wall is sampled every bin; at each sample the first visited bin inwards
    (within 8 bins) is the bin adjacent to the wall, and the sample is covered if that
    bin belongs to the field. Maps without a field score -1 (BNT/opexebo convention).

    The walls are known in network recordings (``arena_vertices``); in animal recordings
    they are estimated from the occupancy, as the convex hull of the visited bins.

    Parameters
    ----------
    rec_or_maps : xarray.Dataset or xarray.DataArray
        A recording (maps made here, smoothed by one bin) or the output of
        :func:`ratemaps` (no shuffles then).
    walls : None, 'occupancy' or array (V, 2)
        The arena polygon: None = the recording's ``arena_vertices`` where known (one per
        environment), else estimated; 'occupancy' = always estimated; or vertices.
    %(n_shuffles)s
    %(seed)s
    percentile, threshold
        The threshold is the shuffles' 99th percentile (each unit's own, or
        ``threshold='pooled'``); no shuffles for maps.
    field_threshold : float, optional
        Fraction of the range for fields (default 0.3).
    min_area : float, optional
        Smallest field in m^2 (default 0.02).
    search_width : int, optional
        Bins searched inwards for a visited bin (default 8).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``border_score`` (unit, [group]), ``border_coverage`` (c_M), ``border_distance``
        (d_m), ``border_wall`` (index of the best-covered wall), ``n_border_fields``; with
        shuffles ``border_score_threshold``, ``border_score_p_value``, … ; attrs give the
        polygon and where it came from.

    Notes
    -----
    Conventions against opexebo's ``border_score`` (square arenas only): the distance of
    a bin is that of its centre to the nearest wall (opexebo counts bins, so a bin along a
    wall is at distance 1 instead of 0.5 bin), normalised by the inradius (opexebo: half
    the shorter side of the map in bins). Given the same fields, the coverages are
    identical and :math:`d_m^{opexebo} = d_m + 1/\\min(n_x, n_y)` exactly on square maps
    filling the arena (see tests/analysis/test_border_score.py).

    References
    ----------
    Solstad, Boccara, Kropff, Moser & Moser (2008), Representation of geometric borders
    in the entorhinal cortex, Science 322:1865-1868.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> xy = np.random.default_rng(0).uniform(-0.5, 0.5, (20000, 2))
    >>> rate = np.exp(-(xy[:, :1] + 0.5) / 0.05)        # fires along the wall x = -0.5
    >>> rec = from_arrays(np.arange(20000) * 0.1, xy, activity=rate, activity_kind="rate")
    >>> res = border_score(rec, walls=[[-.5, -.5], [.5, -.5], [.5, .5], [-.5, .5]],
    ...                    bin_size=0.05, n_shuffles=0)
    >>> bool(res.border_score[0] > 0.8)
    True
    """
    percentile = check_percentile("percentile", CELL_CLASS.border_percentile
                                  if percentile is None else percentile)
    threshold = check_option("threshold", CELL_CLASS.threshold if threshold is None
                             else threshold, ("unit", "pooled"))
    field_threshold = check_number("field_threshold", BORDER.threshold if field_threshold
                                   is None else field_threshold, low=0, high=1,
                                   low_inclusive=True, high_inclusive=False)
    min_area = check_number("min_area", BORDER.min_area if min_area is None else min_area,
                            low=0, low_inclusive=True)
    search_width = check_number("search_width", BORDER.search_width if search_width is None
                                else search_width, low=1, low_inclusive=True, integer=True)
    if isinstance(walls, str):
        check_option("walls", walls, ("occupancy",))
    stack = None
    if isinstance(rec_or_maps, xr.DataArray):
        refuse_map_options(n_shuffles, seed=seed, bin_size=bin_size, sigma=sigma,
                           min_speed=min_speed, by=by, extent=extent)
        maps, n_shuffles, rec = rec_or_maps, 0, None
    else:
        rec = _common.check_recording(rec_or_maps, ["activity", "position"],
                                      why="border score")
        n_shuffles = _common.default_shuffles(n_shuffles, by, CELL_CLASS.n_shuffles)
        stack = MapStack(rec, n_shuffles=n_shuffles, seed=seed, bin_size=bin_size,
                         sigma=BORDER.sigma if sigma is None else sigma,
                         min_speed=min_speed, by=by, extent=extent)
        maps = stack.observed
    maps, lead = check_maps("rec_or_maps", maps)
    x, y, size = bin_coords(maps)
    geo = resolve_walls(walls, maps, lead, x, y, size, search_width=search_width,
                         merge_angle=np.radians(BORDER.merge_angle),
                         min_wall_bins=BORDER.min_wall_bins)
    min_bins = field_bins(size, min_area, BORDER.min_bins)
    offset, why_offset = _common.map_rate_offset(rec, maps)
    kw = dict(threshold=field_threshold, min_bins=min_bins)
    stats = stack_border_stats(maps.values, offset, geo, **kw)
    shuffled = None
    if stack is not None and stack.n_shuffles:
        shuffled = np.concatenate([stack_border_stats(smooth, offset, geo, **kw)["score"]
                                   for smooth, _ in stack.shuffle_batches()])
    return border_dataset(maps, lead, stats, shuffled, geo, percentile, threshold, params=dict(
        n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed),
        field_threshold=field_threshold, min_area=min_area,
        min_field_bins=min_bins, search_width=search_width, merge_angle=BORDER.merge_angle,
        min_wall_bins=BORDER.min_wall_bins, rate_offset=why_offset))


def stack_border_stats(values, offset, geo, **kw):
    """:func:`border_stats` of maps ``(..., U, [G,] ny, nx)``: one arena per group ``G``
    (``len(geo)`` groups; no group axis when ``geo`` has one arena and the maps none).

    Returns a dict of arrays shaped like the maps' leading dims ``(..., U, [G])``.
    """
    values = np.asarray(values, float)
    ny, nx = values.shape[-2:]
    n_units = len(offset)
    lead = values.shape[:-2]
    v = values.reshape(-1, n_units, len(geo), ny, nx)
    shift = np.asarray(offset, float)[None, :, None, None]
    out = {}
    for g, walls in enumerate(geo):
        m = v[:, :, g]
        st = border_stats(m.reshape(-1, ny, nx), (m - shift).reshape(-1, ny, nx), walls,
                          **kw)
        for key, val in st.items():
            out.setdefault(key, []).append(np.asarray(val).reshape(v.shape[0], n_units))
    return {key: np.stack(parts, axis=-1).reshape(lead) for key, parts in out.items()}


def border_dataset(maps, lead, stats, shuffled, geo, percentile, threshold, params):
    shape = tuple(maps.sizes[d] for d in lead)
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    out = xr.Dataset(coords=coords)
    r = lambda a: np.asarray(a).reshape(shape)
    out["border_score"] = (lead, r(stats["score"]), {"units": "1",
                                                     "long_name": "border score"})
    out["border_coverage"] = (lead, r(stats["coverage"]), {
        "units": "1", "long_name": "largest wall coverage by one field (c_M)"})
    out["border_distance"] = (lead, r(stats["distance"]), {
        "units": "1", "long_name": "normalised rate-weighted distance to the walls (d_m)"})
    out["border_wall"] = (lead, r(stats["wall"]), {
        "units": "1", "long_name": "index of the best-covered wall (-1: none)"})
    out["n_border_fields"] = (lead, r(stats["n_fields"]), {
        "units": "1", "long_name": "fields of the border score"})
    if shuffled is not None:
        add_significance(out, "border_score", lead, r(stats["score"]),
                         shuffled.reshape((-1,) + shape), percentile, threshold, "1",
                         "border score")
    attrs = {k: v for k, v in maps.attrs.items()
             if k not in ("analysis", "units", "long_name", "arena_vertices",
                          "arena_environment")}
    attrs.update(_common.provenance(
        "border_score", **params, percentile=percentile, threshold=threshold,
        map_sigma=maps.attrs.get("sigma", "unknown"),
        walls_source=[g.source for g in geo],
        wall_vertices=[g.vertices.tolist() for g in geo],
        walls_used=[g.wall_edges for g in geo],
        inradius=[g.d_max for g in geo],
        no_field="score -1 (coverage 0; BNT/opexebo convention)",
        definition="(c_M - d_m) / (c_M + d_m), Solstad et al. 2008; bin distances from "
                   "the bin centre to the nearest wall, over the arena's inradius"))
    out.attrs = attrs
    return out
