"""Grid score, spacing and orientation from the spatial autocorrelogram of rate maps."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import fft as sfft
from scipy import ndimage

from .._angles import wrap_angle
from .._validators import check_number, check_option
from . import _common
from ._common import refuse_map_options
from .._docs import fill_doc
from ._shuffles import MapStack, add_significance, check_percentile, flat_maps
from .config import CELL_CLASS, GRID
from .place_fields import bin_coords, check_maps

ANGLES = (30, 60, 90, 120, 150)  # degrees; 60 and 120 for a hexagonal lattice
CHUNK = 256  # maps per block of the vectorised computations (memory ~ CHUNK x lags)


# ------------------------------------------------------------------ autocorrelogram
def autocorrelogram(maps, min_overlap):
    """Pearson autocorrelation of each map at every lag, over the bins visited twice.

    .. math:: r(\\tau) = \\frac{n\\sum \\lambda_i\\lambda_{i+\\tau} - \\sum\\lambda_i
              \\sum\\lambda_{i+\\tau}}{\\sqrt{n\\sum\\lambda_i^2 - (\\sum\\lambda_i)^2}
              \\sqrt{n\\sum\\lambda_{i+\\tau}^2 - (\\sum\\lambda_{i+\\tau})^2}}

    with the sums over the n bins ``i`` such that ``i`` and ``i + tau`` are both visited
    (finite). Every sum is a cross-correlation of the maps and their masks, computed by
    FFT. Lags with ``n < min_overlap`` are NaN, and so are lags whose overlapping part
    of the map is constant to 1e-10 of its scale (e.g. an overlap that misses every
    field): their correlation would be FFT round-off.

    Parameters
    ----------
    maps : ndarray (N, ny, nx)
    min_overlap : int

    Returns
    -------
    ndarray (N, 2 ny - 1, 2 nx - 1)
        Zero lag at ``(ny - 1, nx - 1)``; row = lag in y, column = lag in x.
    """
    maps = np.asarray(maps, float)
    n_maps, ny, nx = maps.shape
    out = np.empty((n_maps, 2 * ny - 1, 2 * nx - 1))
    shape = (sfft.next_fast_len(2 * ny - 1, real=True),
             sfft.next_fast_len(2 * nx - 1, real=True))
    rows = np.arange(-(ny - 1), ny) % shape[0]
    cols = np.arange(-(nx - 1), nx) % shape[1]
    for a in range(0, n_maps, CHUNK):
        block = maps[a:a + CHUNK]
        mask = np.isfinite(block)
        with np.errstate(invalid="ignore"):
            mean = np.where(mask, block, 0.0).sum((1, 2)) / mask.sum((1, 2))
        x = np.where(mask, block - mean[:, None, None], 0.0)
        # maps of one recording share their visited bins: one mask transform serves all
        shared = bool((mask == mask[:1]).all())
        fm = sfft.rfft2(mask[:1].astype(float) if shared else mask.astype(float), shape,
                        workers=1)
        fx, fxx = (sfft.rfft2(v, shape, workers=1) for v in (x, x * x))

        def corr(fa, fb):  # sum_p a(p) b(p + tau)
            c = sfft.irfft2(np.conj(fa) * fb, shape, workers=1)
            return c[:, rows][:, :, cols]

        n = np.rint(corr(fm, fm))
        # sum_p m(p) b(p + tau) is sum_p b(p) m(p - tau): the mirror image (lag -tau)
        sx, sxx = corr(fx, fm), corr(fxx, fm)
        sy, syy = sx[:, ::-1, ::-1], sxx[:, ::-1, ::-1]
        sxy = corr(fx, fx)
        with np.errstate(invalid="ignore", divide="ignore"):
            var_x = n * sxx - sx * sx
            var_y = n * syy - sy * sy
            r = (n * sxy - sx * sy) / np.sqrt(var_x * var_y)
        # a constant overlap (variance at round-off) has no correlation
        tiny = 1e-10 * np.maximum(n * np.maximum(sxx, syy), 1e-300)
        r[(n < min_overlap) | (var_x <= tiny) | (var_y <= tiny)] = np.nan
        out[a:a + CHUNK] = np.clip(r, -1.0, 1.0)
    return out


# ------------------------------------------------------------------ geometry of lags
class _Rotations:
    """Bilinear look-up of an autocorrelogram rotated about zero lag, for the lags of a
    disc, sorted by distance (precomputed once per shape)."""

    def __init__(self, shape, r_max):
        h, w = shape
        cy, cx = (h - 1) // 2, (w - 1) // 2
        dy, dx = np.mgrid[-cy:h - cy, -cx:w - cx]
        d2 = dy * dy + dx * dx
        inside = d2 < (r_max + 1) ** 2
        order = np.argsort(d2[inside], kind="stable")
        self.d2 = d2[inside][order]
        self.flat = np.flatnonzero(inside.ravel())[order]
        py, px = dy[inside][order].astype(float), dx[inside][order].astype(float)
        self.tables = []
        for angle in ANGLES:
            t = np.radians(angle)
            ry = cy + np.sin(t) * px + np.cos(t) * py
            rx = cx + np.cos(t) * px - np.sin(t) * py
            y0, x0 = np.floor(ry).astype(int), np.floor(rx).astype(int)
            fy, fx = ry - y0, rx - x0
            ok = (y0 >= 0) & (x0 >= 0) & (y0 + 1 < h) & (x0 + 1 < w)
            # points that land (to round-off) on a lag need no neighbour beyond the edge
            y0, x0 = np.clip(y0, 0, h - 2), np.clip(x0, 0, w - 2)
            snap = ~ok & (np.abs(ry - np.rint(ry)) < 1e-9) & (np.abs(rx - np.rint(rx)) < 1e-9)
            idx = [(y0 + a) * w + (x0 + b) for a in (0, 1) for b in (0, 1)]
            wts = [(1 - fy) * (1 - fx), (1 - fy) * fx, fy * (1 - fx), fy * fx]
            if snap.any():
                exact = np.rint(ry[snap]).astype(int) * w + np.rint(rx[snap]).astype(int)
                for k in range(4):
                    idx[k][snap] = exact
                    wts[k][snap] = 1.0 if k == 0 else 0.0
                ok = ok | snap
            self.tables.append((np.stack(idx), np.stack(wts), ok))

    def rotated(self, flat_acorr, k):
        """Values (N, P) of the autocorrelograms rotated by ANGLES[k] at the disc's lags."""
        idx, wts, ok = self.tables[k]
        vals = np.zeros((flat_acorr.shape[0], idx.shape[1]))
        for j in range(4):
            # a neighbour with zero weight must not turn the value into NaN
            vals += np.where(wts[j] > 0, flat_acorr[:, idx[j]] * wts[j], 0.0)
        vals[:, ~ok] = np.nan
        return vals


