"""Trial generation speed and memory, per task, and the trial cache's read speed.

Speed is in network steps per second (trials x 500 steps / wall time), generated in
batches of ``--batch`` trials as the cache does (one block = 1000 trials). Peak memory is
the highest resident set size above the starting point (sampled every 5 ms; it counts
numba's allocations, which tracemalloc does not see) and tracemalloc's peak of the Python
and numpy allocations.

Peer: the plain-numpy prototype of issue 2 reached about 140,000 steps/s; the target is
500,000 steps/s (300,000 trials x 500 steps in 5 minutes).

    python benchmarks/bench_trials.py [--trials 3000] [--batch 1000] [--threads 2]
"""

import argparse
import os
import sys
import tempfile
import threading
import time
import tracemalloc

PEER_STEPS_PER_S = 140_000
TARGET_STEPS_PER_S = 500_000


class PeakRSS:
    """Highest resident set size (bytes) seen while the block runs, above its start."""

    def __init__(self, interval=0.005):
        import psutil

        self.process = psutil.Process()
        self.interval = interval

    def __enter__(self):
        self.start = self.peak = self.process.memory_info().rss
        self.running = True
        self.thread = threading.Thread(target=self._watch, daemon=True)
        self.thread.start()
        return self

    def _watch(self):
        while self.running:
            self.peak = max(self.peak, self.process.memory_info().rss)
            time.sleep(self.interval)

    def __exit__(self, *exc):
        self.running = False
        self.thread.join()
        self.peak = max(self.peak, self.process.memory_info().rss)
        self.extra = self.peak - self.start


def generate(task, n_trials, batch):
    from hippo_probe.tasks import make_trials

    for first in range(0, n_trials, batch):
        make_trials(task, min(batch, n_trials - first), "train", 0, first=first)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=3000, help="trials per task")
    parser.add_argument("--batch", type=int, default=1000, help="trials per make_trials call")
    parser.add_argument("--threads", type=int, default=2, help="numba threads")
    parser.add_argument("--tasks", nargs="+",
                        default=["localization", "generalized", "specialized"])
    args = parser.parse_args()
    os.environ["NUMBA_NUM_THREADS"] = str(args.threads)   # before numba is imported

    import numba

    from hippo_probe.tasks import cached_trials, make_trials, task_config

    numba.set_num_threads(args.threads)
    for task in args.tasks:                                # compile / load the JIT cache
        make_trials(task, 2, "train", 0)

    print(f"trial generation: {args.trials} trials per task in batches of {args.batch}, "
          f"{args.threads} numba threads, {os.cpu_count()} CPUs")
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(f"peer: plain-numpy prototype ~{PEER_STEPS_PER_S:,} steps/s; "
          f"target {TARGET_STEPS_PER_S:,} steps/s")
    head = (f"{'task':<14}{'steps/s':>12}{'s per 1000 trials':>19}{'x peer':>8}"
            f"{'peak RSS (MB)':>15}{'tracemalloc peak (MB)':>23}")
    print(head)
    print("-" * len(head))
    for task in args.tasks:
        n_steps = task_config(task).world.motion.n_steps
        with PeakRSS() as rss:
            t0 = time.perf_counter()
            generate(task, args.trials, args.batch)
            elapsed = time.perf_counter() - t0
        tracemalloc.start()
        generate(task, min(args.trials, args.batch), args.batch)
        traced = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        rate = args.trials * n_steps / elapsed
        print(f"{task:<14}{rate:>12,.0f}{1000 * elapsed / args.trials:>19.2f}"
              f"{rate / PEER_STEPS_PER_S:>8.1f}{rss.extra / 1e6:>15.0f}{traced / 1e6:>23.0f}")

    # the on-disk cache: first call generates and writes, the second reads
    task = "generalized"
    n = 2 * 1000
    n_steps = task_config(task).world.motion.n_steps
    with tempfile.TemporaryDirectory() as cache:
        t0 = time.perf_counter()
        cached_trials(task, n, "train", 0, cache_dir=cache)
        write = time.perf_counter() - t0
        t0 = time.perf_counter()
        batch = cached_trials(task, n, "train", 0, cache_dir=cache)
        read = time.perf_counter() - t0
        size = sum(os.path.getsize(os.path.join(d, f))
                   for d, _, files in os.walk(cache) for f in files)
    loaded = sum(getattr(batch, k).nbytes for k in ("inputs", "position", "target",
                                                    "head_direction", "contact"))
    print(f"\ncache ({task}, {n} trials = 2 blocks): generate+write {n * n_steps / write:,.0f} "
          f"steps/s; read {n * n_steps / read:,.0f} steps/s ({read:.2f} s, "
          f"{loaded / read / 1e6:,.0f} MB/s in memory, {size / 1e6:.0f} MB on disk)")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
