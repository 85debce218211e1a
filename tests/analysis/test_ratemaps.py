import warnings

import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe.errors import RecordingError
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.ratemaps import spatial_grid

from .conftest import SQUARE, make_recording, place_cell_recording, trajectory


def _reference_maps(rec, edges_x, edges_y):
    """Plain numpy: per-bin mean activity via histogram2d (the definition)."""
    pos = rec.position.values
    act = rec.activity.values.astype(float)
    occ, _, _ = np.histogram2d(pos[:, 1], pos[:, 0], bins=[edges_y, edges_x])
    out = []
    for u in range(act.shape[1]):
        s, _, _ = np.histogram2d(pos[:, 1], pos[:, 0], bins=[edges_y, edges_x],
                                 weights=act[:, u])
        with np.errstate(invalid="ignore"):
            out.append(s / occ)
    return np.array(out), occ


def test_place_field_centres_recovered_within_one_bin(place_rec):
    rec, centres = place_rec
    for sigma in (0, 1.0):
        maps = hp.ratemaps(rec, bin_size=0.05, sigma=sigma)
        peak = maps.fillna(-np.inf).argmax(dim=("y", "x"))
        found = np.c_[maps.x.values[peak["x"].values], maps.y.values[peak["y"].values]]
        assert np.all(np.abs(found - centres) <= 0.05), (sigma, found, centres)


def test_unsmoothed_equals_histogram_definition(place_rec):
    rec, _ = place_rec
    maps = hp.ratemaps(rec, bin_size=0.07, sigma=0)
    grid = spatial_grid(rec, 0.07)
    ref, occ = _reference_maps(rec, grid.x_edges, grid.y_edges)
    np.testing.assert_allclose(maps.values, ref, rtol=1e-5, equal_nan=True)
    np.testing.assert_allclose(maps.occupancy.values, occ * rec.attrs["dt"])
    assert maps.dims == ("unit", "y", "x")
    assert maps.attrs["units"] == "Hz" and maps.attrs["sigma"] == 0


def test_matches_pynapple_tuning_curves(place_rec):
    nap = pytest.importorskip("pynapple")
    rec, _ = place_rec
    maps = hp.ratemaps(rec, bin_size=0.05, sigma=0)
    grid = spatial_grid(rec, 0.05)
    t = rec.time.values
    frame = nap.TsdFrame(t=t, d=rec.activity.values.astype(float))
    feats = nap.TsdFrame(t=t, d=rec.position.values, columns=["x", "y"])
    tc = nap.compute_tuning_curves(frame, feats, bins=[grid.x_edges, grid.y_edges])
    ours = maps.values
    theirs = tc.transpose("unit", "y", "x").values
    ok = np.isfinite(ours)
    assert (ok == np.isfinite(theirs)).all()
    np.testing.assert_allclose(ours[ok], theirs[ok], rtol=1e-5)


def test_unvisited_bins_are_nan_and_occupancy_kept():
    rng = np.random.default_rng(1)
    pos, _ = trajectory(5000, rng)
    pos[:, 0] = -np.abs(pos[:, 0])  # the animal never enters x > 0
    rec = make_recording(pos, np.ones((len(pos), 2)), arena_vertices=SQUARE)
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=1.0)
    right = maps.x > 0.05
    assert maps.where(right).count() == 0
    left = maps.where(~right & (maps.occupancy > 0))
    # normalized convolution: a constant stays exactly constant, also at the edges
    np.testing.assert_allclose(left.values[np.isfinite(left.values)], 1.0, rtol=1e-12)
    assert maps.occupancy.sum() == pytest.approx(len(pos) * rec.attrs["dt"])
    assert maps.attrs["extent"] == [-0.5, 0.5, -0.5, 0.5]  # from the arena, not the data


