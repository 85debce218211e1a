"""Place fields: counts, sizes, peaks and centres of synthetic place cells."""

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis.place_fields import detect_fields

from .cell_fixtures import gaussian, square_walk
from .conftest import SQUARE, make_recording

CENTRES = {
    1: [(0.1, 0.2)],
    2: [(-0.25, -0.25), (0.25, 0.2)],
    3: [(-0.3, 0.25), (0.3, 0.3), (0.05, -0.3)],
}
WIDTH = 0.06


@pytest.fixture(scope="module")
def fields_rec():
    rng = np.random.default_rng(3)
    pos, heading, _ = square_walk(40000, rng)
    rates = [sum(gaussian(pos, c, WIDTH) for c in CENTRES[k]) for k in (1, 2, 3)]
    rates.append(np.full(len(pos), 0.5))                     # no field: constant
    return make_recording(pos, np.stack(rates, 1), head_direction=heading,
                          arena_vertices=SQUARE)


def test_place_cells_with_one_to_three_fields_are_counted_and_located(fields_rec):
    res = hp.place_fields(fields_rec, bin_size=0.04)
    assert res.n_fields.values.tolist() == [1, 2, 3, 0]
    for unit, k in enumerate((1, 2, 3)):
        found = res.field_centroid.values[unit, :k]
        for centre in CENTRES[k]:
            # each true centre has a detected field within half a bin
            assert np.hypot(*(found - centre).T).min() < 0.02
        sizes = res.field_size.values[unit, :k]
        # field = bins above 20% of the peak: a disc of radius sqrt(2 ln 5) s, with s^2
        # the field's variance plus the smoothing's (1 bin) and the binning's (bin^2/12)
        s2 = WIDTH**2 + 0.04**2 * (1 + 1 / 12)
        expected = np.pi * 2 * np.log(5) * s2 / 0.04**2
        np.testing.assert_allclose(sizes, expected, rtol=0.2)
        # the smoothed peak of a unit-height Gaussian field: WIDTH^2 / s^2
        np.testing.assert_allclose(res.field_peak.values[unit, :k], WIDTH**2 / s2, rtol=0.1)
    # fields are numbered by decreasing peak, label maps agree with the sizes
    peaks = res.field_peak.values[2]
    assert (np.diff(peaks) <= 0).all()
    labels = res.field_label.values[2]
    assert [(labels == f).sum() for f in (1, 2, 3)] == res.field_size.values[2].tolist()
    assert res.attrs["threshold"] == 0.2 and res.attrs["min_bins"] == 9


def test_detection_is_offset_invariant_so_signed_activity_needs_no_shift(fields_rec):
    signed = fields_rec.copy()
    signed["activity"] = np.tanh(2 * fields_rec.activity - 1.5).astype(np.float32)
    signed.attrs["activity_kind"] = "lstm_hidden"
    res = hp.place_fields(signed, bin_size=0.04)
    assert res.n_fields.values.tolist()[:3] == [1, 2, 3]


def test_min_bins_and_threshold_rules_on_a_map():
    maps = np.zeros((1, 10, 10))
    maps[0, 1:3, 1:3] = 1.0        # 4 bins
    maps[0, 5:9, 5:9] = 0.5        # 16 bins, half the peak
    maps[0, 0, 9] = np.nan         # unvisited
    f = detect_fields(maps, threshold=0.2, min_bins=9)
    assert f.count.tolist() == [1] and f.size.tolist() == [16]
    f = detect_fields(maps, threshold=0.2, min_bins=4)
    assert f.count.tolist() == [2] and f.peak.tolist() == [1.0, 0.5]
    f = detect_fields(maps, threshold=0.6, min_bins=4)    # the 0.5 field is below 60%
    assert f.count.tolist() == [1]
    # diagonal neighbours join only with 8-connectivity
    diag = np.zeros((1, 6, 6))
    diag[0, [0, 1, 2, 3], [0, 1, 2, 3]] = 1.0
    assert detect_fields(diag, threshold=0.5, min_bins=4).count.tolist() == [0]
    assert detect_fields(diag, threshold=0.5, min_bins=4, connectivity=2).count.tolist() == [1]


def test_arguments_are_checked(fields_rec):
    maps = hp.ratemaps(fields_rec, bin_size=0.05)
    with pytest.raises(ValueError, match="`threshold` must be < 1; got 1.5"):
        hp.place_fields(maps, threshold=1.5)
    with pytest.raises(ValueError, match="`connectivity` must be one of 1, 2; got 3"):
        hp.place_fields(maps, connectivity=3)
    with pytest.raises(ValueError, match="`bin_size` only applies when a recording"):
        hp.place_fields(maps, bin_size=0.1)
    with pytest.raises(TypeError, match="`rec_or_maps` must be a recording"):
        hp.place_fields(maps.values)
