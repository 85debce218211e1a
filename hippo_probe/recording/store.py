"""Zarr storage: ``save_recording`` (atomic) and ``open_recording`` (lazy, checked)."""

from __future__ import annotations

import functools
import json
import os
import uuid
import warnings
from pathlib import Path

import dask.array as da
import numpy as np
import xarray as xr
import zarr
from dask.array.core import getter as dask_getter
from dask.base import tokenize
from zarr.codecs import BloscCodec, Crc32cCodec

from .._atomic import OLD, atomic_path, remove_stale
from .._validators import check_bool, check_path
from ..errors import RecordingError
from .chunk_files import ChunkFiles
from .config import COMPLETE_MARKER, DEFAULTS
from .layout import is_trial_aligned, trial_aligned_chunks, trial_blocks
from .validate import check_block, check_text_variables, json_ready, validate

# CF keys with which xarray changes values as it writes or reads them
_CF_VALUE_CODING = frozenset({"scale_factor", "add_offset", "_Unsigned", "missing_value"})
# xarray's decoders must leave the data as stored (times in seconds are not datetimes)
_OPEN_KW = dict(consolidated=False, decode_times=False, decode_timedelta=False)


def _is_url(path) -> bool:
    return isinstance(path, str) and "://" in path and not path.startswith("file://")


def _local(path) -> Path:
    path = str(check_path("path", path))
    return Path(path[len("file://"):] if path.startswith("file://") else path)


