"""open_recording's chunk-file reader: the values zarr reads, refusals of damaged chunks,
zarr for every other layout, and reads around the page cache on request."""

import errno
import os

import google_crc32c
import numpy as np
import pytest
import xarray as xr
import zarr
from zarr.codecs import BloscCodec, BytesCodec, Crc32cCodec, ShardingCodec, ZstdCodec

from hippo_probe.errors import RecordingError
from hippo_probe.recording import chunk_files, open_recording, save_recording, store
from hippo_probe.recording.chunk_files import ChunkFiles
from hippo_probe.recording.config import RecordingConfig

from .conftest import make_animal_recording, make_network_recording, spy_chunk_files

SMALL = RecordingConfig(chunk_bytes=4000)       # several chunks, the last one partial


def _bytes(values):
    return np.ascontiguousarray(values).view(np.uint8)


@pytest.fixture
def chunk_reads(monkeypatch):
    """Names of the variables read through ChunkFiles, and the flags of each file opened."""
    return spy_chunk_files(monkeypatch, "chunk")


def _network_store(tmp_path):
    rec = make_network_recording(n_trials=7)
    rec.activity.values[3, :2] = [-0.0, 0.0]             # stored bits, not just values
    rec.position.values[5] = np.nan                      # a tracking gap
    path = tmp_path / "r.zarr"
    save_recording(rec, path, config=SMALL)
    return path


@pytest.mark.parametrize("direct_io", [False, True])
@pytest.mark.parametrize("chunks", ["trials", {}, {"time": 37}, {"time": 53, "unit": 5}])
def test_every_data_variable_reads_the_bits_zarr_reads(direct_io, chunks, tmp_path,
                                                       chunk_reads):
    path = _network_store(tmp_path)
    opened = open_recording(path, chunks=chunks, direct_io=direct_io, config=SMALL)
    via_zarr = xr.open_zarr(path, chunks=None, consolidated=False, decode_times=False)
    assert len(opened.activity.chunks[0]) > 3 and opened.activity.shape[0] % 80 != 0
    for name, var in opened.data_vars.items():
        got = var.values
        assert got.dtype == via_zarr[name].dtype, name
        np.testing.assert_array_equal(_bytes(got), _bytes(via_zarr[name].values), name)
    assert chunk_reads["names"] == set(opened.data_vars)
    direct = [flags for flags in chunk_reads["flags"] if flags & os.O_DIRECT]
    assert bool(direct) == direct_io


def test_an_animal_recording_with_unequal_chunks_reads_as_saved(tmp_path, chunk_reads):
    rec = make_animal_recording()
    save_recording(rec, tmp_path / "a.zarr", config=SMALL)
    xr.testing.assert_identical(open_recording(tmp_path / "a.zarr", config=SMALL).load(), rec)
    assert chunk_reads["names"] == set(rec.data_vars)


def test_slices_within_and_across_chunks_and_with_steps(tmp_path):
    data = np.arange(103 * 3, dtype="<i2").reshape(103, 3)
    array = zarr.create_array(tmp_path / "a.zarr", shape=data.shape, chunks=(10, 3),
                              dtype=data.dtype, serializer=BytesCodec(),
                              compressors=[BloscCodec(), Crc32cCodec()])
    array[:] = data
    files = ChunkFiles.of(str(tmp_path / "a.zarr"), "a", array)
    for index in [(slice(0, 10), slice(0, 3)), (slice(95, 103), slice(1, 2)),
                  (slice(5, 67), slice(None)), (slice(None), slice(None)),
                  (slice(3, 90, 7), slice(0, 3, 2)), (slice(40, 40), slice(None)),
                  (slice(None, None, -1), slice(None)), (slice(20, 3, -3), slice(2, 0, -1)),
                  (slice(3, 20, -1), slice(None))]:
        np.testing.assert_array_equal(files[index], data[index], str(index))
    part = files[2:5, :]
    assert part.base is None or part.base.nbytes == part.nbytes   # not a whole chunk kept
    with pytest.raises(TypeError, match="one slice per dimension"):
        files.__getitem__(3)


def _rewrite(path, change):
    """Rewrite a chunk file with ``change(body)`` and a checksum that matches it."""
    body = bytearray(path.read_bytes()[:-4])
    body = change(body)
    path.write_bytes(bytes(body) + google_crc32c.value(bytes(body)).to_bytes(4, "little"))


def _flip(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))


def _declare_more(body):
    nbytes = int.from_bytes(body[4:8], "little")
    body[4:8] = (nbytes + 4).to_bytes(4, "little")
    return body


def _garble_frame(body):
    body[-64:] = bytes(64)           # the header still declares a whole chunk
    return body


DAMAGE = {
    "a flipped byte": (_flip, "CRC32C checksums do not match"),
    "a frame that does not decode": (lambda p: _rewrite(p, _garble_frame), "does not decode"),
    "cut short": (lambda p: p.write_bytes(p.read_bytes()[:10]), "holds 10 bytes"),
    "bytes appended": (lambda p: _rewrite(p, lambda b: b + bytes(2**16)), "holds more than"),
    "a frame of another size": (lambda p: _rewrite(p, _declare_more), "declares"),
    "removed": (lambda p: p.unlink(), "No such file"),
}


@pytest.mark.parametrize("direct_io", [False, True])
@pytest.mark.parametrize("damage", DAMAGE)
def test_a_damaged_chunk_is_refused_naming_its_variable(damage, direct_io, tmp_path):
    path = _network_store(tmp_path)
    opened = open_recording(path, direct_io=direct_io, config=SMALL)
    harm, message = DAMAGE[damage]
    harm(path / "activity" / "c" / "1" / "0")
    opened.activity[:80].load()                              # chunk 0 still reads
    with pytest.raises(RecordingError, match=rf"`activity` of the store .*{message}"):
        opened.activity.load()


