"""Every plot draws into a figure of one's own (``ax=``, ``fig=``, ``axes=``) and returns
that figure; rate-map grids carry a colour bar and titles with peak and region; head-
direction polars agree in units (degrees) between ticks and titles."""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr

import hippo_probe as hp
from hippo_probe import plot

from .conftest import (
    hd_cell_recording,
    place_cell_recording,
    two_environment_recording,
)

NWB = Path(__file__).parents[1] / "data" / "A2929-200711.nwb"
DEG = "\N{DEGREE SIGN}"


@pytest.fixture(scope="module")
def hd_rec():
    rec = hd_cell_recording(np.array([0.5, -1.0]), np.array([4.0, 2.0]), n_samples=4000)
    return rec.assign_coords(region=("unit", ["ADn", "CA1"]))


@pytest.fixture(scope="module")
def mouse():
    pytest.importorskip("pynwb")
    return hp.from_nwb(NWB, epoch="wake")


def _colorbar_axes(fig):
    return [ax for ax in fig.axes if hasattr(ax, "_colorbar")]


# ------------------------------------------------------------------ drawing into a figure
def _grid_results(place, hd_rec):
    """(name, result, n panels, polar) for every result plotted as a grid of panels."""
    rec = place.copy()
    rec["estimate"] = rec.position + 0.05
    rec["estimate"].attrs = {"units": "m", "long_name": "network estimate"}
    x = np.random.default_rng(0).uniform(size=(800, 2)) @ np.eye(2, 8)
    return [
        ("ratemaps", hp.ratemaps(place, bin_size=0.05), 3, False),
        ("spatial_autocorrelation", hp.spatial_autocorrelation(place, bin_size=0.05), 3,
         False),
        ("head_direction_tuning", hp.head_direction_tuning(hd_rec, n_shuffles=0), 2, True),
        ("localization_error", hp.localization_error(rec), 3, False),
        ("correlation_dimension", hp.correlation_dimension(x), 2, False),
    ]


def test_grids_draw_into_the_given_axes(place, hd_rec):
    for name, result, n, polar in _grid_results(place, hd_rec):
        fig, axes = plt.subplots(1, n + 1, figsize=(2 * n, 2), squeeze=False,
                                 subplot_kw={"projection": "polar"} if polar else {})
        got = result.hp.plot(axes=axes)
        assert got is fig, name
        assert all(ax.has_data() for ax in axes[0, :n]), name
        assert not axes[0, n].has_data(), name  # a spare axes is left empty


def test_grids_draw_into_a_given_subfigure(place, hd_rec):
    for name, result, n, polar in _grid_results(place, hd_rec):
        fig = plt.figure(figsize=(8, 3), layout="constrained")
        left, right = fig.subfigures(1, 2)
        right.add_subplot().plot([0, 1])  # the user's own panel stays as it is
        got = result.hp.plot(fig=left)
        assert got is left, name
        assert len([ax for ax in left.axes if ax.has_data()]) >= n, name
        assert len(right.axes) == 1, name


def test_single_axes_plots_draw_into_the_given_ax(place):
    two = two_environment_recording(n_units=6, n_trials=6, samples_per_trial=800)
    t = np.arange(5) * 0.1
    acc = xr.Dataset({"accuracy": ("trial_time", np.linspace(0.5, 0.9, 5),
                                   {"units": "1", "long_name": "accuracy"})},
                     coords={"trial_time": ("trial_time", t, {"units": "s",
                                                              "long_name": "time in trial"})},
                     attrs={"analysis": "classification_accuracy", "chance": 0.5})
    results = {
        "spatial_information": hp.spatial_information(place, bin_size=0.1),
        "spatial_selectivity": hp.spatial_selectivity(place, bin_size=0.1),
        "remapping_similarity": hp.remapping_similarity(two),
        "classification_accuracy": acc,
    }
    for name, result in results.items():
        fig, (a, b) = plt.subplots(1, 2)
        assert result.hp.plot(ax=b) is fig, name
        assert b.has_data() and not a.has_data(), name
    si = results["spatial_information"]["information"]
    fig, ax = plt.subplots()
    assert plot.scatter(si, si, ax=ax) is fig
    assert plot.bars(si, ax=ax) is fig
    assert plot.cumulative({"a": [1, 2, 3]}, ax=ax) is fig


def test_cell_classes_plot_as_fractions_into_the_given_ax(place):
    cells = hp.classify_cells(place, n_shuffles=5, seed=0, bin_size=0.1)
    fig, ax = plt.subplots()
    assert cells.hp.plot(ax=ax) is fig
    heights = [p.get_height() for p in ax.patches]
    assert sum(heights) == pytest.approx(1.0)  # the classes share out the units
    assert ax.get_ylabel() == "fraction of units"


