"""Fixtures shared by the tests of the study's scripts."""

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def analysis_script():
    """``load(name)``: the module ``analyses/<name>.py``, imported with ``analyses/`` on
    the path only while it loads (the scripts import their neighbours)."""
    def load(name):
        folder = str(ROOT / "analyses")
        sys.path.insert(0, folder)
        try:
            spec = importlib.util.spec_from_file_location(name, ROOT / "analyses" / f"{name}.py")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
        finally:
            sys.path.remove(folder)
        return module
    return load
