"""Where the examples find the repository's mouse session (not an example itself)."""

from pathlib import Path

try:
    HERE = Path(__file__).resolve().parent
except NameError:            # run cell by cell in Jupyter from the examples folder
    HERE = Path.cwd()

#: The real mouse session shipped with the tests (ADn head-direction cells, CA1 cells).
MOUSE_NWB = HERE.parent / "tests" / "data" / "A2929-200711.nwb"
