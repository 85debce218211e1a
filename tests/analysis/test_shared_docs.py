"""The shared parameter descriptions fill every analysis's docstring."""

import inspect

import pytest

import hippo_probe as hp
from hippo_probe._docs import DOCS, fill_doc


def test_a_placeholder_line_becomes_the_entry_indented_as_it_was():
    def f():
        """Do it.

        Parameters
        ----------
        %(bin_size)s
        x : int
        """
    doc = fill_doc(f).__doc__
    assert "        bin_size : float, optional\n            Side of the square" in doc
    assert "%(" not in doc and "        x : int" in doc


def test_an_unknown_entry_is_an_error_when_the_module_loads():
    def g():
        """%(no_such_parameter)s"""
    with pytest.raises(KeyError, match="no_such_parameter"):
        fill_doc(g)


@pytest.mark.parametrize("name", ["ratemaps", "spatial_information", "spatial_selectivity",
                                  "place_field_stability", "place_fields", "grid_score",
                                  "border_score", "classify_cells", "context_cells",
                                  "map_scorecard", "head_direction_tuning", "speed_score",
                                  "conjunctive_tuning", "remapping_similarity"])
def test_every_analysis_docstring_is_filled_and_states_its_parameters(name):
    func = getattr(hp, name)
    doc = inspect.getdoc(func)
    assert "%(" not in doc
    for param in inspect.signature(func).parameters:
        if param in DOCS or param in ("bin_size", "min_speed", "extent", "seed"):
            assert f"\n{param} :" in doc or f"\n{param}, " in doc, (name, param)


@pytest.mark.parametrize("name", ["particle_filter", "pf_slam", "naive_bayes",
                                  "single_hypothesis", "path_integration"])
def test_every_baseline_docstring_is_filled_and_states_its_parameters(name):
    import hippo_probe.baselines as baselines

    func = getattr(baselines, name)
    doc = inspect.getdoc(func)
    assert "%(" not in doc
    for param in inspect.signature(func).parameters:
        assert f"\n{param} :" in doc, (name, param)
