"""The map scorecard gives the expected verdicts on populations whose answer is known."""

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis.map_scorecard import treves_rolls
from hippo_probe.recording import from_arrays


def _population(kind, n_units=24, n_trials=12, n=1500, seed=0):
    """Units in two environments (trials alternate): Gaussian place fields drawn anew in
    each environment ("remapping place cells"), or the same planar gradients in both."""
    rng = np.random.default_rng(seed)
    env = np.repeat(np.arange(n_trials) % 2, n)
    heading = np.cumsum(rng.normal(0, 0.3, n * n_trials))
    xy = np.cumsum(0.02 * np.c_[np.cos(heading), np.sin(heading)], axis=0)
    xy = np.abs((xy + 0.5) % 2 - 1) - 0.5                       # folded into the 1 m box
    if kind == "place":
        centres = rng.uniform(-0.4, 0.4, (2, n_units, 2))        # new fields per arena
        d2 = ((xy[:, None, :] - centres[env]) ** 2).sum(-1)
        rate = 10 * np.exp(-d2 / (2 * 0.08 ** 2))
    else:
        slopes = rng.normal(size=(n_units, 2))
        rate = 5 + 3 * xy @ slopes.T                              # the same in both arenas
    t = np.concatenate([k * (n * 0.1 + 10) + 0.1 * np.arange(1, n + 1)
                        for k in range(n_trials)])
    return from_arrays(t, xy, activity=rate, trial=np.repeat(np.arange(n_trials), n),
                       environment=env, activity_kind="rate")


def test_remapping_place_cells_get_both_verdicts():
    card = hp.map_scorecard(_population("place"), bin_size=0.05)
    assert card.attrs["place_fields"] and card.attrs["global_remapping"]
    assert card.fraction_place_like > 0.8
    assert card.within_map_correlation > 0.8 and abs(card.across_map_correlation) < 0.2
    assert card.lifetime_sparseness < 0.3


def test_planar_gradients_get_neither_verdict():
    card = hp.map_scorecard(_population("gradient"), bin_size=0.05)
    assert not card.attrs["place_fields"] and not card.attrs["global_remapping"]
    assert card.fraction_place_like < 0.2
    assert card.across_map_correlation > 0.9
    assert card.lifetime_sparseness > 0.7


def test_treves_rolls_sparseness_is_one_for_uniform_and_one_over_n_for_one_active():
    assert treves_rolls(np.ones(10), 0) == pytest.approx(1.0)
    assert treves_rolls(np.r_[1.0, np.zeros(9)], 0) == pytest.approx(0.1)


def test_one_environment_is_refused():
    rec = _population("place").pipe(lambda r: hp.select_trials(r, environments=[0]))
    with pytest.raises(ValueError, match="at least 2 environments"):
        hp.map_scorecard(rec, bin_size=0.05)


def test_a_unit_silenced_in_one_arena_counts_as_remapped_and_not_as_a_place_cell():
    rec = _population("gradient")
    # half the units fall silent in environment 1: their maps share nothing across
    # arenas, so they lower the across-arena median instead of dropping out of it
    rate = rec.activity.values.copy()
    rate[np.ix_(rec.environment.values == 1, np.arange(12))] = 0.0
    quiet = rec.assign(activity=(rec.activity.dims, rate, rec.activity.attrs))
    card = hp.map_scorecard(quiet, bin_size=0.05)
    full = hp.map_scorecard(rec, bin_size=0.05)
    assert float(card.fraction_silent) == pytest.approx(12 / 48)
    assert card.across_map_correlation < full.across_map_correlation
    # of 36 active unit-arena pairs none is a place cell; a silent unit is not counted
    assert float(card.fraction_place_like) == pytest.approx(float(full.fraction_place_like),
                                                         abs=0.05)


def test_a_signed_activity_is_offset_by_its_recording_minimum():
    rec = _population("place")
    signed = rec.assign(activity=rec.activity - 5.0)
    signed.attrs["activity_kind"] = "lstm_hidden"
    card = hp.map_scorecard(signed, bin_size=0.05)
    assert "minimum over the recording" in card.attrs["rate_offset"]
    assert card.attrs["place_fields"] and card.attrs["global_remapping"]


def test_units_silent_in_most_of_an_arena_are_still_called_silent():
    rec = _population("place")
    rate = rec.activity.values.copy()
    # 18 of 24 units silent in environment 1: the median peak there is 0
    rate[np.ix_(rec.environment.values == 1, np.arange(18))] = 0.0
    quiet = rec.assign(activity=(rec.activity.dims, rate, rec.activity.attrs))
    card = hp.map_scorecard(quiet, bin_size=0.05)
    assert float(card.fraction_silent) == pytest.approx(18 / 48)
    assert int(card.n_units_place_like.sel(environment=1)) <= 6


def test_units_active_in_one_arena_only_are_counted_of_the_units_active_anywhere():
    rec = _population("place")
    rate = rec.activity.values.copy()
    # units 0-5 silent in environment 1, units 6-9 silent in environment 0, 10-11 in both
    for units, env in ((range(6), 1), (range(6, 10), 0), (range(10, 12), 0),
                       (range(10, 12), 1)):
        rate[np.ix_(rec.environment.values == env, list(units))] = 0.0
    quiet = rec.assign(activity=(rec.activity.dims, rate, rec.activity.attrs))
    card = hp.map_scorecard(quiet, bin_size=0.05)
    assert float(card.fraction_active_in_one_environment) == pytest.approx(10 / 22)
    assert float(hp.map_scorecard(rec, bin_size=0.05)
                 .fraction_active_in_one_environment) == 0.0
