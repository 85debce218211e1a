import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

import hippo_probe as hp
from hippo_probe import plot

from .conftest import (
    hd_cell_recording,
    two_environment_recording,
)


def test_ratemaps_plot_themselves_with_arena_outline(place):
    maps = hp.ratemaps(place, bin_size=0.05)
    fig = maps.hp.plot()
    assert isinstance(fig, Figure)
    panels = [ax for ax in fig.axes if ax.images]
    assert len(panels) == 3
    # the square arena's outline is drawn on every panel
    outline = panels[0].get_lines()[0].get_xydata()
    np.testing.assert_allclose(np.abs(outline), 0.5)
    assert fig._suptitle.get_text() == "mean activity (Hz)"
    assert panels[0].get_title().endswith("peak 0.65 Hz")  # each panel: its own peak
    assert fig.axes[-1].get_ylabel() == "mean activity (Hz)"  # a colour bar, 0..peak
    shared = maps.hp.plot(scale="shared")
    assert shared.axes[-1].get_ylabel() == "mean activity (Hz)"  # one colour bar
    assert panels[0].get_xlabel() == "x position (m)"
    assert panels[0].get_ylabel() == "y position (m)"


def test_grouped_maps_plot_one_group_with_its_arena():
    rec = two_environment_recording(n_units=4, n_trials=4, samples_per_trial=800)
    maps = hp.ratemaps(rec, bin_size=0.1, by="environment")
    fig = maps.hp.plot(group=1)
    assert "environment 1 (2 of 2; `group=` shows another)" in fig._suptitle.get_text()
    # by default the first, and the title says there are others
    assert "environment 0 (1 of 2;" in maps.hp.plot()._suptitle.get_text()
    by_trial = hp.ratemaps(rec, bin_size=0.1, by="trial").hp.plot(group=3)
    assert "trial 3 (4 of 4;" in by_trial._suptitle.get_text()
    assert by_trial.axes[0].get_lines()  # the trial's arena outline


def test_hd_polar_titles_carry_r_and_direction():
    rec = hd_cell_recording(np.array([0.5, -1.0]), np.array([4.0, 2.0]), n_samples=4000)
    res = hp.head_direction_tuning(rec, n_shuffles=0)
    fig = res.hp.plot()
    titles = [ax.get_title() for ax in fig.axes]
    assert any("R = 0." in t for t in titles)
    # the ticks are in degrees, and so is the title
    assert "head direction (\N{DEGREE SIGN})" in fig._suptitle.get_text()


def test_remapping_cumulative_plot():
    rec = two_environment_recording(n_units=6, n_trials=6, samples_per_trial=800)
    fig = hp.remapping_similarity(rec).hp.plot()
    ax = fig.axes[0]
    assert len(ax.get_lines()) == 4
    assert ax.get_xlabel() == "population-vector correlation"
    assert ax.get_ylabel() == "cumulative fraction"


def test_per_unit_results_plot_as_distributions(place):
    for res in (hp.spatial_information(place, bin_size=0.1),
                hp.spatial_selectivity(place, bin_size=0.1)):
        fig = res.hp.plot()
        assert fig.axes[0].get_ylabel() == "cumulative fraction"
        assert fig.axes[0].get_xlabel()


def test_every_scored_result_plots_itself(place):
    """The results the guides promise ``.hp.plot()`` for: the scores per unit as their
    distributions, the decoders' accuracy over time, the dimension estimates as bars."""
    rec = two_environment_recording(n_units=4, n_trials=6, samples_per_trial=800)
    results = [hp.place_fields(place, bin_size=0.05),
               hp.grid_score(place, bin_size=0.05, n_shuffles=0),
               hp.border_score(place, bin_size=0.05, n_shuffles=0),
               hp.speed_score(place, n_shuffles=0),
               hp.decode_environment(rec, n_folds=2),
               hp.intrinsic_dimension(np.random.default_rng(0).uniform(size=(600, 3)))]
    for res in results:
        fig = res.hp.plot()
        assert isinstance(fig, Figure) and fig.axes[0].has_data(), res.attrs["analysis"]
    assert results[0].hp.plot().axes[0].get_ylabel() == "cumulative fraction"
    with pytest.raises(ValueError, match="nothing to draw"):
        plot.plot_result(hp.map_scorecard(rec, bin_size=0.1))


def test_error_curves_and_unknown_results(place):
    rec = place.copy()
    rec["estimate"] = rec.position + 0.05
    rec["estimate"].attrs = {"units": "m", "long_name": "network estimate"}
    fig = hp.localization_error(rec).hp.plot()
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "Euclidean error (m)", "radial error (m)", "angular error (rad)"]
    assert fig.axes[0].get_xlabel() == "time in trial (s)"
    rec["estimate_pf"] = rec.position - 0.02
    rec["estimate_pf"].attrs = {"units": "m", "long_name": "particle filter estimate"}
    fig = hp.localization_error(rec, ["estimate", "estimate_pf"]).hp.plot()
    legend = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert legend[:2] == ["network", "particle filter (oracle)"]
    with pytest.raises(ValueError, match="no hippo_probe plot"):
        place.activity.hp.plot()


def test_correlation_sum_plot():
    x = np.random.default_rng(0).uniform(size=(800, 2)) @ np.eye(2, 8)
    fig = plot.plot_result(hp.correlation_dimension(x))
    assert fig.axes[0].get_title().startswith("D = ")


def test_a_per_unit_result_by_environment_draws_one_distribution_each():
    rec = two_environment_recording(n_units=4, n_trials=4, samples_per_trial=800)
    fig = hp.spatial_information(rec, by="environment", bin_size=0.1).hp.plot()
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert [label.split(" (")[0] for label in labels] == ["environment 0", "environment 1"]
    assert all("(n=4" in label for label in labels)


def test_refused_estimates_are_shown_with_their_reason():
    """NaN bars and a D without scaling range say so, instead of an empty panel."""
    counts = np.random.default_rng(0).poisson(0.05, size=(3000, 6)).astype(float)
    with pytest.warns(hp.AnalysisWarning):
        res = hp.intrinsic_dimension(counts)
    fig = res.hp.plot()
    title = fig.axes[0].get_title()
    assert "TwoNN: NaN" in title and "MLE: NaN" in title
    assert [t.get_text() for t in fig.axes[0].texts] == ["NaN", "NaN"]
    with pytest.warns(hp.AnalysisWarning, match="correlation dimension is NaN"):
        cd = hp.correlation_dimension(counts)
    fig = cd.hp.plot()
    assert fig.axes[0].get_title() == "D = NaN"
    assert "dimension: NaN, no window of" in fig._suptitle.get_text()


def test_rate_maps_outline_their_place_fields(place):
    maps = hp.ratemaps(place, bin_size=0.05)
    fields = hp.place_fields(maps)
    fig = maps.hp.plot(fields=fields)
    n = int(fields["n_fields"].isel(unit=0))
    assert n >= 1
    assert f"{n} field" in fig.axes[0].get_title()
    assert fig.axes[0].collections            # the fields' outline (a contour)
    with pytest.raises(ValueError, match="detected on other bins"):
        maps.hp.plot(fields=hp.place_fields(hp.ratemaps(place, bin_size=0.1)))
    with pytest.raises(ValueError, match="`fields` must be the output of"):
        maps.hp.plot(fields=maps)
