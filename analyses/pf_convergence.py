"""Is the oracular particle filter converged? The same trials at several particle counts.

The figures compare the networks with the oracular particle filter at its default size
(1,000 particles with a known start, 2,000 with an unknown one). If more particles lowered
its error, every network / PF ratio would be understated. This runs the filter at each
``--particles`` count on the same test trials of each task and prints the mean Euclidean
error at 50 / 100 / 200 s.

    python analyses/pf_convergence.py [--trials 50] [--particles 1000 10000] [--out figures/]
        [--outlier-everywhere] [--contact-proposals M] [--regularization H]
"""

import argparse
import json
import time
from pathlib import Path


from hippo_probe._atomic import write_text
from hippo_probe.baselines import particle_filter
from hippo_probe.tasks import make_trials
from _filter_options import add_filter_options, baseline_config

ROOT = Path(__file__).resolve().parents[1]
TIMES_S = (50, 100, 200)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=50)
    ap.add_argument("--particles", type=int, nargs="+", default=[1000, 10000])
    ap.add_argument("--tasks", nargs="+",
                    default=["localization", "generalized", "specialized"])
    ap.add_argument("--world", default="darkness", choices=["darkness", "compass"])
    ap.add_argument("--out", default=str(ROOT / "figures"))
    add_filter_options(ap, particles=False)
    a = ap.parse_args()
    baseline = baseline_config(a)
    rows, table = [], {}
    for task in a.tasks:
        batch = make_trials(task, a.trials, "test", 0, world=a.world)
        for n in a.particles:
            t0 = time.time()
            res = particle_filter(batch, n, baseline=baseline)
            err = res.error(batch).mean(axis=1)                          # (T,) over trials
            at = {f"{t}s": float(err[int(round(t / batch.dt)) - 1]) for t in TIMES_S}
            table.setdefault(task, {})[str(n)] = at
            rows.append(f"| {task} | {n:,} | " + " / ".join(f"{v:.3f}" for v in at.values())
                        + f" | {time.time() - t0:.0f} s |")
            print(rows[-1], flush=True)
    lines = ["| task | particles | PF error at 50 / 100 / 200 s (m) | time |",
             "| --- | --- | --- | --- |", *rows]
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "pf_convergence.md",
               f"{a.trials} test trials per task, the same trials at every particle count."
               "\n\n" + "\n".join(lines) + "\n")
    write_text(out / "pf_convergence.json", json.dumps(
        {"trials": a.trials, "errors": table}, indent=1))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
