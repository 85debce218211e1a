"""Training-step speed of PeepholeLSTM beside torch.nn.LSTM, in one run.

One "step" = forward over a (T, B, F) sequence, a linear (x, y) readout and MSE loss at
every step, backward, and an Adam update — what one optimizer step of training costs.
Peer: ``torch.nn.LSTM`` (fused C++ kernel, no peepholes). Also shown: a naive per-step
Python loop with peepholes under autograd (``unbind``), the obvious alternative.

    python benchmarks/bench_lstm.py [--batch 64] [--steps 500] [--hidden 256] [--threads 2]
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


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=64)
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--hidden", type=int, default=256)
    ap.add_argument("--features", type=int, default=9)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--naive", action="store_true", help="also time the naive Python loop")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(0)
    x = torch.randn(a.steps, a.batch, a.features)
    y = torch.randn(a.steps, a.batch, 2)
    print(f"batch {a.batch}, {a.steps} steps, {a.hidden} units, {a.threads} threads, "
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
    print(f"{'':40s} {'best s':>8s} {'median s':>9s} {'seq/s':>8s} {'throughput vs peer':>19s}")
    for name, (best, med) in results.items():
        print(f"{name:40s} {best:8.3f} {med:9.3f} {a.batch / med:8.1f} {peer / med:18.2f}x")


if __name__ == "__main__":
    main()
