"""The Examples sections of the public docstrings run and show what they say."""

import doctest
import importlib
import pkgutil

import pytest

import hippo_probe

# the packages whose examples are quick (the rest make trials or load networks and are
# exercised by their own tests)
PACKAGES = ("hippo_probe.analysis", "hippo_probe.recording")
MODULES = sorted(
    info.name for package in PACKAGES
    for info in pkgutil.iter_modules(importlib.import_module(package).__path__,
                                     package + ".")
    if not info.name.rsplit(".", 1)[-1].startswith("__")) + [
    "hippo_probe.pretrained.summary"]       # reads the shipped logs only: quick, no torch


#: modules whose examples need an optional dependency (an extra), skipped without it
NEEDS = {"hippo_probe.analysis.intrinsic_dimension": "skdim",
         "hippo_probe.analysis.decode_environment": "sklearn",
         "hippo_probe.recording.nwb": "pynwb",
         "hippo_probe.recording.pynapple_bridge": "pynapple"}


@pytest.mark.parametrize("name", MODULES)
def test_examples(name):
    if name in NEEDS:
        pytest.importorskip(NEEDS[name])
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed"


def test_the_modules_are_found():
    assert "hippo_probe.analysis.decode_environment" in MODULES
    assert hippo_probe.__version__
