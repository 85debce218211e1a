"""The recording's names, dims, units and labels (schema v1) in one table.

Code that builds a recording takes ``dims``, ``units`` and ``long_name`` from here instead
of retyping them; :func:`annotate` fills the attrs of every known variable that lacks
them, and :func:`hippo_probe.recording.validate` checks a recording against this table.

The schema itself is described for users in ``recordings/README.md`` and for developers
in ``shared/DESIGN.md`` ("The recording (schema v1)").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SCHEMA_VERSION = 1

#: Values of the dataset attr ``source``.
SOURCES = ("network", "animal")

#: ``activity`` units for the common values of the dataset attr ``activity_kind``; any other
#: non-empty ``activity_kind`` is allowed (its units are then up to the producer).
ACTIVITY_UNITS = {
    "lstm_hidden": "1",       # tanh-bounded hidden state, dimensionless
    "spike_count": "count",   # spikes per tracking sample
    "rate": "Hz",
}

#: ``activity_kind`` values whose activity is signed (the LSTM's h lies in (-1, 1)): a
#: measure that needs a non-negative rate shifts each unit by its minimum.
SIGNED_KINDS = ("lstm_hidden",)

#: Dataset attrs every recording must carry, with the Python types they may take.
REQUIRED_ATTRS = {
    "schema_version": (int, np.integer),
    "source": (str,),
    "activity_kind": (str,),
    "dt": (float, int, np.floating, np.integer),
    "created_by": (str,),
}

#: Dataset attrs the schema names but does not require (network: task, seed, checkpoint;
#: animal: session_id, subject, species).
OPTIONAL_ATTRS = ("task", "seed", "checkpoint", "session_id", "subject", "species")

#: Labels of the ``space`` and ``cov`` dims.
SPACE = ("x", "y")
COV = ("xx", "yy", "xy")


@dataclass(frozen=True)
class VariableSpec:
    """How one named variable of the recording looks.

    Attributes
    ----------
    dims : tuple of str
        Its dims, in order.
    units : str
        Its ``units`` attr ("1" for dimensionless numbers and ids, "" for labels).
    long_name : str
        Its ``long_name`` attr (plots label their axes with it).
    coord : bool
        Stored as a coordinate (True) or a data variable (False).
    required : bool
        Every recording has it.
    kind : str
        Allowed numpy dtype kinds ("f" float, "i"/"u" integer, "b" bool, "U"/"O"/"T" text).
    """

    dims: tuple
    units: str
    long_name: str
    coord: bool = False
    required: bool = False
    kind: str = "f"


_LABEL = "UOTS"    # numpy kinds of string arrays (unicode, object, StringDType, bytes)
_ID = "iu" + _LABEL

#: Every variable the schema names -> its :class:`VariableSpec`.
VARIABLES: dict[str, VariableSpec] = {
    # index coords and per-sample coords
    "time": VariableSpec(("time",), "s", "time since session start", True, True),
    "trial": VariableSpec(("time",), "1", "trial", True, True, "iu"),
    "trial_time": VariableSpec(("time",), "s", "time since trial start", True, True),
    "environment": VariableSpec(("time",), "1", "environment", True, True, "iu"),
    "unit": VariableSpec(("unit",), "1", "unit", True, True, _ID),
    "space": VariableSpec(("space",), "", "spatial axis", True, True, _LABEL),
    "cov": VariableSpec(("cov",), "", "covariance component", True, False, _LABEL),
    # trial table
    "trial_id": VariableSpec(("trial_id",), "1", "trial", True, True, "iu"),
    "trial_start": VariableSpec(("trial_id",), "s", "trial start", True, True),
    "trial_stop": VariableSpec(("trial_id",), "s", "trial stop", True, True),
    "trial_environment": VariableSpec(("trial_id",), "1", "environment of the trial",
                                      True, True, "iu"),
    "start_position": VariableSpec(("trial_id", "space"), "m", "start position", True),
    # environment table
    "environment_id": VariableSpec(("environment_id",), "1", "environment", True, True,
                                   "iu"),
    "arena_vertices": VariableSpec(("environment_id", "vertex", "space"), "m",
                                   "arena vertex"),
    # measurements
    "activity": VariableSpec(("time", "unit"), "1", "activity", required=True),
    "position": VariableSpec(("time", "space"), "m", "position", required=True),
    "head_direction": VariableSpec(("time",), "rad", "head direction"),
    "speed": VariableSpec(("time",), "m/s", "speed"),
    "contact": VariableSpec(("time",), "1", "boundary contact", kind="b"),
    "heading_drift": VariableSpec(("time",), "rad",
                                  "heading drift (sensed minus true head direction)"),
    "estimate_drift_pf": VariableSpec(("time",), "rad",
                                      "particle filter heading drift estimate"),
    "pf_drift_sd": VariableSpec(("time",), "rad", "particle filter heading drift s.d."),
    "estimate_drift_pfslam": VariableSpec(("time",), "rad", "PF-SLAM heading drift estimate"),
    # estimates (network and baselines), arena frame
    "estimate": VariableSpec(("time", "space"), "m", "network position estimate"),
    "estimate_pi": VariableSpec(("time", "space"), "m", "path integration estimate"),
    "estimate_sh": VariableSpec(("time", "space"), "m", "single hypothesis estimate"),
    "estimate_nb": VariableSpec(("time", "space"), "m", "naive Bayes estimate"),
    "estimate_pf": VariableSpec(("time", "space"), "m", "particle filter estimate"),
    "estimate_pfslam": VariableSpec(("time", "space"), "m", "PF-SLAM estimate"),
    "pf_cov": VariableSpec(("time", "cov"), "m2", "particle filter posterior covariance"),
    "class_probability": VariableSpec(("time", "environment_id"), "1",
                                      "network probability of the environment"),
    "class_probability_pfslam": VariableSpec(("time", "environment_id"), "1",
                                             "PF-SLAM probability of the environment"),
    "readout_weight": VariableSpec(("environment_id", "unit"), "1",
                                   "classifier readout weight"),
}

#: The index coords (dimension coordinates) the schema names.
INDEX_COORDS = ("time", "unit", "space", "cov", "trial_id", "environment_id")

#: Per-sample coords loaded eagerly on open so ``groupby`` works on lazy recordings.
SAMPLE_COORDS = ("trial", "trial_time", "environment")

#: Trial table columns (coords along ``trial_id``).
TRIAL_TABLE = ("trial_start", "trial_stop", "trial_environment", "start_position")


def attrs_for(name: str) -> dict:
    """Return ``{"units": ..., "long_name": ...}`` of a schema variable.

    Examples
    --------
    >>> attrs_for("position")
    {'units': 'm', 'long_name': 'position'}
    """
    spec = VARIABLES[name]
    return {"units": spec.units, "long_name": spec.long_name}


def annotate(rec):
    """Fill ``units``/``long_name`` of every schema variable of ``rec`` that lacks them.

    Attrs already present are kept, so a producer can set its own (e.g. ``activity``
    units for a custom ``activity_kind``). ``activity`` units default from the dataset
    attr ``activity_kind`` (see :data:`ACTIVITY_UNITS`). Returns a new Dataset; the data
    are not copied.

    Examples
    --------
    >>> import xarray as xr
    >>> ds = annotate(xr.Dataset(coords={"time": [0.0, 0.1]}))
    >>> ds.time.attrs["units"]
    's'
    """
    rec = rec.copy()
    for name in rec.variables:
        if name not in VARIABLES:
            continue
        defaults = attrs_for(name)
        if name == "activity":
            kind = rec.attrs.get("activity_kind")
            defaults["units"] = ACTIVITY_UNITS.get(kind, defaults["units"])
        for key, value in defaults.items():
            rec.variables[name].attrs.setdefault(key, value)
    return rec
