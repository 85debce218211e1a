"""analyses/variant_learning_curves.py: the variants' validation curves from the shipped logs."""

import numpy as np
import pytest


@pytest.fixture(scope="module")
def script(analysis_script):
    return analysis_script("variant_learning_curves")


def test_the_table_gives_mean_and_range_over_seeds(script):
    curves = {"a": {0: (np.array([0, 250, 500]), np.array([0.3, 0.2, 0.1])),
                    1: (np.array([0, 250, 500]), np.array([0.3, 0.4, 0.3]))},
              "b": {0: (np.array([0, 250]), np.array([0.3, 0.25]))}}
    assert script.error_at(curves["b"][0], 250) == 0.25
    assert np.isnan(script.error_at(curves["b"][0], 500))
    lines = script.table(curves, [250, 500]).splitlines()
    assert lines[0] == "| network | seeds | 250 steps | 500 steps |"
    assert lines[2] == "| `a` | 2 | 0.300 (0.200–0.400) | 0.200 (0.100–0.300) |"
    assert lines[3] == "| `b` | 1 | 0.250 | — |"


def test_every_shipped_seed_of_each_network_is_read(script):
    from hippo_probe.pretrained import shipped_seeds

    for name in script.NETWORKS:
        by_seed = script.curves(name)
        assert list(by_seed) == shipped_seeds(name) and by_seed
        steps, errors = by_seed[0]
        assert steps[0] == 0 and steps[-1] == 20000 and np.all(errors > 0)
