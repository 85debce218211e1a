"""save_recording's chunk-file writer: the files zarr writes, byte for byte; zarr for every
other layout; writes around the page cache on request; nothing left by a failed write."""

import errno
import fcntl
import json
import os

import dask
import numpy as np
import pytest
import xarray as xr

from hippo_probe.recording import chunk_files, open_recording, save_recording, store
from hippo_probe.recording.chunk_files import ChunkFiles
from hippo_probe.recording.config import COMPLETE_MARKER, RecordingConfig

from .conftest import make_animal_recording, make_network_recording, spy_chunk_files

SMALL = RecordingConfig(chunk_bytes=4000)       # several chunks, the last one partial


def _zarr_writes(monkeypatch):
    """Make save_recording write every chunk through zarr (xarray's delayed write)."""
    monkeypatch.setattr(store, "_write_chunks",
                        lambda prepared, path, pending, direct_io: pending.compute())


@pytest.fixture
def chunk_writes(monkeypatch):
    """Names of the variables written through ChunkFiles, and the flags of each file the
    chunk-file module opened (through os.open: O_DIRECT writes)."""
    return spy_chunk_files(monkeypatch, "write_chunk")


def _files(root):
    return sorted(p.relative_to(root) for p in root.rglob("*") if p.is_file())


def _root_metadata(path):
    """The root zarr.json without what differs between two saves of one recording."""
    meta = json.loads((path / "zarr.json").read_text())
    meta["attributes"][COMPLETE_MARKER].pop("store_id")
    return meta


def _assert_same_store(ours, theirs):
    assert _files(ours) == _files(theirs)
    for name in _files(ours):
        if name != type(name)("zarr.json"):
            assert (ours / name).read_bytes() == (theirs / name).read_bytes(), str(name)
    assert _root_metadata(ours) == _root_metadata(theirs)


def _recordings():
    network = make_network_recording(n_trials=7)
    network.activity.values[3, :2] = [-0.0, 0.0]            # stored bits, not just values
    network.position.values[5] = np.nan                      # a tracking gap
    network["count"] = ("time", "unit"), (network.activity.values > 0.5).astype("i2"), {
        "units": "1", "long_name": "active units"}
    return {"network": network, "animal": make_animal_recording()}


@pytest.mark.parametrize("lazy", [False, True])
@pytest.mark.parametrize("direct_io", [False, True])
@pytest.mark.parametrize("kind", ["network", "animal"])
def test_the_chunk_files_are_those_zarr_writes(kind, direct_io, lazy, tmp_path, monkeypatch,
                                               chunk_writes):
    rec = _recordings()[kind]
    rec = rec.chunk({"time": 45}) if lazy else rec       # cut unlike the stored chunks
    save_recording(rec, tmp_path / "ours.zarr", direct_io=direct_io, config=SMALL)
    # lazy variables are written as chunk files; those in memory by zarr with the metadata
    assert chunk_writes["names"] == (set(rec.data_vars) if lazy else set())
    assert any(flags & os.O_DIRECT for flags in chunk_writes["flags"]) == (lazy and direct_io)
    assert len(list((tmp_path / "ours.zarr" / "activity" / "c").iterdir())) > 3
    _zarr_writes(monkeypatch)
    save_recording(rec, tmp_path / "zarr.zarr", config=SMALL)
    _assert_same_store(tmp_path / "ours.zarr", tmp_path / "zarr.zarr")
    xr.testing.assert_identical(open_recording(tmp_path / "ours.zarr").load(), rec.load())


def test_a_store_in_another_layout_is_written_by_zarr(tmp_path, chunk_writes):
    """Without checksums no variable is in the chunk files' layout: zarr writes them."""
    rec = make_network_recording(n_trials=7)
    path = tmp_path / "r.zarr"
    save_recording(rec.chunk(), path, config=RecordingConfig(chunk_bytes=4000,
                                                             checksum=False))
    assert chunk_writes["names"] == set()
    xr.testing.assert_identical(open_recording(path).load(), rec)


def test_one_variable_xarray_would_encode_sends_all_to_zarr(tmp_path, monkeypatch,
                                                            chunk_writes):
    rec = make_network_recording(n_trials=7)
    rec.position.attrs["_FillValue"] = -1.0               # xarray writes NaN as -1.0
    rec.position.values[5] = np.nan
    rec = rec.chunk()
    save_recording(rec, tmp_path / "ours.zarr", config=SMALL)
    assert chunk_writes["names"] == set()
    _zarr_writes(monkeypatch)
    save_recording(rec, tmp_path / "zarr.zarr", config=SMALL)
    _assert_same_store(tmp_path / "ours.zarr", tmp_path / "zarr.zarr")


@pytest.mark.parametrize("available, direct", [(0.0, True), (float("inf"), False)])
def test_auto_writes_around_the_cache_only_what_memory_cannot_hold(available, direct,
                                                                    tmp_path, monkeypatch,
                                                                    chunk_writes):
    monkeypatch.setattr(store, "available_memory", lambda: available)
    save_recording(make_network_recording().chunk(), tmp_path / "r.zarr", config=SMALL)
    assert "activity" in chunk_writes["names"]
    assert any(flags & os.O_DIRECT for flags in chunk_writes["flags"]) == direct


def _refusing_direct(monkeypatch, where):
    """Make O_DIRECT fail with EINVAL (as on tmpfs) at ``where``: "open" or "write"."""
    os_open, pwritev = os.open, os.pwritev
    refused = []

    def opened(path, flags, *args, **kwargs):
        if flags & os.O_DIRECT and where == "open":
            refused.append(path)
            raise OSError(errno.EINVAL, "Invalid argument")
        return os_open(path, flags, *args, **kwargs)

    def written(fd, buffers, offset):
        if fcntl.fcntl(fd, fcntl.F_GETFL) & os.O_DIRECT:
            refused.append(fd)
            raise OSError(errno.EINVAL, "Invalid argument")
        return pwritev(fd, buffers, offset)

    monkeypatch.setattr(chunk_files.os, "open", opened)
    monkeypatch.setattr(chunk_files.os, "pwritev", written)
    return refused