def test_by_environment_and_trial_equal_maps_of_subsets():
    rng = np.random.default_rng(2)
    pos, _ = trajectory(6000, rng)
    act = np.c_[pos[:, 0] + 1, np.cos(3 * pos[:, 1])]
    trial = np.repeat(np.arange(6), 1000)
    env = trial % 2
    act[env == 1] *= 2
    rec = make_recording(pos, act, trial=trial, environment=env, arena_vertices=SQUARE)
    by_env = hp.ratemaps(rec, bin_size=0.1, sigma=1, by="environment")
    assert by_env.dims == ("unit", "environment", "y", "x")
    for e in (0, 1):
        sub = rec.isel(time=np.flatnonzero(env == e))
        alone = hp.ratemaps(sub, bin_size=0.1, sigma=1, extent=(-0.5, 0.5, -0.5, 0.5))
        np.testing.assert_allclose(by_env.sel(environment=e).values, alone.values,
                                   rtol=1e-12, equal_nan=True)
    by_trial = hp.ratemaps(rec, bin_size=0.1, sigma=0, by="trial")
    assert by_trial.sizes["trial"] == 6
    np.testing.assert_array_equal(by_trial.environment.values, [0, 1, 0, 1, 0, 1])
    sub = rec.isel(time=np.flatnonzero(trial == 3))
    alone = hp.ratemaps(sub, bin_size=0.1, sigma=0, extent=(-0.5, 0.5, -0.5, 0.5))
    np.testing.assert_allclose(by_trial.sel(trial=3).values, alone.values, rtol=1e-12,
                               equal_nan=True)


def test_dask_backed_recording_equals_eager(place_rec):
    rec, _ = place_rec
    lazy = rec.chunk({"time": 3000, "unit": 2})
    eager = hp.ratemaps(rec, bin_size=0.05, sigma=1.0, by="trial")
    got = hp.ratemaps(lazy, bin_size=0.05, sigma=1.0, by="trial")
    np.testing.assert_allclose(got.values, eager.values, rtol=1e-12, equal_nan=True)
    np.testing.assert_array_equal(got.activity_min.values, eager.activity_min.values)


def test_min_speed_keeps_only_fast_samples():
    rng = np.random.default_rng(3)
    pos, _ = trajectory(4000, rng)
    speed = rng.uniform(0, 0.3, len(pos))
    act = np.c_[speed]
    rec = make_recording(pos, act, speed=("time", speed, {"units": "m/s",
                                                          "long_name": "speed"}))
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=0, min_speed=0.15)
    assert np.nanmin(maps.values) >= 0.15
    assert maps.occupancy.sum() == pytest.approx((speed >= 0.15).sum() * 0.1)


