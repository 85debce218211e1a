import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.ratemaps import spatial_grid

from .conftest import SQUARE, make_recording, place_cell_recording, trajectory


def _half_arena_recording(kind="rate"):
    rng = np.random.default_rng(5)
    pos, _ = trajectory(20000, rng)
    act = np.c_[(pos[:, 0] < 0).astype(float), np.full(len(pos), 3.0),
                1.0 + 0.5 * np.sin(4 * pos[:, 1])]
    return make_recording(pos, act, arena_vertices=SQUARE, activity_kind=kind), pos


def test_half_arena_unit_carries_log2_of_inverse_occupancy():
    rec, pos = _half_arena_recording()
    info = hp.spatial_information(rec, bin_size=0.1)
    q = (pos[:, 0] < 0).mean()  # bin edges fall on x = 0
    assert info.information.sel(unit=0).item() == pytest.approx(-np.log2(q), rel=1e-10)
    assert info.information.sel(unit=1).item() == pytest.approx(0.0, abs=1e-12)
    assert info.mean_rate.sel(unit=0).item() == pytest.approx(q, rel=1e-10)
    # bits/s = mean rate (Hz) x bits/spike
    assert info.information_rate.sel(unit=0).item() == pytest.approx(q * -np.log2(q))
    assert info.information.attrs["units"] == "bits/spike"


def test_exact_skaggs_agrees_with_pynapple_and_opexebo_clips():
    nap = pytest.importorskip("pynapple")
    rec, _ = _half_arena_recording()
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=0)
    ours = hp.spatial_information(maps)
    grid = spatial_grid(rec, 0.1)
    t = rec.time.values
    frame = nap.TsdFrame(t=t, d=rec.activity.values.astype(float))
    feats = nap.TsdFrame(t=t, d=rec.position.values, columns=["x", "y"])
    tc = nap.compute_tuning_curves(frame, feats, bins=[grid.x_edges, grid.y_edges])
    # pynapple's mean rate defaults to spikes / epoch duration; Skaggs' is the
    # occupancy-weighted mean of the map, passed explicitly (the stated convention)
    mi = nap.compute_mutual_information(tc, rates=ours.mean_rate.values)
    np.testing.assert_allclose(ours.information.values, mi["bits/spike"].values, rtol=1e-6)

    opexebo = pytest.importorskip("opexebo")
    occ = maps.occupancy.values
    clipped = [opexebo.analysis.rate_map_stats(maps.sel(unit=u).values, occ)
               ["spatial_information_content"] for u in maps.unit.values]
    # unit 2 has bins below its mean: opexebo drops their (negative) terms
    assert clipped[2] > ours.information.values[2] + 1e-3
    p = occ / occ.sum()
    lam = maps.sel(unit=2).values
    r = lam / (p * lam).sum()
    assert ours.information.values[2] == pytest.approx((p * r * np.log2(r)).sum())


def test_uniform_units_carry_no_information_after_shuffle_correction():
    rng = np.random.default_rng(6)
    pos, _ = trajectory(30000, rng)
    counts = rng.poisson(0.3, (len(pos), 6)).astype(np.float32)
    rec = make_recording(pos, counts, arena_vertices=SQUARE, activity_kind="spike_count")
    info = hp.spatial_information(rec, bin_size=0.1, n_shuffles=40, seed=1)
    raw, corr = info.information.values, info.information_corrected.values
    assert (raw > 0.005).all()  # finite-sample bias
    assert np.all(np.abs(corr) < 3 * info.shuffle_std.values + 1e-3)
    assert np.abs(corr).max() < 0.25 * raw.min()
    assert (info.p_value > 0.02).all()


def test_place_cells_are_significant(place_rec):
    rec, _ = place_rec
    info = hp.spatial_information(rec, bin_size=0.05, n_shuffles=20)
    assert (info.information_corrected > 1.0).all()
    assert (info.p_value == 1 / 21).all()