@pytest.mark.parametrize("where", ["open", "write"])
def test_without_o_direct_the_chunks_are_written_through_the_cache(where, tmp_path,
                                                                   monkeypatch):
    rec = make_network_recording(n_trials=7, n_units=200)
    config = RecordingConfig(chunk_bytes=64_000)           # chunk files of several pages
    save_recording(rec.chunk(), tmp_path / "cached.zarr", direct_io=False, config=config)
    refused = _refusing_direct(monkeypatch, where)
    save_recording(rec.chunk(), tmp_path / "direct.zarr", direct_io=True, config=config)
    assert len(refused) > 3
    _assert_same_store(tmp_path / "direct.zarr", tmp_path / "cached.zarr")


@pytest.mark.parametrize("size", [1, 4095, 4096, 8192, 8193, 3 * 4096 + 7])
def test_direct_writes_of_any_size_and_short_writes_write_every_byte(size, tmp_path,
                                                                     monkeypatch):
    pwritev = os.pwritev

    def short(fd, buffers, offset):            # at most 4096 bytes a call
        return pwritev(fd, [memoryview(buffers[0])[:4096]], offset)

    monkeypatch.setattr(chunk_files.os, "pwritev", short)
    data = np.random.default_rng(size).integers(0, 256, size, dtype=np.uint8).tobytes()
    for direct in (True, False):
        path = tmp_path / f"{direct}.bin"
        chunk_files._write_file(path, [data[:size // 3], data[size // 3:]], direct)
        assert path.read_bytes() == data


def test_a_failed_chunk_write_leaves_nothing(tmp_path, monkeypatch):
    written = []
    write_file = chunk_files._write_file

    def full_disk(path, parts, direct):
        if len(written) == 3:
            raise OSError(errno.ENOSPC, "No space left on device")
        written.append(path)
        write_file(path, parts, direct)

    monkeypatch.setattr(chunk_files, "_write_file", full_disk)
    with pytest.raises(OSError, match="No space left"):
        save_recording(make_network_recording().chunk(), tmp_path / "r.zarr", config=SMALL)
    assert written and list(tmp_path.iterdir()) == []


def test_a_lazily_made_nan_fails_the_save_before_its_chunk_is_written(tmp_path,
                                                                     chunk_writes):
    rec = make_network_recording(n_trials=7).chunk({"time": 80})
    rec["activity"] = rec.activity.where(rec.trial_time < 10)   # NaN in a later trial
    with dask.config.set(scheduler="sync"), pytest.raises(Exception, match="activity"):
        save_recording(rec, tmp_path / "r.zarr", config=SMALL)
    assert list(tmp_path.iterdir()) == []


def _writer(tmp_path, shape=(25, 3), chunks=(10, 3)):
    import zarr
    from zarr.codecs import BloscCodec, BytesCodec, Crc32cCodec

    array = zarr.create_array(tmp_path / "a.zarr", shape=shape, chunks=chunks, dtype="f4",
                              serializer=BytesCodec(),
                              compressors=[BloscCodec(), Crc32cCodec()])
    return array, ChunkFiles.of(str(tmp_path / "a.zarr"), "a", array)


def test_assigned_chunks_read_back_and_misfits_are_refused(tmp_path):
    array, files = _writer(tmp_path)
    data = np.arange(75, dtype="f4").reshape(25, 3)
    files[0:10, :] = data[:10]
    files[10:20] = data[10:20]
    files.write_chunk(2, data[20:])
    np.testing.assert_array_equal(array[:], data)
    np.testing.assert_array_equal(files[:, :], data)
    with pytest.raises(ValueError, match=r"chunk 1 of `a` is \(10, 3\) float32; got "
                                         r"\(10, 3\) float64"):
        files.write_chunk(1, data[10:20].astype("f8"))
    with pytest.raises(ValueError, match=r"chunk 2 of `a` is \(5, 3\)"):
        files.write_chunk(2, data[:10])
    with pytest.raises(IndexError, match="chunk 3 of `a`: the array has 3"):
        files.write_chunk(3, data[:5])
    for index in [(slice(5, 15), slice(None)), (slice(0, 5), slice(None)),
                  (slice(20, 25), slice(0, 2))]:
        with pytest.raises((ValueError, TypeError), match="a whole chunk at a time"):
            files[index] = data[index]
    reader = ChunkFiles(files.folder, "a", files.shape, files.chunk_shape, files.dtype)
    with pytest.raises(TypeError, match="made for reading"):
        reader.write_chunk(0, data[:10])
    np.testing.assert_array_equal(array[:], data)          # none of it written


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_save_direct_io_must_be_a_bool_or_auto(value, tmp_path):
    with pytest.raises(ValueError, match=r"`direct_io` must be True, False or 'auto'; got"):
        save_recording(make_network_recording(), tmp_path / "r.zarr", direct_io=value)
    assert list(tmp_path.iterdir()) == []


def test_a_chunk_written_after_its_store_was_removed_makes_nothing(tmp_path):
    """A write still running when a failed save removes its temporary store."""
    import shutil

    _, files = _writer(tmp_path)
    shutil.rmtree(tmp_path / "a.zarr")
    with pytest.raises(FileNotFoundError):
        files.write_chunk(0, np.zeros((10, 3), "f4"))
    assert list(tmp_path.iterdir()) == []
