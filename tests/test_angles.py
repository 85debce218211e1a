"""One definition of angle wrapping (hippo_probe._angles), used everywhere."""

import re
from pathlib import Path

import numpy as np
import pytest

from hippo_probe import _angles
from hippo_probe._angles import wrap_angle, wrap_angle_scalar

PACKAGE = Path(_angles.__file__).parent
TWO_PI = r"(2(\.0)?\s*\*\s*(np|math)\.pi|(np|math)\.tau|TWO_PI|TAU)"
#: Ways to wrap an angle by hand, each a second definition of wrap_angle.
HAND_WRAPS = [
    r"angle\(\s*np\.exp\(\s*1j",                       # np.angle(np.exp(1j * a))
    rf"%\s*\(?\s*{TWO_PI}",                              # (a + pi) % (2 * pi) - pi
    rf"np\.(mod|remainder|fmod)\(.*{TWO_PI}",            # np.mod(a + pi, 2 * pi)
    r"arctan2\(\s*(np\.|math\.)?sin\(",                  # arctan2(sin(a), cos(a))
]


def test_angles_are_wrapped_only_by_wrap_angle():
    """One implementation of angle wrapping: a new hand-written wrap fails here."""
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name == "_angles.py":
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#")[0]
            if any(re.search(p, code) for p in HAND_WRAPS):
                found.append(f"{path.relative_to(PACKAGE)}:{number}: {line.strip()}")
    assert not found, "wrap angles with hippo_probe._angles.wrap_angle:\n" + "\n".join(found)


@pytest.mark.parametrize("line", [
    "turn = np.abs(np.angle(np.exp(1j * (a - b))))",
    "r = (a + math.pi) % (2.0 * math.pi) - math.pi",
    "r = np.mod(a + np.pi, 2 * np.pi) - np.pi",
    "d = np.arctan2(np.sin(a - b), np.cos(a - b))",
])
def test_the_scan_sees_a_hand_written_wrap(line):
    assert any(re.search(p, line) for p in HAND_WRAPS)


def test_the_array_and_scalar_wraps_agree_on_the_half_open_interval():
    a = np.r_[np.linspace(-20, 20, 4001), -np.pi, np.pi, np.nextafter(-np.pi, -4)]
    w = wrap_angle(a)
    assert ((w >= -np.pi) & (w < np.pi)).all()
    np.testing.assert_allclose([wrap_angle_scalar(x) for x in a], w, rtol=0, atol=1e-12)


def test_the_scalar_wrap_is_numbas_modulo_bit_for_bit():
    """The kernels' wrap skips ``fmod`` near the circle; it must give what numba's ``%``
    gives for every float, at the fast path's edges (x + pi = +-2 pi, +-4 pi), far out,
    at signed zeros and at inf and NaN."""
    numba = pytest.importorskip("numba")
    import math

    @numba.njit
    def by_modulo(a):
        r = (a + math.pi) % (2.0 * math.pi) - math.pi
        return r - 2.0 * math.pi if r >= math.pi else r

    @numba.njit
    def mismatches(values):
        bad = 0
        for v in values:
            u, w = wrap_angle_scalar(v), by_modulo(v)
            same = (u == w and math.copysign(1.0, u) == math.copysign(1.0, w)) or \
                (math.isnan(u) and math.isnan(w))
            bad += 0 if same else 1
        return bad

    def around(x, ulps=3000):
        up = [x]
        down = [x]
        for _ in range(ulps):
            up.append(np.nextafter(up[-1], np.inf))
            down.append(np.nextafter(down[-1], -np.inf))
        return np.array(up + down)

    rng = np.random.default_rng(0)
    values = np.concatenate(
        [rng.uniform(-30, 30, 200_000), rng.normal(0, 1, 200_000),
         rng.uniform(-1e6, 1e6, 10_000),
         np.array([0.0, -0.0, np.inf, -np.inf, np.nan, 1e300, -1e300, 5e-324, -5e-324])]
        + [around(k * np.pi) for k in (-7, -5, -3, -1, 0, 1, 3, 5, 7)])
    assert mismatches(values) == 0
