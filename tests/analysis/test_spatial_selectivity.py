import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning

from .conftest import SQUARE, make_recording, trajectory

BIN = 0.1


def _binned_function_recording(noise_sd, n=20000, seed=10):
    """Unit 0: a function of the 0.1 m bin plus Gaussian noise; unit 1: noise only."""
    rng = np.random.default_rng(seed)
    pos, _ = trajectory(n, rng)
    ix = np.clip(np.floor((pos + 0.5) / BIN), 0, 9)
    f = np.sin(ix[:, 0]) + np.cos(1.7 * ix[:, 1])
    act = np.c_[f + noise_sd * rng.standard_normal(n), rng.standard_normal(n)]
    return make_recording(pos, act, arena_vertices=SQUARE, activity_kind="lstm_hidden"), f


def test_function_of_position_is_fully_selective():
    rec, _ = _binned_function_recording(0.0)
    sel = hp.spatial_selectivity(rec, bin_size=BIN)
    assert sel.selectivity.sel(unit=0) == pytest.approx(1.0, abs=1e-6)
    assert sel.selectivity.sel(unit=1) < 3 * sel.chance


def test_variance_explained_by_position_matches_signal_to_total_ratio():
    rec, f = _binned_function_recording(0.8)
    sel = hp.spatial_selectivity(rec, bin_size=BIN)
    expected = f.var() / (f.var() + 0.8**2)
    assert sel.selectivity.sel(unit=0) == pytest.approx(expected, abs=0.02)
    # offset- and scale-invariant
    shifted = rec.assign(activity=rec.activity * -3.0 + 7.0)
    again = hp.spatial_selectivity(shifted, bin_size=BIN)
    np.testing.assert_allclose(again.selectivity, sel.selectivity, rtol=1e-4)


def test_equals_brute_force_definition():
    rec, _ = _binned_function_recording(0.5, n=5000)
    sel = hp.spatial_selectivity(rec, bin_size=0.13)
    maps = hp.ratemaps(rec, bin_size=0.13, sigma=0)
    act = rec.activity.values.astype(float)
    for u in range(2):
        lam, occ = maps.isel(unit=u).values, maps.occupancy.values
        ok = occ > 0
        p = occ[ok] / occ[ok].sum()
        between = (p * (lam[ok] - act[:, u].mean()) ** 2).sum()
        assert sel.selectivity.values[u] == pytest.approx(between / act[:, u].var(), rel=1e-4)


def test_by_environment_and_lazy():
    rec, _ = _binned_function_recording(0.5, n=8000)
    env = np.repeat([0, 1], 4000)
    rec = rec.assign_coords(environment=("time", env, rec.environment.attrs),
                            trial=("time", env, rec.trial.attrs))    # a trial per arena
    eager = hp.spatial_selectivity(rec, bin_size=BIN, by="environment")
    lazy = hp.spatial_selectivity(rec.chunk({"time": 1500}), bin_size=BIN, by="environment")
    assert eager.selectivity.dims == ("unit", "environment")
    np.testing.assert_allclose(lazy.selectivity, eager.selectivity, rtol=1e-10)
    half = hp.spatial_selectivity(rec.isel(time=slice(4000, None)), bin_size=BIN)
    np.testing.assert_allclose(eager.selectivity.sel(environment=1), half.selectivity,
                               rtol=1e-10)


def test_constant_unit_is_nan_with_reason():
    rec, _ = _binned_function_recording(0.5, n=3000)
    act = rec.activity.values.copy()
    act[:, 1] = 0.25
    rec["activity"] = (("time", "unit"), act, rec.activity.attrs)
    with pytest.warns(AnalysisWarning, match="spatial selectivity is NaN"):
        sel = hp.spatial_selectivity(rec, bin_size=BIN)
    assert np.isnan(sel.selectivity.sel(unit=1))
    assert "constant" in sel.attrs["nan_reasons"]["unit=1"]
