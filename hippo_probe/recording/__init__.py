"""Recordings: one session layout for networks and animals (schema v1).

A recording is a plain ``xarray.Dataset`` stored as a zarr store; see
``recordings/README.md`` for the format and :mod:`hippo_probe.recording.schema` for the
names, dims, units and long names in one table. Nothing here imports torch.
"""

from .. import _accessor  # noqa: F401  (registers the ``.hp`` xarray accessor)
from .arrays import bin_spikes, from_arrays
from .config import DEFAULTS, RecordingConfig
from .layout import stack_trials, trial_aligned_chunks, trial_blocks, trial_layout
from .nwb import from_nwb, to_nwb
from .pynapple_bridge import from_pynapple, to_pynapple
from .schema import SCHEMA_VERSION, VARIABLES, annotate, attrs_for
from .select import select_trials
from .spikes import poisson_spikes
from .store import open_recording, save_recording
from .validate import check_analysable, validate

__all__ = [
    "DEFAULTS", "RecordingConfig", "SCHEMA_VERSION", "VARIABLES", "annotate", "attrs_for",
    "bin_spikes", "check_analysable", "from_arrays", "from_nwb", "from_pynapple", "open_recording",
    "poisson_spikes", "save_recording", "select_trials", "stack_trials", "to_nwb",
    "to_pynapple", "trial_aligned_chunks", "trial_blocks", "trial_layout", "validate",
]
