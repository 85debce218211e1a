"""analyses/arena_readout.py: a later run reuses the variant's time constant only when it
was chosen on the same features, size, C and candidates."""

from dataclasses import replace

import pytest

from hippo_probe.paper import readout as R


@pytest.fixture(scope="module")
def script(analysis_script):
    return analysis_script("arena_readout")


def earlier(taus=R.READOUT.taus, size=4000, c=1.0, features="net-abc"):
    kinds = R.feature_kinds(replace(R.READOUT, taus=taus))[1:]
    return {"features": features,
            "leaky_tau_choice": {"train_trials": size, "c": c, "chosen": kinds[1],
                                 "validation_accuracy_late": dict.fromkeys(kinds, 0.5)}}


def test_the_same_scan_is_reused(script):
    choice = script.earlier_tau_choice(earlier(), "net-abc", 4000, 1.0, R.READOUT)
    assert choice["chosen"] == R.feature_kinds(R.READOUT)[2]


@pytest.mark.parametrize("before", [
    None,
    {"features": "net-abc"},                          # no variant fitted before
    earlier(features="net-other"),                    # another network or protocol
    earlier(size=2000),                               # chosen at another size
    earlier(c=10.0),                                  # or another C
    earlier(taus=(10.0, 200.0)),                      # among other candidates
])
def test_any_other_scan_is_not(script, before):
    assert script.earlier_tau_choice(before, "net-abc", 4000, 1.0, R.READOUT) is None
