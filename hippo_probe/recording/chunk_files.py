"""Reading and writing a local store's numeric arrays one chunk file at a time.

zarr-python 3 sends every chunk read and write through one event-loop thread, so dask's
threads queue behind it: on two cores a local store reads at about half the speed at
which the same chunks are decoded directly (zarr-python issue #2710), and a 4 GB store
was written at 280-300 MB/s through zarr against 350-460 MB/s writing the same chunk
files directly through the page cache (560-640 around it). For the layout
:func:`~hippo_probe.recording.save_recording` writes (a regular grid chunked along the
first dimension only, little-endian bytes, Blosc, a CRC32C checksum, zarr's default chunk
keys), :class:`ChunkFiles` reads a chunk's file, checks its checksum with google-crc32c and
decodes it with numcodecs' Blosc (the codec zarr's Blosc wraps), without the event loop;
and writes a chunk as zarr would, byte for byte: padded to the whole chunk with the fill
value, encoded by numcodecs' Blosc with the array's settings, followed by its CRC32C.
Any other array (other codecs, sharding, chunks across another dimension, a URL) is read
and written through zarr as before.

A chunk file is read and written through the page cache, or around it (``O_DIRECT``,
Linux): the kernel then moves the bytes between the disk and this process's buffer
without filling and copying through its cache, which costs as much processor time as the
codec (on a cold read, 7 s of system time for 9 GB of chunks against under 1 s without
the cache; saving 4 GB, 7-10 s against 1-2 s).
"""

from __future__ import annotations

import errno
import mmap
import os
import sys
import threading

import google_crc32c
import numcodecs
import numpy as np
import zarr
from numcodecs.blosc import MAX_OVERHEAD
from zarr.codecs import BloscCodec, BytesCodec, Crc32cCodec

_CRC_BYTES = 4
_BLOSC_MAX_OVERHEAD = MAX_OVERHEAD          # a Blosc frame's header: 16 bytes
_PAGE = mmap.PAGESIZE
_buffers = threading.local()     # one page-aligned buffer per thread for O_DIRECT I/O
# zarr's names of Blosc's shuffles, as numcodecs numbers them
_SHUFFLES = {"noshuffle": numcodecs.Blosc.NOSHUFFLE, "shuffle": numcodecs.Blosc.SHUFFLE,
             "bitshuffle": numcodecs.Blosc.BITSHUFFLE}


def _aligned_buffer(nbytes) -> mmap.mmap:
    """This thread's page-aligned buffer of at least ``nbytes`` (whole pages), reused.

    An anonymous mapping is shared with a forked child, so a child makes its own rather
    than writing into its parent's."""
    size = max(_PAGE, -(-nbytes // _PAGE) * _PAGE)
    buffer = getattr(_buffers, "buffer", None)
    if buffer is None or len(buffer) < size or _buffers.pid != os.getpid():
        buffer = _buffers.buffer = mmap.mmap(-1, size)
        _buffers.pid = os.getpid()
    return buffer


def _read_direct(fd, most) -> np.ndarray:
    """Read the file ``fd`` (opened with ``O_DIRECT``) into this thread's buffer, up to its
    end or the buffer's (``most + 1`` bytes rounded up to whole pages)."""
    buffer = _aligned_buffer(most + 1)
    view, done = memoryview(buffer), 0
    while done < len(buffer):
        n = os.preadv(fd, [view[done:]], done)   # short only at the end (or EINVAL)
        if n == 0:
            break
        done += n
    return np.frombuffer(buffer, np.uint8, count=done)


def _read_file(path, most, direct) -> np.ndarray:
    """The bytes of the file ``path``, at most ``most + 1`` of them (through the page cache)
    or a few more (a whole page, around it: ``O_DIRECT``, when ``direct`` and the file
    system allows it; then a view of this thread's buffer, valid until its next read)."""
    if direct and hasattr(os, "O_DIRECT"):
        try:
            fd = os.open(path, os.O_RDONLY | os.O_DIRECT)
        except OSError as err:
            if err.errno != errno.EINVAL:        # EINVAL: this file system has no O_DIRECT
                raise
        else:
            try:
                return _read_direct(fd, most)
            except OSError as err:
                if err.errno != errno.EINVAL:
                    raise
            finally:
                os.close(fd)
    with open(path, "rb") as f:
        return np.frombuffer(f.read(most + 1), np.uint8)


def _pwrite_all(fd, view, offset) -> None:
    """Write all of ``view`` to ``fd`` from ``offset`` (a write may be short)."""
    done = 0
    while done < len(view):
        n = os.pwritev(fd, [view[done:]], offset + done)
        if n == 0:
            raise OSError(errno.EIO, f"a write of {len(view) - done} bytes wrote none")
        done += n


def _write_direct(path, parts) -> bool:
    """Write ``parts`` (bytes-like) one after the other as the new file ``path`` around
    the page cache: the whole pages with ``O_DIRECT`` from this thread's aligned buffer,
    the last part-page through the cache. False where the file system refuses
    ``O_DIRECT`` (then what was written is to be overwritten)."""
    size = sum(len(part) for part in parts)
    buffer = _aligned_buffer(size)
    view, at = memoryview(buffer), 0
    for part in parts:
        view[at:at + len(part)] = part
        at += len(part)
    whole = size - size % _PAGE
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_DIRECT, 0o644)
    except OSError as err:
        if err.errno == errno.EINVAL:            # this file system has no O_DIRECT
            return False
        raise
    try:
        try:
            _pwrite_all(fd, view[:whole], 0)
        except OSError as err:
            if err.errno == errno.EINVAL:
                return False
            raise
        if whole < size:                 # O_DIRECT writes whole blocks: the rest cached
            import fcntl  # Unix only, as O_DIRECT is

            fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_DIRECT)
            _pwrite_all(fd, view[whole:size], whole)
    finally:
        os.close(fd)
    return True


