"""The forward-pass benchmark at a handful of trials: both sides run and report."""

import importlib.util
from pathlib import Path

BENCH = Path(__file__).parents[2] / "benchmarks" / "bench_record.py"


def test_benchmark_small_size(capsys):
    spec = importlib.util.spec_from_file_location("bench_record", BENCH)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    bench.main(["--trials", "8", "--repeats", "2"])
    table = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    rows = {line.split(" | ")[0][2:]: line.split(" | ")[1:] for line in table[1:]}
    assert list(rows) == ["pass 1 (s)", "pass 2 (s)", "user CPU of the passes (s)",
                          "system CPU of the passes (s)", "peak memory, VmHWM (MB)"]
    for label in ("pass 1 (s)", "pass 2 (s)", "peak memory, VmHWM (MB)"):
        ours, peer, ratio = rows[label]
        assert float(ours) > 0 and float(peer) > 0, label
        assert float(ratio.rstrip(" |")) > 0, label
    # each side's own process: its peak holds torch and a network, not the other side's
    assert 100 < float(rows["peak memory, VmHWM (MB)"][0]) < 4000
