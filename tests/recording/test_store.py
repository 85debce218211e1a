"""save_recording / open_recording: exact, lazy, trial-aligned, atomic, checked."""

import json
import os

import numpy as np
import pytest
import xarray as xr

from hippo_probe.errors import RecordingError
from hippo_probe.recording import open_recording, save_recording, select_trials, validate
from hippo_probe.recording.config import COMPLETE_MARKER, RecordingConfig

from .conftest import assert_trial_aligned, make_network_recording


def _assert_same(opened, original):
    xr.testing.assert_identical(opened.load(), original)
    for name, var in original.variables.items():
        got = opened.variables[name]
        assert got.dims == var.dims, name
        if var.dtype.kind not in "OUT":      # a string coord's numpy dtype may differ
            assert got.dtype == var.dtype, name
    assert list(opened.attrs) == list(original.attrs)


@pytest.mark.parametrize("which", ["network_recording", "animal_recording"])
def test_round_trip_is_exact(which, request, tmp_path):
    rec = request.getfixturevalue(which)
    save_recording(rec, tmp_path / "r.zarr")
    _assert_same(open_recording(tmp_path / "r.zarr"), rec)


def test_open_is_lazy_with_coords_loaded(network_recording, tmp_path):
    save_recording(network_recording, tmp_path / "r.zarr")
    rec = open_recording(tmp_path / "r.zarr")
    assert all(v.chunks is not None for v in rec.data_vars.values())
    assert all(c.chunks is None for c in rec.coords.values())
    by_trial = rec.activity.groupby("trial").mean()
    by_env = rec.position.groupby("environment").mean()
    assert by_trial.chunks is not None                         # still lazy
    np.testing.assert_allclose(
        by_trial.compute(), network_recording.activity.groupby("trial").mean(), rtol=1e-6)
    np.testing.assert_allclose(
        by_env.compute(), network_recording.position.groupby("environment").mean())


def test_chunks_align_with_trials_equal_and_unequal(tmp_path):
    config = RecordingConfig(chunk_bytes=12 * 4 * 100)     # 100 samples of 12 units
    rec = make_network_recording(n_steps=40, n_trials=6)
    save_recording(rec, tmp_path / "eq.zarr", config=config)
    meta = json.loads((tmp_path / "eq.zarr" / "activity" / "zarr.json").read_text())
    assert meta["chunk_grid"]["configuration"]["chunk_shape"] == [80, 12]   # 2 whole trials
    assert {c["name"] for c in meta["codecs"][1:]} == {"blosc", "crc32c"}
    # unequal trials (a selection), stored chunks regular: dask chunks are trial-aligned
    uneven = select_trials(rec, trials=[5, 8, 11]).isel(time=slice(0, 110))
    uneven = uneven.isel(trial_id=slice(0, 3))
    uneven = uneven.assign_coords(trial_stop=("trial_id", np.minimum(
        uneven.trial_stop.values, uneven.time.values[-1]), uneven.trial_stop.attrs))
    save_recording(validate(uneven), tmp_path / "uneq.zarr", config=config)
    opened = open_recording(tmp_path / "uneq.zarr", config=config)
    assert opened.activity.chunks[0] == (80, 30)
    assert_trial_aligned(opened.trial.values, opened.activity.chunks[0])
    _assert_same(opened, uneven)


def test_compressed_and_strings_variable_length(animal_recording, tmp_path):
    rec = animal_recording.copy()
    rec["activity"] = rec.activity * 0 + 1          # compressible
    save_recording(rec, tmp_path / "r.zarr")
    stored = sum(f.stat().st_size for f in (tmp_path / "r.zarr" / "activity").rglob("*")
                 if f.is_file() and f.name != "zarr.json")
    assert stored < rec.activity.nbytes / 10
    for name in ("region", "unit", "space"):
        meta = json.loads((tmp_path / "r.zarr" / name / "zarr.json").read_text())
        assert meta["data_type"] == "string", name


def test_existing_destination_needs_overwrite(network_recording, animal_recording, tmp_path):
    path = tmp_path / "r.zarr"
    save_recording(network_recording, path)
    before = sorted(p.name for p in path.rglob("*"))
    with pytest.raises(FileExistsError, match="pass overwrite=True"):
        save_recording(animal_recording, path)
    assert sorted(p.name for p in path.rglob("*")) == before
    save_recording(animal_recording, path, overwrite=True)
    _assert_same(open_recording(path), animal_recording)
    assert os.listdir(tmp_path) == ["r.zarr"]          # no temp or old copies left


def test_overwrite_refuses_a_directory_that_is_not_a_store(network_recording, tmp_path):
    (tmp_path / "notes").mkdir()
    (tmp_path / "notes" / "keep.txt").write_text("precious")
    with pytest.raises(FileExistsError, match="not a zarr store"):
        save_recording(network_recording, tmp_path / "notes", overwrite=True)
    assert (tmp_path / "notes" / "keep.txt").read_text() == "precious"


def test_invalid_recording_writes_nothing(network_recording, tmp_path):
    bad = network_recording.copy()
    del bad.attrs["source"]
    with pytest.raises(RecordingError, match="`source`"):
        save_recording(bad, tmp_path / "r.zarr")
    assert os.listdir(tmp_path) == []


@pytest.fixture
def saved(network_recording, tmp_path):
    path = tmp_path / "r.zarr"
    save_recording(network_recording, path)
    return path


def _first_chunk(store, name):
    return next(p for p in (store / name / "c").rglob("*") if p.is_file())


