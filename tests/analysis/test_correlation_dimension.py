import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.correlation_dimension import pair_counts

from .conftest import make_recording

N = 2000
SIERPINSKI = np.log(3) / np.log(2)


def _embed(x, rng, dim=256):
    q, _ = np.linalg.qr(rng.standard_normal((dim, x.shape[1])))
    return x @ q.T  # isometric: distances unchanged


def _sets():
    rng = np.random.default_rng(16)
    plane = _embed(rng.uniform(0, 1, (N, 2)), rng)
    u, v = rng.uniform(0, 2 * np.pi, (2, N))
    torus = _embed(np.c_[np.cos(u), np.sin(u), np.cos(v), np.sin(v)], rng)  # flat 2-torus
    corners = np.array([[0, 0], [1, 0], [0.5, np.sqrt(3) / 2]])
    p, pts = np.zeros(2), []
    for k in range(N + 50):  # chaos game
        p = (p + corners[rng.integers(3)]) / 2
        if k >= 50:
            pts.append(p)
    sierpinski = _embed(np.array(pts), rng)
    return {"plane": (plane, 2.0), "torus": (torus, 2.0), "sierpinski": (sierpinski, SIERPINSKI)}


@pytest.fixture(scope="module")
def sets():
    return _sets()


@pytest.mark.parametrize("name", ["plane", "torus", "sierpinski"])
def test_known_dimensions_and_scikit_dimension(sets, name):
    skdim = pytest.importorskip("skdim")
    points, truth = sets[name]
    res = hp.correlation_dimension(points, theiler=0)
    d = res.attrs["dimension"]
    assert d == pytest.approx(truth, rel=0.1)
    assert res.attrs["r_min"] < res.attrs["r_max"]
    theirs = skdim.id.CorrInt().fit(points).dimension_
    assert d == pytest.approx(theirs, rel=0.1)


def test_pair_counts_equal_brute_force_with_theiler_window():
    rng = np.random.default_rng(17)
    x = rng.normal(size=(300, 5))
    order = np.arange(300)
    trial = np.repeat([0, 1, 2], 100)
    edges = np.logspace(-1, 1, 30)
    counts, n_pairs = pair_counts(x, order, trial, theiler=7, edges=edges, block=64)
    i, j = np.triu_indices(300, 1)
    keep = ~((trial[i] == trial[j]) & (np.abs(i - j) < 7))
    d = np.linalg.norm(x[i[keep]] - x[j[keep]], axis=1)
    assert n_pairs == keep.sum()
    np.testing.assert_array_equal(counts, [(d < r).sum() for r in edges])


def test_recording_input_drops_transients_and_reads_lazily():
    rng = np.random.default_rng(18)
    n_trials, per = 4, 1500
    angle = rng.uniform(0, 2 * np.pi, (n_trials * per, 2))
    ring = np.c_[np.cos(angle[:, 0]), np.sin(angle[:, 0]), np.cos(angle[:, 1]),
                 np.sin(angle[:, 1])] @ rng.standard_normal((4, 40)) / 4
    trial = np.repeat(np.arange(n_trials), per)
    first = np.r_[True, trial[1:] != trial[:-1]]
    ring[np.flatnonzero(first)[:, None] + np.arange(30)] += 50.0  # a far-away transient
    rec = make_recording(np.zeros((len(ring), 2)), ring, trial=trial,
                         activity_kind="lstm_hidden")
    res = hp.correlation_dimension(rec, max_points=2000)
    lazy = hp.correlation_dimension(rec.chunk({"time": 1000}), max_points=2000)
    assert res.attrs["dimension"] == pytest.approx(lazy.attrs["dimension"], rel=1e-9)
    assert res.attrs["n_eligible"] == n_trials * (per - 150)
    assert res.attrs["dimension"] == pytest.approx(2.0, rel=0.15)


def test_bad_input():
    with pytest.raises(ValueError, match="array of shape"):
        hp.correlation_dimension(np.zeros(10))
    with pytest.raises(ValueError, match="`c_range` must be"):
        hp.correlation_dimension(np.random.default_rng(0).normal(size=(50, 3)), c_range=(0.5, 0.1))
    with pytest.raises(ValueError, match="NaN or inf"):
        hp.correlation_dimension(np.full((50, 3), np.nan))
    with pytest.warns(AnalysisWarning, match="correlation dimension is NaN"):
        res = hp.correlation_dimension(np.random.default_rng(0).normal(size=(12, 3)), theiler=0)
    assert np.isnan(res.attrs["dimension"])


def _pair_counts_with_arrays(points, order, trial, theiler, edges, block):
    """The array formulation pair_counts replaced (masks, sqrt, searchsorted per block)."""
    m = len(points)
    sq = (points**2).sum(axis=1)
    hist = np.zeros(len(edges) + 1, np.int64)
    n_pairs = 0
    cols = np.arange(m)
    for i0 in range(0, m, block):
        i1 = min(m, i0 + block)
        d2 = sq[i0:i1, None] + sq[None, :] - 2.0 * (points[i0:i1] @ points.T)
        keep = cols[None, :] > np.arange(i0, i1)[:, None]
        keep &= ~((trial[i0:i1, None] == trial[None, :])
                  & (np.abs(order[i0:i1, None] - order[None, :]) < theiler))
        d = np.sqrt(np.maximum(d2[keep], 0.0))
        hist += np.bincount(np.searchsorted(edges, d, side="right"), minlength=len(edges) + 1)
        n_pairs += int(keep.sum())
    return np.cumsum(hist)[:-1], n_pairs


@pytest.mark.parametrize("n,units,block", [(1500, 64, 256), (1500, 256, 256),
                                           (3001, 256, 512), (200, 3, 512)])
