import numpy as np
import pytest
from scipy.special import i0, i1

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.analysis.head_direction_tuning import rayleigh_p
from hippo_probe.recording import from_arrays

from .conftest import hd_cell_recording, make_recording, trajectory

PREFERRED = np.array([-2.5, -1.0, 0.0, 0.7, 2.0, 3.1])
KAPPA = np.array([0.5, 1.0, 2.0, 4.0, 8.0, 16.0])


def _angle_error(a, b):
    return np.abs(np.angle(np.exp(1j * (np.asarray(a) - np.asarray(b)))))


def test_von_mises_units_recover_direction_and_analytic_length():
    rec = hd_cell_recording(PREFERRED, KAPPA)
    res = hp.head_direction_tuning(rec, n_shuffles=20)
    assert res.tuning_curve.dims == ("unit", "direction")
    assert np.degrees(_angle_error(res.preferred_direction.values, PREFERRED)).max() < 5
    analytic = i1(KAPPA) / i0(KAPPA)  # R of exp(kappa cos(theta - mu))
    np.testing.assert_allclose(res.mean_vector_length.values, analytic, atol=0.02)
    assert (res.p_value.values == 1 / 21).all()
    assert "rayleigh" in res.attrs and "rayleigh_p" not in res


def test_tuning_curve_is_occupancy_normalised_mean():
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    res = hp.head_direction_tuning(rec, n_bins=12, n_shuffles=0)
    hd = rec.head_direction.values
    k = np.floor((hd + np.pi) / (2 * np.pi) * 12).astype(int)
    act = rec.activity.values.astype(float)
    for b in range(12):
        np.testing.assert_allclose(res.tuning_curve.values[:, b], act[k == b].mean(axis=0),
                                   rtol=1e-6)
    assert res.occupancy.sum() == pytest.approx(5000 * 0.1)


def test_spike_units_get_rayleigh_and_untuned_units_are_not_significant():
    rng = np.random.default_rng(8)
    rec = hd_cell_recording(np.array([1.0, 0.0]), np.array([3.0, 0.0]), n_samples=20000,
                            activity_kind="spike_count")
    res = hp.head_direction_tuning(rec, n_shuffles=50, seed=rng.integers(1000))
    assert res.tuning_curve.attrs["units"] == "Hz"
    assert res.rayleigh_p.sel(unit=0) < 1e-10
    assert res.rayleigh_p.sel(unit=1) > 0.01  # kappa = 0: uniform
    assert res.p_value.sel(unit=0) == pytest.approx(1 / 51)
    assert res.p_value.sel(unit=1) > 0.05
    assert res.mean_vector_length.sel(unit=1) < 0.1


def test_rayleigh_p_matches_exact_large_sample_limit():
    # for large n, p ~ exp(-n r^2)
    assert rayleigh_p(10000, 0.02) == pytest.approx(np.exp(-10000 * 0.02**2), rel=0.05)
    assert rayleigh_p(50, 0.0) == pytest.approx(1.0)


def test_signed_activity_shifted_and_stated():
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    signed = rec.copy()
    signed["activity"] = rec.activity * 2 - 1
    signed.attrs["activity_kind"] = "lstm_hidden"
    a = hp.head_direction_tuning(rec, n_shuffles=0)
    b = hp.head_direction_tuning(signed, n_shuffles=0)
    assert "minimum over the recording" in b.attrs["rate_offset"]
    # the offset itself is returned, per unit: the signed activity's minimum
    np.testing.assert_allclose(b.rate_offset, signed.activity.min("time"), rtol=1e-6)
    np.testing.assert_array_equal(a.rate_offset, 0.0)       # spike-like: nothing removed
    # (2a - 1) - min(2a - 1) = 2 (a - min a): the same R as a - min a
    shifted = rec.copy()
    shifted["activity"] = rec.activity - rec.activity.min("time")
    c = hp.head_direction_tuning(shifted, n_shuffles=0)
    np.testing.assert_allclose(b.mean_vector_length, c.mean_vector_length, rtol=1e-5)
    # removing a positive floor sharpens the curve
    assert (a.mean_vector_length < c.mean_vector_length).all()


def test_lazy_equals_eager_and_by_environment():
    rec = hd_cell_recording(PREFERRED[:3], KAPPA[:3], n_samples=6000)
    # two trials, one per environment (an environment never changes within a trial)
    rec = rec.assign_coords(environment=("time", np.repeat([0, 1], 3000),
                                         rec.environment.attrs),
                            trial=("time", np.repeat([0, 1], 3000), rec.trial.attrs))
    eager = hp.head_direction_tuning(rec, by="environment")
    lazy = hp.head_direction_tuning(rec.chunk({"time": 1000}), by="environment")
    assert eager.mean_vector_length.dims == ("unit", "environment")
    assert eager.attrs["n_shuffles"] == 0          # none by default with `by`
    for name in ("tuning_curve", "mean_vector_length"):
        np.testing.assert_allclose(lazy[name], eager[name], rtol=1e-10)
    eager = hp.head_direction_tuning(rec, n_shuffles=5)
    lazy = hp.head_direction_tuning(rec.chunk({"time": 1000}), n_shuffles=5)
    np.testing.assert_allclose(lazy["p_value"], eager["p_value"], rtol=1e-10)