def test_wrong_axes_are_refused_with_the_reason(place, hd_rec):
    maps = hp.ratemaps(place, bin_size=0.05)
    _, axes = plt.subplots(1, 2)
    with pytest.raises(ValueError, match="needs 3"):
        maps.hp.plot(axes=axes)
    with pytest.raises(ValueError, match="polar"):
        hp.head_direction_tuning(hd_rec, n_shuffles=0).hp.plot(axes=axes)
    with pytest.raises(ValueError, match="not both"):
        maps.hp.plot(fig=plt.figure(), axes=axes)
    with pytest.raises(TypeError, match="`ax`"):
        hp.spatial_information(place, bin_size=0.1).hp.plot(ax=axes)


# ------------------------------------------------------------------ rate-map grids
def test_ratemap_grid_has_a_colour_bar_in_the_activitys_units(place):
    maps = hp.ratemaps(place, bin_size=0.05)
    per_unit = maps.hp.plot()
    (bar,) = _colorbar_axes(per_unit)
    assert bar.get_ylabel() == "mean activity (Hz)"
    assert [t.get_text() for t in bar.get_yticklabels()] == ["0", "peak"]
    (bar,) = _colorbar_axes(maps.hp.plot(scale="shared"))
    assert bar.get_ylabel() == "mean activity (Hz)"
    assert bar.get_ylim()[1] == pytest.approx(float(maps.max()))


def test_ratemap_titles_name_unit_peak_and_units():
    spikes = place_cell_recording(np.array([[0.2, 0.2]]), n_samples=6000,
                                  activity_kind="spike_count")
    maps = hp.ratemaps(spikes, bin_size=0.05)
    title = maps.hp.plot().axes[0].get_title()
    assert title == f"unit 0\npeak {plot._num(float(maps.max()))} Hz"
    hidden = place_cell_recording(np.array([[0.2, 0.2]]), n_samples=6000,
                                  activity_kind="lstm_hidden")
    title = hp.ratemaps(hidden, bin_size=0.05).hp.plot().axes[0].get_title()
    assert title.startswith("unit 0\npeak 0.") and "Hz" not in title
    assert "min \N{MINUS SIGN}0." in title  # signed activity: its floor is stated


def test_ratemap_titles_carry_the_region(place):
    rec = place.assign_coords(region=("unit", ["CA1", "CA1", "ADn"]))
    fig = hp.ratemaps(rec, bin_size=0.05).hp.plot()
    titles = [ax.get_title() for ax in fig.axes if ax.images]
    assert titles[0].startswith("unit 0 \N{MIDDLE DOT} CA1\n")
    assert titles[2].startswith("unit 2 \N{MIDDLE DOT} ADn\n")


# ------------------------------------------------------------------ head-direction polars
def test_hd_polar_ticks_and_titles_are_in_degrees(hd_rec):
    res = hp.head_direction_tuning(hd_rec, n_shuffles=0)
    fig = res.hp.plot()
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == [
        f"0{DEG}", f"90{DEG}", f"180{DEG}", f"270{DEG}"]
    pref = np.degrees(res["preferred_direction"].values[1]) % 360
    assert f"pref {pref:.0f}{DEG}" in fig.axes[1].get_title()
    assert f"R = {res['mean_vector_length'].values[1]:.2f}" in fig.axes[1].get_title()
    suptitle = fig._suptitle.get_text()
    assert f"head direction ({DEG})" in suptitle and "rad" not in suptitle


def test_hd_polar_titles_carry_the_region(hd_rec):
    fig = hp.head_direction_tuning(hd_rec, n_shuffles=0).hp.plot()
    assert fig.axes[0].get_title().startswith("unit 0 \N{MIDDLE DOT} ADn\n")
    assert fig.axes[1].get_title().startswith("unit 1 \N{MIDDLE DOT} CA1\n")


def test_mouse_session_polars_tell_adn_from_ca1(mouse):
    res = hp.head_direction_tuning(mouse, n_shuffles=0)
    fig = res.hp.plot()
    regions = mouse["region"].values
    titles = [ax.get_title() for ax in fig.axes[:len(regions)]]
    for title, region in zip(titles, regions):
        assert f"\N{MIDDLE DOT} {region}\n" in title
    maps = hp.ratemaps(mouse, bin_size=0.05)
    fig = maps.hp.plot()
    assert _colorbar_axes(fig)[0].get_ylabel() == "firing rate (Hz)"
    assert all(" Hz" in ax.get_title() for ax in fig.axes if ax.images)


def test_a_recording_plots_itself_as_an_overview():
    import numpy as np

    from hippo_probe.recording import from_arrays

    rng = np.random.default_rng(0)
    t = np.concatenate([np.arange(1, 101) * 0.1, 20 + np.arange(1, 101) * 0.1])
    rec = from_arrays(t, rng.uniform(-0.5, 0.5, (200, 2)), activity=rng.random((200, 5)),
                      trial=np.repeat([0, 1], 100), activity_kind="rate")
    fig = rec.hp.plot()
    path, act = fig.axes[:2]
    assert path.get_xlabel() == "x (m)" and act.get_xlabel() == "time in trial (s)"
    assert act.images[0].get_array().shape == (5, 100)      # the first trial, all units
