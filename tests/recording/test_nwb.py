"""NWB import/export on a real mouse session (tests/data/A2929-200711.README.md)."""

import datetime
import warnings

import numpy as np
import pynwb
import pytest
import xarray as xr
from pynwb.behavior import CompassDirection, Position, SpatialSeries

from hippo_probe.cli import main as cli
from hippo_probe.errors import RecordingError
from hippo_probe.recording import (from_arrays, from_nwb, open_recording, save_recording,
                                   to_nwb, validate)

from .conftest import NWB_PATH

WAKE_SPIKES_TRACKED = 44_618       # README: wake spikes inside 670.64-1199.99 s


@pytest.fixture(scope="module")
def wake():
    return from_nwb(NWB_PATH, epoch="wake")


@pytest.fixture(scope="module")
def nwb_file():
    with pynwb.NWBHDF5IO(str(NWB_PATH), "r") as io:
        nwb = io.read()
        pos = nwb.acquisition["Position"]
        yield {
            "t": pos["x"].timestamps[:], "x": pos["x"].data[:], "z": pos["z"].data[:],
            "ry": nwb.acquisition["CompassDirection"]["ry"].data[:],
            "spikes": [nwb.units["spike_times"][i] for i in range(len(nwb.units))],
        }


def test_wake_units_and_regions(wake):
    assert wake.sizes["unit"] == 15
    assert wake.region.values.tolist() == ["adn"] * 7 + ["ca1"] * 8
    assert wake.attrs["source"] == "animal" and wake.attrs["activity_kind"] == "spike_count"
    assert wake.attrs["session_id"] == "A2929-200711"


def test_wake_spike_counts_add_up(wake, nwb_file):
    assert int(wake.activity.sum()) == WAKE_SPIKES_TRACKED
    t = nwb_file["t"]
    per_unit = [((s >= t[0]) & (s <= t[-1])).sum() for s in nwb_file["spikes"]]
    np.testing.assert_array_equal(wake.activity.sum("time").values, per_unit)
    # nearest-sample binning: a spike lands on the sample closest to it
    s = nwb_file["spikes"][0]
    s = s[(s >= t[0]) & (s <= t[-1])]
    nearest = np.abs(t[:, None] - s[None, :200]).argmin(0)
    expected = np.bincount(nearest, minlength=t.size)[:nearest.max() + 1]
    np.testing.assert_array_equal(wake.activity.values[:nearest.max() + 1, 0], expected)


def test_wake_floor_plane_position(wake, nwb_file):
    assert wake.attrs["nwb_floor_axes"] == ["x", "z"]        # chosen by spread: y is vertical
    np.testing.assert_array_equal(wake.position.values, np.c_[nwb_file["x"], nwb_file["z"]])
    np.testing.assert_array_equal(wake.time.values, nwb_file["t"])
    assert wake.trial_start.item() == nwb_file["t"][0] and wake.trial_time[0] == 0