def test_block_products_are_those_of_the_full_matrix_bit_for_bit(n, units, block):
    """The upper triangle's products equal the full matrix's, element for element, in
    every block: the partial last block too (a product of the points with themselves
    would go to a symmetric kernel and round differently), and a single block."""
    from hippo_probe.analysis.correlation_dimension import block_products

    rng = np.random.default_rng(3)
    x = np.tanh(rng.standard_normal((n, 8)) @ rng.standard_normal((8, units)))
    for i0 in range(0, n, block):
        i1 = min(n, i0 + block)
        np.testing.assert_array_equal(block_products(x, i0, i1), (x[i0:i1] @ x.T)[:, i0:])


def test_pair_counts_are_bit_for_bit_those_of_the_array_formulation():
    """Same squared distances, same bins: the figures' numbers do not move (LSTM-like
    states: tanh of correlated Gaussians, edges as correlation_dimension draws them)."""
    rng = np.random.default_rng(3)
    x = np.tanh(rng.standard_normal((1500, 8)) @ rng.standard_normal((8, 64)))
    order = np.tile(np.arange(500), 3)
    trial = np.repeat([0, 1, 2], 500)
    edges = np.logspace(-3, np.log10(2 * np.sqrt((x ** 2).sum(1)).max()), 121)
    ours = pair_counts(x, order, trial, theiler=10, edges=edges, block=256)
    theirs = _pair_counts_with_arrays(x, order, trial, 10, edges, 256)
    assert ours[1] == theirs[1]
    np.testing.assert_array_equal(ours[0], theirs[0])


@pytest.mark.parametrize("edges", [np.linspace(0.0, 6.0, 25), np.array([2.5]),
                                   np.sort(np.random.default_rng(4).uniform(0, 6, 40))])
def test_pair_counts_match_searchsorted_for_any_increasing_edges(edges):
    """Edges from 0, a single edge, irregular edges: the bins are searchsorted's."""
    rng = np.random.default_rng(5)
    x = rng.normal(size=(200, 3))
    x[1] = x[0]                                          # a distance of exactly 0
    order, trial = np.arange(200), np.zeros(200, np.int64)
    ours = pair_counts(x, order, trial, theiler=0, edges=edges, block=64)
    theirs = _pair_counts_with_arrays(x, order, trial, 0, edges, 64)
    assert ours[1] == theirs[1] == 200 * 199 // 2
    np.testing.assert_array_equal(ours[0], theirs[0])
    with pytest.raises(ValueError, match="`edges` must be a non-empty increasing"):
        pair_counts(x, order, trial, theiler=0, edges=np.array([]))


def test_squared_thresholds_bin_exactly_as_the_square_root_would():
    """``s >= t[k]`` exactly when ``edges[k] <= sqrt(s)``: at every threshold and its
    neighbouring doubles, for edges from subnormal squares to overflowing ones."""
    from hippo_probe.analysis.correlation_dimension import squared_thresholds

    rng = np.random.default_rng(6)
    edges = np.sort(np.r_[0.0, 1e-170, 1e-160, 10.0 ** rng.uniform(-8, 3, 500), 1e155])
    t = squared_thresholds(edges)
    finite = t[np.isfinite(t)]
    with np.errstate(over="ignore"):
        squares = edges * edges
    s = np.r_[0.0, finite, np.nextafter(finite, np.inf), np.nextafter(finite, -np.inf),
              squares[np.isfinite(squares)], np.inf]
    s = s[s >= 0]
    np.testing.assert_array_equal(s[:, None] >= t[None, :],
                                  edges[None, :] <= np.sqrt(s)[:, None])


def test_count_rows_bins_extreme_squared_distances_as_searchsorted():
    """The compiled binning against searchsorted on the square root, one squared distance
    at a time: 0, -0.0, negatives, subnormals, the largest double, inf, NaN, every
    threshold and its neighbours, the guess table's cell boundaries."""
    from hippo_probe.analysis.correlation_dimension import (
        _GUESS_SHIFT, _count_rows, bin_guesses, squared_thresholds)

    edges = np.array([-1.0, 0.0, 1e-200, 3e-162, 1e-160, 1e-5, 1.0,
                      np.nextafter(1.0, 2.0), 1e154, 1.35e154, 1e300, np.inf])
    t = squared_thresholds(edges)
    guesses, offset = bin_guesses(t)
    finite = t[np.isfinite(t)]
    cells = np.arange(offset, offset + len(guesses) + 1, max(1, len(guesses) // 64))
    boundaries = (cells << _GUESS_SHIFT).view(np.float64)
    rng = np.random.default_rng(8)
    values = np.r_[0.0, -0.0, -1e-300, 5e-324, 2.2250738585072014e-308,
                   np.finfo(float).max, np.inf, np.nan, finite, np.nextafter(finite, np.inf),
                   np.nextafter(finite, -np.inf), boundaries,
                   np.nextafter(boundaries, -np.inf),
                   rng.uniform(-1, 1, 500) * 10.0 ** rng.uniform(-320, 308, 500)]
    for s in values:
        hist = np.zeros(len(edges) + 1, np.int64)
        _count_rows(np.zeros((1, 2)), np.array([0.0, s]), 0, np.arange(2),
                    np.zeros(2, np.int64), 0.0, t, guesses, offset, hist)
        with np.errstate(invalid="ignore"):
            want = np.searchsorted(edges, np.sqrt(np.maximum(s, 0.0)), side="right")
        assert np.flatnonzero(hist).tolist() == [want], s
    with pytest.raises(ValueError, match="without NaN"):
        pair_counts(np.zeros((3, 2)), np.arange(3), np.zeros(3, np.int64), theiler=0,
                    edges=np.array([0.5, np.nan, 2.0]))
