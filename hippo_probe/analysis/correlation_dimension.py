"""Correlation dimension of the activity's trajectory (Grassberger-Procaccia)."""

from __future__ import annotations

import numba
import numpy as np
import xarray as xr

from .._validators import check_number, check_real, check_seed
from . import _common
from .config import CORRELATION_DIMENSION as CFG



def _points(data, *, max_points, transient, seed):
    """Select at most ``max_points`` samples; returns (points, order, trial, info)."""
    rng = np.random.default_rng(check_seed("seed", seed))
    if isinstance(data, xr.Dataset):
        _common.check_recording(data, ["activity"], why="correlation dimension")
        n = data.sizes["time"]
        trial = _common.values(data["trial"]) if "trial" in data.coords or "trial" in data \
            else np.zeros(n, np.int64)
        starts = np.r_[0, np.flatnonzero(trial[1:] != trial[:-1]) + 1]
        lengths = np.diff(np.r_[starts, n])
        pos_in_trial = np.arange(n) - np.repeat(starts, lengths)
        keep = pos_in_trial >= np.floor(transient * np.repeat(lengths, lengths))
        eligible = np.flatnonzero(keep)
        chosen = np.sort(rng.choice(eligible, min(max_points, eligible.size), replace=False))
        act = _common.activity(data).isel(time=chosen)
        points = np.asarray(act.values, np.float64)
        info = dict(source="recording", n_samples=n, n_eligible=int(eligible.size),
                    transient_fraction=transient)
        return points, chosen, trial[chosen], info
    arr = check_real("rec_or_array", data).astype(np.float64)
    if arr.ndim != 2:
        raise ValueError(f"`rec_or_array` must be a recording or a (samples, dims) array; "
                         f"got an array of shape {arr.shape}")
    n = arr.shape[0]
    start = int(np.floor(transient * n))
    chosen = np.sort(rng.choice(np.arange(start, n), min(max_points, n - start),
                                replace=False))
    info = dict(source="array", n_samples=n, n_eligible=n - start, transient_fraction=transient)
    return arr[chosen], chosen, np.zeros(len(chosen), np.int64), info


#: The bin guess reads a squared distance's exponent and top 6 mantissa bits: 64 cells
#: per octave, each far narrower than a bin (the default 50 bins per decade of r are 0.13
#: octave of r² wide), so the guess is the bin or the one below it.
_GUESS_SHIFT = 46


def squared_thresholds(edges) -> np.ndarray:
    """For each edge ``e``, the smallest double ``t`` with ``sqrt(t) >= e``.

    ``edges[k] <= sqrt(s)`` holds exactly when ``s >= t[k]`` (the square root is
    correctly rounded, hence monotone), so a squared distance is binned without its square
    root, in the bins ``searchsorted(edges, sqrt(s), side="right")`` gives. Edges <= 0
    get ``-inf``: every distance reaches them.
    """
    edges = np.asarray(edges, np.float64)
    with np.errstate(over="ignore"):            # an overflowing square is walked down
        t = np.where(edges > 0, edges * edges, -np.inf)
    for k in np.flatnonzero(edges > 0):
        e = edges[k]
        while np.sqrt(t[k]) < e:                     # e * e rounded down
            t[k] = np.nextafter(t[k], np.inf)
        while t[k] > 0 and np.sqrt(np.nextafter(t[k], -np.inf)) >= e:   # rounded up
            t[k] = np.nextafter(t[k], -np.inf)
    return t


def bin_guesses(thresholds) -> tuple[np.ndarray, int]:
    """A table of first guesses of the bin, indexed by a squared distance's bit pattern.

    The bits of a non-negative double, read as an integer, grow with it; cell ``c`` of
    the table holds the number of thresholds at or below the smallest double whose bits
    shifted right by ``_GUESS_SHIFT`` are ``c + offset``: a lower bound of the bin of
    every double of the cell. Returns ``(table, offset)``.
    """
    finite = thresholds[np.isfinite(thresholds) & (thresholds > 0)]
    if finite.size == 0:
        return np.zeros(1, np.int64), 0
    lo, hi = (int(np.float64(v).view(np.int64)) >> _GUESS_SHIFT
              for v in (finite[0], finite[-1]))
    cells = np.arange(lo, hi + 1, dtype=np.int64)
    starts = (cells << _GUESS_SHIFT).view(np.float64)
    return np.searchsorted(thresholds, starts, side="right").astype(np.int64), lo