def test_speed_derived_from_position_when_missing():
    n = 400
    pos = np.c_[np.linspace(-0.4, 0.4, n), np.zeros(n)]
    pos[n // 2:, 0] = pos[n // 2, 0]  # stops half-way
    rec = make_recording(pos, np.ones((n, 1)), arena_vertices=SQUARE)
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=0, min_speed=0.01)
    # moving: 0.8 m / 399 steps / 0.1 s = 0.02 m/s; standing still: 0
    assert maps.occupancy.sum() == pytest.approx(n // 2 * 0.1, abs=0.11)


def test_signed_activity_keeps_minimum_for_later_shift():
    centres = np.array([[0.2, 0.2]])
    rec = place_cell_recording(centres, activity_kind="lstm_hidden", n_samples=3000)
    maps = hp.ratemaps(rec, bin_size=0.1)
    assert maps.activity_min.values[0] == pytest.approx(rec.activity.values.min())
    assert maps.attrs["activity_kind"] == "lstm_hidden"


def test_spike_counts_are_reported_in_hz():
    rec = place_cell_recording(np.array([[0.0, 0.0]]), activity_kind="spike_count",
                               n_samples=30000, width=0.15)
    maps = hp.ratemaps(rec, bin_size=0.1, sigma=0)
    assert maps.attrs["units"] == "Hz"
    assert 7.0 < float(maps.max()) < 13.0  # peak rate 10 Hz


def test_missing_variable_is_a_clear_error(place_rec):
    rec, _ = place_rec
    with pytest.raises(ValueError, match=r"`rec` must contain \['position'\]"):
        hp.ratemaps(rec.drop_vars("position"))
    with pytest.raises(TypeError, match="recording"):
        hp.ratemaps(rec.activity)


def test_all_nan_positions_is_a_clear_error(place_rec):
    rec, _ = place_rec
    bad = rec.copy()
    bad["position"] = bad.position * np.nan
    with pytest.raises(ValueError, match="all positions are NaN"):
        hp.ratemaps(bad.drop_vars("arena_vertices"))
    with pytest.raises(ValueError, match="all positions are NaN"):
        hp.ratemaps(bad)


def test_bins_larger_than_arena_is_a_clear_error(place_rec):
    rec, _ = place_rec
    with pytest.raises(ValueError, match=r"`bin_size` must be > 0 and smaller than the arena"):
        hp.ratemaps(rec, bin_size=2.0)
    with pytest.raises(ValueError, match="`bin_size` must be > 0"):
        hp.ratemaps(rec, bin_size=-1.0)
    with pytest.raises(ValueError, match="`by` must be one of"):
        hp.ratemaps(rec, by="session")


def test_fewer_samples_than_bins_warns(place_rec):
    rec, _ = place_rec
    with pytest.warns(AnalysisWarning, match="valid samples for .* bins"):
        maps = hp.ratemaps(rec.isel(time=slice(0, 50)), bin_size=0.02)
    assert maps.count() > 0


def test_nan_activity_is_refused_in_memory_and_named_when_lazy(place_rec):
    rec, _ = place_rec
    act = rec.activity.values.copy()
    act[100, 2] = np.nan
    bad = rec.assign(activity=(("time", "unit"), act, rec.activity.attrs))
    with pytest.raises(RecordingError, match=r"`activity` must not contain NaN or inf; "
                                             r"found nan at index \(100, 2\)"):
        hp.ratemaps(bad, bin_size=0.1, sigma=0)
    # a lazy recording's values are not read by the entry check: the map's pass names it
    with pytest.warns(AnalysisWarning, match=r"NaN or inf for units \[np.int64\(2\)\]|"
                                              r"NaN or inf for units \[2\]"):
        hp.ratemaps(bad.chunk({"time": 500}), bin_size=0.1, sigma=0)


def test_quiet_on_good_input(place_rec):
    rec, _ = place_rec
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hp.ratemaps(rec, bin_size=0.05)


def test_extent_from_data_without_arena():
    rng = np.random.default_rng(4)
    pos, _ = trajectory(3000, rng)
    rec = make_recording(pos * 0.5, np.ones((3000, 1)))
    maps = hp.ratemaps(rec, sigma=0)
    ext = maps.attrs["extent"]
    assert ext[0] == pytest.approx(pos[:, 0].min() * 0.5)
    assert ext[1] == pytest.approx(pos[:, 0].max() * 0.5)
    assert maps.occupancy.sum() == pytest.approx(300.0)  # every sample counted
    assert isinstance(maps, xr.DataArray) and max(maps.sizes["x"], maps.sizes["y"]) == 32


def test_threaded_bin_sums_equal_single_thread():
    from hippo_probe.analysis._binning import bin_sums

    rng = np.random.default_rng(19)
    act = rng.normal(size=(120_000, 7)).astype(np.float32)
    bins = rng.integers(-1, 50, len(act))
    one = bin_sums(act, bins, 50, shifts=(0, 999), want_sq=True, threads=1)
    two = bin_sums(act, bins, 50, shifts=(0, 999), want_sq=True, threads=2)
    np.testing.assert_allclose(two.sums, one.sums, rtol=1e-12)
    np.testing.assert_array_equal(two.counts, one.counts)
    np.testing.assert_array_equal(two.amin, one.amin)
    np.testing.assert_allclose(two.sumsq, one.sumsq, rtol=1e-12)
    ref = np.array([act[bins == b].astype(float).sum(axis=0) for b in range(50)])
    np.testing.assert_allclose(one.sums[0], ref, rtol=1e-10)


def test_minimum_counts_samples_outside_every_bin():
    from hippo_probe.analysis._binning import bin_sums

    act = np.arange(200_000, dtype=np.float32)[:, None] + 5
    act[150_000] = -3  # the minimum sits in a stretch where no sample is binned
    bins = np.zeros(len(act), np.int64)
    bins[100_000:] = -1
    for threads in (1, 2):
        assert bin_sums(act, bins, 1, threads=threads).amin[0] == -3
    import dask.array as da

    assert bin_sums(da.from_array(act, chunks=(20_000, 1)), bins, 1).amin[0] == -3
