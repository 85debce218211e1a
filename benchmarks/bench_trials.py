"""Trial generation speed and memory, per task, and the trial cache's read speed.

Speed is in network steps per second (trials x 500 steps / wall time), generated in
batches of ``--batch`` trials as the cache does (one block = 1000 trials); best and median
of ``--repeat`` runs (the machine is shared, so the best run is the closest to the code's
own speed), with the CPU time of all threads per 1000 trials beside it. Peak memory is
the growth of the highest resident set size while generating ``--batch`` trials in a fresh
process (it counts numba's allocations, which tracemalloc does not see) and tracemalloc's
peak of the Python and numpy allocations.

Peer: a plain-numpy prototype of the simulator reached about 140,000 steps/s; the target is
500,000 steps/s (300,000 trials x 500 steps in 5 minutes).

    python benchmarks/bench_trials.py [--trials 2000] [--batch 1000] [--repeat 3]
                                      [--threads 2]
"""

import argparse
import os
import sys
import subprocess
import tempfile
import time
import tracemalloc

PEER_STEPS_PER_S = 140_000
TARGET_STEPS_PER_S = 500_000


def peak_rss_growth(task, n_trials, batch, threads):
    """MB by which a fresh process's peak RSS grows while it generates the trials.

    Reads VmHWM from /proc (Linux): unlike ``ru_maxrss``, it is not inherited from the
    parent process.
    """
    code = f"""
import os
os.environ["NUMBA_NUM_THREADS"] = "{threads}"
def peak_kb():
    with open("/proc/self/status") as f:
        return int(next(line for line in f if line.startswith("VmHWM")).split()[1])
from hippo_probe.tasks import make_trials
make_trials({task!r}, 2, "train", 0)
before = peak_kb()
for first in range(0, {n_trials}, {batch}):
    make_trials({task!r}, min({batch}, {n_trials} - first), "train", 0, first=first)
print(peak_kb() - before)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    return int(done.stdout.split()[-1]) / 1e3


def generate(task, n_trials, batch):
    from hippo_probe.tasks import make_trials

    for first in range(0, n_trials, batch):
        make_trials(task, min(batch, n_trials - first), "train", 0, first=first)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=2000, help="trials per task")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per task")
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
    head = (f"{'task':<14}{'best steps/s':>14}{'median':>11}{'x peer':>8}"
            f"{'CPU s/1000 trials':>19}{'+peak RSS (MB)':>15}{'tracemalloc (MB)':>18}")
    print(head)
    print("-" * len(head))
    for task in args.tasks:
        n_steps = task_config(task).world.motion.n_steps
        walls, cpus = [], []
        for _ in range(args.repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            generate(task, args.trials, args.batch)
            walls.append(time.perf_counter() - t0)
            cpus.append(time.process_time() - c0)
        rss = peak_rss_growth(task, args.batch, args.batch, args.threads)
        tracemalloc.start()
        generate(task, min(args.trials, args.batch), args.batch)
        traced = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        best = args.trials * n_steps / min(walls)
        median = args.trials * n_steps / sorted(walls)[len(walls) // 2]
        cpu = 1000 * min(cpus) / args.trials
        print(f"{task:<14}{best:>14,.0f}{median:>11,.0f}{best / PEER_STEPS_PER_S:>8.1f}"
              f"{cpu:>19.2f}{rss:>15.0f}{traced / 1e6:>18.0f}")

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
