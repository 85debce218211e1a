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
    """Compass world: the heading names the touched wall, so a reset lands near it."""
    batch = make_trials("specialized", 8, "test", 0, world="compass")
    res = single_hypothesis(batch)
    t, b = np.nonzero(batch.contact)
    # right after a reset the hypothesis is a few cm from the truth, whatever PI's drift
    error = res.error(batch)[t, b]
    assert np.median(error) < 0.05
    assert res.attrs["mean_resets"] == batch.contact.sum(axis=0).mean()


def test_in_darkness_it_falls_with_the_first_contacts_then_rises():
    """The study's single hypothesis: resets onto the wall that the drifting heading
    points to help at first, then the drift makes them wrong more and more often; its
    error rises steadily and ends far above the particle filter's."""
    batch = make_trials("localization", 60, "test", 0)
    sh = single_hypothesis(batch).error(batch).mean(axis=1)
    pf = particle_filter(batch).error(batch).mean(axis=1)
    pi = path_integration(batch).error(batch).mean(axis=1)

    def at(seconds, width=10):
        k = int(round(seconds / batch.dt))
        return sh[k - width:k + width].mean()

    assert at(40) < 0.8 * at(4)                  # the first contacts help ...
    assert at(100) > at(40) and at(190) > at(100)  # ... then the error rises
    assert sh[-25:].mean() > 2 * pf[-25:].mean()
    assert pi[-25:].mean() > sh[-25:].mean()
