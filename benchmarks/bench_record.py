"""A recording's forward pass: a shipped network on test trials, beside torch.nn.LSTM.

Ours: the forward pass of ``hippo_probe.record`` (``record._run_network``: the network
250 trials at a time without autograd, through the peephole LSTM's inference path, whose
h is bit for bit the plain float32 forward's; each batch's h copied into one (trials,
steps, units) array), without building the recording around it. Peer: ``torch.nn.LSTM``
of the same size (no peepholes) with a linear position readout, on the same inputs in
the same batches, each batch's h copied out the same way. Each side runs in a fresh
process on ``--threads`` threads (ours first, then the peer) and makes ``--repeats``
passes; printed are the seconds of every pass, the user and system CPU seconds of the
passes, and the process's peak resident memory (VmHWM), with the ratios ours / peer.

    python benchmarks/bench_record.py [--network localization] [--trials 1000]
        [--repeats 3] [--threads 1]

The first pass of a process is the slowest: the memory it writes is new to the process
and the kernel zeroes every page of it first (system time).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

CHILD = """
import json, resource, sys, time
import numpy as np
import torch
import hippo_probe as hp
from hippo_probe.tasks import make_trials

args = json.loads(sys.argv[1])
torch.set_num_threads(args["threads"])
net = hp.load_pretrained(args["network"])
batch = make_trials(net.task, args["trials"], "test", 0)
T, B = batch.inputs.shape[:2]
H = net.lstm.hidden_size
CHUNK = args["chunk"]
if args["side"] == "ours":
    from hippo_probe.model.record import _run_network

    def one_pass():
        return _run_network(net, batch, CHUNK)
else:
    torch.manual_seed(0)
    lstm = torch.nn.LSTM(net.lstm.input_size, H)
    readout = torch.nn.Linear(H, 2)
    x = torch.from_numpy(batch.inputs)

    @torch.no_grad()
    def one_pass():
        h_out = np.empty((B, T, H), np.float32)
        for lo in range(0, B, CHUNK):
            h, _ = lstm(x[:, lo:lo + CHUNK])
            readout(h)
            h_out[lo:lo + h.shape[1]] = np.swapaxes(h.numpy(), 0, 1)
        return h_out
seconds = []
before = resource.getrusage(resource.RUSAGE_SELF)
for _ in range(args["repeats"]):
    t0 = time.perf_counter()
    out = one_pass()
    seconds.append(time.perf_counter() - t0)
    del out
usage = resource.getrusage(resource.RUSAGE_SELF)
hwm = next(l for l in open("/proc/self/status") if l.startswith("VmHWM"))
print(json.dumps({"seconds": seconds, "user_s": usage.ru_utime - before.ru_utime,
                  "system_s": usage.ru_stime - before.ru_stime,
                  "peak_MB": int(hwm.split()[1]) / 1024}))
"""

#: Trials a batch, as ``record`` runs them by default.
CHUNK = 250

THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                    "NUMBA_NUM_THREADS")


def measure(side: str, network: str, trials: int, repeats: int, threads: int) -> dict:
    """One side's passes in a fresh process (its own peak memory, its own page faults)."""
    env = dict(os.environ, **dict.fromkeys(THREAD_VARIABLES, str(threads)))
    arg = json.dumps({"side": side, "network": network, "trials": trials,
                      "repeats": repeats, "threads": threads, "chunk": CHUNK})
    run = subprocess.run([sys.executable, "-c", CHILD, arg], capture_output=True, text=True,
                         env=env, check=False)
    if run.returncode != 0:
        raise RuntimeError(f"the {side} process failed:\n{run.stderr[-3000:]}")
    return json.loads(run.stdout.strip().splitlines()[-1])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--network", default="localization",
                    help="a shipped network (default: localization)")
    ap.add_argument("--trials", type=int, default=1000, help="test trials (default 1000)")
    ap.add_argument("--repeats", type=int, default=3, help="passes per process (default 3)")
    ap.add_argument("--threads", type=int, default=1, help="threads per process (default 1)")
    args = ap.parse_args(argv)
    print(f"load average before: {os.getloadavg()}", flush=True)
    out = {side: measure(side, args.network, args.trials, args.repeats, args.threads)
           for side in ("ours", "peer")}
    ours, peer = out["ours"], out["peer"]
    print(f"{args.network}, {args.trials} trials, {args.threads} thread(s), "
          f"{args.repeats} passes per process")
    print("| | record's forward pass | torch.nn.LSTM + readout | ours / peer |")
    print("|---|---|---|---|")
    for k in range(args.repeats):
        a, b = ours["seconds"][k], peer["seconds"][k]
        print(f"| pass {k + 1} (s) | {a:.2f} | {b:.2f} | {a / b:.2f} |")
    for key, label in (("user_s", "user CPU of the passes (s)"),
                       ("system_s", "system CPU of the passes (s)"),
                       ("peak_MB", "peak memory, VmHWM (MB)")):
        ratio = f"{ours[key] / peer[key]:.2f}" if peer[key] > 0 else "—"
        print(f"| {label} | {ours[key]:.1f} | {peer[key]:.1f} | {ratio} |")
    print(f"load average after:  {os.getloadavg()}")


if __name__ == "__main__":
    main()
