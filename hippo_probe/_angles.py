"""Angle wrapping: the one definition, for arrays and for numba kernels."""

from __future__ import annotations

import math

import numba
import numpy as np


def wrap_angle(angle):
    """Wrap radians into [-pi, pi).

    .. math:: \\operatorname{wrap}(a) = ((a + \\pi) \\bmod 2\\pi) - \\pi

    One ulp below ``-pi`` the float modulo rounds up to ``2 pi`` and would give ``+pi``;
    that value is folded back so the interval is half-open as documented.
    """
    r = np.mod(np.asarray(angle, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(r >= np.pi, r - 2 * np.pi, r)


_TWO_PI = 2.0 * math.pi


@numba.njit(cache=True, nogil=True, inline="always")
def wrap_angle_scalar(a):
    """:func:`wrap_angle` of one float, for numba kernels.

    Bit for bit ``(a + pi) % (2 pi) - pi`` as numba computes it (C's ``fmod``, then
    Python's sign rule), without the call to ``fmod`` where ``|a + pi| < 4 pi``: there
    the remainder is ``x``, ``x - 2 pi`` or ``x + 2 pi``, each exact (Sterbenz's lemma),
    and ``fmod`` is exact too. The particle filters wrap an angle per particle and wall.
    """
    x = a + math.pi
    if -_TWO_PI < x < _TWO_PI:              # fmod(x, 2 pi), exactly
        f = x
    elif _TWO_PI <= x < 2.0 * _TWO_PI:
        f = x - _TWO_PI
    elif -2.0 * _TWO_PI < x <= -_TWO_PI:
        f = x + _TWO_PI
    else:                                   # far out, inf or NaN: numba's own modulo
        f = x % _TWO_PI
    if f < 0.0:                             # the sign of the divisor, as Python's %
        f += _TWO_PI
    elif f == 0.0:
        f = 0.0                             # +0, never -0
    r = f - math.pi
    return r - _TWO_PI if r >= math.pi else r
