"""The recording benchmark at 1/100 of its size (100,000 samples × 256 units, 102 MB)."""

import importlib.util
from pathlib import Path

BENCH = Path(__file__).parents[2] / "benchmarks" / "bench_recording.py"


def test_benchmark_small_size(tmp_path):
    spec = importlib.util.spec_from_file_location("bench_recording", BENCH)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    out = bench.run(samples=100_000, units=256, raw_mb=50, directory=tmp_path)
    assert out["activity_MB"] == 100_000 * 256 * 4 / 1e6
    assert out["peak_rss_MB"] < bench.TARGET_PEAK_RSS_MB
    # memory is bounded by chunks, not by the data: reading 102 MB adds well under 102 MB
    assert out["read_peak_rss_MB"] < out["build_peak_rss_MB"] + 100
    assert out["chunks_per_trial_aligned"]
    assert min(out[f"{phase}_MBps"] for phase in (
        "write", "direct_write", "zarr_write", "read", "direct_read", "zarr_read",
        "raw_write", "raw_read", "raw_write_first", "raw_read_first", "raw_write_last",
        "raw_read_last")) > 0
    assert out["raw_MB"] == 50
    assert list(tmp_path.iterdir()) == []          # the store is removed afterwards
