"""Is the arena's identity linearly present in a network's units? A probe outside training.

Readout retraining (Fig. 3F) trains a softmax readout on the hidden states of a frozen
network by stochastic gradient descent inside the training loop. This script asks the same
question with a convex fit run to convergence: a multinomial logistic regression
(scikit-learn, standardized units, several L2 strengths C) from the hidden state at one
time to the arena among the specialized task's 100, trained on training-split trials and
scored on test-split trials. The specialized network, whose own readout is trained for
this, is the positive control: the probe should find in it about what its readout finds.

    python analyses/arena_probe.py [--train-trials 1500] [--test-trials 500] [--out figures/]

Writes ``arena_probe.json`` and ``arena_probe.md`` (accuracy at 50, 100, 200 s, per
network and C; chance 0.01).
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
import torch
from sklearn.linear_model import LogisticRegression
from sklearn.preprocessing import StandardScaler

import hippo_probe as hp
from hippo_probe.tasks import make_trials

ROOT = Path(__file__).resolve().parents[1]
TIMES_S = (50, 100, 200)
C_VALUES = (0.01, 1.0, 100.0)      # strong to almost no L2 penalty (standardized units)


def hidden_states(net, split, n_trials, seed=0):
    """(T, B, H) hidden states of a loaded network on specialized-task trials, and labels."""
    trials = make_trials("specialized", n_trials, split, seed)
    with torch.no_grad():
        _, _, h = net(torch.from_numpy(trials.inputs))
    return h.numpy(), np.asarray(trials.environment), trials


def probe(h_train, y_train, h_test, y_test, step, c):
    """Accuracy on train and test of a logistic regression fitted at one time step (with
    its neighbours +-2 steps as extra samples)."""
    window = slice(max(step - 2, 0), step + 3)
    x = h_train[window].reshape(-1, h_train.shape[-1])
    y = np.tile(y_train, h_train[window].shape[0])
    scale = StandardScaler().fit(x)
    clf = LogisticRegression(C=c, max_iter=1000).fit(scale.transform(x), y)
    return (float(clf.score(scale.transform(h_train[step]), y_train)),
            float(clf.score(scale.transform(h_test[step]), y_test)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--train-trials", type=int, default=1500)
    ap.add_argument("--test-trials", type=int, default=500)
    ap.add_argument("--networks", nargs="+", default=["generalized", "specialized"])
    ap.add_argument("--out", default=str(ROOT / "figures"))
    a = ap.parse_args()
    torch.set_num_threads(1)
    results = {}
    lines = ["| network | C | " + " | ".join(f"test accuracy at {t} s (train)" for t in TIMES_S)
             + " |", "| --- | --- |" + " --- |" * len(TIMES_S)]
    for network in a.networks:
        t0 = time.time()
        net = hp.load_pretrained(network)
        h_train, y_train, trials = hidden_states(net, "train", a.train_trials)
        h_test, y_test, _ = hidden_states(net, "test", a.test_trials)
        dt = trials.dt
        results[network] = {}
        for c in C_VALUES:
            row = {}
            for t in TIMES_S:
                step = int(round(t / dt)) - 1
                row[f"{t}s"] = dict(zip(("train", "test"),
                                        probe(h_train, y_train, h_test, y_test, step, c)))
            results[network][str(c)] = row
            lines.append(f"| {network} | {c:g} | " + " | ".join(
                f"{row[f'{t}s']['test']:.2f} ({row[f'{t}s']['train']:.2f})" for t in TIMES_S)
                + " |")
        print(f"{network}: {time.time() - t0:.0f} s")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "arena_probe.json").write_text(json.dumps(
        {"train_trials": a.train_trials, "test_trials": a.test_trials, "chance": 0.01,
         "results": results}, indent=1))
    (out / "arena_probe.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
