"""Shared argument validators: one voice for every error message.

Each helper raises ``ValueError`` (or ``TypeError`` for a wrong type) with a message that
names the argument, the value received and what was expected, e.g.
"`bin_size` must be > 0; got -1.0".
"""

from __future__ import annotations

import numbers
from collections.abc import Iterable

import numpy as np


def _fmt(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def check_option(name: str, value, allowed: Iterable):
    """Return ``value`` if it is one of ``allowed``; otherwise raise ValueError."""
    allowed = tuple(allowed)
    if value not in allowed:
        options = ", ".join(repr(a) for a in allowed)
        raise ValueError(f"`{name}` must be one of {options}; got {_fmt(value)}")
    return value


def check_bool(name: str, value, *, allow_none: bool = False):
    """``value`` if it is a bool (numpy's included; None too when ``allow_none``).

    A string is refused rather than read by its truth: ``"no"`` and ``"False"`` are
    truthy and would silently flip the option.
    """
    if value is None and allow_none:
        return None
    if not isinstance(value, (bool, np.bool_)):
        expected = "True, False or None" if allow_none else "True or False"
        raise TypeError(f"`{name}` must be {expected}; got {_fmt(value)}")
    return bool(value)


def check_number(name: str, value, *, low=None, high=None, low_inclusive=False,
                 high_inclusive=True, integer=False):
    """Return ``value`` as a Python number after range checks.

    ``low``/``high`` bound the value; inclusivity is set by ``low_inclusive`` and
    ``high_inclusive``.
    """
    kind = numbers.Integral if integer else numbers.Real
    if isinstance(value, bool) or not isinstance(value, kind):
        expected = "an integer" if integer else "a real number"
        raise TypeError(f"`{name}` must be {expected}; got {_fmt(value)}")
    if not integer and not np.isfinite(value):
        raise ValueError(f"`{name}` must be finite; got {_fmt(value)}")
    if low is not None:
        bad = value < low if low_inclusive else value <= low
        if bad:
            op = ">=" if low_inclusive else ">"
            raise ValueError(f"`{name}` must be {op} {low}; got {_fmt(value)}")
    if high is not None:
        bad = value > high if high_inclusive else value >= high
        if bad:
            op = "<=" if high_inclusive else "<"
            raise ValueError(f"`{name}` must be {op} {high}; got {_fmt(value)}")
    return int(value) if integer else float(value)


def check_positive(name: str, value, *, integer=False):
    """Return ``value`` if it is a finite number > 0."""
    return check_number(name, value, low=0, integer=integer)


def check_nonnegative_int(name: str, value):
    """Return ``value`` if it is an integer >= 0."""
    return check_number(name, value, low=0, low_inclusive=True, integer=True)


def check_shape(name: str, array, shape: tuple):
    """Check ``array.shape`` against ``shape`` (``None`` entries match any length)."""
    array = np.asarray(array)
    ok = array.ndim == len(shape) and all(
        s is None or s == a for s, a in zip(shape, array.shape)
    )
    if not ok:
        want = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
        raise ValueError(f"`{name}` must have shape {want}; got {array.shape}")
    return array


def check_finite(name: str, array, *, allow_nan=False):
    """Raise ValueError if ``array`` holds inf (or NaN unless ``allow_nan``)."""
    array = np.asarray(array)
    if array.dtype.kind in "fc":
        bad = np.isinf(array) if allow_nan else ~np.isfinite(array)
        if bad.any():
            what = "inf" if allow_nan else "NaN or inf"
            idx = tuple(int(i) for i in np.argwhere(bad)[0])
            raise ValueError(
                f"`{name}` must not contain {what}; found {array[idx]!r} at index {idx}"
            )
    return array


def check_dims(name: str, obj, dims: Iterable[str]):
    """Check that an xarray object has (at least) the given dims."""
    missing = [d for d in dims if d not in obj.dims]
    if missing:
        raise ValueError(
            f"`{name}` must have dims {tuple(dims)}; missing {missing} (has {tuple(obj.dims)})"
        )
    return obj


def check_variables(name: str, ds, variables: Iterable[str], *, why: str = ""):
    """Check that dataset ``ds`` holds each of ``variables`` (data vars or coords)."""
    missing = [v for v in variables if v not in ds.variables]
    if missing:
        reason = f" ({why})" if why else ""
        raise ValueError(
            f"`{name}` must contain {missing}{reason}; it has {sorted(map(str, ds.variables))}"
        )
    return ds


def check_real(name: str, array):
    """Return ``array`` if it holds real numbers (refuses complex: its imaginary part would
    be dropped silently by a cast, and booleans, strings and objects)."""
    array = np.asarray(array)
    if array.dtype.kind not in "iuf":
        what = ("complex numbers (the imaginary part would be lost)"
                if array.dtype.kind == "c" else f"dtype {array.dtype}")
        raise TypeError(f"`{name}` must hold real numbers; got {what}")
    return array


def check_seed(name: str, value):
    """Return ``value`` if it can seed :func:`numpy.random.default_rng` (None, an int >= 0
    or a ``numpy.random.Generator``/``SeedSequence``)."""
    if value is None or isinstance(value, (np.random.Generator, np.random.SeedSequence)):
        return value
    return check_nonnegative_int(name, value)


def check_path(name: str, value):
    """Return ``value`` as a ``pathlib.Path`` (str, bytes or os.PathLike accepted)."""
    import os
    from pathlib import Path

    if isinstance(value, (str, bytes, os.PathLike)):
        path = os.fsdecode(os.fspath(value))
        if path:
            return Path(path)
    raise TypeError(f"`{name}` must be a file path (str or os.PathLike); got {_fmt(value)}")


def check_allocation(name: str, shape, itemsize: int = 8, *, limit: int = 2**31,
                     shuffles: int = 1):
    """Refuse, before allocating it, a result of ``shape`` larger than ``limit`` bytes
    (default 2 GiB), naming the argument that set its size and the memory it would take.

    With ``shuffles`` > 1 the result is made once per shuffle (and the observed data):
    when one copy fits but all of them do not, ``n_shuffles`` is named instead."""
    def size(n):
        return int(np.prod([int(s) for s in shape], dtype=np.float64)) * itemsize * n
    if size(1) <= limit < size(shuffles):
        raise ValueError(f"`n_shuffles` = {shuffles - 1} asks for {shuffles} results of "
                         f"shape {tuple(int(s) for s in shape)} ({size(shuffles) / 2**30:.1f}"
                         f" GiB, more than the {limit / 2**30:.0f} GiB limit); choose fewer "
                         f"shuffles")
    if size(1) > limit:
        raise ValueError(f"`{name}` asks for a result of shape {tuple(int(s) for s in shape)}"
                         f" ({size(1) / 2**30:.1f} GiB, more than the {limit / 2**30:.0f} "
                         f"GiB limit); choose fewer or larger bins")
    return shape
