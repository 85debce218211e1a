"""Is the arena's identity linearly present in a network's units? A probe outside training.

Readout retraining (Fig. 3F) trains a softmax readout on the hidden states of a frozen
network by stochastic gradient descent inside the training loop. This script asks the same
question with a convex fit run to convergence, :func:`hippo_probe.decode_environment` (a
multinomial logistic regression on standardized units, at several L2 strengths C), from the
hidden state at one time to the arena among the specialized task's 100: trained on
training-split trials and scored on test-split trials. The specialized network, whose own
readout is trained for this, is the positive control: the probe should find in it about
what its readout finds.

    python analyses/arena_probe.py [--train-trials 1500] [--test-trials 500]
        [--networks generalized specialized] [--seeds 0 1 2] [--out figures/]

Writes ``arena_probe.json`` and ``arena_probe.md`` (accuracy at 50, 100, 200 s, per
network, training seed and C; chance 0.01).
"""

import argparse
import json
import time
from pathlib import Path

import hippo_probe as hp
from hippo_probe._atomic import write_text
from hippo_probe._threads import limit_threads
from hippo_probe.tasks import make_trials

ROOT = Path(__file__).resolve().parents[1]
TIMES_S = (50, 100, 200)
C_VALUES = (0.01, 1.0, 100.0)      # strong to almost no L2 penalty (standardized units)


def recording(net, split, n_trials, seed=0):
    """The network recorded on specialized-task trials of ``split`` (in its own world)."""
    return hp.record(net, make_trials("specialized", n_trials, split, seed, world=net.world))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train-trials", type=int, default=1500)
    ap.add_argument("--test-trials", type=int, default=500)
    ap.add_argument("--networks", nargs="+", default=["generalized", "specialized"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0],
                    help="training seeds of the networks (default: 0)")
    ap.add_argument("--out", default=str(ROOT / "figures"))
    a = ap.parse_args()
    limit_threads(1)          # one process per core: BLAS too, not only torch
    results = {}
    lines = ["| network | seed | C | " + " | ".join(
        f"test accuracy at {t} s (train)" for t in TIMES_S) + " |",
        "| --- | --- | --- |" + " --- |" * len(TIMES_S)]
    for network in a.networks:
        results[network] = {}
        for seed in a.seeds:
            t0 = time.time()
            net = hp.load_pretrained(network, seed=seed)
            train = recording(net, "train", a.train_trials)
            test = recording(net, "test", a.test_trials)
            results[network][str(seed)] = {}
            for c in C_VALUES:
                res = hp.decode_environment(train, test=test, times=TIMES_S, c=c)
                row = {f"{t}s": {"train": float(res.train_accuracy.sel(trial_time=t)),
                                 "test": float(res.accuracy.sel(trial_time=t))}
                       for t in TIMES_S}
                results[network][str(seed)][str(c)] = row
                lines.append(f"| {network} | {seed} | {c:g} | " + " | ".join(
                    f"{row[f'{t}s']['test']:.2f} ({row[f'{t}s']['train']:.2f})"
                    for t in TIMES_S) + " |")
            print(f"{network}, seed {seed}: {time.time() - t0:.0f} s")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "arena_probe.json", json.dumps(
        {"train_trials": a.train_trials, "test_trials": a.test_trials, "chance": 0.01,
         "results": results}, indent=1), what="probe results")
    write_text(out / "arena_probe.md", "\n".join(lines) + "\n", what="probe table")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