def central_radius(acorr, threshold):
    """Radius (whole bins, floored) of the disc with the area of each autocorrelogram's
    central peak: the 4-connected region around zero lag where ``r > threshold``."""
    _, h, w = acorr.shape
    with np.errstate(invalid="ignore"):
        above = acorr > threshold
    structure = np.zeros((3, 3, 3), bool)
    structure[1] = ndimage.generate_binary_structure(2, 1)
    labels, _ = ndimage.label(above, structure=structure)
    centre = labels[:, (h - 1) // 2, (w - 1) // 2]
    area = np.bincount(labels.ravel(), minlength=labels.max() + 1)[centre]
    area = np.where(centre > 0, area, 0)
    return np.floor(np.sqrt(area / np.pi)).astype(int)


def _ring_correlations(acorr, rot: _Rotations, r_in, r_max):
    """Correlation of each autocorrelogram with its rotations over the rings
    ``r_in < d < R`` for every integer ``R`` in 1..r_max.

    Returns (N, 5, r_max + 1): entry ``[:, k, R]`` for ``ANGLES[k]`` (NaN where the ring
    is empty or ``R <= r_in``).
    """
    n_maps = acorr.shape[0]
    flat = acorr.reshape(n_maps, -1)
    x = flat[:, rot.flat]
    radii = np.arange(r_max + 1)
    # d < R  <=>  d^2 <= R^2 - 1 ;  d > r  <=>  d^2 > r^2  (d^2 is an integer)
    hi = np.searchsorted(rot.d2, radii**2 - 1, side="right")        # (R,)
    lo = np.searchsorted(rot.d2, np.minimum(r_in, r_max) ** 2, side="right")  # (N,)
    out = np.full((n_maps, len(ANGLES), r_max + 1), np.nan)
    rows = np.arange(n_maps)[:, None]
    for k in range(len(ANGLES)):
        y = rot.rotated(flat, k)
        valid = np.isfinite(x) & np.isfinite(y)
        xv, yv = np.where(valid, x, 0.0), np.where(valid, y, 0.0)
        sums = []
        for q in (valid.astype(float), xv, yv, xv * xv, yv * yv, xv * yv):
            c = np.concatenate([np.zeros((n_maps, 1)), np.cumsum(q, axis=1)], axis=1)
            sums.append(c[:, hi] - c[rows, lo[:, None]])
        n, sx, sy, sxx, syy, sxy = sums
        with np.errstate(invalid="ignore", divide="ignore"):
            r = (n * sxy - sx * sy) / np.sqrt((n * sxx - sx**2) * (n * syy - sy**2))
        r[(n < 3) | (radii[None, :] <= r_in[:, None])] = np.nan
        out[:, k] = r
    return out


def gridness(ring_r):
    """``min(r60, r120) - max(r30, r90, r150)`` from ring correlations (..., 5, R)."""
    return np.minimum(ring_r[..., 1, :], ring_r[..., 3, :]) - np.max(
        ring_r[..., [0, 2, 4], :], axis=-2)


def _sweep(g, first, window):
    """Maximum over outer radii ``R >= first`` of ``g`` averaged over ``window``
    consecutive radii; the plain mean when fewer radii than ``window`` are defined."""
    n_maps, n_r = g.shape
    radii = np.arange(n_r)
    g = np.where(radii[None] >= first[:, None], g, np.nan)
    ok = np.isfinite(g)
    csum = np.concatenate([np.zeros((n_maps, 1)), np.cumsum(np.where(ok, g, 0.0), 1)], 1)
    ccnt = np.concatenate([np.zeros((n_maps, 1)), np.cumsum(ok, 1)], 1)
    win_sum = csum[:, window:] - csum[:, :-window]
    win_cnt = ccnt[:, window:] - ccnt[:, :-window]
    with np.errstate(invalid="ignore"):
        means = np.where(win_cnt == window, win_sum / window, -np.inf)
        best = means.max(axis=1, initial=-np.inf)      # no window fits: the fallback
        fallback = np.where(ok.any(1), np.nansum(np.where(ok, g, 0), 1) / ok.sum(1), np.nan)
    return np.where(np.isfinite(best), best, fallback)


# ------------------------------------------------------------------ peaks
def _peak_candidates(acorr, r_in, r_max, threshold):
    """Boolean (N, H, W): local maxima (3 x 3) above ``threshold`` in ``r_in < d <= r_max``."""
    _, h, w = acorr.shape
    a = np.where(np.isfinite(acorr), acorr, -np.inf)
    mf = ndimage.maximum_filter(a, size=(1, 3, 3), mode="constant", cval=-np.inf)
    dy, dx = np.mgrid[-(h - 1) // 2:(h + 1) // 2, -(w - 1) // 2:(w + 1) // 2]
    d = np.sqrt(dy * dy + dx * dx)
    return ((a == mf) & (a > threshold) & (d[None] > r_in[:, None, None])
            & (d[None] <= r_max)), dy, dx


def _subbin(a, y, x):
    """Parabolic sub-bin offset of a peak at (y, x) of a 2-D array (0 if undefined)."""
    def offset(m, c, p):
        den = m - 2 * c + p
        return 0.0 if not np.isfinite(den) or den >= 0 else 0.5 * (m - p) / den
    h, w = a.shape
    oy = offset(a[y - 1, x], a[y, x], a[y + 1, x]) if 0 < y < h - 1 else 0.0
    ox = offset(a[y, x - 1], a[y, x], a[y, x + 1]) if 0 < x < w - 1 else 0.0
    return float(np.clip(oy, -0.5, 0.5)), float(np.clip(ox, -0.5, 0.5))


def six_peaks(acorr, r_in, r_max, threshold, min_orientation):
    """The (up to) six peaks nearest the centre of each autocorrelogram.

    Candidates are local maxima above ``threshold`` outside the central peak; taken by
    increasing distance, a candidate in a direction within ``min_orientation`` (rad) of a
    nearer kept peak is dropped. Positions are refined by a parabola through each peak and
    its neighbours along x and along y.

    Returns a list (per map) of arrays (k, 2) of (dy, dx) lags in bins, k <= 6.
    """
    cand, dy, dx = _peak_candidates(acorr, r_in, r_max, threshold)
    m_idx, yy, xx = np.nonzero(cand)
    split = np.searchsorted(m_idx, np.arange(acorr.shape[0] + 1))
    cy, cx = (acorr.shape[1] - 1) // 2, (acorr.shape[2] - 1) // 2
    out = []
    for m in range(acorr.shape[0]):
        ys, xs = yy[split[m]:split[m + 1]], xx[split[m]:split[m + 1]]
        off = np.c_[dy[ys, xs], dx[ys, xs]].astype(float)
        order = np.argsort(np.hypot(off[:, 0], off[:, 1]), kind="stable")
        kept, angles = [], []
        for i in order:
            ang = np.arctan2(off[i, 0], off[i, 1])
            if any(abs(wrap_angle(ang - b)) < min_orientation for b in angles):
                continue
            oy, ox = _subbin(acorr[m], ys[i], xs[i])
            kept.append((ys[i] - cy + oy, xs[i] - cx + ox))
            angles.append(ang)
            if len(kept) == 6:
                break
        out.append(np.array(kept, float).reshape(-1, 2))
    return out


def spacing_orientation(peaks):
    """Median distance (bins) and orientation (rad, in [0, pi/3)) of each map's peaks.

    .. math:: \\phi = \\frac{1}{6}\\arg\\sum_k e^{6 i \\theta_k} \\bmod 60^\\circ

    the direction of the lattice's axes counter-clockwise from +x, from the six peaks'
    directions :math:`\\theta_k`. NaN with fewer than three peaks.
    """
    spacing = np.full(len(peaks), np.nan)
    orientation = np.full(len(peaks), np.nan)
    for m, p in enumerate(peaks):
        if len(p) >= 3:
            spacing[m] = np.median(np.hypot(p[:, 0], p[:, 1]))
            theta = np.arctan2(p[:, 0], p[:, 1])
            orientation[m] = np.mod(np.angle(np.exp(6j * theta).sum()) / 6, np.pi / 3)
    return spacing, orientation


# ------------------------------------------------------------------ scores of a stack
def grid_stats(maps, *, min_overlap, central_threshold, peak_threshold, min_orientation,
               max_radius, max_central, window, annulus, min_outer, want_peaks=True):
    """Grid score (and peak geometry) of a stack of maps (N, ny, nx).

    Returns a dict of arrays (N,): ``score``, ``central_radius`` (bins), and with
    ``want_peaks`` (always for ``annulus="peaks"``) ``spacing`` (bins), ``orientation``
    (rad), ``n_peaks``.
    """
    maps = np.asarray(maps, float)
    n_maps, ny, nx = maps.shape
    r_max = int(np.floor(max_radius * min(ny, nx)))
    r_max = max(1, min(r_max, min(ny, nx) - 1))
    rot = _Rotations((2 * ny - 1, 2 * nx - 1), r_max)
    score = np.full(n_maps, np.nan)
    radius = np.zeros(n_maps, int)
    spacing = np.full(n_maps, np.nan)
    orientation = np.full(n_maps, np.nan)
    n_peaks = np.zeros(n_maps, int)
    used_sweep = np.zeros(n_maps, bool)
    want_peaks = want_peaks or annulus == "peaks"
    for a in range(0, n_maps, CHUNK):
        ac = autocorrelogram(maps[a:a + CHUNK], min_overlap)
        r_in = central_radius(ac, central_threshold)
        # a central peak wider than half the annulus leaves no room for a ring of peaks:
        # NaN, and no ring correlations to compute
        room = r_in < max_central * r_max
        g = np.full((len(ac), r_max + 1), np.nan)
        if room.any():
            g[room] = gridness(_ring_correlations(ac[room], rot, r_in[room], r_max))
        first = np.maximum(min_outer, r_in + 1)
        sweep = _sweep(g, first, window)
        sl = slice(a, a + len(ac))
        radius[sl] = r_in
        if want_peaks:
            peaks = six_peaks(ac, r_in, r_max, peak_threshold, np.radians(min_orientation))
            sp, ori = spacing_orientation(peaks)
            spacing[sl], orientation[sl] = sp, ori
            n_peaks[sl] = [len(p) for p in peaks]
        if annulus == "peaks":
            block = sweep.copy()
            for i, p in enumerate(peaks):
                if len(p) >= 3:
                    outer = int(np.rint(np.hypot(p[:, 0], p[:, 1]).max() + r_in[i]))
                    outer = min(max(outer, r_in[i] + 1), r_max)
                    block[i] = g[i, outer]
            used_sweep[sl] = n_peaks[sl] < 3
            score[sl] = block
        else:
            score[sl] = sweep
        score[sl] = np.where(room, score[sl], np.nan)
    return {"score": score, "central_radius": radius, "spacing": spacing,
            "orientation": orientation, "n_peaks": n_peaks, "used_sweep": used_sweep,
            "r_max": r_max}


def grid_kwargs(min_overlap, annulus):
    """The options of :func:`grid_stats` (defaults from :data:`~.config.GRID`), checked."""
    return dict(
        min_overlap=check_number("min_overlap", GRID.min_overlap if min_overlap is None
                                 else min_overlap, low=1, low_inclusive=True, integer=True),
        central_threshold=GRID.central_threshold, peak_threshold=GRID.peak_threshold,
        min_orientation=GRID.min_orientation, max_radius=GRID.max_radius,
        max_central=GRID.max_central,
        window=GRID.window, min_outer=GRID.min_outer,
        annulus=check_option("annulus", GRID.annulus if annulus is None else annulus,
                             ("sweep", "peaks")))


# ------------------------------------------------------------------ public functions
@fill_doc
def spatial_autocorrelation(rec_or_maps, *, min_overlap=None, bin_size=None, sigma=None,
                            min_speed=None, by=None, extent=None):
    """Spatial autocorrelogram of every unit's rate map.

    .. math:: r(\\tau) = \\mathrm{corr}_i\\left(\\lambda_i, \\lambda_{i+\\tau}\\right)

    the Pearson correlation of the map with itself shifted by the lag
    :math:`\\tau = (\\tau_x, \\tau_y)`, over the bins visited in both (unvisited bins are
    left out, not set to 0). Lags with fewer than ``min_overlap`` such bins are NaN.

    Parameters
    ----------
    rec_or_maps : xarray.Dataset or xarray.DataArray
        A recording (maps made with :func:`ratemaps`) or the output of :func:`ratemaps`.
    min_overlap : int, optional
        Default 20 bins (Sargolini et al. 2006).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.DataArray
        Dims (unit, [group], lag_y, lag_x), lags in metres.

    References
    ----------
    Hafting, Fyhn, Molden, Moser & Moser (2005), Microstructure of a spatial map in the
    entorhinal cortex, Nature 436:801-806. Sargolini et al. (2006), Science 312:758-762.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> xy = np.random.default_rng(0).uniform(-0.5, 0.5, (20000, 2))
    >>> rec = from_arrays(np.arange(20000) * 0.1, xy, activity=np.cos(20 * xy[:, :1]),
    ...                   activity_kind="rate")
    >>> ac = spatial_autocorrelation(rec, bin_size=0.05)
    >>> float(ac.sel(lag_x=0, lag_y=0)[0])
    1.0
    """
    from .ratemaps import ratemaps

    if isinstance(rec_or_maps, xr.DataArray):
        refuse_map_options(bin_size=bin_size, sigma=sigma, min_speed=min_speed, by=by,
                           extent=extent)
    maps = rec_or_maps if isinstance(rec_or_maps, xr.DataArray) else ratemaps(
        rec_or_maps, bin_size=bin_size, sigma=GRID.sigma if sigma is None else sigma,
        min_speed=min_speed, by=by, extent=extent)
    maps, lead = check_maps("rec_or_maps", maps)
    min_overlap = grid_kwargs(min_overlap, None)["min_overlap"]
    flat, shape = flat_maps(maps.values)
    ac = autocorrelogram(flat, min_overlap)
    _, _, size = bin_coords(maps)
    ny, nx = flat.shape[1:]
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    coords["lag_y"] = ("lag_y", size * np.arange(-(ny - 1), ny),
                       {"units": "m", "long_name": "lag in y"})
    coords["lag_x"] = ("lag_x", size * np.arange(-(nx - 1), nx),
                       {"units": "m", "long_name": "lag in x"})
    attrs = _common.provenance("spatial_autocorrelation", min_overlap=min_overlap,
                               map_sigma=maps.attrs.get("sigma", "unknown"),
                               bin_size=size, units="1", long_name="autocorrelation",
                               unvisited="left out of every sum (not set to 0)")
    return xr.DataArray(ac.reshape(shape + ac.shape[1:]), dims=lead + ("lag_y", "lag_x"),
                        coords=coords, attrs=attrs, name="autocorrelation")


@fill_doc
def grid_score(rec_or_maps, *, n_shuffles=None, seed=None, percentile=None, threshold=None,
               annulus=None, min_overlap=None, bin_size=None, sigma=None, min_speed=None,
               by=None, extent=None):
    """Grid score, spacing and orientation of every unit's rate map.

    .. math:: g = \\min(r_{60}, r_{120}) - \\max(r_{30}, r_{90}, r_{150})

    with :math:`r_\\alpha` the Pearson correlation, over an annulus around zero lag, of
    the spatial autocorrelogram (:func:`spatial_autocorrelation`) and its rotation by
    :math:`\\alpha` degrees. The annulus excludes the central peak (the region around zero
    lag where r > 0.1; its radius is that of the disc of equal area, in whole bins); a
    central peak wider than half the largest annulus (0.9 x the map's shorter side) leaves
    no room for a ring of peaks, and the score is NaN (broad or ramp-like maps). The
    annulus' outer radius is chosen from the peaks:

    - ``annulus="sweep"`` (default; Langston et al. 2010 as implemented by the BNT and
      opexebo): g for every outer radius from the central radius + 1 bin (at least 3) to
      0.9 x the map's shorter side, averaged over 3 consecutive radii; the maximum;
    - ``annulus="peaks"`` (Sargolini et al. 2006): the annulus reaches the six peaks
      nearest the centre plus one central radius (the sweep where fewer than three peaks
      are found).

    Spacing is the median distance of the six peaks nearest the centre (local maxima with
    r > 0.1, refined to sub-bin precision by a parabola; of two peaks within 15 degrees of
    each other the nearer is kept); orientation is the direction of the lattice's axes,
    :math:`\\frac{1}{6}\\arg\\sum_k e^{6i\\theta_k}` taken in [0, 60) degrees
    counter-clockwise from +x (returned in radians).

    Significance: the same score of ``n_shuffles`` circular time shifts of the activity
    against the trajectory (maps re-binned for each shift); ``grid_score_threshold`` is
    their ``percentile`` (default 95th, Langston et al. 2010). Units whose own score is
    NaN get no shuffles (NaN threshold; with ``threshold="pooled"`` the pool is that of
    the units with a score).

    Parameters
    ----------
    rec_or_maps : xarray.Dataset or xarray.DataArray
        A recording (maps made here, smoothed by one bin by default; may be dask-backed)
        or the output of :func:`ratemaps` (no shuffles then).
    n_shuffles : int, optional
        Default 100 for a recording without ``by``, 0 for maps or with ``by`` (refused
        with ``by``: the shifts would mix the groups' activity into each group's null;
        shuffle a group alone by selecting its trials, :func:`~hippo_probe.select_trials`).
    %(seed)s
    percentile : float, optional
        Percentile of the shuffles used as threshold (default 95).
    threshold : {'unit', 'pooled'}, optional
        Each unit's own shuffles (default) or all units' together.
    annulus : {'sweep', 'peaks'}, optional
    min_overlap : int, optional
        Lags with fewer bins visited twice are NaN (default 20).
    %(bin_size)s
    %(sigma_maps)s
    %(min_speed)s
    %(by)s
    %(extent)s

    Returns
    -------
    xarray.Dataset
        ``grid_score`` (unit, [group]); ``grid_spacing`` (m), ``grid_orientation`` (rad),
        ``n_peaks``, ``central_radius`` (m); with shuffles ``grid_score_threshold``,
        ``grid_score_p_value``, ``grid_score_shuffle_mean``, ``grid_score_shuffle_std``.

    Notes
    -----
    Conventions that differ from opexebo's ``grid_score`` (and the BNT's): unvisited bins
    are left out of the autocorrelogram (opexebo sets them to 0 rate), and lags whose
    overlap is constant are NaN (opexebo correlates the far tails); rotated lags are
    interpolated bilinearly and pairs with an undefined lag are left out (opexebo rotates
    with zero fill); the central peak is the region above r = 0.1 (opexebo: an adaptive
    place-field search); the sweep's windows include the last three radii (opexebo's loop
    stops one window short); spacing is the median of six peak distances (opexebo: the
    mean of three). On fully visited maps the autocorrelograms are identical to 1e-10;
    with opexebo's central radius the ring correlations match to 1e-3, and with ours the
    scores correlate at r > 0.95 over the test maps and differ by up to 0.3
    (tests/analysis/test_grid_score.py).

    References
    ----------
    Sargolini, Fyhn, Hafting, McNaughton, Witter, Moser & Moser (2006), Conjunctive
    representation of position, direction, and velocity in entorhinal cortex, Science
    312:758-762. Langston, Ainge, Couey, Canto, Bjerknes, Witter, Moser & Moser (2010),
    Development of the spatial representation system in the rat, Science 328:1576-1580.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> xy = np.random.default_rng(0).uniform(-0.5, 0.5, (40000, 2))
    >>> k = 4 * np.pi / (np.sqrt(3) * 0.3)      # spacing 0.3 m
    >>> waves = [np.cos(k * (xy @ [np.cos(a), np.sin(a)])) for a in (0, np.pi/3, 2*np.pi/3)]
    >>> rate = np.exp(sum(waves))[:, None]
    >>> rec = from_arrays(np.arange(40000) * 0.1, xy, activity=rate, activity_kind="rate")
    >>> res = grid_score(rec, bin_size=0.025, n_shuffles=0)
    >>> bool(res.grid_score[0] > 1), round(float(res.grid_spacing[0]), 2)
    (True, 0.3)
    """
    kw = grid_kwargs(min_overlap, annulus)
    percentile = check_percentile("percentile", CELL_CLASS.grid_percentile
                                  if percentile is None else percentile)
    threshold = check_option("threshold", CELL_CLASS.threshold if threshold is None
                             else threshold, ("unit", "pooled"))
    stack = None
    if isinstance(rec_or_maps, xr.DataArray):
        refuse_map_options(n_shuffles, seed=seed, bin_size=bin_size, sigma=sigma,
                           min_speed=min_speed, by=by, extent=extent)
        maps = rec_or_maps
        n_shuffles = 0
    else:
        rec = _common.check_recording(rec_or_maps, ["activity", "position"],
                                      why="grid score")
        n_shuffles = _common.default_shuffles(n_shuffles, by, CELL_CLASS.n_shuffles)
        stack = MapStack(rec, n_shuffles=n_shuffles, seed=seed, bin_size=bin_size,
                         sigma=GRID.sigma if sigma is None else sigma, min_speed=min_speed,
                         by=by, extent=extent)
        maps = stack.observed
    maps, lead = check_maps("rec_or_maps", maps)
    flat, shape = flat_maps(maps.values)
    stats = grid_stats(flat, **kw)
    shuffled = None
    if stack is not None and stack.n_shuffles:
        parts = [shuffled_scores(smooth, stats["score"], kw)
                 for smooth, _ in stack.shuffle_batches()]
        shuffled = np.concatenate(parts).reshape((-1,) + shape)
    return grid_dataset(maps, lead, shape, stats, shuffled, percentile, threshold,
                        params=dict(n_shuffles=n_shuffles, seed=_common.shuffle_seed(seed),
                                    **kw))


def shuffled_scores(smooth, observed, kw):
    """Grid scores (K, N) of shuffled maps (K, ..., ny, nx) whose observed maps (N,) have a
    finite score; NaN for the others (a unit without a measurable annulus cannot be a grid
    cell, whatever its shuffles)."""
    k = smooth.shape[0]
    flat = np.asarray(smooth, float).reshape(k, -1, *smooth.shape[-2:])
    keep = np.isfinite(observed)
    out = np.full((k, flat.shape[1]), np.nan)
    if keep.any():
        sub = flat[:, keep].reshape(-1, *flat.shape[-2:])
        out[:, keep] = grid_stats(sub, want_peaks=False, **kw)["score"].reshape(k, -1)
    return out


def grid_dataset(maps, lead, shape, stats, shuffled, percentile, threshold, params):
    """Label grid statistics (and their shuffles) as a Dataset."""
    _, _, size = bin_coords(maps)
    coords = {k: c for k, c in maps.coords.items() if set(c.dims) <= set(lead)}
    out = xr.Dataset(coords=coords)
    r = lambda a: np.asarray(a).reshape(shape)
    out["grid_score"] = (lead, r(stats["score"]), {"units": "1", "long_name": "grid score"})
    out["grid_spacing"] = (lead, r(stats["spacing"] * size), {
        "units": "m", "long_name": "grid spacing"})
    out["grid_orientation"] = (lead, r(stats["orientation"]), {
        "units": "rad", "long_name": "grid orientation (axes mod 60 deg, from +x)"})
    out["n_peaks"] = (lead, r(stats["n_peaks"]), {
        "units": "1", "long_name": "peaks found around the centre (at most 6)"})
    out["central_radius"] = (lead, r(stats["central_radius"] * size), {
        "units": "m", "long_name": "radius of the autocorrelogram's central peak"})
    if shuffled is not None:
        add_significance(out, "grid_score", lead, r(stats["score"]), shuffled, percentile,
                         threshold, "1", "grid score")
    attrs = {k: v for k, v in maps.attrs.items()
             if k not in ("analysis", "units", "long_name", "arena_vertices",
                          "arena_environment")}
    attrs.update(_common.provenance(
        "grid_score", **params, percentile=percentile, threshold=threshold,
        rotations_deg=list(ANGLES), max_outer_radius_bins=stats["r_max"],
        map_sigma=maps.attrs.get("sigma", "unknown"),
        definition="min(r60, r120) - max(r30, r90, r150) of the autocorrelogram over an "
                   "annulus excluding the central peak (Sargolini et al. 2006; Langston et "
                   "al. 2010)"))
    out.attrs = _common.report_nan(attrs, _common.entry_labels(out["grid_score"]),
                                   nan_reasons(stats), "grid score")
    return out


def nan_reasons(stats):
    """Why each NaN grid score is NaN (empty string where it is not)."""
    return ["" if np.isfinite(s) else
            "map or autocorrelogram undefined (constant or unvisited map)" if rad == 0 else
            "central peak wider than half the largest annulus (a broad or ramp-like map): "
            "no room for a ring of peaks"
            for s, rad in zip(stats["score"], stats["central_radius"])]