def _heading_agreement(position, head_direction, time, window=0.5, min_speed=0.2):
    """Resultant length and mean of (head direction - direction of movement) while running."""
    step = int(round(window / np.median(np.diff(time))))
    d = position[step:] - position[:-step]
    speed = np.hypot(*d.T) / (time[step:] - time[:-step])
    moving = np.arctan2(d[:, 1], d[:, 0])
    hd = head_direction[step // 2: step // 2 + moving.size]
    ok = (speed > min_speed) & np.isfinite(hd) & np.isfinite(moving)
    z = np.exp(1j * (hd[ok] - moving[ok])).mean()
    return np.abs(z), np.degrees(np.angle(z)), ok.sum()


def test_head_direction_follows_movement_when_running(wake, nwb_file):
    assert wake.attrs["nwb_head_direction_sign"] == -1        # (x, z) floor: wrap(-ry)
    hd = wake.head_direction.values
    assert (hd >= -np.pi).all() and (hd < np.pi).all()
    r, offset, n = _heading_agreement(wake.position.values, hd, wake.time.values)
    assert n > 500 and r > 0.7 and abs(offset) < 15
    # the other sign convention follows movement clearly worse
    flipped = np.mod(np.asarray(nwb_file["ry"]) + np.pi, 2 * np.pi) - np.pi
    r_flipped, _, _ = _heading_agreement(wake.position.values, flipped, wake.time.values)
    assert r_flipped < r - 0.1


def test_options_floor_axes_and_sign():
    rec = from_nwb(NWB_PATH, epoch="wake", floor_axes=("z", "x"), head_direction_sign=1)
    assert rec.attrs["nwb_floor_axes"] == ["z", "x"]
    assert rec.attrs["nwb_head_direction_sign"] == 1
    with pytest.raises(ValueError, match="`floor_axes` must be one of"):
        from_nwb(NWB_PATH, floor_axes=("x", "w"))


def test_wake_validates_and_round_trips_through_zarr(wake, tmp_path):
    validate(wake, check_data=True)
    save_recording(wake, tmp_path / "wake.zarr")
    back = open_recording(tmp_path / "wake.zarr")
    xr.testing.assert_identical(back.load(), wake)


@pytest.mark.parametrize("epoch", ["wake", None], ids=["default epoch", "every epoch"])
def test_wake_round_trips_through_nwb(wake, tmp_path, epoch):
    to_nwb(wake, tmp_path / "wake.nwb")
    back = from_nwb(tmp_path / "wake.nwb", epoch=epoch)
    xr.testing.assert_identical(back, wake)


@pytest.mark.parametrize("read", [lambda p: from_nwb(p), lambda p: from_nwb(p, epoch=None)],
                         ids=["defaults", "every epoch"])
def test_network_recording_round_trips_through_nwb(network_recording, tmp_path, read):
    to_nwb(network_recording, tmp_path / "net.nwb")
    back = read(tmp_path / "net.nwb")
    for name in ("position", "head_direction", "activity", "trial", "trial_start",
                 "trial_stop", "trial_environment", "environment"):
        assert back[name].dtype == network_recording[name].dtype
        np.testing.assert_array_equal(back[name].values, network_recording[name].values)
    xr.testing.assert_identical(back, network_recording)
    with pytest.raises(FileExistsError, match="pass overwrite=True"):
        to_nwb(network_recording, tmp_path / "net.nwb")


def _write_nwb(path, *, position=True, trials=None, spikes=(), unit="cm", hd_unit="degrees"):
    nwb = pynwb.NWBFile(session_description="synthetic", identifier="synthetic",
                        session_start_time=datetime.datetime(2020, 1, 1,
                                                             tzinfo=datetime.timezone.utc))
    t = np.arange(1000) * 0.01
    if position:
        behavior = nwb.create_processing_module("behavior", "behaviour")
        xy = np.c_[np.cos(t), np.sin(t)] * 40
        behavior.add(Position(spatial_series=SpatialSeries(
            name="pos", data=xy, timestamps=t, unit=unit, reference_frame="", conversion=0.5)))
        behavior.add(CompassDirection(spatial_series=SpatialSeries(
            name="hd", data=np.degrees(t + np.pi / 2) % 360, timestamps=t, unit=hd_unit,
            reference_frame="")))
    for times in spikes:
        nwb.add_unit(spike_times=times)
    if trials is not None:
        nwb.add_trial_column("arena", "arena id")
        for (a, b), env, *trial_id in trials:          # an id of its own, if given
            nwb.add_trial(start_time=a, stop_time=b, arena=env,
                          **({"id": trial_id[0]} if trial_id else {}))
    with pynwb.NWBHDF5IO(str(path), "w") as io:
        io.write(nwb)
    return t


def test_processing_behavior_conversion_units_and_touching_trials(tmp_path):
    spikes = [np.array([0.0, 0.004, 1.0, 4.99, 5.0, 5.004, 9.99])]
    t = _write_nwb(tmp_path / "s.nwb", trials=[((0.0, 5.0), 2), ((5.0, 9.99), 7)],
                   spikes=spikes)
    with pytest.warns(UserWarning, match=r"1 of the 7 spikes inside the trials .* fall where "
                                         r"the tracking has no sample"):
        rec = from_nwb(tmp_path / "s.nwb", epoch=None, environment="arena")
    # conversion 0.5 and cm: 40 units * 0.5 = 20 cm = 0.2 m
    np.testing.assert_allclose(np.hypot(*rec.position.values.T), 0.2)
    kept = np.isin(t, rec.time.values)
    assert kept.sum() == t.size - 1
    np.testing.assert_allclose(rec.head_direction.values,
                               np.mod(t[kept] + np.pi / 2 + np.pi, 2 * np.pi) - np.pi, atol=1e-9)
    assert rec.trial_environment.values.tolist() == [2, 7]
    # the trials touch at 5.0 s: the second trial's first samples are left out for the gap
    first_of_second = rec.time.values[rec.trial.values == rec.trial_id.values[1]][0]
    last_of_first = rec.time.values[rec.trial.values == rec.trial_id.values[0]][-1]
    assert first_of_second - last_of_first >= 2 * rec.attrs["dt"] * 0.9
    # every spike inside a trial, but that of the sample left out (no position kept
    # there): 5.004 s, between the first trial's last sample (5.0) and the second's
    # first kept one (5.02)
    assert int(rec.activity.sum()) == spikes[0].size - 1


def test_an_environment_column_follows_trial_ids_in_any_order(tmp_path):
    """Trial ids need not be sorted in the table: trial 5 (first) in arena 1, trial 3 in
    arena 2."""
    _write_nwb(tmp_path / "s.nwb", trials=[((0.0, 4.0), 1, 5), ((5.0, 9.99), 2, 3)],
               spikes=[np.array([1.0])])
    rec = from_nwb(tmp_path / "s.nwb", epoch=None, environment="arena")
    assert rec.trial_id.values.tolist() == [5, 3]
    assert rec.trial_environment.values.tolist() == [1, 2]


def _write_series(path, position=(), bare=(), spikes=None):
    """A file whose Position holds the series ``position`` and whose behaviour module
    holds the bare series ``bare``: each (name, data, unit), sampled at 100 Hz; one unit
    for each array of ``spikes``."""
    nwb = pynwb.NWBFile(session_description="synthetic", identifier="synthetic",
                        session_start_time=datetime.datetime(2020, 1, 1,
                                                             tzinfo=datetime.UTC))
    behavior = nwb.create_processing_module("behavior", "behaviour")

    def series(name, data, unit):
        return SpatialSeries(name=name, data=data, unit=unit, reference_frame="", rate=100.0)

    if position:
        behavior.add(Position(spatial_series=[series(*spec) for spec in position]))
    for spec in bare:
        behavior.add(series(*spec))
    for times in [np.array([1.0])] if spikes is None else spikes:
        nwb.add_unit(spike_times=times)
    with pynwb.NWBHDF5IO(str(path), "w") as io:
        io.write(nwb)


_T = np.arange(1000) * 0.01
_XY = np.c_[0.5 + 0.4 * np.cos(_T), 0.5 + 0.2 * np.sin(_T)]       # a 1 m-wide loop
_HD = np.mod(_T * 3, 2 * np.pi) - np.pi                             # spread ~1.8 rad


def test_two_2d_series_are_not_paired_across_and_the_choice_is_asked_for(tmp_path):
    """Two LEDs: the widest two columns are the two LEDs' x; pairing them would map x
    against x. Refused, naming floor_axes; named, the LED's own columns are used."""
    _write_series(tmp_path / "s.nwb", position=[("led_front", 2 * _XY, "meters"),
                                                ("led_back", 2 * _XY + 0.01, "meters")])
    with pytest.raises(RecordingError, match=r"holds several 2-D series \['led_back', "
                                             r"'led_front'\].*floor_axes="):
        from_nwb(tmp_path / "s.nwb", epoch=None)
    rec = from_nwb(tmp_path / "s.nwb", epoch=None, floor_axes=("led_front[0]", "led_front[1]"))
    samples = np.round(rec.time.values / 0.01).astype(int)
    np.testing.assert_allclose(rec.position.values, 2 * _XY[samples])


def test_a_head_direction_beside_the_position_is_not_a_floor_axis(tmp_path):
    """Its spread (radians) is larger than the arena's (m): chosen by spread, it became
    the x axis. A 2-D series gives the floor, whatever the unit of the angle."""
    _write_series(tmp_path / "s.nwb", position=[("head_direction", _HD, "meters"),
                                                ("position", _XY, "meters")])
    rec = from_nwb(tmp_path / "s.nwb", epoch=None)
    assert rec.attrs["nwb_floor_axes"] == ["position[0]", "position[1]"]


def test_a_bare_angle_series_is_not_the_position_and_is_said_not_to_be_imported(tmp_path):
    _write_series(tmp_path / "s.nwb", bare=[("head_direction", _HD, "radians"),
                                            ("position", _XY, "meters")])
    with pytest.warns(UserWarning, match=r"no CompassDirection, so no head direction is "
                                         r"imported; the series \['processing/behavior/"
                                         r"head_direction'\], in an angle unit, was not"):
        rec = from_nwb(tmp_path / "s.nwb", epoch=None)
    assert rec.attrs["nwb_position"] == "processing/behavior/position"
    assert "head_direction" not in rec


def test_centimetres_under_the_default_metres_are_said_to_be_too_large(tmp_path):
    """pynwb's SpatialSeries unit defaults to "meters": a lab's centimetres then read as
    an 80 m arena."""
    _write_series(tmp_path / "s.nwb", position=[("position", 100 * _XY, "meters")])
    with pytest.warns(UserWarning, match=r"spans 80 m x 40 m, larger than any rodent arena "
                                         r"\(its unit in .*s\.nwb: 'meters', read as m\): if "
                                         r"it is in centimetres, pass position_units='cm'"):
        from_nwb(tmp_path / "s.nwb", epoch=None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        rec = from_nwb(tmp_path / "s.nwb", epoch=None, position_units="cm")
    np.testing.assert_allclose(rec.position.max("time").values, _XY.max(axis=0))


def test_spike_times_in_milliseconds_are_said_to_come_after_the_session(tmp_path):
    """Of 10 s of spikes in ms, only those of the first 10 ms fall inside the session:
    a map from them looks like a sparse cell."""
    _write_series(tmp_path / "s.nwb", position=[("position", _XY, "meters")],
                  spikes=[np.arange(0.001, 9.99, 0.05) * 1000])
    with pytest.warns(UserWarning, match=r"199 of the 200 spike times .* \(100%\) come after "
                                         r"the end of everything else the file times "
                                         r"\(9\.99 s.*are the spike times in seconds"):
        from_nwb(tmp_path / "s.nwb", epoch=None)


def test_a_unit_observed_for_part_of_the_time_is_refused_unless_left_out(tmp_path):
    """Unit 1 was sorted only for the first half: its zero counts after would read as
    silence (half its rate). Refused, naming the units to import instead."""
    nwb = pynwb.NWBFile(session_description="synthetic", identifier="synthetic",
                        session_start_time=datetime.datetime(2020, 1, 1,
                                                             tzinfo=datetime.UTC))
    nwb.create_processing_module("behavior", "behaviour").add(Position(spatial_series=[
        SpatialSeries(name="pos", data=_XY, unit="meters", reference_frame="", rate=100.0)]))
    nwb.add_unit(spike_times=np.arange(0.05, 9.9, 0.1), obs_intervals=[[0.0, 10.0]])
    nwb.add_unit(spike_times=np.arange(0.05, 5.0, 0.1), obs_intervals=[[0.0, 5.0]])
    with pynwb.NWBHDF5IO(str(tmp_path / "s.nwb"), "w") as io:
        io.write(nwb)
    with pytest.raises(RecordingError, match=r"units \[1\] .* were observed for only part of "
                                             r"the imported time .*unit 1: 50%.*units=\[0\]"):
        from_nwb(tmp_path / "s.nwb", epoch=None)
    rec = from_nwb(tmp_path / "s.nwb", epoch=None, units=[0])
    assert rec.unit.values.tolist() == [0] and int(rec.activity.sum()) == 99
    with pytest.raises(ValueError, match=r"`units` must be ids of the Units table \(\[0, 1\]\)"
                                         r"; got \[7\]"):
        from_nwb(tmp_path / "s.nwb", epoch=None, units=[0, 7])


@pytest.mark.parametrize("hd_unit, said", [("gradians", "not an angle this reader knows"),
                                            ("", "no unit")])
def test_an_unknown_head_direction_unit_is_taken_as_radians_aloud(tmp_path, hd_unit, said):
    """The file's angles are degrees: taken as radians (said), they wrap at 360, which
    radians never do, so they are refused; named as degrees, they are read right."""
    t = _write_nwb(tmp_path / "s.nwb", spikes=[np.array([0.5])], hd_unit=hd_unit)
    with pytest.warns(UserWarning, match=f"head direction in .* has .*{said}.*taken as "
                                         f"radians"), \
            pytest.raises(RecordingError, match=r"read as radians .* but jumps by 359 "
                                                r"between samples .*: it is in degrees; pass "
                                                r"head_direction_units='deg'"):
        from_nwb(tmp_path / "s.nwb", epoch=None)
    rec = from_nwb(tmp_path / "s.nwb", epoch=None, head_direction_units="deg")
    np.testing.assert_allclose(rec.head_direction.values,
                               np.mod(t + np.pi / 2 + np.pi, 2 * np.pi) - np.pi, atol=1e-9)


def test_degrees_labelled_radians_are_refused(tmp_path):
    """R of a head-direction cell fell from 0.81 to 0.03 when its degrees were read as
    the radians the file claimed."""
    _write_nwb(tmp_path / "s.nwb", spikes=[np.array([0.5])], hd_unit="radians")
    with pytest.raises(RecordingError, match=r"\(its unit: 'radians'\) but jumps by 359"):
        from_nwb(tmp_path / "s.nwb", epoch=None)


def test_bad_inputs_write_nothing(tmp_path, capsys):
    dest = tmp_path / "out.zarr"
    readme = NWB_PATH.with_suffix(".README.md")
    _write_nwb(tmp_path / "nopos.nwb", position=False, spikes=[np.array([0.5])])
    cases = [
        ([str(readme), str(dest)], "not a readable NWB file"),
        ([str(tmp_path / "nopos.nwb"), str(dest)], "has no epochs table; pass epoch=None"),
        ([str(tmp_path / "nopos.nwb"), str(dest), "--epoch", "all"], "has no Position"),
        ([str(NWB_PATH), str(dest), "--epoch", "run"], "`epoch` must be one of the epochs "
                                                       "of the file ['sleep', 'wake']"),
    ]
    for argv, message in cases:
        assert cli(["import-nwb", *argv]) == 2
        assert message in capsys.readouterr().err
        assert sorted(p.name for p in tmp_path.iterdir()) == ["nopos.nwb"]
    with pytest.raises(RecordingError, match="not a readable NWB file"):
        from_nwb(readme)


def test_cli_import(tmp_path, capsys):
    dest = tmp_path / "rec.zarr"
    assert cli(["import-nwb", str(NWB_PATH), str(dest)]) == 0
    assert "44618 spike_count" in capsys.readouterr().out
    assert open_recording(dest).sizes["unit"] == 15
    assert cli(["import-nwb", str(NWB_PATH), str(dest)]) == 2
    assert "already exists" in capsys.readouterr().err


def test_cli_import_takes_the_position_units(tmp_path, capsys):
    """The shipped file's positions have no unit: metres with a warning that names the
    option, or the unit given, without one."""
    with pytest.warns(UserWarning, match="--position-units"):
        assert cli(["import-nwb", str(NWB_PATH), str(tmp_path / "m.zarr")]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        assert cli(["import-nwb", str(NWB_PATH), str(tmp_path / "cm.zarr"),
                    "--position-units", "cm"]) == 0
    metres = open_recording(tmp_path / "m.zarr").position.values
    np.testing.assert_allclose(open_recording(tmp_path / "cm.zarr").position.values,
                               metres * 0.01, rtol=1e-6)
    assert cli(["import-nwb", str(NWB_PATH), str(tmp_path / "x.zarr"),
                "--position-units", "inch"]) == 2
    assert "position_units" in capsys.readouterr().err


def _damaged_copy(tmp_path, damage):
    """A copy of the session with ``damage(h5py.File)`` applied to it."""
    import shutil

    import h5py

    path = tmp_path / "damaged.nwb"
    shutil.copy(NWB_PATH, path)
    with h5py.File(path, "r+") as f:
        damage(f)
    return path


def test_an_erased_position_axis_is_refused_not_replaced(tmp_path):
    """An axis read as all NaN (erased storage) must not let the vertical axis take its
    place among the floor axes (which also turns the head direction's axis)."""
    def erase_x(f):
        f["acquisition/Position/x/data"][:] = np.nan
    path = _damaged_copy(tmp_path, erase_x)
    with pytest.raises(RecordingError, match="position axis 'x' .* no finite value"):
        from_nwb(path, epoch="wake")
    rec = from_nwb(path, epoch="wake", floor_axes=("y", "z"), position_units="m")
    assert rec.attrs["nwb_floor_axes"] == ["y", "z"]


def test_spikes_left_outside_the_units_index_are_refused(tmp_path):
    def cut_last_unit(f):
        f["units/spike_times_index"][-1] -= 100
    with pytest.raises(RecordingError, match="100 spikes belong to no unit"):
        from_nwb(_damaged_copy(tmp_path, cut_last_unit), epoch="wake", position_units="m")


def test_a_damaged_hdf5_file_is_a_recording_error_naming_it(tmp_path):
    path = tmp_path / "tail.nwb"
    data = bytearray(NWB_PATH.read_bytes())
    data[-(1 << 20):] = bytes(1 << 20)                 # the last MiB zeroed
    path.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match="tail.nwb"):
        from_nwb(path, epoch="wake")


def test_unit_labels_survive_nwb_and_the_store_or_are_refused(tmp_path):
    """A bool unit coord came back from NWB as uint8 (0/1 then select by position); a
    missing text label came back as '' or 'nan', a label of its own."""
    rng = np.random.default_rng(0)
    t, xy = np.arange(200) * 0.02, rng.uniform(-0.3, 0.3, (200, 2))
    good = from_arrays(t, xy, activity=rng.poisson(1, (200, 3)),
                       unit={"unit": ["a", "b", "c"], "good": [True, False, True]})
    to_nwb(good, tmp_path / "good.nwb")
    back = from_nwb(tmp_path / "good.nwb")
    assert back.good.dtype == bool
    assert back.isel(unit=back.good.values).unit.values.tolist() == ["a", "c"]
    gap = from_arrays(t, xy, activity=rng.poisson(1, (200, 3)),
                      unit={"unit": [0, 1, 2], "region": np.array(["ca1", None, "adn"],
                                                                  dtype=object)})
    for write, what in ((lambda p: to_nwb(gap, p), "an NWB file"),
                        (lambda p: save_recording(gap, p), "a store")):
        with pytest.raises(RecordingError, match=rf"`region` holds 1 values that are not "
                                                 rf"strings \(first nan at 1\).*{what} keeps "
                                                 rf"text labels as strings only"):
            write(tmp_path / "gap")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["good.nwb"]


def test_numpy_values_inside_attrs_are_written_as_plain_values(tmp_path, wake):
    rec = wake.assign_attrs(meta={"gain": np.float32(1.5), "ids": [np.int64(1)]})
    save_recording(rec, tmp_path / "r.zarr")
    to_nwb(rec, tmp_path / "r.nwb")
    for back in (open_recording(tmp_path / "r.zarr"), from_nwb(tmp_path / "r.nwb")):
        assert back.attrs["meta"] == {"gain": 1.5, "ids": [1]}
    assert isinstance(rec.attrs["meta"]["gain"], np.float32)        # the caller's, as given