def test_bad_input():
    rng = np.random.default_rng(9)
    pos, hd = trajectory(500, rng)
    rec = make_recording(pos, np.ones((500, 2)), head_direction=hd)
    with pytest.raises(ValueError, match=r"`rec` must contain \['head_direction'\]"):
        hp.head_direction_tuning(rec.drop_vars("head_direction"))
    nan_hd = rec.assign(head_direction=rec.head_direction * np.nan)
    with pytest.raises(ValueError, match="all NaN"):
        hp.head_direction_tuning(nan_hd)
    # two bins placed a cell tuned to 0 rad at 90 degrees with R 0.02 (60 bins: 0.70)
    with pytest.raises(ValueError, match="`n_bins` must be >= 8; got 2"):
        hp.head_direction_tuning(rec, n_bins=2)
    zero = rec.assign(activity=rec.activity * 0)
    with pytest.warns(AnalysisWarning, match="mean vector length is NaN"):
        res = hp.head_direction_tuning(zero, n_shuffles=0)
    assert np.isnan(res.mean_vector_length).all()
    assert "sums to 0" in res.attrs["nan_reasons"]["unit=0"]


@pytest.mark.parametrize("stuck", [[0.5], [0.5, 0.6]])
def test_a_stuck_sensor_gives_no_mean_vector_length(stuck):
    """A head direction stuck at one or two values visits one or two bins: every curve
    then has R near 1 (and a tiny Rayleigh p) whatever the cell does. No number, and the
    reason, instead; conjunctive_tuning's lengths likewise."""
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    rec["head_direction"][:] = np.resize(stuck, rec.sizes["time"])
    with pytest.warns(AnalysisWarning, match=r"left 3[45]\d degrees unvisited"):
        res = hp.head_direction_tuning(rec, n_shuffles=10)
    assert np.isnan(res.mean_vector_length.values).all()
    assert np.isnan(res.preferred_direction.values).all()
    assert np.isnan(res.p_value.values).all()
    assert "stuck or misread sensor" in str(res.attrs["nan_reasons"])


@pytest.mark.parametrize("arc, kept", [(180, True), (186, False)])
def test_the_coverage_rule_is_half_the_circle_unvisited(arc, kept):
    """Directions spread over the circle but for an unvisited arc of ``arc`` degrees (30
    and 31 of the 60 bins): R is kept at exactly half, NaN beyond."""
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    span = np.radians(360 - arc)
    rec["head_direction"][:] = -np.pi + (rec.head_direction.values + np.pi) * span / (2 * np.pi)
    res = hp.head_direction_tuning(rec, n_shuffles=0)
    assert np.isfinite(res.mean_vector_length.values).all() == kept


def test_an_untuned_cell_s_length_over_a_partly_visited_circle_is_given_and_warned():
    """Half the circle visited: a flat 5 Hz cell read R = 0.64 (2 / pi) unflagged. The
    length a flat curve has there comes with it, and a warning."""
    rng = np.random.default_rng(0)
    hd = np.abs(np.cumsum(rng.normal(0, 0.2, 20000)) % (2 * np.pi) - np.pi)   # [0, pi]
    rec = from_arrays(np.arange(20000) * 0.02, np.zeros((20000, 2)),
                      spike_times=[np.sort(rng.uniform(0, 400, 2000))], head_direction=hd)
    with pytest.warns(AnalysisWarning, match=r"left up to 180 degrees of the circle "
                                             r"unvisited: there a flat, untuned curve reads "
                                             r"a mean vector length of 0\.64"):
        res = hp.head_direction_tuning(rec, n_shuffles=0)
    assert res.attrs["untuned_length"] == pytest.approx(2 / np.pi)
    assert res.mean_vector_length.item() == pytest.approx(2 / np.pi, abs=0.05)


def test_a_few_discrete_headings_over_the_circle_keep_their_length():
    """Eight headings 45 degrees apart visit 8 of 60 bins, yet cover the circle."""
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    rec["head_direction"][:] = np.round(rec.head_direction.values / (np.pi / 4)) * np.pi / 4 \
        - 1e-9
    res = hp.head_direction_tuning(rec, n_shuffles=0)
    assert np.isfinite(res.mean_vector_length.values).all()


def test_conjunctive_tuning_follows_the_same_coverage_rule():
    rec = hd_cell_recording(PREFERRED[:2], KAPPA[:2], n_samples=5000)
    rec["head_direction"][:] = 0.5
    with pytest.warns(AnalysisWarning, match="R: head direction left .* direction factor"):
        res = hp.conjunctive_tuning(rec, n_shuffles=5)
    assert np.isnan(res.hd_mean_vector_length).all()
    assert np.isnan(res.pxd_direction_length).all()
    assert np.isnan(res.hd_mean_vector_length_p_value).all()