def _samples_per_chunk(rec, config):
    """Samples per chunk so the widest per-sample variable's chunk is ~``chunk_bytes``."""
    row = max((v.dtype.itemsize * int(np.prod(v.shape[1:])) for v in rec.variables.values()
               if v.dims[:1] == ("time",)), default=8)
    return max(1, config.chunk_bytes // max(row, 1))


def storage_time_chunk(rec, config=DEFAULTS) -> int:
    """The zarr chunk length along ``time``: whole trials when the trials are equally long.

    With equal trials of ``L`` samples the chunk holds as many whole trials as fit in
    ``config.chunk_bytes`` (or, for trials longer than that, the largest divisor of
    ``L`` that fits, when it is not tiny), so every chunk boundary is a trial boundary.
    Otherwise (zarr chunks are regular) it is the size that fits, and
    :func:`open_recording` aligns the dask chunks with the trials instead.
    """
    target = _samples_per_chunk(rec, config)
    starts, stops, _ = trial_blocks(rec["trial"].values)
    lengths = np.unique(stops - starts)
    if lengths.size != 1:
        return int(min(target, rec.sizes["time"]))
    length = int(lengths[0])
    if length <= target:
        return length * min(target // length, len(starts))
    divisors = [d for d in range(1, target + 1) if length % d == 0]
    return divisors[-1] if divisors[-1] >= target // 4 else target


def _encoding(rec, time_chunk, config):
    compressors = [BloscCodec(cname=config.compressor, clevel=config.clevel,
                              shuffle=config.shuffle)]
    if config.checksum:
        compressors.append(Crc32cCodec())
    encoding = {}
    for name, var in rec.variables.items():
        along_time = time_chunk
        if name in rec.coords and var.ndim == 1:
            # coords are loaded whole on open: few large chunks read fastest
            along_time = max(time_chunk, config.chunk_bytes // max(var.dtype.itemsize, 1))
        chunks = tuple(min(along_time, size) if dim == "time" else max(size, 1)
                       for dim, size in zip(var.dims, var.shape))
        entry = {"chunks": chunks} if chunks else {}
        if var.dtype.kind not in "OUT":           # strings: zarr's vlen-utf8 + zstd
            entry["compressors"] = compressors
        encoding[name] = entry
    return encoding


def _prepare(rec, time_chunk):
    """Strings as variable-length strings; coords in memory; lazy data variables
    rechunked to the zarr chunks along time and checked block by block as computed."""
    rec = rec.drop_encoding()
    # zarr writes top-level numpy scalars in attrs, not those inside lists and dicts
    rec = rec.copy(deep=False)      # new variables: the caller's attrs stay as they are
    rec.attrs = json_ready(dict(rec.attrs))
    for var in rec.variables.values():
        var.attrs = json_ready(dict(var.attrs))
    text = {name: var.astype(object) for name, var in rec.variables.items()
            if var.dtype.kind in "UST"}
    if text:
        rec = rec.assign_coords({k: v for k, v in text.items() if k in rec.coords})
        rec = rec.assign({k: v for k, v in text.items() if k in rec.data_vars})
    rec = rec.assign_coords({name: coord.variable.compute()
                             for name, coord in rec.coords.items() if coord.chunks is not None})
    # variables in memory stay there: xarray writes them through zarr when it writes the
    # metadata, faster for them than a dask graph of small chunk files
    kind = rec.attrs.get("activity_kind")
    return rec.assign({name: _checked(name, var.chunk({dim: time_chunk if dim == "time"
                                                       else -1 for dim in var.dims}), kind)
                       for name, var in rec.data_vars.items() if var.chunks is not None})


def _checked(name, var, kind):
    """``var`` (dask-backed) with each block checked against the schema as it is computed
    for writing (``kind``: the recording's ``activity_kind``), so lazily made NaNs, or
    spike counts that are not whole numbers, fail the save (and nothing is left on disk)
    instead of reaching the store unchecked."""

    def check(block, block_info=None):
        origin = [lo for lo, _ in block_info[0]["array-location"]] if block_info else None
        return check_block(name, block, origin, kind)

    return var.copy(data=da.map_blocks(check, var.data, dtype=var.dtype))


def _write(rec, store, config, storage_options=None, direct_io=False):
    """Write ``rec`` to ``store`` and mark it complete last."""
    time_chunk = storage_time_chunk(rec, config)
    prepared = _prepare(rec, time_chunk)
    # locally, the lazy variables' chunks are written below (xarray writes the rest)
    by_chunk_files = not _is_url(os.fspath(store)) and any(
        var.chunks is not None for var in prepared.data_vars.values())
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*does not have a Zarr V3 specification")
        pending = prepared.to_zarr(store, mode="w-", zarr_format=3, consolidated=False,
                                   write_empty_chunks=True, storage_options=storage_options,
                                   encoding=_encoding(prepared, time_chunk, config),
                                   compute=not by_chunk_files)
    if by_chunk_files:
        _write_chunks(prepared, store, pending, direct_io)
    group = zarr.open_group(store, mode="r+", storage_options=storage_options)
    arrays = dict(group.arrays())
    nchunks = {name: int(array.nchunks) for name, array in arrays.items()}
    # store_id: which save this is, so that a lazy reader can tell the store it opened
    # from one saved over it later (StoreGuard)
    marker = {"complete": True, "nchunks": nchunks, "store_id": uuid.uuid4().hex,
              "layouts": {name: _layout(array) for name, array in arrays.items()}}
    if not _is_url(os.fspath(store)):
        marker["chunk_digest"] = _chunk_digests(Path(store), list(nchunks))
    group.attrs[COMPLETE_MARKER] = marker


def _write_chunks(prepared, store, pending, direct_io):
    """Compute ``prepared``'s lazy data variables and write their chunks into ``store``
    (local, its arrays created): as chunk files (:class:`ChunkFiles`), when each of them
    is in the layout they cover and xarray would write its values as they are; otherwise
    all through zarr (``pending``, xarray's delayed write)."""
    group = zarr.open_group(store, mode="r")
    lazy = {name: var for name, var in prepared.data_vars.items() if var.chunks is not None}
    writers = {}
    for name, var in lazy.items():
        array = group.get(name)
        files = ChunkFiles.of(os.path.join(store, name), name, array) \
            if isinstance(array, zarr.Array) else None
        if files is None or files.dtype != var.dtype or files.shape != var.shape \
                or not _encodes_as_is(var) or not _stored_chunks(var.data, files):
            pending.compute()
            return
        writers[name] = files
    if direct_io == "auto":
        direct_io = sum(var.nbytes for var in lazy.values()) > available_memory()
    for files in writers.values():
        files.direct_io = direct_io
    da.store([lazy[name].data for name in writers], list(writers.values()), lock=False)


def _encodes_as_is(var) -> bool:
    """Whether xarray writes ``var``'s values as they are: no CF attribute or encoding
    that would scale, offset, mask or retype them."""
    return not ((_CF_VALUE_CODING | {"_FillValue", "dtype", "calendar"})
                & (var.attrs.keys() | var.encoding.keys()))


def _stored_chunks(data, files) -> bool:
    """Whether the dask array ``data``'s chunks are ``files``' stored chunks."""
    length, rows = files.chunk_shape[0], data.chunks[0]
    return all(n == length for n in rows[:-1]) and 0 < rows[-1] <= length \
        and all(len(c) == 1 for c in data.chunks[1:])


def _layout(array) -> dict:
    """What decides how ``array``'s bytes read as values, recorded in the completion marker
    so that an edited shape, type or byte order is refused on opening (the chunks'
    checksums cover only their bytes): shape, chunk shape, data type, byte order, the
    codecs' names and the dimension names. Plain values that the zarr versions this
    package supports all give alike (not their metadata's serialisation, which differs
    between them); attributes may change (see StoreGuard)."""
    meta = array.metadata.to_dict()
    codecs = [c if isinstance(c, dict) else c.to_dict() for c in meta.get("codecs") or []]
    endian = next((c.get("configuration", {}).get("endian") for c in codecs
                   if c.get("name") == "bytes"), None)
    dtype = np.dtype(array.dtype)
    return {"shape": [int(n) for n in array.shape], "chunks": [int(n) for n in array.chunks],
            # variable-length strings are typed differently by zarr 3.0 and 3.1
            "dtype": "text" if dtype.kind in "OTUS" else dtype.name,
            "byte_order": None if endian is None else str(endian),
            "codecs": [str(c.get("name")) for c in codecs],
            "dimension_names": [str(d) for d in meta.get("dimension_names") or []]}


def _chunk_digests(root: Path, names) -> dict:
    """Per array, the sha256 of its chunks' names and CRC32C checksums (each chunk's last
    4 bytes): a chunk deleted, replaced by another with its own checksum, or copied from
    another array changes it. Reads 4 bytes a chunk. Not an authentication code: whoever
    edits the chunks can edit this too."""
    import hashlib

    digests = {}
    for name in names:
        h = hashlib.sha256()
        folder = root / name / "c"
        files = sorted(p for p in folder.rglob("*") if p.is_file()) if folder.is_dir() \
            else []
        for path in files:
            with open(path, "rb") as f:
                f.seek(max(path.stat().st_size - 4, 0))
                tail = f.read(4)
            h.update(str(path.relative_to(folder)).encode() + b"\0" + tail)
        digests[name] = h.hexdigest()
    return digests


def save_recording(rec, path, overwrite=False, *, direct_io="auto", config=DEFAULTS,
                   storage_options=None):
    """Save a recording as a zarr store, atomically.

    The store is written to a temporary directory beside ``path`` and renamed into place
    only when complete (a marker attr is written last), so a crash leaves either nothing
    or the previous store at ``path``, never a half store. With ``overwrite=True`` an
    existing store is replaced only after the new one is complete: the old store is
    renamed aside, the new one renamed in, then the old one deleted. Arrays are chunked
    along ``time`` at trial boundaries (see :func:`storage_time_chunk`), compressed
    (Blosc lz4 + byte shuffle) with a CRC32C checksum per chunk; string coords are
    stored as variable-length strings.

    In a local store, xarray and zarr write the metadata, the coords and the variables in
    memory, and the lazy (dask) data variables' chunks are computed and written one chunk
    file at a time
    (:class:`~hippo_probe.recording.chunk_files.ChunkFiles`: the files zarr writes, byte
    for byte, without zarr's event-loop thread, behind which dask's threads would queue):
    on two cores 1.0–1.9× as fast as ``Dataset.to_zarr`` (see the benchmarks guide). A
    recording with a lazy variable in another layout (text, a ``_FillValue`` attr,
    ``config.checksum=False``) is written through zarr.

    Parameters
    ----------
    rec : xarray.Dataset
        A recording; checked with :func:`validate` first (nothing is written if it fails).
    path : str or os.PathLike
        Destination directory (conventionally ``recordings/NAME.zarr``), or an fsspec URL
        (``s3://…``); on a URL the write is not atomic (object stores have no rename) but
        the completion marker is still written last, so a half store never opens.
    overwrite : bool
        Replace an existing store at ``path``.
    direct_io : bool or "auto"
        Write the lazy data variables' chunk files around the operating system's page
        cache (``O_DIRECT``, Linux; elsewhere, and on file systems without it, through
        the cache): about a fifth of the system time, 0.98–1.6× the speed in the
        benchmarks guide's runs, but nothing of them stays cached for reading back.
        ``"auto"`` (default): only when they are larger than the memory available (as
        for :func:`open_recording`), which the cache could not keep anyway.
    config : RecordingConfig
        Chunk size and codec.
    storage_options : dict, optional
        fsspec options for a URL.

    Raises
    ------
    FileExistsError
        ``path`` exists and ``overwrite`` is False, or ``path`` exists and is not a zarr
        store (never replaced, even with ``overwrite``).
    RecordingError
        ``rec`` breaks the schema.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from hippo_probe.recording import from_arrays, open_recording
    >>> t = np.arange(50) * 0.1
    >>> rec = from_arrays(t, np.zeros((50, 2)), activity=np.ones((50, 3)))
    >>> path = os.path.join(tempfile.mkdtemp(), "demo.zarr")
    >>> save_recording(rec, path)
    >>> open_recording(path).activity.shape
    (50, 3)
    """
    overwrite = check_bool("overwrite", overwrite)
    _check_direct_io(direct_io)
    validate(rec)
    check_text_variables(rec, "a store")
    if _is_url(path):
        _save_url(rec, path, overwrite, config, storage_options)
        return
    dest = _local(path).absolute()
    if dest.exists() or dest.is_symlink():
        if not overwrite:
            raise FileExistsError(f"`path` already exists: {dest}; pass overwrite=True to "
                                  "replace it")
        if not (dest / "zarr.json").is_file():
            raise FileExistsError(f"`path` exists and is not a zarr store: {dest}; refusing "
                                  "to replace it")
    with atomic_path(dest, overwrite=overwrite, what="path") as tmp:
        _write(rec, str(tmp), config, direct_io=direct_io)


def _save_url(rec, url, overwrite, config, storage_options):
    import fsspec

    fs, root = fsspec.core.url_to_fs(url, **(storage_options or {}))
    if fs.exists(root):
        if not overwrite:
            raise FileExistsError(f"`path` already exists: {url}; pass overwrite=True to "
                                  "replace it")
        if not fs.exists(f"{root.rstrip('/')}/zarr.json"):
            raise FileExistsError(f"`path` exists and is not a zarr store: {url}; refusing "
                                  "to replace it")
        fs.rm(root, recursive=True)
    _write(rec, url, config, storage_options)


def _refuse_links_out(root: Path) -> None:
    """A store is one folder: a chunk, array or group that is a symlink leading outside it
    would read another store's data as this one's."""
    root = root.resolve()
    for folder, dirs, files in os.walk(root):
        for name in dirs + files:
            item = Path(folder) / name
            if item.is_symlink():
                target = item.resolve()
                if target != root and root not in target.parents:
                    raise RecordingError(f"`path` {str(root)!r} is not a self-contained "
                                         f"store: {str(item.relative_to(root))!r} links to "
                                         f"{str(target)!r}, outside it; refused")


def _check_complete(path, storage_options):
    """Open the root group and check the completion marker and the chunk counts."""
    label = os.fspath(path)
    if not _is_url(label):
        _refuse_links_out(Path(label))
    try:
        group = zarr.open_group(path, mode="r", storage_options=storage_options)
    except Exception as err:   # zarr raises many kinds for a missing or garbled zarr.json
        raise RecordingError(f"`path` is not a readable zarr store: {label} "
                             f"({type(err).__name__}: {err})") from err
    marker = group.attrs.get(COMPLETE_MARKER)
    if not isinstance(marker, dict) or not marker.get("complete"):
        raise RecordingError(f"`path` holds a half-written or foreign zarr store: {label} "
                             "(no completion marker; save_recording writes it last)")
    layouts = marker.get("layouts")
    for name, expected in marker.get("nchunks", {}).items():
        try:
            array = group[name]
            claimed = array.nchunks       # from the metadata's shape: nothing allocated
            written = _layout(array) if isinstance(layouts, dict) else None
            found = array.nchunks_initialized if claimed == expected else None
        except Exception as err:
            raise RecordingError(f"`path` is a corrupt store: array `{name}` cannot be "
                                 f"opened in {label} ({type(err).__name__}: {err})") from err
        if claimed != expected:
            raise RecordingError(
                f"`path` is a corrupt or altered store: the metadata of array `{name}` in "
                f"{label} claims shape {tuple(array.shape)}, {claimed} chunks, where "
                f"{expected} were written; refused before reading it")
        was = layouts.get(name) if written is not None else None
        if written is not None and written != was:
            was = was if isinstance(was, dict) else {}
            changed = sorted(k for k in written.keys() | was.keys()
                             if written.get(k) != was.get(k))
            raise RecordingError(
                f"`path` is a corrupt or altered store: the metadata of array `{name}` in "
                f"{label} differs from what was written: "
                + "; ".join(f"{k} {was.get(k)!r} written, now {written.get(k)!r}"
                            for k in changed))
        if found != expected:
            raise RecordingError(f"`path` is a corrupt store: array `{name}` has {found} of "
                                 f"its {expected} chunks in {label}")
    digests = marker.get("chunk_digest")
    if isinstance(digests, dict) and not _is_url(label):
        found = _chunk_digests(Path(label), list(digests))
        for name, expected in digests.items():
            if found[name] != expected:
                raise RecordingError(f"`path` is a corrupt or altered store: the chunks of "
                                     f"array `{name}` in {label} are not those written (a "
                                     f"chunk deleted, replaced or copied from elsewhere)")


def open_recording(path, chunks="trials", *, direct_io="auto", storage_options=None,
                   config=DEFAULTS):
    """Open a recording saved by :func:`save_recording`, lazily.

    Data variables are dask arrays (nothing is read until computed); all coords, among
    them the per-sample ``trial``, ``trial_time`` and ``environment``, are loaded, so
    ``rec.groupby("trial")`` and ``rec.groupby("environment")`` work on the lazy
    recording. The store is checked first: a missing completion marker (a half-written
    store), a missing chunk, an unreadable array or a schema violation raises
    :class:`~hippo_probe.errors.RecordingError`; a corrupted chunk raises when read (its
    CRC32C checksum fails).

    A lazy recording reads its store when computed. If the store at ``path`` is replaced
    (``save_recording(..., overwrite=True)``) or removed after it was opened, a read
    raises :class:`~hippo_probe.errors.RecordingError` instead of returning the new
    store's data (or zarr's fill value for chunks that are gone): re-open it, or
    ``.load()`` what must stay fixed. Metadata rewritten in place (an attribute set,
    consolidated metadata, a touched file) is the same store and reads on
    (:class:`StoreGuard`: a stat per chunk, and the store id of the completion marker when
    the stat changed). Made for local stores read through dask (not for URLs, nor with
    ``chunks=None``); stores saved before store ids existed count any change of their
    metadata as a replacement; a network file system may show another client's
    replacement only after its attribute cache expires.

    The data variables of a local store in the layout :func:`save_recording` writes are
    read one chunk file at a time (:class:`~hippo_probe.recording.chunk_files.ChunkFiles`:
    CRC32C check by google-crc32c and Blosc decoding by numcodecs, without zarr's
    event-loop thread, which keeps dask's threads waiting on each other): the same
    values, on two cores 1.1–1.6× as fast from the disk and 1.4× from the page cache
    (see the benchmarks guide). Other stores, and ``chunks=None``, are read through
    zarr.

    Parameters
    ----------
    path : str or os.PathLike
        A local store or an fsspec URL.
    chunks : "trials", dict or None
        ``"trials"`` (default): dask chunks along ``time`` that never straddle two
        trials (whole trials, up to ``config.chunk_bytes`` per chunk). Otherwise passed
        to :func:`xarray.open_zarr` (``{}`` = the stored chunks; ``None`` = no dask).
    direct_io : bool or "auto"
        Read chunk files around the operating system's page cache (``O_DIRECT``, Linux;
        elsewhere, and on file systems without it, through the cache). A read from the
        disk then costs about a quarter of the system time (a third less processor time
        in all), but a second read finds nothing cached. ``"auto"`` (default): only when
        the data variables' chunk files are larger than the memory available when
        opening (Linux's ``MemAvailable``, and the limit of this process's cgroup), since
        the cache could not keep them for a second read anyway. ``True`` suits a
        recording read once.
    storage_options : dict, optional
        fsspec options for a URL.
    config : RecordingConfig
        Chunk size.

    Returns
    -------
    xarray.Dataset

    Examples
    --------
    >>> rec = open_recording("recordings/A2929-200711.zarr")       # doctest: +SKIP
    >>> rec.activity.groupby("trial").mean().compute()              # doctest: +SKIP
    """
    if not (chunks == "trials" or chunks is None or isinstance(chunks, (dict, int))) \
            or isinstance(chunks, bool):
        raise ValueError(f"`chunks` must be 'trials', a dict of chunk sizes per dimension, "
                         f"an int or None; got {chunks!r}")
    _check_direct_io(direct_io)
    sizes = chunks.values() if isinstance(chunks, dict) else [chunks]
    for size in sizes:
        if isinstance(size, bool) or (isinstance(size, (int, np.integer)) and size < 1):
            raise ValueError(f"`chunks` sizes must be whole numbers of samples >= 1 (a "
                             f"chunk of the whole recording would defeat lazy reading); "
                             f"got {chunks!r}")
    if not _is_url(path):
        local = _local(path)
        remove_stale(local.parent)       # temporaries of saves here that died
        if not local.exists():
            aside = sorted(local.parent.glob(f".{local.name}{OLD}*"))
            hint = (f"; an interrupted overwrite left the previous version at {aside[0]}"
                    if aside else "")
            raise FileNotFoundError(f"`path` does not exist: {local}{hint}")
        path = str(local)
    _check_complete(path, storage_options)
    guard = None if _is_url(path) else StoreGuard(path)
    storage = {} if chunks == "trials" else chunks
    try:
        rec = _open(path, storage, storage_options, guard)
        if chunks == "trials":
            aligned = _trial_chunks(rec, config)
            if aligned is not None:
                rec = _open(path, {"time": aligned}, storage_options, guard)
        if guard is not None:                  # a local store
            rec = _read_by_chunk_files(rec, path, guard, direct_io)
    except RecordingError:
        raise
    except Exception as err:
        name = _unreadable_array(path, storage_options)
        which = f"array `{name}` of " if name else ""
        raise RecordingError(f"`path` is a corrupt store: {which}{os.fspath(path)} cannot be "
                             f"read ({type(err).__name__}: {err})") from err
    return validate(rec)


def _check_direct_io(direct_io) -> None:
    if not (isinstance(direct_io, (bool, np.bool_)) or (isinstance(direct_io, str)
                                                        and direct_io == "auto")):
        raise ValueError(f"`direct_io` must be True, False or 'auto'; got {direct_io!r}")


def _unreadable_array(path, storage_options):
    """The first coordinate of a local store (what opening reads) that fails to read, to
    name it in the error; None if none does, for a URL, or if the store cannot tell."""
    if _is_url(os.fspath(path)):
        return None
    try:
        group = zarr.open_group(path, mode="r", storage_options=storage_options)
        arrays = dict(group.arrays())
        # coordinates: the dimensions' arrays and those xarray lists as coordinates
        names = {d for a in arrays.values() for d in a.metadata.dimension_names or ()}
        names |= set(str(group.attrs.get("coordinates", "")).split())
        for name in sorted(names & arrays.keys()):
            try:
                arrays[name][...]
            except Exception:
                return name
    except Exception:          # naming is a courtesy: the original error is what matters
        return None
    return None


def _signature(path):
    """Cheap stat signature of a local store: the inode of its folder and the inode and
    modification time of its ``zarr.json``; None if either is gone."""
    try:
        folder, meta = os.stat(path), os.stat(os.path.join(path, "zarr.json"))
    except OSError:
        return None
    return folder.st_ino, meta.st_ino, meta.st_mtime_ns


def _store_id(path):
    """The ``store_id`` of a local store's completion marker (None: gone, unreadable, or
    saved before store ids existed)."""
    try:
        with open(os.path.join(path, "zarr.json"), "rb") as f:
            attrs = json.load(f).get("attributes") or {}
    except (OSError, ValueError):
        return None
    marker = attrs.get(COMPLETE_MARKER)
    return marker.get("store_id") if isinstance(marker, dict) else None


class StoreGuard:
    """Refuses reads of a lazily opened local store once another store was saved over it
    (or it was removed).

    Each chunk read first compares a stat signature (:func:`_signature`); only when it
    changed is the ``store_id`` that :func:`save_recording` writes into the completion
    marker read again: the same id is the same store whose metadata was rewritten (an
    attribute set in place, consolidated metadata, a touched file), and reading goes on;
    another id, or none, is another store. Picklable, so dask's distributed workers carry
    it (the signature holds no device number, which differs between hosts).
    """

    def __init__(self, path):
        self.path = os.path.abspath(path)      # an os.chdir later must not matter
        self.signature = _signature(self.path)
        self.store_id = _store_id(self.path)

    def check(self):
        now = _signature(self.path)
        if now == self.signature:
            return
        if now is not None and self.store_id is not None \
                and _store_id(self.path) == self.store_id:
            self.signature = now                 # the same store, metadata rewritten
            return
        raise RecordingError(f"`path` {self.path} was replaced or removed after this "
                             f"recording was opened; its data now would come from another "
                             f"store (or be missing): open it again (or .load() a recording "
                             f"that must outlive an overwrite)")


def _read_chunk(path, guard, array, index, *args, **kwargs):
    """dask's getter, with a failure (a chunk that fails its CRC32C checksum, a chunk file
    gone since opening) raised as a RecordingError naming the variable and the store, and
    a read from a store replaced or removed since opening refused (``guard``, a
    :class:`StoreGuard`, or None for URLs). The guard checks after the read: a store
    replaced during it is caught, and an overwrite never brings the opened store back."""
    try:
        block = dask_getter(array, index, *args, **kwargs)
    except Exception as err:
        if guard is not None:
            guard.check()
        inner = array
        while getattr(inner, "array", None) is not None or getattr(inner, "_array", None) \
                is not None:
            inner = getattr(inner, "array", None) or getattr(inner, "_array")
        name = str(getattr(inner, "name", "") or "?").lstrip("/")
        raise RecordingError(f"`{name}` of the store {os.fspath(path)} could not be read at "
                             f"{_slices(index)}: {type(err).__name__}: {err} (a damaged "
                             f"chunk; re-copy or re-save the recording)") from err
    if guard is not None:
        guard.check()
    return block


def _slices(index) -> str:
    parts = [f"{s.start}:{s.stop}" if isinstance(s, slice) else str(s)
             for s in (index if isinstance(index, tuple) else (index,))]
    return "[" + ", ".join(parts) + "]"


def _open(path, chunks, storage_options, guard=None):
    getitem = functools.partial(_read_chunk, path, guard)
    with warnings.catch_warnings():
        # trial-aligned dask chunks may cut stored chunks; intended (see open_recording)
        warnings.filterwarnings("ignore", message="The specified chunks separate")
        rec = xr.open_zarr(path, chunks=chunks, storage_options=storage_options,
                           from_array_kwargs={"getitem": getitem},
                           **_OPEN_KW)
    rec.attrs.pop(COMPLETE_MARKER, None)
    # string coords come back as numpy's StringDType; in memory (from_arrays, from_nwb,
    # record) they are object arrays of str: one layout, so the same dtype
    return rec.assign_coords({name: _object_strings(coord.variable.load())
                              for name, coord in rec.coords.items()})


def _read_by_chunk_files(rec, path, guard, direct_io):
    """``rec`` with each lazy data variable whose stored layout :class:`ChunkFiles` covers
    read through it instead of zarr's event loop: the same dask chunks, values, attrs and
    encoding, and the same getter (:func:`_read_chunk`, with ``guard``). ``direct_io``:
    True, False or "auto" (see :func:`open_recording`)."""
    getitem = functools.partial(_read_chunk, path, guard)
    group = zarr.open_group(path, mode="r")
    readers = {}
    for name, var in rec.data_vars.items():
        if var.chunks is None or not _decodes_as_stored(var):
            continue
        array = group.get(name)
        files = ChunkFiles.of(os.path.join(path, name), name, array) \
            if isinstance(array, zarr.Array) else None
        if files is not None and files.dtype == var.dtype and files.shape == var.shape:
            readers[name] = files
    if direct_io == "auto":
        direct_io = _stored_bytes(f.folder for f in readers.values()) > available_memory()
    faster = {}
    for name, files in readers.items():
        files.direct_io = direct_io
        var = rec[name]
        data = da.from_array(files, chunks=var.data.chunks, getitem=getitem,
                             name=f"read-{name}-{tokenize(var.data.name, direct_io)}",
                             meta=np.empty((0,) * var.ndim, var.dtype))
        faster[name] = var.copy(data=data)
    return rec.assign(faster)


def _stored_bytes(folders) -> int:
    """Bytes of the chunk files below each array folder: what reading them brings into
    the page cache."""
    total = 0
    for folder in folders:
        for root, _, names in os.walk(os.path.join(folder, "c")):
            for name in names:
                try:
                    total += os.stat(os.path.join(root, name)).st_size
                except OSError:           # gone: the read will say so
                    pass
    return total


def available_memory() -> float:
    """Bytes of memory available now without swapping: Linux's ``MemAvailable`` (free
    memory plus the page cache that can be dropped), or less where this process's cgroup
    (v2) has a memory limit, its limit minus its use; infinite where neither can be read."""
    available = float("inf")
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = float(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        with open("/proc/self/cgroup") as f:
            group = next(line[3:].strip() for line in f if line.startswith("0::"))
        folder = os.path.join("/sys/fs/cgroup", group.lstrip("/"))
        with open(os.path.join(folder, "memory.max")) as f:
            limit = f.read().strip()
        if limit != "max":
            with open(os.path.join(folder, "memory.current")) as f:
                available = min(available, float(limit) - float(f.read()))
    except (OSError, ValueError, StopIteration):
        pass
    return available


def _decodes_as_stored(var) -> bool:
    """Whether xarray's decoding leaves ``var``'s values as stored: no scale or offset,
    and no fill value to mask but NaN in a float array (masking NaN changes nothing)."""
    encoding = var.encoding
    if _CF_VALUE_CODING & encoding.keys():
        return False
    fill = encoding.get("_FillValue")
    return fill is None or (var.dtype.kind == "f" and bool(np.isnan(fill)))


def _object_strings(var):
    return var.astype(object) if var.dtype.kind in "TUS" else var


def _trial_chunks(rec, config):
    """Trial-aligned dask chunks along time, or None when the stored ones already are."""
    trial = rec["trial"].values
    stored = next((v.chunks[v.dims.index("time")] for v in rec.data_vars.values()
                   if "time" in v.dims and v.chunks is not None), None)
    if stored is None:
        return None
    if is_trial_aligned(trial, stored):
        return None
    return trial_aligned_chunks(trial, _samples_per_chunk(rec, config))

