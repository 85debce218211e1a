"""Context cells: units that project strongly onto the arena classifier."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import stats

from .._validators import check_finite
from . import _common
from .._docs import fill_doc
from .spatial_selectivity import spatial_selectivity


def _weights(rec, weights):
    """Classifier weights as (class, unit) aligned with ``rec.unit``."""
    if weights is None:
        rec = _common.check_recording(rec, ["readout_weight"],
                                why="context cells need the classifier's weights; pass "
                                    "`weights` or record them")
        weights = rec["readout_weight"]
    if isinstance(weights, xr.DataArray):
        if "unit" not in weights.dims or weights.ndim != 2:
            raise ValueError(f"`weights` must be 2-D with a 'unit' dim; got dims "
                             f"{weights.dims}")
        if "unit" in weights.coords and "unit" in rec.coords:
            weights = weights.sel(unit=rec["unit"].values)
        other = next(d for d in weights.dims if d != "unit")
        return check_finite("weights", np.asarray(weights.transpose(other, "unit").values,
                                                  float))
    w = np.asarray(weights, float)
    n_units = rec.sizes["unit"]
    if w.ndim != 2 or w.shape[1] != n_units:
        raise ValueError(f"`weights` must have shape (n_classes, n_units={n_units}); got "
                         f"{w.shape}")
    return check_finite("weights", w)


@fill_doc
def context_cells(rec, weights=None, *, bin_size=None, min_speed=None):
    """Projection strength of each unit onto the classifier, and its spatial selectivity.

    .. math:: P_u = \\lVert W_{:,u} \\rVert_2 = \\Bigl(\\sum_e W_{e,u}^2\\Bigr)^{1/2}

    with :math:`W` the readout weights of the arena classifier (classes x units). Spatial
    selectivity (:func:`spatial_selectivity`) is computed within each environment and
    averaged over environments, so a unit that only signals *which* arena it is in counts
    as non-spatial. Context cells are units with large :math:`P_u` and low selectivity;
    the Spearman rank correlation between the two measures summarises the relation.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording with ``activity``, ``position`` (and ``environment``); its
        ``readout_weight`` (environment_id, unit) is used when ``weights`` is None.
    weights : array (n_classes, n_units) or DataArray with a 'unit' dim, optional
        Classifier weights.
    %(bin_size)s
    %(min_speed)s

    Returns
    -------
    xarray.Dataset
        ``projection_strength`` and ``spatial_selectivity`` over ``unit``; attrs
        ``rank_correlation`` (Spearman rho) and ``rank_correlation_p``.

    References
    ----------
    Kanitscheider & Fiete (2017), Training recurrent networks to generate hypotheses
    about how the brain solves hard navigation problems, NIPS 30 (Fig. 4E, context cells).
    Spearman (1904), The proof and measurement of association between two things, Am. J.
    Psychol. 15:72-101.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.arange(4000) * 0.1
    >>> xy = 0.5 * np.c_[np.cos(t / 7), np.sin(t / 5)]
    >>> act = np.c_[np.cos(4 * xy), np.random.default_rng(0).normal(size=(4000, 2))]
    >>> rec = from_arrays(t, xy, activity=act, activity_kind="lstm_hidden")
    >>> weights = np.array([[0.1, 0.0, 2.0, 1.0], [0.0, 0.2, -1.0, 3.0]])
    >>> res = context_cells(rec, weights)
    >>> res.projection_strength.values.round(2)
    array([0.1 , 0.2 , 2.24, 3.16])
    >>> round(res.attrs["rank_correlation"], 2)
    -0.8
    """
    rec = _common.check_recording(rec, ["activity", "position"], why="context cells")
    w = _weights(rec, weights)
    strength = np.sqrt((w**2).sum(axis=0))
    n_env = len(np.unique(_common.values(rec["environment"]))) if "environment" in rec.coords \
        else 1
    by = "environment" if n_env > 1 else None
    sel = spatial_selectivity(rec, bin_size=bin_size, min_speed=min_speed, by=by)
    selectivity = sel["selectivity"]
    if by is not None:
        selectivity = selectivity.mean("environment", skipna=True)
    selectivity = selectivity.values
    ok = np.isfinite(strength) & np.isfinite(selectivity)
    if ok.sum() >= 3:
        rho, p = stats.spearmanr(strength[ok], selectivity[ok])
        why = ""
    else:
        rho, p = np.nan, np.nan
        why = f"only {ok.sum()} units with both measures finite (need 3)"
    coords = {name: c for name, c in rec["activity"].coords.items() if c.dims == ("unit",)}
    out = xr.Dataset(coords=coords)
    out["projection_strength"] = ("unit", strength, {
        "units": "1", "long_name": "projection strength onto the classifier"})
    out["spatial_selectivity"] = ("unit", selectivity, {
        "units": "1", "long_name": "spatial selectivity (mean over environments)"})
    attrs = _common.provenance(
        "context_cells", rec, weights="rec.readout_weight" if weights is None else "given",
        rank_correlation=float(rho), rank_correlation_p=float(p), n_units_used=int(ok.sum()),
        selectivity=f"spatial_selectivity by={by!r}, averaged over environments",
        bin_size=sel.attrs["bin_size"])
    out.attrs = _common.report_nan(attrs, ["rank_correlation"], [why], "rank correlation")
    return out
