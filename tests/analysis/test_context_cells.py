import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning

from .conftest import SQUARE, gaussian_fields, make_recording, trajectory


def _context_recording(n_units=20, n_trials=6, per_trial=2500, seed=14):
    """Units 0-9 carry position (place fields, same in both arenas, small readout
    weights); units 10-19 carry the arena identity only (large weights)."""
    rng = np.random.default_rng(seed)
    pos = np.concatenate([trajectory(per_trial, rng)[0] for _ in range(n_trials)])
    trial = np.repeat(np.arange(n_trials), per_trial)
    env = trial % 2
    half = n_units // 2
    centres = rng.uniform(-0.4, 0.4, (half, 2))
    place = gaussian_fields(pos, centres, 0.1)
    level = rng.uniform(0.2, 1.0, (2, half))
    context = level[env] + 0.05 * rng.standard_normal((len(pos), half))
    act = np.c_[place + 0.05 * rng.standard_normal(place.shape), context]
    weights = np.c_[rng.normal(0, 0.1, (2, half)), rng.normal(0, 1.0, (2, half))]
    weights[:, half:] += np.sign(weights[:, half:])  # context units: |w| > 1
    rec = make_recording(pos, act, trial=trial, environment=env, arena_vertices=SQUARE,
                         activity_kind="lstm_hidden")
    rec["readout_weight"] = (("environment_id", "unit"), weights,
                             {"units": "1", "long_name": "classifier readout weight"})
    return rec, weights


def test_context_units_project_strongly_and_are_not_spatial():
    rec, weights = _context_recording()
    res = hp.context_cells(rec, bin_size=0.1)
    np.testing.assert_allclose(res.projection_strength, np.linalg.norm(weights, axis=0))
    sel = res.spatial_selectivity.values
    assert sel[:10].min() > 0.5 and sel[10:].max() < 0.1
    assert res.attrs["rank_correlation"] < -0.7
    assert res.attrs["rank_correlation_p"] < 1e-3


def test_explicit_weights_and_bad_shapes():
    rec, weights = _context_recording(n_trials=2, per_trial=2000)
    a = hp.context_cells(rec.drop_vars("readout_weight"), weights, bin_size=0.1)
    b = hp.context_cells(rec, bin_size=0.1)
    np.testing.assert_allclose(a.projection_strength, b.projection_strength)
    wt = xr.DataArray(weights.T, dims=("unit", "cls"), coords={"unit": rec.unit.values})
    c = hp.context_cells(rec, wt, bin_size=0.1)
    np.testing.assert_allclose(c.projection_strength, b.projection_strength)
    with pytest.raises(ValueError, match=r"`weights` must have shape \(n_classes, n_units=20\)"):
        hp.context_cells(rec, weights.T, bin_size=0.1)
    with pytest.raises(ValueError, match="readout_weight"):
        hp.context_cells(rec.drop_vars("readout_weight"))


def test_too_few_units_gives_nan_with_reason():
    rec, weights = _context_recording(n_units=2, n_trials=2, per_trial=2000)
    with pytest.warns(AnalysisWarning, match="rank correlation is NaN"):
        res = hp.context_cells(rec, bin_size=0.1)
    assert np.isnan(res.attrs["rank_correlation"])
    assert "need 3" in res.attrs["nan_reasons"]["rank_correlation"]
