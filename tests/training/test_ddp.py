"""DistributedDataParallel under torchrun (gloo on CPU), 2 processes, tiny configuration."""

import subprocess
import sys

import torch

ARGS = ["--task", "specialized", "--trials", "32", "--steps", "3", "--batch-size", "8",
        "--hidden-size", "8", "--validate-every", "3", "--validation-trials", "8",
        "--test-trials", "8",
        "--threads", "1", "--no-progress"]


def test_two_process_ddp_matches_one_process(tmp_path):
    cache = str(tmp_path / "cache")
    one = subprocess.run([sys.executable, "-m", "hippo_probe.cli", "train", *ARGS,
                          "--cache-dir", cache, "--out", str(tmp_path / "one")],
                         capture_output=True, text=True, timeout=300)
    assert one.returncode == 0, one.stderr[-2000:]
    two = subprocess.run([sys.executable, "-m", "torch.distributed.run", "--standalone",
                          "--nproc_per_node", "2", "-m", "hippo_probe.cli", "train", *ARGS,
                          "--cache-dir", cache, "--out", str(tmp_path / "two")],
                         capture_output=True, text=True, timeout=300)
    assert two.returncode == 0, two.stderr[-3000:]
    a = torch.load(tmp_path / "one" / "checkpoint.pt", weights_only=False)
    b = torch.load(tmp_path / "two" / "checkpoint.pt", weights_only=False)
    assert b["log"]["world_size"] == 2 and a["log"]["world_size"] == 1
    # each rank took half of every global batch; DDP averages the gradients, so the
    # parameters equal the single-process run's up to float summation order
    for k in a["model"]:
        torch.testing.assert_close(a["model"][k], b["model"][k], rtol=1e-4, atol=1e-5)
