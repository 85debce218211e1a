"""Head-direction x place conjunctive tuning: the factorial model separates position
from direction; its HD curve is that of head_direction_tuning."""

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis.conjunctive_tuning import factorize

from .cell_fixtures import gaussian, ou, square_walk
from .conftest import SQUARE, make_recording


@pytest.fixture(scope="module")
def conj_rec():
    rng = np.random.default_rng(9)
    n = 30000
    pos, heading, _ = square_walk(n, rng, turn=1.5)
    hd = np.mod(heading + np.pi, 2 * np.pi) - np.pi
    place = gaussian(pos, (0.15, -0.1), 0.1)
    tuned = np.exp(3 * (np.cos(hd - 0.7) - 1))
    units = [place, tuned, place * tuned, 0.5 * place + 0.5 * tuned]
    act = np.c_[np.stack(units, 1), 0.3 + 0.1 * ou(n, rng, 6)]
    return make_recording(pos, act, head_direction=heading, arena_vertices=SQUARE)


def test_factorial_model_recovers_a_product_exactly():
    rng = np.random.default_rng(0)
    counts = rng.integers(1, 20, (12, 30)).astype(float)
    f_true = rng.uniform(0.5, 2, 30)
    g_true = rng.uniform(0.2, 3, 12)
    f, g, _ = factorize(f_true[None] * g_true[:, None] * counts, counts, 500, 1e-12)
    w = counts.sum(1) / counts.sum()
    np.testing.assert_allclose(g, g_true / (g_true * w).sum(), rtol=1e-6)
    np.testing.assert_allclose(f * g[:, None] * counts,
                               f_true[None] * g_true[:, None] * counts, rtol=1e-6)


def test_place_hd_and_conjunctive_cells_are_told_apart(conj_rec):
    res = hp.conjunctive_tuning(conj_rec, n_shuffles=50)
    length = res.pxd_direction_length.values
    info = res.pxd_position_information.values
    above_d = length > res.pxd_direction_length_threshold.values
    above_p = info > res.pxd_position_information_threshold.values
    assert above_d[:4].tolist() == [False, True, True, True]
    assert above_p[:4].tolist() == [True, False, True, True]
    assert res.conjunctive.values[:4].tolist() == [False, False, True, True]
    assert not res.conjunctive.values[4:].any()
    # the direction factor of the HD and conjunctive cells peaks at 0.7 rad
    np.testing.assert_allclose(res.pxd_preferred_direction.values[[1, 2]], 0.7, atol=0.1)
    assert res.position_factor.dims == ("unit", "y", "x")
    assert res.direction_factor.sizes["pxd_direction"] == 12


def test_hd_tuning_is_that_of_head_direction_tuning(conj_rec):
    res = hp.conjunctive_tuning(conj_rec, n_shuffles=10, seed=4)
    ref = hp.head_direction_tuning(conj_rec, n_shuffles=10, seed=4)
    np.testing.assert_allclose(res.hd_mean_vector_length, ref.mean_vector_length,
                               atol=1e-12)
    np.testing.assert_allclose(res.hd_mean_vector_length_p_value, ref.p_value, atol=1e-12)


def test_signed_activity_is_shifted_to_a_nonnegative_rate(conj_rec):
    signed = conj_rec.copy()
    signed["activity"] = (np.tanh(2 * conj_rec.activity - 1)).astype(np.float32)
    signed.attrs["activity_kind"] = "lstm_hidden"
    res = hp.conjunctive_tuning(signed, n_shuffles=20)
    assert "minimum over the recording" in res.attrs["rate_offset"]
    assert res.conjunctive.values[2] and not res.conjunctive.values[0]


def test_random_units_score_near_their_shuffles(conj_rec):
    res = hp.conjunctive_tuning(conj_rec, n_shuffles=100, seed=1)
    for name in ("hd_mean_vector_length", "pxd_direction_length",
                 "pxd_position_information"):
        z = ((res[name] - res[f"{name}_shuffle_mean"])
             / res[f"{name}_shuffle_std"]).values[4:]
        assert np.abs(z).max() < 4, (name, z)


def test_arguments_are_checked(conj_rec):
    with pytest.raises(ValueError, match="must contain \\['head_direction'\\]"):
        hp.conjunctive_tuning(conj_rec.drop_vars("head_direction"))
    with pytest.raises(ValueError, match="`n_directions` must be >= 2; got 1"):
        hp.conjunctive_tuning(conj_rec, n_directions=1)


def test_the_factorial_model_converges_for_a_unit_silent_in_some_directions():
    """A place visited only in directions where the unit never fires has an expected count
    of 0: its factor is 0, and the model converges instead of resetting every other
    iteration (as it did while 0/0 spread NaN through the next product)."""
    import warnings

    from hippo_probe.analysis.conjunctive_tuning import factorize

    counts = np.array([[5.0, 5, 0], [5, 5, 0], [5, 5, 0], [0, 0, 8]])   # place 2: dir 3 only
    sums = np.array([[[4.0, 2, 0], [3, 1, 0], [0, 0, 0], [0, 0, 0]]])   # silent in 2 and 3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        f, g, n_iter = factorize(sums, counts, 500, 1e-10)
    assert n_iter < 500 and np.isfinite(f).all() and np.isfinite(g).all()
    assert f[0, 2] == 0 and g[0, 3] == 0
    # the model reproduces the observed sums where it can (a product of the factors)
    fitted = g[0][:, None] * f[0][None, :] * counts
    np.testing.assert_allclose(fitted.sum(0), sums[0].sum(0), rtol=1e-6)
