"""Speed and memory of the oracular particle filter and of PF-SLAM.

Speed is in particle-steps per second (trials x 500 steps x particles / wall time) on
``--threads`` threads, best and median of ``--repeat`` runs (the machine is shared, so the
best run is the closest to the code's own speed), with the CPU time of all threads beside
it; the time of the issue's full runs (1,000 test trials) is extrapolated linearly in
trials (trials are independent; ``--trials 1000`` measures it outright), and as it would
take on idle cores (CPU time / threads: "idle"). Peak memory is the growth of the highest
resident set size of a fresh process while it filters ``--trials`` trials (it counts
numba's allocations, which tracemalloc does not see).

Targets: PF, 1,000 particles, 1,000 trials x 500 steps in under 60 s;
PF-SLAM, 10,000 particles, the same trials in under 10 minutes: about 8.3 million
particle-steps per second each, in the darkness world (particles carry a heading drift,
the contact likelihood is evaluated per particle); the compass world's numbers beside.
Peer: the plain-numpy distance to 10 walls (:func:`hippo_probe.world.arena.wall_distance`)
alone, measured here on the same
particles, which reached 1-7 million particle-steps per second on this machine before
the filter was written.

    python benchmarks/bench_particle_filter.py [--trials 100] [--repeat 3] [--threads 2]
        [--worlds darkness compass]
"""

import argparse
import os
import subprocess
import sys
import time

TARGET_PARTICLE_STEPS_PER_S = {"pf": 1000 * 1000 * 500 / 60,
                               "pfslam": 10_000 * 1000 * 500 / 600}


def peak_rss_growth(method, n_trials, n_particles, threads, world):
    """MB by which a fresh process's peak RSS grows while it filters the trials (VmHWM
    from /proc, Linux)."""
    code = f"""
def peak_kb():
    with open("/proc/self/status") as f:
        return int(next(line for line in f if line.startswith("VmHWM")).split()[1])
from hippo_probe.baselines import particle_filter, pf_slam
from hippo_probe.tasks import make_trials
run = {{"pf": particle_filter, "pfslam": pf_slam}}[{method!r}]
batch = make_trials("specialized", {n_trials}, "test", 0, world={world!r})
run(batch.select([0]), {n_particles}, threads=1)
before = peak_kb()
run(batch, {n_particles}, threads={threads})
print(peak_kb() - before)
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    return int(done.stdout.split()[-1]) / 1e3


def numpy_peer(n_particles, repeat):
    """Particle-steps per second of the plain-numpy wall distance (10 walls)."""
    import numpy as np

    from hippo_probe.tasks import fixed_arenas
    from hippo_probe.world.arena import wall_distance

    vertices = fixed_arenas("specialized")[0]
    points = np.random.default_rng(0).uniform(-0.2, 0.2, (n_particles, 2))
    best = np.inf
    for _ in range(repeat):
        began = time.perf_counter()
        for _ in range(20):
            wall_distance(vertices, points)
        best = min(best, (time.perf_counter() - began) / 20)
    return n_particles / best


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=100, help="specialized test trials")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per method")
    parser.add_argument("--threads", type=int, default=2, help="threads of the filters")
    parser.add_argument("--pf-particles", type=int, default=1000)
    parser.add_argument("--slam-particles", type=int, default=10_000)
    parser.add_argument("--worlds", nargs="+", default=["darkness", "compass"])
    args = parser.parse_args()
    os.environ["NUMBA_NUM_THREADS"] = str(args.threads)    # before numba is imported
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

    import numpy as np

    from hippo_probe.baselines import particle_filter, pf_slam
    from hippo_probe.tasks import make_trials

    with open("/proc/loadavg") as f:
        load = " ".join(f.read().split()[:3])
    print(f"particle filters on {args.trials} specialized test trials x 500 steps, "
          f"{args.threads} threads, {os.cpu_count()} cores; load average before: {load}")
    runs = {"pf": (particle_filter, args.pf_particles),
            "pfslam": (pf_slam, args.slam_particles)}
    header = (f"{'world':<10}{'method':<8}{'particles':>10}{'best M p-steps/s':>18}"
              f"{'median':>9}{'CPU ns/p-step':>15}{'1000 trials':>13}{'idle':>8}"
              f"{'target':>9}{'peak MB':>9}")
    print(header)
    print("-" * len(header))
    for world, (name, (run, n)) in [(w, r) for w in args.worlds for r in runs.items()]:
        batch = make_trials("specialized", args.trials, "test", 0, world=world)
        run(batch.select([0]), n, threads=1)               # compile / load the JIT cache
        walls, cpus = [], []
        for _ in range(args.repeat):
            began, cpu = time.perf_counter(), time.process_time()
            run(batch, n, threads=args.threads)
            walls.append(time.perf_counter() - began)
            cpus.append(time.process_time() - cpu)
        work = args.trials * batch.n_steps * n
        rate = work / np.array(walls)
        full = min(walls) * 1000 / args.trials
        target = 1000 * batch.n_steps * n / TARGET_PARTICLE_STEPS_PER_S[name]
        peak = peak_rss_growth(name, args.trials, n, args.threads, world)
        idle = min(cpus) * 1000 / args.trials / args.threads
        print(f"{world:<10}{name:<8}{n:>10}{rate.max() / 1e6:>18.2f}{np.median(rate) / 1e6:>9.2f}"
              f"{min(cpus) / work * 1e9:>15.0f}{full:>12.0f}s{idle:>7.0f}s{target:>8.0f}s"
              f"{peak:>9.0f}")
    peer = numpy_peer(args.pf_particles, args.repeat)
    print(f"peer: numpy wall_distance alone, {args.pf_particles} particles: "
          f"{peer / 1e6:.2f} M particle-steps/s (1 thread)")
    with open("/proc/loadavg") as f:
        print(f"load average after: {' '.join(f.read().split()[:3])}")


if __name__ == "__main__":
    main()
