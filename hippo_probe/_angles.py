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


@numba.njit(cache=True, nogil=True, inline="always")
def wrap_angle_scalar(a):
    """:func:`wrap_angle` of one float, for numba kernels."""
    r = (a + math.pi) % (2.0 * math.pi) - math.pi
    return r - 2.0 * math.pi if r >= math.pi else r