def test_without_o_direct_the_file_is_read_through_the_page_cache(tmp_path, monkeypatch):
    path = _network_store(tmp_path)
    expected = open_recording(path, direct_io=False, config=SMALL).activity.values
    os_open = os.open

    def refuse_direct(path, flags, *args, **kwargs):
        if flags & os.O_DIRECT:           # what tmpfs answers
            raise OSError(errno.EINVAL, "Invalid argument")
        return os_open(path, flags, *args, **kwargs)

    monkeypatch.setattr(chunk_files.os, "open", refuse_direct)
    got = open_recording(path, direct_io=True, config=SMALL).activity.values
    np.testing.assert_array_equal(_bytes(got), _bytes(expected))


@pytest.mark.parametrize("available, direct", [(0.0, True), (float("inf"), False),
                                               ("between", False)])
def test_auto_reads_around_the_cache_only_what_memory_cannot_hold(available, direct, tmp_path,
                                                                   monkeypatch, chunk_reads):
    rec = make_network_recording(n_trials=7, n_units=200)
    rec["activity"] = rec.activity * (rec.activity > 0.99)   # sparse: compresses well
    path = tmp_path / "r.zarr"
    save_recording(rec, path, config=RecordingConfig(chunk_bytes=64_000))
    stored = sum(f.stat().st_size for name in rec.data_vars
                 for f in (path / name / "c").rglob("*") if f.is_file())
    if available == "between":      # the files fit, the decoded arrays would not
        decoded = sum(var.nbytes for var in rec.data_vars.values())
        assert stored < decoded / 2
        available = (stored + decoded) / 2
    monkeypatch.setattr(store, "available_memory", lambda: available)
    open_recording(path).activity.load()
    assert any(flags & os.O_DIRECT for flags in chunk_reads["flags"]) == direct


def test_a_forked_child_reads_into_its_own_buffer(tmp_path):
    """The O_DIRECT buffer is shared memory: a child must not write into its parent's."""
    path = _network_store(tmp_path)
    files = ChunkFiles.of(str(path / "activity"), "activity",
                          zarr.open_array(str(path / "activity"), mode="r"))
    files.direct_io = True
    files.chunk(0)
    parents = chunk_files._aligned_buffer(1)
    before = bytes(parents[:4096])
    pid = os.fork()
    if pid == 0:                                   # the child: read another chunk, leave
        code = 0
        try:
            files.chunk(1)
            code = 3 if chunk_files._aligned_buffer(1) is parents else 0
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert bytes(parents[:4096]) == before


def test_a_store_in_another_layout_is_read_by_zarr(tmp_path, chunk_reads):
    """Saved without checksums, no variable fits the chunk-file reader: zarr reads them."""
    rec = make_network_recording(n_trials=7)
    path = tmp_path / "r.zarr"
    save_recording(rec, path, config=RecordingConfig(chunk_bytes=4000, checksum=False))
    xr.testing.assert_identical(open_recording(path, config=SMALL).load(), rec)
    assert chunk_reads["names"] == set()


@pytest.mark.parametrize("value", ["yes", 1, None])
def test_direct_io_must_be_a_bool_or_auto(value, tmp_path):
    path = _network_store(tmp_path)
    with pytest.raises(ValueError, match=r"`direct_io` must be True, False or 'auto'; got"):
        open_recording(path, direct_io=value)


OTHER_LAYOUTS = {
    "zstd, no checksum": {"compressors": [ZstdCodec()]},
    "no compression": {"compressors": [Crc32cCodec()]},
    "big-endian": {"serializer": BytesCodec(endian="big"),
                   "compressors": [BloscCodec(), Crc32cCodec()]},
    "chunked along the second dimension": {"chunks": (10, 2),
                                           "compressors": [BloscCodec(), Crc32cCodec()]},
    "zarr 2 chunk keys": {"chunk_key_encoding": {"name": "v2"},
                          "compressors": [BloscCodec(), Crc32cCodec()]},
}


@pytest.mark.parametrize("layout", OTHER_LAYOUTS)
def test_other_layouts_are_left_to_zarr(layout, tmp_path):
    options = {"chunks": (10, 4), "serializer": BytesCodec(), **OTHER_LAYOUTS[layout]}
    array = zarr.create_array(tmp_path / "a.zarr", shape=(30, 4), dtype="f4", **options)
    assert ChunkFiles.of(str(tmp_path / "a.zarr"), "a", array) is None
    sharded = zarr.create_array(tmp_path / "s.zarr", shape=(30, 4), dtype="f4",
                                chunks=(10, 4), shards=(30, 4))
    assert isinstance(sharded.metadata.codecs[0], ShardingCodec)
    assert ChunkFiles.of(str(tmp_path / "s.zarr"), "s", sharded) is None


@pytest.mark.parametrize("encoding, dtype, as_stored", [
    ({}, "f4", True),
    ({"_FillValue": np.nan}, "f4", True),
    ({"_FillValue": -9999.0}, "f8", False),               # xarray masks it to NaN
    ({"scale_factor": 0.1}, "f4", False),
    ({"_FillValue": 0}, "i4", False),
])
def test_only_variables_xarray_leaves_as_stored_are_read_directly(encoding, dtype,
                                                                  as_stored):
    var = xr.Variable("time", np.zeros(3, dtype), encoding=encoding)
    assert store._decodes_as_stored(var) == as_stored
