"""Single hypothesis: better than path integration, worse than the particle filter."""

import numpy as np

from hippo_probe.baselines import particle_filter, path_integration, single_hypothesis
from hippo_probe.tasks import make_trials


def test_sh_beats_pi_but_not_pf():
    batch = make_trials("generalized", 24, "test", 0)
    late = slice(100, None)                            # after 40 s
    pi = path_integration(batch).error(batch)[late].mean()
    sh = single_hypothesis(batch).error(batch)[late].mean()
    pf = particle_filter(batch, 300).error(batch)[late].mean()
    assert pf < sh < pi
    assert sh < 0.5 * pi


def test_reset_lands_near_the_touched_wall():
    batch = make_trials("specialized", 8, "test", 0)
    res = single_hypothesis(batch)
    t, b = np.nonzero(batch.contact)
    # right after a reset the hypothesis is a few cm from the truth, whatever PI's drift
    error = res.error(batch)[t, b]
    assert np.median(error) < 0.05
    assert res.attrs["mean_resets"] == batch.contact.sum(axis=0).mean()
