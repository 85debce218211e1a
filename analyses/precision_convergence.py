"""Does training in bf16 converge as well as in float32? Validation curves side by side.

The same 1,000-step run of the generalized task in the darkness world (seed 0, init seed
0) in fp32 and in bf16, and, as the yardstick of run-to-run variation, both again with
another init seed (1): bf16 converges as well if its gap to fp32 is no larger than the gap
between two seeds of one precision. Reads the runs' ``log.json`` (copies in
``analyses/data/precision_convergence/``) and writes a figure.

    hippo-probe train --task generalized --steps 1000 --precision fp32 --validate-every 100 \\
        --validation-trials 500 --test-trials 200 --threads 1 --out runs/convergence/fp32
    (the same with --precision bf16, and both with --init-seed 1 --out runs/convergence/*_seed1)
    python analyses/precision_convergence.py [--runs analyses/data/precision_convergence]
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from hippo_probe._atomic import save_figure  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
RUNS = {"fp32": "fp32, init seed 0", "bf16": "bf16, init seed 0",
        "fp32_seed1": "fp32, init seed 1", "bf16_seed1": "bf16, init seed 1"}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default=str(ROOT / "analyses" / "data" / "precision_convergence"))
    ap.add_argument("--out", default=str(ROOT / "paper_figures" / "png" /
                                         "precision_convergence.png"))
    a = ap.parse_args()
    logs = {name: json.loads((Path(a.runs) / f"{name}.json").read_text())
            for name in RUNS if (Path(a.runs) / f"{name}.json").exists()}
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.6), constrained_layout=True)
    for name, log in logs.items():
        val = log["validation"]
        ax[0].plot([v["step"] for v in val], [v["mean_error_m"] for v in val], marker="o",
                   ms=3, label=f"{RUNS[name]} ({log['wall_time_s'] / 60:.0f} min)")
        mse = np.array([t["mse"] for t in log["train"]])
        smooth = np.convolve(mse, np.ones(50) / 50, mode="valid")
        ax[1].plot(np.arange(len(smooth)) + 50, smooth, label=RUNS[name])
        last = float(mse[-200:].mean())
        print(f"{RUNS[name]:<20} final validation error {val[-1]['mean_error_m']:.4f} m, "
              f"best {min(v['mean_error_m'] for v in val):.4f} m, test "
              f"{log['test']['mean_error_m']:.4f} m, train MSE over the last 200 steps "
              f"{last:.5f} m^2, wall {log['wall_time_s']:.0f} s")
    ax[0].set(xlabel="optimizer step", ylabel="validation error (m)",
              title="validation (500 trials)")
    ax[1].set(xlabel="optimizer step", ylabel="training MSE (m²), 50-step mean",
              title="training loss")
    for axis in ax:
        axis.legend(fontsize=8, frameon=False)
    fig.suptitle("generalized task, darkness world: bf16 vs fp32 training (1 thread each)")
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    save_figure(fig, a.out, dpi=120)
    print(f"saved {a.out}")


if __name__ == "__main__":
    main()
