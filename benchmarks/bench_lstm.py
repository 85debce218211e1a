"""Training-step speed of PeepholeLSTM beside torch.nn.LSTM, in one run.

One "step" = forward over a (T, B, F) sequence, a linear (x, y) readout and MSE loss at
every step, backward, and an Adam update — what one optimizer step of training costs.
Peer: ``torch.nn.LSTM`` (fused C++ kernel, no peepholes). Also shown: a naive per-step
Python loop with peepholes under autograd (``unbind``), the obvious alternative.

    python benchmarks/bench_lstm.py [--batch 64] [--steps 500] [--hidden 256]
        [--threads 1 2] [--naive] [--plot benchmarks/bench_lstm.png]

``--plot`` saves a bar chart of the median time per training step of each implementation
at each thread count, labelled with its throughput relative to torch.nn.LSTM.
"""

import argparse
import os
import time

import torch
from torch import nn

from hippo_probe.model.lstm import PeepholeLSTM


class NaiveLoop(nn.Module):
    def __init__(self, f, h):
        super().__init__()
        self.cell = PeepholeLSTM(f, h)

    def forward(self, x):
        p = self.cell
        H = p.hidden_size
        h = x.new_zeros(x.shape[1], H)
        c = torch.zeros_like(h)
        out = []
        for xt in x.unbind(0):
            z = torch.addmm(p.bias, xt, p.weight_x.t()) + h @ p.weight_h.t()
            zi, zf, zg, zo = z.split(H, 1)
            i = torch.sigmoid(zi + p.weight_peephole[0] * c)
            f = torch.sigmoid(zf + p.weight_peephole[1] * c)
            c = f * c + i * torch.tanh(zg)
            o = torch.sigmoid(zo + p.weight_peephole[2] * c)
            h = o * torch.tanh(c)
            out.append(h)
        return torch.stack(out), None


def time_step(core, readout, x, y, repeats):
    params = list(core.parameters()) + list(readout.parameters())
    opt = torch.optim.Adam(params, lr=1e-3)

    def step():
        opt.zero_grad(set_to_none=True)
        h, _ = core(x)
        loss = ((readout(h) - y) ** 2).mean()
        loss.backward()
        opt.step()

    step()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        step()
        times.append(time.perf_counter() - t0)
    return min(times), sorted(times)[len(times) // 2]


def plot(results, threads, path, title):
    """Grouped bars: median seconds per step, per implementation and thread count, each
    labelled with its throughput as a multiple of torch.nn.LSTM's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    names = list(results[threads[0]])
    fig, ax = plt.subplots(figsize=(7, 3.9), constrained_layout=True)
    width = 0.8 / len(names)
    for k, name in enumerate(names):
        xs = np.arange(len(threads)) + (k - (len(names) - 1) / 2) * width
        med = [results[t][name][1] for t in threads]
        bars = ax.bar(xs, med, width, label=name)
        for bar, t, m in zip(bars, threads, med):
            peer = results[t][names[0]][1]
            ax.annotate(f"{peer / m:.2f}x", (bar.get_x() + bar.get_width() / 2, m),
                        ha="center", va="bottom", fontsize=8)
    ax.set_xticks(np.arange(len(threads)), [f"{t} thread{'s' * (t > 1)}" for t in threads])
    ax.set_ylabel("median time per training step (s)")
    ax.set_title(title, fontsize=9)
    ax.set_ylim(0, 1.12 * max(r[1] for t in threads for r in results[t].values()))
    ax.legend(frameon=False, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.1),
              ncol=len(names))  # below the axes: never over a bar
    fig.savefig(path, dpi=130)
    print(f"saved {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--hidden", type=int, default=256)
    ap.add_argument("--features", type=int, default=9)
    ap.add_argument("--threads", type=int, nargs="+", default=[2])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--naive", action="store_true", help="also time the naive Python loop")
    ap.add_argument("--plot", default=None, help="save a bar chart here (PNG)")
    a = ap.parse_args()
    torch.manual_seed(0)
    x = torch.randn(a.steps, a.batch, a.features)
    y = torch.randn(a.steps, a.batch, 2)
    load = os.getloadavg()[0]
    all_results = {}
    for threads in a.threads:
        torch.set_num_threads(threads)
        print(f"batch {a.batch}, {a.steps} steps, {a.hidden} units, {threads} threads, "
              f"load avg {os.getloadavg()[0]:.2f}")
        rows = [("torch.nn.LSTM (peer, no peepholes)", nn.LSTM(a.features, a.hidden)),
                ("hippo_probe PeepholeLSTM", PeepholeLSTM(a.features, a.hidden))]
        if a.naive:
            rows.append(("naive per-step loop (unbind)", NaiveLoop(a.features, a.hidden)))
        results = {}
        for name, core in rows:
            readout = nn.Linear(a.hidden, 2)
            results[name] = time_step(core, readout, x, y, a.repeats)
        peer = results[rows[0][0]][1]
        print(f"{'':40s} {'best s':>8s} {'median s':>9s} {'seq/s':>8s} "
              f"{'throughput vs peer':>19s}")
        for name, (best, med) in results.items():
            print(f"{name:40s} {best:8.3f} {med:9.3f} {a.batch / med:8.1f} "
                  f"{peer / med:18.2f}x")
        all_results[threads] = results
    if a.plot:
        plot(all_results, a.threads, a.plot,
             f"one Adam step: batch {a.batch} x {a.steps} steps x {a.hidden} units "
             f"(load avg {load:.1f} at start)")


if __name__ == "__main__":
    main()