@numba.njit(cache=True)
def _count_rows(dots, sq, i0, order, trial, theiler, thresholds, guesses, offset, hist):
    """Add the pairs (i, j > i) of rows ``i0 ..`` into ``hist`` (bin k: ``k`` edges <= d);
    returns how many were counted.

    ``dots`` holds the rows' dot products with the points from ``i0`` on (one BLAS
    product; column ``c`` is point ``i0 + c``: the pairs j > i need no earlier point), and
    the squared distance is formed as ``(|x_i|^2 + |x_j|^2) - 2 x_i.x_j``, the operations and
    their order those of the array expression it replaced, without fast-math. It is
    binned against the edges' squared thresholds (:func:`squared_thresholds`), so the
    counts are bit for bit those of ``searchsorted(edges, sqrt(s))``, with no square root
    or logarithm per pair: the bin is guessed from the bits of ``s``
    (:func:`bin_guesses`, a lower bound) and raised against the thresholds themselves.
    """
    rows, m = dots.shape[0], i0 + dots.shape[1]
    n_edges = thresholds.shape[0]
    last = guesses.shape[0] - 1
    value = np.empty(1, np.float64)
    bits = value.view(np.int64)               # the same 8 bytes, read as an integer
    pairs = 0
    for r in range(rows):
        i = i0 + r
        for j in range(i + 1, m):
            if trial[i] == trial[j] and abs(order[i] - order[j]) < theiler:
                continue                      # inside the Theiler window
            s = sq[i] + sq[j] - 2.0 * dots[r, j - i0]
            k = 0
            if s > 0.0:
                value[0] = s
                cell = (bits[0] >> _GUESS_SHIFT) - offset
                if cell >= 0:                 # below the table: below every threshold > 0
                    k = guesses[min(cell, last)]
            elif s != s:                      # NaN (inf - inf): past every edge, as
                k = n_edges                   # searchsorted puts it
            else:
                s = 0.0
            while k < n_edges and thresholds[k] <= s:   # the guess is never too high
                k += 1
            hist[k] += 1
            pairs += 1
    return pairs


def block_products(points, i0: int, i1: int) -> np.ndarray:
    """Dot products of points ``i0 .. i1-1`` with the points from ``i0`` on: the block's
    row of the upper triangle, half the work of a row of the full matrix.

    Each product is the one the full row ``points[i0:i1] @ points.T`` holds, bit for bit
    (tested): BLAS computes an element of a general product the same way whatever its
    width. The last block is the exception: there the two operands are the same points,
    and NumPy hands a product of an array with its own transpose to a symmetric kernel
    (``syrk``), which rounds differently; it gets the full row, sliced.
    """
    if i1 == len(points) and i0 > 0:
        return np.ascontiguousarray((points[i0:i1] @ points.T)[:, i0:])
    return points[i0:i1] @ points[i0:].T


def pair_counts(points, order, trial, theiler, edges, block=None):
    """Histogram of pairwise distances over ``edges``, computed in row blocks.

    Pairs (i < j) in the same trial with ``|order_i - order_j| < theiler`` are skipped
    (Theiler window). Returns (counts of d < edges[k] for each k, number of pairs).
    Memory: one ``block x n`` matrix of dot products at a time; only the products of
    pairs at or above the diagonal's block are computed (:func:`block_products`), each
    the same as in the full matrix, so the counts are too.
    """
    block = CFG.block if block is None else block
    points = np.ascontiguousarray(points, np.float64)
    m = len(points)
    sq = (points**2).sum(axis=1)
    order = np.ascontiguousarray(order, np.int64)
    trial = np.ascontiguousarray(trial, np.int64)
    edges = np.ascontiguousarray(edges, np.float64)
    if edges.ndim != 1 or edges.size == 0 or np.isnan(edges).any() \
            or (np.diff(edges) <= 0).any():
        raise ValueError(f"`edges` must be a non-empty increasing 1-D array without NaN; "
                         f"got {edges.size} values")
    thresholds = squared_thresholds(edges)
    guesses, offset = bin_guesses(thresholds)
    hist = np.zeros(len(edges) + 1, np.int64)
    n_pairs = 0
    for i0 in range(0, m, block):
        i1 = min(m, i0 + block)
        n_pairs += _count_rows(block_products(points, i0, i1), sq, i0, order, trial,
                               float(theiler), thresholds, guesses, offset, hist)
    return np.cumsum(hist)[:-1], n_pairs


