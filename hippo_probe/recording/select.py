"""``select_trials``: a lazy subset of a recording's trials or environments."""

from __future__ import annotations

import numpy as np

from ..errors import RecordingError
from .layout import trial_blocks
from .validate import _v


def select_trials(rec, trials=None, environments=None):
    """Keep only some trials (and/or environments) of a recording, lazily.

    The samples of the kept trials are selected along ``time`` (dask arrays stay lazy;
    whole trials are taken, so trial-aligned chunks stay trial-aligned), and the trial
    table is subset to match. The environment table (``environment_id``,
    ``arena_vertices``, ``readout_weight``, the ``class_probability`` columns) is kept
    whole: it describes the classifier's classes, not only the environments visited.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording.
    trials : int or sequence of int, optional
        Trial ids to keep (default: all).
    environments : int or sequence of int, optional
        Keep only trials in these environments (default: all).

    Returns
    -------
    xarray.Dataset
        A recording (valid if ``rec`` was) holding the trials that match both filters, in
        their original order.

    Raises
    ------
    RecordingError
        An unknown trial or environment id, or a selection that keeps no trial.

    Examples
    --------
    >>> import numpy as np
    >>> from hippo_probe.recording import from_arrays
    >>> t = np.r_[0:1:0.1, 2:3:0.1]
    >>> rec = from_arrays(t, np.zeros((20, 2)), activity=np.ones((20, 1)),
    ...                   trial=np.repeat([0, 1], 10), environment=np.repeat([3, 5], 10))
    >>> select_trials(rec, environments=5).trial_id.values
    array([1])
    """
    trial_ids = rec["trial_id"].values
    keep = np.ones(trial_ids.size, dtype=bool)
    for name, wanted, known, values in (
            ("trials", trials, trial_ids, trial_ids),
            ("environments", environments, rec["environment_id"].values,
             rec["trial_environment"].values)):
        if wanted is None:
            continue
        wanted = np.atleast_1d(np.asarray(wanted))
        unknown = ~np.isin(wanted, known)
        if unknown.any():
            raise RecordingError(f"`{name}` must be ids of this recording; "
                                 f"{_v(wanted[unknown][0])} is not among {known.tolist()[:20]}")
        keep &= np.isin(values, wanted)
    if not keep.any():
        raise RecordingError(f"no trial matches `trials`={_v(trials)} and "
                             f"`environments`={_v(environments)}")
    starts, stops, _ = trial_blocks(rec["trial"].values)
    index = np.concatenate([np.arange(a, b) for a, b in zip(starts[keep], stops[keep])])
    return rec.isel(time=index, trial_id=np.flatnonzero(keep))