def test_signed_activity_is_shifted_by_its_minimum():
    rec = place_cell_recording(np.array([[0.1, 0.1], [-0.2, 0.0]]), activity_kind="lstm_hidden",
                               n_samples=8000)
    info = hp.spatial_information(rec, bin_size=0.1)
    assert "minimum over the recording" in info.attrs["rate_offset"]
    shifted = rec.copy()
    act = rec.activity.values
    shifted["activity"] = (("time", "unit"), act - act.min(axis=0))
    shifted.attrs["activity_kind"] = "rate"
    ref = hp.spatial_information(shifted, bin_size=0.1)
    np.testing.assert_allclose(info.information.values, ref.information.values, rtol=1e-5)


def test_maps_and_recording_inputs_agree(place_rec):
    rec, _ = place_rec
    a = hp.spatial_information(rec, bin_size=0.05, by="trial")
    b = hp.spatial_information(hp.ratemaps(rec, bin_size=0.05, sigma=0, by="trial"))
    np.testing.assert_allclose(a.information.values, b.information.values)
    assert a.information.dims == ("unit", "trial")
    with pytest.raises(ValueError, match="`n_shuffles` needs a recording"):
        hp.spatial_information(hp.ratemaps(rec), n_shuffles=5)


def test_zero_activity_unit_is_nan_with_reason():
    rec, _ = _half_arena_recording()
    act = rec.activity.values.copy()
    act[:, 1] = 0
    rec["activity"] = (("time", "unit"), act)
    with pytest.warns(AnalysisWarning, match="spatial information is NaN for 1 entries"):
        info = hp.spatial_information(rec, bin_size=0.1)
    assert np.isnan(info.information.sel(unit=1))
    assert "mean activity is 0" in info.attrs["nan_reasons"]["unit=1"]
    assert np.isfinite(info.information.sel(unit=0))


def test_dask_and_shuffles_lazy_equal_eager(place_rec):
    rec, _ = place_rec
    eager = hp.spatial_information(rec, bin_size=0.05, n_shuffles=5, seed=3)
    lazy = hp.spatial_information(rec.chunk({"time": 4000}), bin_size=0.05, n_shuffles=5,
                                  seed=3)
    for name in ("information", "shuffle_mean", "information_corrected"):
        np.testing.assert_allclose(lazy[name].values, eager[name].values, rtol=1e-10)


def test_negative_values_in_a_nonnegative_kind_are_shifted_with_a_warning():
    rec, _ = _half_arena_recording()
    rec["activity"] = rec.activity - 0.5  # "rate" kind, but now half negative
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=0)
    assert np.isnan(maps.activity_min).all() and "not tracked" in maps.activity_min.attrs["note"]
    with pytest.warns(AnalysisWarning, match="negative values"):
        info = hp.spatial_information(maps)
    assert "map minus its minimum" in info.attrs["rate_offset"]
    # unit 0 (0/1 -> -0.5/0.5): shifting by the map's minimum restores the 0/1 unit
    q = (_half_arena_recording()[1][:, 0] < 0).mean()
    assert info.information.sel(unit=0).item() == pytest.approx(-np.log2(q), rel=1e-6)


def test_the_information_rate_is_bits_per_second_of_spikes_only():
    """bits/s = bits/spike x spikes/s; a signal that is not a rate has no bits/s (it
    used to depend on the sample interval)."""
    rng = np.random.default_rng(5)
    t = np.arange(30000) * 0.02
    xy = np.c_[0.5 * np.cos(t / 7), 0.5 * np.sin(t / 5)]
    rate = 10 * np.exp(-((xy - 0.2) ** 2).sum(1) / 0.02)
    spikes = hp.recording.from_arrays(t, xy, activity=rng.poisson(rate * 0.02)[:, None]
                                      .astype(float), activity_kind="spike_count")
    res = hp.spatial_information(spikes, bin_size=0.05)
    np.testing.assert_allclose(res.information_rate, res.information * res.mean_rate)
    assert res.information_rate.attrs["units"] == "bits/s"
    signal = spikes.assign_attrs(activity_kind="lstm_hidden")
    res = hp.spatial_information(signal, bin_size=0.05)
    assert np.isfinite(res.information).all() and np.isnan(res.information_rate).all()
    assert "not a rate" in res.information_rate.attrs["note"]
