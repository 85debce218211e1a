"""Every number of the recording subsystem, in one place, with its reason."""

from __future__ import annotations

from dataclasses import dataclass

from .._validators import check_number, check_option, check_positive


@dataclass(frozen=True)
class RecordingConfig:
    """Storage and validation constants.

    Attributes
    ----------
    chunk_bytes : int
        Target size of one chunk along ``time`` (uncompressed, of the widest per-sample
        variable, usually ``activity``): 8 MiB. Zarr and dask work best with chunks of a
        few MB to a few tens of MB: much smaller and the per-chunk overhead (a file, a
        task, a codec call) dominates; much larger and a lazy analysis touching one trial
        reads far more than it needs and memory per worker grows. 8 MiB is 32 network
        trials of 256 units × 256 steps, or about 8,000 samples of 256 units.
    compressor : str
        Blosc inner codec: ``"lz4"``. Float32 activity is noisy and compresses little
        whatever the codec; speed then matters more than the last percent. Measured on
        tanh-of-Gaussian float32 (8000 × 256, byte shuffle, one thread): lz4 level 5 keeps
        91.8 % of the bytes at about 335 MB/s encode and 1,340 MB/s decode, zstd level 3
        88.4 % at 89 and 353 MB/s. Sparse spike counts shrink many-fold with either.
    clevel : int
        Blosc compression level: 5, the Blosc default (lz4 gains nothing above it on
        float noise and loses little speed).
    shuffle : str
        Blosc byte shuffle: regroups the bytes of float32 words so sign and exponent bytes,
        which repeat, sit together; the usual large gain for float arrays.
    checksum : bool
        Append a CRC32C checksum to every chunk, so a corrupted or truncated chunk raises
        on read instead of silently returning wrong numbers.
    gap_jitter : float
        Trials must be separated by a gap of at least one ``dt``: the first sample of a
        trial comes at least ``2 dt`` after the last sample of the previous one (one
        sample interval plus the gap). Real tracking clocks jitter, so the test is
        ``>= 2 dt (1 - gap_jitter)``; 0.1 tolerates 10 % jitter, far more than the 0.6 %
        of the 120 Hz tracking of the bundled mouse session.
    time_atol : float
        Absolute tolerance (s) when ``validate`` checks ``trial_time == time -
        trial_start``: 1 µs, far below any sampling interval yet above float64 rounding
        of session times up to about 10^9 s.
    max_read_bytes : int
        Largest dataset read whole from a file someone else wrote (an NWB file's series,
        tables and spike times), checked from its declared shape before reading: 16 GiB,
        a day of 1,000 units at 30 Hz in float64 is 21 GB... of spike counts 2.6 GB, while
        a crafted header can declare terabytes in a few bytes of HDF5.
    """

    chunk_bytes: int = 8 * 2**20
    compressor: str = "lz4"
    clevel: int = 5
    shuffle: str = "shuffle"
    checksum: bool = True
    gap_jitter: float = 0.1
    time_atol: float = 1e-6
    max_read_bytes: int = 16 * 2**30

    def __post_init__(self):
        check_positive("chunk_bytes", self.chunk_bytes, integer=True)
        check_option("compressor", self.compressor, ("zstd", "lz4", "lz4hc", "zlib", "blosclz"))
        check_number("clevel", self.clevel, low=0, low_inclusive=True, high=9, integer=True)
        check_option("shuffle", self.shuffle, ("noshuffle", "shuffle", "bitshuffle"))
        check_number("gap_jitter", self.gap_jitter, low=0, low_inclusive=True, high=0.5,
                     high_inclusive=False)
        check_positive("time_atol", self.time_atol)


DEFAULTS = RecordingConfig()

#: Root attr that marks a store as completely written (set last by ``save_recording``;
#: stripped on open, so it never shows in ``rec.attrs``).
COMPLETE_MARKER = "_hippo_probe_store"
