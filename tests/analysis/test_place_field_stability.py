import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning

from .conftest import SQUARE, gaussian_fields, make_recording, place_cell_recording, trajectory


def _remapping_recording(n_trials=4, per_trial=5000, seed=12):
    """Unit 0 stable at (0.2, 0.2); unit 1 moves its field half-way through the trials;
    unit 2 is noise."""
    rng = np.random.default_rng(seed)
    pos = np.concatenate([trajectory(per_trial, rng)[0] for _ in range(n_trials)])
    trial = np.repeat(np.arange(n_trials), per_trial)
    late = trial >= n_trials // 2
    stable = gaussian_fields(pos, [[0.2, 0.2]], 0.1)[:, 0]
    moving = np.where(late, gaussian_fields(pos, [[-0.25, -0.2]], 0.1)[:, 0],
                      gaussian_fields(pos, [[0.25, -0.2]], 0.1)[:, 0])
    act = np.c_[stable, moving, rng.random(len(pos))]
    return make_recording(pos, act, trial=trial, arena_vertices=SQUARE)


def test_stable_fields_correlate_and_moved_field_does_not():
    rec = _remapping_recording()
    res = hp.place_field_stability(rec, bin_size=0.05)
    s = res.stability.sel(environment=0).values
    assert s[0] > 0.95
    assert s[1] < 0.2
    assert abs(s[2]) < 0.3
    assert "halves of 4 trials" in res.attrs["split_used"]
    # alternating trials mix both fields into both parts: the moved field looks stable
    alt = hp.place_field_stability(rec, bin_size=0.05, split="odd_even")
    assert alt.stability.sel(environment=0).values[1] > 0.9


def test_single_trial_is_split_in_time_and_lazy_matches():
    rec = place_cell_recording(np.array([[0.1, -0.1], [-0.3, 0.3]]), n_samples=12000)
    res = hp.place_field_stability(rec, bin_size=0.05)
    assert (res.stability > 0.9).all()
    assert "one trial" in res.attrs["split_used"]
    lazy = hp.place_field_stability(rec.chunk({"time": 2500}), bin_size=0.05)
    np.testing.assert_allclose(lazy.stability, res.stability, rtol=1e-10)


def test_constant_unit_is_nan_with_reason():
    rec = _remapping_recording(n_trials=2, per_trial=3000)
    act = rec.activity.values.copy()
    act[:, 2] = 1.0
    rec["activity"] = (("time", "unit"), act, rec.activity.attrs)
    with pytest.warns(AnalysisWarning, match="place-field stability is NaN"):
        res = hp.place_field_stability(rec, bin_size=0.1)
    assert np.isnan(res.stability.sel(unit=2, environment=0))
    assert "constant" in res.attrs["nan_reasons"]["unit=2, environment=0"]
    with pytest.raises(ValueError, match="`split` must be one of"):
        hp.place_field_stability(rec, split="random")
