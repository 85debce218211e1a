"""Geometry references for the world's tests, written independently of hippo_probe."""

import numpy as np
import pytest


def _cross(u, v):
    return u[..., 0] * v[..., 1] - u[..., 1] * v[..., 0]


def segments_cross(p0, p1, q0, q1):
    """Whether segments p0-p1 and q0-q1 share a point (arrays (..., 2), broadcast).

    Parametric solve ``p0 + t (p1 - p0) = q0 + u (q1 - q0)`` with t, u in [0, 1];
    collinear overlapping segments also count as crossing.
    """
    r, s = p1 - p0, q1 - q0
    den = _cross(r, s)
    qp = q0 - p0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(qp, s) / den
        u = _cross(qp, r) / den
    proper = (den != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    # parallel: cross only if collinear and the projections overlap
    rr = np.sum(r * r, axis=-1)
    collinear = (den == 0) & (_cross(qp, r) == 0) & (rr > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = np.sum(qp * r, axis=-1) / rr
        t1 = t0 + np.sum(s * r, axis=-1) / rr
    overlap = np.maximum(np.minimum(t0, t1), 0) <= np.minimum(np.maximum(t0, t1), 1)
    # a zero-length p (the agent stayed put) crosses only if p0 lies on q
    ss = np.sum(s * s, axis=-1)
    with np.errstate(divide="ignore", invalid="ignore"):
        along = np.sum((p0 - q0) * s, axis=-1) / ss
    on_q = (rr == 0) & (_cross(p0 - q0, s) == 0) & (along >= 0) & (along <= 1)
    return proper | (collinear & overlap) | on_q


def boundary_samples(vertices, per_edge):
    """Points densely spaced along every wall of polygons (..., V, 2) -> (..., V*per_edge, 2)."""
    a = np.asarray(vertices, dtype=float)
    b = np.roll(a, -1, axis=-2)
    t = np.linspace(0.0, 1.0, per_edge)[:, None]                        # (S, 1)
    pts = a[..., :, None, :] + t * (b - a)[..., :, None, :]              # (..., V, S, 2)
    return pts.reshape(*a.shape[:-2], -1, 2)


@pytest.fixture(scope="session")
def geometry():
    """The reference geometry helpers above, as a namespace."""

    class Geometry:
        cross = staticmethod(segments_cross)
        boundary = staticmethod(boundary_samples)

    return Geometry