def test_half_written_store_is_refused(saved):
    meta = json.loads((saved / "zarr.json").read_text())
    del meta["attributes"][COMPLETE_MARKER]
    (saved / "zarr.json").write_text(json.dumps(meta))
    with pytest.raises(RecordingError, match="half-written"):
        open_recording(saved)


def test_missing_chunk_is_refused(saved):
    _first_chunk(saved, "position").unlink()
    with pytest.raises(RecordingError, match="array `position` has"):
        open_recording(saved)


def test_garbled_metadata_is_refused(saved):
    (saved / "zarr.json").write_text('{"zarr_format": 3, "node_')
    with pytest.raises(RecordingError, match="not a readable zarr store"):
        open_recording(saved)
    (saved / "zarr.json").unlink()
    with pytest.raises(RecordingError, match="not a readable zarr store"):
        open_recording(saved)


def _edit_array_metadata(store, name, edit):
    path = store / name / "zarr.json"
    meta = json.loads(path.read_text())
    edit(meta)
    path.write_text(json.dumps(meta))


def test_a_shape_claimed_beyond_the_chunks_written_is_refused_before_reading(saved):
    """A header that claims more samples than were written must not make the reader
    allocate them (a billion samples of time would be 8 GB)."""
    def grow(meta):
        meta["shape"][0] = 10 ** 9
    _edit_array_metadata(saved, "time", grow)
    with pytest.raises(RecordingError, match=r"array `time`.*claims shape \(1000000000,\)"):
        open_recording(saved)


def test_a_store_whose_marker_has_no_layouts_opens_and_is_still_bounded(saved):
    """Stores saved before the marker held layouts open as before; a shape claiming more
    chunks than were written is refused for them too."""
    meta = json.loads((saved / "zarr.json").read_text())
    del meta["attributes"][COMPLETE_MARKER]["layouts"]
    (saved / "zarr.json").write_text(json.dumps(meta))
    assert open_recording(saved).sizes["time"] > 0

    def grow(meta):
        meta["shape"][0] *= 1000
    _edit_array_metadata(saved, "time", grow)
    with pytest.raises(RecordingError, match="array `time`.*claims shape"):
        open_recording(saved)


def test_a_shape_cut_within_the_chunks_is_refused(saved):
    """Samples cut from the end of every per-sample array (the chunk count unchanged) would
    open as a shorter, valid-looking recording."""
    def cut(meta):
        meta["shape"][0] -= 5
    for name in ("time", "trial", "trial_time", "environment", "position", "activity"):
        if (saved / name).is_dir():
            _edit_array_metadata(saved, name, cut)
    with pytest.raises(RecordingError, match=r"differs from what was written: shape \[\d+"
                                             r".*written, now \["):
        open_recording(saved)


def test_a_byte_order_edit_is_refused(saved):
    """The chunks' checksums cover their bytes, not how to read them: big-endian floats
    read from little-endian bytes are plausible tiny numbers."""
    def big_endian(meta):
        meta["codecs"][0]["configuration"]["endian"] = "big"
    _edit_array_metadata(saved, "activity", big_endian)
    with pytest.raises(RecordingError, match="array `activity`.*byte_order 'little' "
                                             "written, now 'big'"):
        open_recording(saved)


def test_an_attribute_edit_still_opens(saved):
    """Attributes are not the layout: a unit label set on an array is the same store."""
    _edit_array_metadata(saved, "activity",
                         lambda m: m.setdefault("attributes", {}).update(note="checked"))
    assert open_recording(saved).activity.attrs["note"] == "checked"


def test_corrupted_chunk_fails_its_checksum(saved):
    chunk = _first_chunk(saved, "activity")
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    rec = open_recording(saved)                    # lazy: metadata and coords are fine
    with pytest.raises(Exception, match="(?i)checksum|crc"):
        rec.activity.values


def test_missing_path(tmp_path):
    with pytest.raises(FileNotFoundError, match="does not exist"):
        open_recording(tmp_path / "nothing.zarr")


def test_select_trials_lazy(network_recording, tmp_path):
    save_recording(network_recording, tmp_path / "r.zarr")
    rec = open_recording(tmp_path / "r.zarr")
    sub = select_trials(rec, environments=[0, 2], trials=[5, 8, 11, 14])
    assert sub.activity.chunks is not None
    assert sub.trial_id.values.tolist() == [5, 11, 14]
    assert sub.environment_id.values.tolist() == [0, 1, 2]      # class table kept whole
    validate(sub.load(), check_data=True)
    expected = network_recording.where(network_recording.trial.isin([5, 11, 14]), drop=True)
    np.testing.assert_array_equal(sub.activity.values, expected.activity.values)
    with pytest.raises(RecordingError, match="`trials` must be ids"):
        select_trials(rec, trials=[4])
    with pytest.raises(RecordingError, match="no trial matches"):
        select_trials(rec, trials=[5], environments=[1])


def test_saving_dask_chunked_along_units(network_recording, tmp_path):
    lazy = network_recording.chunk({"time": 37, "unit": 5})
    save_recording(lazy, tmp_path / "r.zarr")
    xr.testing.assert_identical(open_recording(tmp_path / "r.zarr").load(), network_recording)


@pytest.mark.parametrize("name", ["time", "trial"])
def test_a_corrupted_coordinate_chunk_is_named(saved, name):
    """Coords are read on opening: a bad chunk there fails open_recording, naming it."""
    chunk = _first_chunk(saved, name)
    data = bytearray(chunk.read_bytes())
    data[len(data) // 2] ^= 0xFF
    chunk.write_bytes(bytes(data))
    with pytest.raises(RecordingError, match=f"`{name}` of .* (cannot|could not) be read"):
        open_recording(saved)