def _write_file(path, parts, direct) -> None:
    """Write ``parts`` one after the other as the new file ``path``, around the page cache
    when ``direct`` and the file system allows it, otherwise through it."""
    if direct and hasattr(os, "O_DIRECT") and _write_direct(path, parts):
        return
    with open(path, "wb") as f:
        f.writelines(parts)


class ChunkFiles:
    """A numeric array of a local zarr v3 store, read and written chunk by chunk as files.

    Array-like (``shape``, ``dtype``, ``ndim``, indexing by a tuple of slices), for
    :func:`dask.array.from_array`; and a target for :func:`dask.array.store` whose chunks
    are the stored ones along the first dimension (assigning whole chunks only). Use
    :meth:`of`, which returns None for an array whose layout it does not cover.

    Each chunk file is read whole, but never more than a chunk can take
    (``prod(chunk_shape) · itemsize`` plus Blosc's 16-byte header and the 4-byte checksum);
    a longer or shorter file, a checksum that does not match (CRC32C of everything before
    the last 4 bytes, little-endian, as zarr's ``crc32c`` codec writes it) or a Blosc
    frame that does not decode, or not to exactly one chunk, raises ``ValueError``. A chunk file
    that is missing raises ``FileNotFoundError`` (zarr would return its fill value;
    :func:`~hippo_probe.recording.open_recording` has already checked that every chunk
    was written). Chunks at the end of the array are stored whole, padded, as zarr
    writes them.

    With ``direct_io`` the files are read around the page cache (``O_DIRECT``) where the
    file system allows it (elsewhere, as on some network file systems, through it):
    cheaper for data read once or larger than memory, slower for data read again while
    it would still be cached. A chunk that two requests share (dask chunks cutting stored
    ones, as trial-aligned chunks of unequal trials do) is then read from the disk twice.
    Each thread keeps one page-aligned buffer as large as the largest chunk it read or
    wrote.

    A chunk is written as zarr writes it, byte for byte: an edge chunk padded with the
    array's fill value, the bytes encoded by numcodecs' Blosc with the array's codec
    settings, then the CRC32C of the frame (4 bytes, little-endian), in a new file that
    replaces any chunk file there was.

    Parameters
    ----------
    folder : str
        The array's folder (the one holding its ``zarr.json``).
    name : str
        The array's name, for error messages.
    shape, chunk_shape : tuple of int
        The array's shape and its chunks' shape (whole along every dimension but the
        first).
    dtype : numpy.dtype
        The stored data type (numeric, little-endian on a little-endian machine).
    direct_io : bool
        Read and write around the page cache.
    fill_value : scalar
        What pads an edge chunk when it is written.
    compressor : numcodecs.Blosc, optional
        The encoder for writing (None: read only).
    """

    def __init__(self, folder, name, shape, chunk_shape, dtype, direct_io=False, *,
                 fill_value=0, compressor=None):
        self.folder = os.path.abspath(folder)      # an os.chdir later must not matter
        self.name = str(name)
        self.direct_io = bool(direct_io)
        self.shape, self.chunk_shape = tuple(shape), tuple(chunk_shape)
        self.dtype = np.dtype(dtype)
        self.ndim = len(self.shape)
        self._chunk_nbytes = int(np.prod(self.chunk_shape)) * self.dtype.itemsize
        self._blosc = numcodecs.Blosc()        # decoding reads the codec from each frame
        self.fill_value = fill_value
        self.compressor = compressor

    @classmethod
    def of(cls, folder, name, array: zarr.Array) -> ChunkFiles | None:
        """A reader and writer of ``array``, the zarr array ``name`` in the folder
        ``folder``, or None when its layout is not the one :func:`save_recording` writes.
        The writer encodes with the array's Blosc settings (typesize included, as zarr
        passes it to numcodecs)."""
        meta = array.metadata
        if getattr(meta, "zarr_format", None) != 3 or array.ndim < 1:
            return None
        codecs = tuple(meta.codecs)
        dtype = np.dtype(array.dtype) if isinstance(array.dtype, np.dtype) else None
        if dtype is None or dtype.kind not in "biuf" or sys.byteorder != "little":
            return None
        if len(codecs) != 3 or not isinstance(codecs[0], BytesCodec) \
                or not isinstance(codecs[1], BloscCodec) \
                or not isinstance(codecs[2], Crc32cCodec):
            return None
        endian = getattr(codecs[0].endian, "value", codecs[0].endian)
        if endian != "little" and not (endian is None and dtype.itemsize == 1):
            return None
        encoding = meta.chunk_key_encoding
        if getattr(encoding, "name", None) != "default" or encoding.separator != "/":
            return None
        if getattr(meta, "storage_transformers", ()):
            return None
        chunks = tuple(getattr(meta.chunk_grid, "chunk_shape", ()) or ())
        if len(chunks) != array.ndim or chunks[1:] != tuple(array.shape[1:]) \
                or 0 in chunks:
            return None
        blosc = codecs[1]
        compressor = numcodecs.Blosc(
            cname=getattr(blosc.cname, "value", blosc.cname), clevel=int(blosc.clevel),
            shuffle=_SHUFFLES[getattr(blosc.shuffle, "value", blosc.shuffle)],
            blocksize=int(blosc.blocksize), typesize=int(blosc.typesize))
        return cls(folder, name, array.shape, chunks, dtype,
                   fill_value=meta.fill_value, compressor=compressor)

    def __repr__(self):
        return (f"ChunkFiles({self.folder!r}, shape={self.shape}, chunks={self.chunk_shape}, "
                f"dtype={self.dtype})")

    def _path(self, i: int) -> str:
        return os.path.join(self.folder, "c", str(i), *["0"] * (self.ndim - 1))

    def chunk(self, i: int) -> np.ndarray:
        """Chunk ``i`` along the first dimension, whole (an edge chunk with its padding)."""
        path = self._path(i)
        most = self._chunk_nbytes + _BLOSC_MAX_OVERHEAD + _CRC_BYTES
        data = _read_file(path, most, self.direct_io)
        if not _CRC_BYTES + _BLOSC_MAX_OVERHEAD <= data.size <= most:
            size = f"more than {most}" if data.size > most else str(data.size)
            raise ValueError(f"chunk file {path} holds {size} bytes; a chunk of "
                             f"{self.chunk_shape} {self.dtype} holds "
                             f"{_CRC_BYTES + _BLOSC_MAX_OVERHEAD} to {most}")
        body = data[:-_CRC_BYTES]
        stored = int(data[-_CRC_BYTES:].view("<u4")[0])
        computed = google_crc32c.value(body)
        if computed != stored:
            raise ValueError(f"chunk file {path}: stored and computed CRC32C checksums do "
                             f"not match ({stored:#010x} vs {computed:#010x})")
        # Blosc's header: uncompressed size at bytes 4-7, frame size at 12-15 (uint32 LE)
        nbytes, cbytes = (int(n) for n in body[:16].view("<u4")[[1, 3]])
        if nbytes != self._chunk_nbytes or cbytes != body.size:
            raise ValueError(f"chunk file {path}: its Blosc frame declares {nbytes} bytes "
                             f"in {cbytes}; a chunk is {self._chunk_nbytes} bytes in a "
                             f"file of {body.size} before the checksum")
        out = np.empty(self.chunk_shape, self.dtype)
        try:
            self._blosc.decode(body, out=out)
        except RuntimeError as err:                  # numcodecs: "error during blosc ..."
            raise ValueError(f"chunk file {path}: its Blosc frame does not decode "
                             f"({err})") from err
        return out

    def __getitem__(self, index):
        index = index if isinstance(index, tuple) else (index,)
        if len(index) != self.ndim or not all(isinstance(s, slice) for s in index):
            raise TypeError(f"ChunkFiles takes one slice per dimension; got {index!r}")
        rows, rest = range(*index[0].indices(self.shape[0])), index[1:]
        if not rows:
            return np.empty((0,) + self.shape[1:], self.dtype)[(slice(None),) + rest]
        start, stop = min(rows[0], rows[-1]), max(rows[0], rows[-1]) + 1
        if rows.step != 1:
            return self[(slice(start, stop),) + rest][rows[0] - start::rows.step]
        length = self.chunk_shape[0]
        first, last = start // length, (stop - 1) // length
        if first == last:          # the usual case: one chunk, whole, without a copy
            offset = first * length
            chunk = self.chunk(first)
            block = chunk[(slice(start - offset, stop - offset),) + rest]
            # a part is copied: a view would keep the whole chunk alive with it
            return block if block.nbytes == chunk.nbytes else block.copy()
        parts = []
        for i in range(first, last + 1):
            offset = i * length
            lo, hi = max(start, offset) - offset, min(stop, offset + length) - offset
            parts.append(self.chunk(i)[(slice(lo, hi),) + rest])
        return np.concatenate(parts, axis=0)

    def write_chunk(self, i: int, values) -> None:
        """Write ``values`` as chunk ``i`` along the first dimension.

        Parameters
        ----------
        i : int
            The chunk's index along the first dimension.
        values : array_like
            A whole chunk, or at the end of the array the part of one the array holds,
            of the array's dtype (not cast).

        Raises
        ------
        TypeError
            This instance was made without a compressor (for reading).
        IndexError
            ``i`` is not a chunk of the array.
        ValueError
            ``values`` has another shape or dtype.
        FileNotFoundError
            The array's folder is gone (a save abandoned meanwhile): nothing is created.
        """
        if self.compressor is None:
            raise TypeError(f"{self!r} was made for reading; ChunkFiles.of makes writers")
        length = self.chunk_shape[0]
        n_chunks = -(-self.shape[0] // length)
        if not 0 <= i < n_chunks:
            raise IndexError(f"chunk {i} of `{self.name}`: the array has {n_chunks}")
        values = np.asarray(values)
        expected = (min(length, self.shape[0] - i * length),) + self.chunk_shape[1:]
        if values.shape != expected or values.dtype != self.dtype:
            raise ValueError(f"chunk {i} of `{self.name}` is {expected} {self.dtype}; got "
                             f"{values.shape} {values.dtype}")
        if values.shape != self.chunk_shape:     # zarr stores edge chunks whole, padded
            whole = np.full(self.chunk_shape, self.fill_value, self.dtype)
            whole[:values.shape[0]] = values
            values = whole
        # as zarr: the bytes, with the typesize of the metadata; zarr also switches off
        # Blosc's own threads on import (numcodecs.blosc.use_threads), without which a
        # frame encoded on the main thread can differ from zarr's, byte for byte
        frame = self.compressor.encode(np.ascontiguousarray(values).view(np.uint8).ravel())
        checksum = google_crc32c.value(frame).to_bytes(_CRC_BYTES, "little")
        path = self._path(i)
        # only the folders below the array's: a task still running when a failed save
        # removes its temporary store must not make part of it again
        folder = self.folder
        for part in os.path.relpath(os.path.dirname(path), self.folder).split(os.sep):
            folder = os.path.join(folder, part)
            try:
                os.mkdir(folder)
            except FileExistsError:
                pass
        _write_file(path, [frame, checksum], self.direct_io)

    def __setitem__(self, index, values):
        """``files[start:stop] = values`` writes one chunk (for
        :func:`dask.array.store`): ``start`` a chunk's first row and ``stop`` its end or
        the array's, whole along every other dimension."""
        index = index if isinstance(index, tuple) else (index,)
        index += (slice(None),) * (self.ndim - len(index))
        length = self.chunk_shape[0]
        whole = all(isinstance(s, slice) and s.step in (None, 1)
                    and s.indices(n)[:2] == (0, n) for s, n in zip(index[1:], self.shape[1:]))
        rows = index[0] if index else None
        if len(index) != self.ndim or not whole or not isinstance(rows, slice) \
                or rows.step not in (None, 1):
            raise TypeError(f"ChunkFiles are written a whole chunk at a time; got {index!r}")
        start, stop, _ = rows.indices(self.shape[0])
        if start % length or stop != min(start + length, self.shape[0]):
            raise ValueError(f"ChunkFiles are written a whole chunk at a time (chunks of "
                             f"{length} along the first dimension); got rows {start}:{stop}")
        self.write_chunk(start // length, values)
