"""Warnings and errors a user meets in a notebook: each points at the user's own line and
says what to do; provenance records what was used."""

import warnings

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.recording import from_arrays


def two_arena_rec(n=4000, environments=(0, 1)):
    """A place unit recorded in trials alternating between ``environments``."""
    rng = np.random.default_rng(0)
    trial = np.repeat(np.arange(8), n // 8)
    t = (np.arange(n) + trial) * 0.1                  # trials a sample apart
    xy = np.c_[0.5 * np.cos(t / 7), 0.5 * np.sin(t / 5)] + rng.normal(0, 0.01, (n, 2))
    act = np.exp(-((xy - 0.2) ** 2).sum(1, keepdims=True) / 0.02)
    env = np.asarray(environments)[trial % len(environments)]
    return from_arrays(t, xy, activity=act, trial=trial, environment=env,
                       activity_kind="rate")


def caught(call):
    with warnings.catch_warnings(record=True) as found:
        warnings.simplefilter("always")
        result = call()
    return result, [w for w in found if issubclass(w.category, AnalysisWarning)]


def test_pooling_environments_warns_at_the_callers_line():
    rec = two_arena_rec()
    _, found = caught(lambda: hp.ratemaps(rec, bin_size=0.1))
    (w,) = [w for w in found if "spans 2 environments" in str(w.message)]
    assert 'by="environment"' in str(w.message)
    assert w.filename == __file__                   # the user's line, not the package's
    for call in (lambda: hp.ratemaps(rec, bin_size=0.1, by="environment"),
                 lambda: hp.ratemaps(two_arena_rec(environments=(3,)), bin_size=0.1)):
        _, found = caught(call)
        assert not [w for w in found if "environments" in str(w.message)]
    _, found = caught(lambda: hp.spatial_information(rec, bin_size=0.1))
    assert any("spans 2 environments" in str(w.message) for w in found)
    # a novel-arena task: every trial its own arena, where maps per arena are one trial
    _, found = caught(lambda: hp.ratemaps(two_arena_rec(environments=range(8)),
                                          bin_size=0.1))
    (w,) = [w for w in found if "spans 8 environments" in str(w.message)]
    assert "an arena of its own" in str(w.message) and 'arenas="fixed"' in str(w.message)


def test_a_min_occupancy_no_bin_reaches_is_named():
    rec = two_arena_rec(environments=(0,))
    maps, found = caught(lambda: hp.ratemaps(rec, bin_size=0.1, min_occupancy=1e6))
    assert np.isnan(maps.values).all()
    assert any("every bin is NaN" in str(w.message) and "min_occupancy" in str(w.message)
               for w in found)
    info, _ = caught(lambda: hp.spatial_information(rec, bin_size=0.1, min_occupancy=1e6))
    assert "below `min_occupancy`" in info.attrs["nan_reasons"]["unit=0"]


def test_default_bins_that_do_not_fit_blame_the_extent_not_bin_size():
    rec = two_arena_rec(environments=(0,))
    pos = rec.position.values.copy()
    pos[10, 0] = 50.0                                   # one tracking glitch
    rec["position"] = (rec.position.dims, pos)
    with pytest.raises(ValueError, match="pass `extent=`") as err:
        caught(lambda: hp.ratemaps(rec))
    assert "`bin_size` must be" not in str(err.value)


def test_too_few_shuffles_for_a_units_own_percentile_warn():
    rec = two_arena_rec(n=3000, environments=(0,))
    for n_shuffles, threshold, expect in ((20, "unit", True), (100, "unit", False),
                                          (20, "pooled", False)):
        table, found = caught(lambda: hp.classify_cells(
            rec, n_shuffles=n_shuffles, threshold=threshold))
        warned = [w for w in found if "cannot resolve the percentile" in str(w.message)]
        assert bool(warned) == expect, (n_shuffles, threshold)
        if expect:
            assert "head_direction (99th)" in str(warned[0].message)
            assert "place (95th)" not in str(warned[0].message)   # 20 resolve the 95th
    assert table.attrs["seed"] == 0                     # the default seed, as used


@pytest.mark.parametrize("analysis", ["spatial_information", "head_direction_tuning",
                                      "speed_score"])
def test_provenance_records_the_default_shuffle_seed(analysis):
    rec = from_arrays(np.arange(2000) * 0.1, np.c_[np.cos(np.arange(2000) / 50),
                                                   np.sin(np.arange(2000) / 70)],
                      activity=np.random.default_rng(1).random((2000, 2)),
                      head_direction=np.angle(np.exp(1j * np.arange(2000) / 30)),
                      activity_kind="rate")
    result, _ = caught(lambda: getattr(hp, analysis)(rec, n_shuffles=3))
    assert result.attrs["seed"] == 0


def test_a_memory_refusal_names_the_shuffles_when_they_are_the_cause():
    rec = two_arena_rec(n=3000, environments=(0,))
    rec["head_direction"] = ("time", np.angle(np.exp(1j * np.arange(3000) / 30.0)))
    with pytest.raises(ValueError, match="`n_shuffles` = 10000000 asks for"):
        hp.head_direction_tuning(rec, n_shuffles=10**7)
    with pytest.raises(ValueError, match="`n_shuffles` = 3000000 asks for"):
        hp.spatial_information(rec, bin_size=0.01, n_shuffles=3 * 10**6)
    with pytest.raises(ValueError, match="`bin_size` asks for"):   # one map is too big
        hp.ratemaps(rec, bin_size=1e-5)


def test_a_recordings_activity_given_for_maps_is_named_as_such():
    rec = two_arena_rec(n=800, environments=(0,))
    with pytest.raises(ValueError, match=r"a recording \(xarray.Dataset\) or the output of "
                                         r"ratemaps\(\).*got a DataArray with dims"):
        hp.place_fields(rec.activity)


def test_the_shared_shuffle_docs_state_the_configured_minimum_shift():
    from hippo_probe._docs import DOCS
    from hippo_probe.analysis.config import SHUFFLE

    assert f"``SHUFFLE.min_shift`` ({SHUFFLE.min_shift:g}) s" in DOCS["n_shuffles"]


def test_a_constant_position_is_blamed_not_an_extent_never_given():
    t = np.arange(200) * 0.1
    xy = np.c_[np.full(200, 0.2), np.linspace(-0.4, 0.4, 200)]
    rec = from_arrays(t, xy, activity=np.random.default_rng(0).random((200, 2)))
    with pytest.raises(ValueError, match=r"`rec.position`'s x is constant \(0.2 m\)"):
        hp.ratemaps(rec)
