"""The package's exceptions, in one place.

Every error the package raises on bad input is a ``ValueError`` subclass (or a plain
``ValueError``/``TypeError`` from :mod:`hippo_probe._validators`), so callers can catch
``ValueError`` without importing anything from here.
"""


class HippoProbeError(ValueError):
    """Base class of hippo_probe's own errors."""


class RecordingError(HippoProbeError):
    """A recording breaks the schema (names the variable and the rule broken)."""


class CheckpointError(HippoProbeError):
    """A checkpoint file is missing, corrupt, or from an incompatible configuration."""


class RunInUseError(HippoProbeError):
    """A training run's folder is being trained in by another process."""
