"""Shared parameter descriptions: one text for each parameter that many functions take
(the analyses' map and shuffle options, the baselines' common arguments), as MNE's
``docdict``, filled into their docstrings by :func:`fill_doc`.

A docstring names an entry on a line of its own, ``%(bin_size)s``, indented as a
parameter; the entry's lines take that indentation. Defaults that differ between
analyses have their own entry (``sigma_maps`` smooths by one bin, ``sigma_unsmoothed``
not at all).
"""

from __future__ import annotations

import re

DOCS = {
    "bin_size": """\
bin_size : float, optional
    Side of the square spatial bins (m); default: the extent's longer side / 32.""",
    "sigma_maps": """\
sigma : float, optional
    Gaussian smoothing width of the rate maps, in bins (default 1; 0 = none); the
    activity sums and the occupancy are smoothed, then divided.""",
    "sigma_unsmoothed": """\
sigma : float, optional
    Gaussian smoothing width of the rate maps, in bins (default 0, none).""",
    "min_occupancy": """\
min_occupancy : float, optional
    Bins visited for less than this many seconds are NaN (default 0).""",
    "min_speed": """\
min_speed : float, optional
    Only samples at or above this speed (m/s) count; speed is ``rec.speed`` or derived
    from ``position`` within each trial (default: every sample).""",
    "by": """\
by : {None, 'environment', 'trial'}
    One result per environment or per trial (on one grid of bins), or one overall
    (None: every environment's positions pooled; warned when there are several).""",
    "extent": """\
extent : (x_min, x_max, y_min, y_max), optional
    Area covered by the bins (m); default: the arenas' bounding box when the recording
    has ``arena_vertices``, else the finite positions'. Samples outside are not
    counted.""",
    "n_shuffles": """\
n_shuffles : int, optional
    Circular time shifts of the activity against the behaviour, each by at least
    ``SHUFFLE.min_shift`` (20) s, for the null distribution (default 100; 0 = none). Not
    with ``by``: a shift over the whole recording would mix the groups' activity into
    each group's null (refused; the default is then 0). Shuffle a group alone by
    selecting its trials (:func:`~hippo_probe.select_trials`).""",
    "seed": """\
seed : int, optional
    Seed of the shuffles' shifts (default ``SHUFFLE.seed``): the same seed, the same
    shifts.""",
    # the baselines (hippo_probe.baselines)
    "batch": """\
batch : TrialBatch
    The trials (:func:`hippo_probe.tasks.make_trials`).""",
    "baseline_config": """\
config : TaskConfig, optional
    Must be the batch's own (``batch.config``, the default) if given.
baseline : BaselineConfig, optional
    The baselines' settings (default ``BaselineConfig()``).""",
    "threads": """\
threads : int, optional
    Trials run in parallel on this many threads (default: numba's thread count, all
    cores unless ``NUMBA_NUM_THREADS`` or ``numba.set_num_threads`` says fewer).""",
}

_PLACEHOLDER = re.compile(r"^(?P<indent>[ \t]*)%\((?P<key>\w+)\)s[ \t]*$", re.MULTILINE)


def fill_doc(func):
    """Replace each ``%(key)s`` line of ``func``'s docstring by :data:`DOCS` [key],
    indented like the placeholder; an unknown key is an error when the module loads."""
    doc = func.__doc__
    if doc:
        def entry(match):
            key, indent = match["key"], match["indent"]
            if key not in DOCS:
                raise KeyError(f"{func.__qualname__}: no shared description {key!r}")
            return "\n".join(indent + line if line else line
                             for line in DOCS[key].splitlines())
        func.__doc__ = _PLACEHOLDER.sub(entry, doc)
    return func