def scaling_fit(log_r, log_c, c_range, min_decades):
    """Slope of log C vs log r over the most linear window inside ``c_range``.

    Among windows at least ``min_decades`` wide in r with ``c_range[0] <= C <= c_range[1]``,
    the one with the smallest RMS residual per decade of width is used.
    Returns (slope, intercept, index_lo, index_hi) or None if no window fits.
    """
    lo, hi = np.log10(c_range[0]), np.log10(c_range[1])
    idx = np.flatnonzero((log_c >= lo) & (log_c <= hi))
    if idx.size < 3:
        return None
    x, y = log_r[idx], log_c[idx]
    # least squares over every window [a, b] at once, from prefix sums
    cum = [np.r_[0.0, np.cumsum(v)] for v in (np.ones_like(x), x, y, x * x, x * y, y * y)]
    a, b = np.triu_indices(len(x), k=2)
    n, sx, sy, sxx, sxy, syy = (c[b + 1] - c[a] for c in cum)
    vx = sxx - sx**2 / n
    cxy = sxy - sx * sy / n
    vy = syy - sy**2 / n
    width = x[b] - x[a]
    ok = (width >= min_decades) & (vx > 0)
    if not ok.any():
        return None
    slope = np.where(ok, cxy / np.where(ok, vx, 1.0), 0.0)
    rms = np.sqrt(np.maximum(vy - slope * cxy, 0.0) / n)
    score = np.where(ok, rms / np.where(ok, width, 1.0), np.inf)
    k = int(np.argmin(score))
    intercept = (sy[k] - slope[k] * sx[k]) / n[k]
    return slope[k], intercept, idx[a[k]], idx[b[k]]


def sampling_options(cfg, is_rec, max_points, theiler, transient):
    """``(max_points, theiler, transient)`` checked, defaults from ``cfg`` (a config with
    those fields; arrays default to no transient): the state sampling shared with
    :func:`~hippo_probe.analysis.intrinsic_dimension`."""
    max_points = check_number("max_points", cfg.max_points if max_points is None
                              else max_points, low=10, low_inclusive=True, integer=True)
    theiler = check_number("theiler", cfg.theiler if theiler is None else theiler, low=0,
                           low_inclusive=True, integer=True)
    transient = check_number("transient", (cfg.transient if is_rec else 0.0)
                             if transient is None else transient, low=0, low_inclusive=True,
                             high=1, high_inclusive=False)
    return max_points, theiler, transient


def correlation_dimension(rec_or_array, *, max_points=None, theiler=None, transient=None,
                          c_range=None, min_decades=None, seed=None):
    """Correlation dimension of the activity's trajectory (Grassberger-Procaccia).

    .. math:: C(r) = \\frac{1}{N_{pairs}} \\#\\{(i, j): \\lVert x_i - x_j\\rVert < r\\},
              \\qquad C(r) \\propto r^{D}

    over pairs of (sub-sampled) states :math:`x_i`, excluding pairs closer in time than
    the Theiler window within a trial; each trial's initial transient is dropped. ``D`` is
    the slope of :math:`\\log C` vs :math:`\\log r` over the scaling range: the most linear
    window, at least ``min_decades`` wide, where ``c_range[0] <= C <= c_range[1]``. Pair
    distances are counted block by block into a log-spaced histogram, so memory stays
    ``O(block x points)``; only the selected samples of a lazy recording are read.

    Parameters
    ----------
    rec_or_array : xarray.Dataset or array (samples, dims)
        A recording (its ``activity``, trials from ``trial``) or points in time order.
    max_points : int, optional
        Samples drawn at random (default 4000).
    theiler : int, optional
        Theiler window in samples (default 10).
    transient : float, optional
        Fraction of each trial dropped at its start (default 0.1 for recordings; arrays
        default to 0).
    c_range : (float, float), optional
        C(r) range searched for the scaling range (default (1e-4, 0.1)).
    min_decades : float, optional
        Minimal width of the scaling range in decades of r (default 0.5).
    seed : int, optional
        Seed of the subsampling.

    Returns
    -------
    xarray.Dataset
        ``log_c`` (log10 C) over ``log_r`` (log10 r) — the curve — and ``local_slope``;
        attrs ``dimension`` (D), ``r_min``/``r_max`` (the scaling range), ``n_points``,
        ``n_pairs``.

    References
    ----------
    Grassberger & Procaccia (1983), Measuring the strangeness of strange attractors,
    Physica D 9:189-208. Theiler (1986), Spurious dimension from correlation integrals of
    filtered noise, Phys. Rev. A 34:2427.

    Examples
    --------
    >>> import numpy as np
    >>> x = np.random.default_rng(0).uniform(size=(2000, 2)) @ np.eye(2, 10)
    >>> res = correlation_dimension(x)
    >>> bool(abs(res.attrs["dimension"] - 2.0) < 0.2)
    True
    """
    is_rec = isinstance(rec_or_array, xr.Dataset)
    max_points, theiler, transient = sampling_options(CFG, is_rec, max_points, theiler,
                                                      transient)
    c_range = CFG.c_range if c_range is None else tuple(c_range)
    if not (len(c_range) == 2 and 0 < c_range[0] < c_range[1] <= 1):
        raise ValueError(f"`c_range` must be (low, high) with 0 < low < high <= 1; got "
                         f"{c_range}")
    min_decades = check_number("min_decades", CFG.min_decades if min_decades is None
                               else min_decades, low=0)
    seed = CFG.seed if seed is None else seed
    points, order, trial, info = _points(rec_or_array, max_points=max_points,
                                         transient=transient, seed=seed)
    if not np.isfinite(points).all():
        raise ValueError("`rec_or_array` holds NaN or inf in the selected samples: distances "
                         "are undefined")
    if not np.isfinite((points ** 2).sum(axis=1)).all():
        raise ValueError("`rec_or_array` holds values too large to square (beyond about "
                         "1e154): its distances overflow; rescale it")
    if len(points) < 10:
        raise ValueError(f"correlation dimension needs at least 10 samples after dropping "
                         f"the transient; got {len(points)}")
    spread = np.sqrt(((points - points.mean(axis=0)) ** 2).sum(axis=1)).max()
    r_top = 2 * spread * (1 + 1e-9)  # no distance exceeds twice the largest radius
    edges = np.logspace(np.log10(r_top) - CFG.decades, np.log10(r_top),
                        CFG.decades * CFG.per_decade + 1)
    counts, n_pairs = pair_counts(points, order, trial, theiler, edges)
    if n_pairs == 0 or spread == 0:
        raise ValueError("no pair of distinct samples outside the Theiler window: the "
                         "correlation sum is undefined")
    c = counts / n_pairs
    shown = c > 0
    log_r, log_c = np.log10(edges[shown]), np.log10(c[shown])
    fit = scaling_fit(log_r, log_c, c_range, min_decades)
    slopes = np.gradient(log_c, log_r) if len(log_r) > 1 else np.full(len(log_r), np.nan)
    out = xr.Dataset(coords={"log_r": ("log_r", log_r, {"units": "log10(activity units)",
                                                        "long_name": "log10 radius"})})
    out["log_c"] = ("log_r", log_c, {"units": "1", "long_name": "log10 correlation sum"})
    out["local_slope"] = ("log_r", slopes, {"units": "1",
                                            "long_name": "local slope d log C / d log r"})
    attrs = _common.provenance(
        "correlation_dimension", rec_or_array if is_rec else None, max_points=max_points,
        theiler=theiler, c_range=list(c_range), min_decades=min_decades, seed=seed,
        n_points=len(points), n_pairs=n_pairs, **info)
    if fit is None:
        attrs.update(dimension=np.nan, r_min=np.nan, r_max=np.nan)
        why = (f"no window of {min_decades} decades with {c_range[0]} <= C(r) <= "
               f"{c_range[1]}: too few points or no scaling range")
    else:
        slope, _, a, b = fit
        attrs.update(dimension=float(slope), r_min=float(10 ** log_r[a]),
                     r_max=float(10 ** log_r[b]))
        why = ""
    out.attrs = _common.report_nan(attrs, ["dimension"], [why], "correlation dimension")
    return out
