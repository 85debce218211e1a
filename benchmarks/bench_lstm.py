"""Training-step speed of PeepholeLSTM (bf16 and float32) beside torch.nn.LSTM, in one run.

One "step" = forward over a (T, B, F) sequence, a linear (x, y) readout and MSE loss at
every step, backward, and an Adam update — what one optimizer step of training costs.
Peer: ``torch.nn.LSTM`` in float32 (fused C++ kernel, no peepholes); also the peer under
``torch.autocast("cpu", dtype=torch.bfloat16)``, the stock way to use the CPU's bf16
units. Ours: ``PeepholeLSTM(precision="bf16")`` (matmuls in bf16 on AMX, state and
optimizer in float32) and ``PeepholeLSTM()`` (float32, the fused training kernels), and
the float32 gate-major Function the fused kernels replaced in training ("unfused").
Optional: a naive per-step Python loop with peepholes under autograd (``unbind``), the
obvious alternative. On a CPU without bf16 units (no AVX512-BF16 or AMX), where oneDNN
emulates bf16 ~20x slower, the bf16 rows are left out unless ``--bf16`` asks for them.

Beside the times: the matmul GFLOP/s our step achieves — the FLOPs of all its matmuls,
2 T B (F+H) 4H forward and twice that backward, over the step's time — against a plain
matmul of the same shapes in the same precision, measured in the same run (the machine's
ceiling for this work). With bf16, the step's per-step products also run with their
weights prepacked once for oneDNN (private ops the step does not use): how much of the
gap to the ceiling is the weights' repacking on every call.

    python benchmarks/bench_lstm.py [--batch 64 256] [--steps 500] [--hidden 256]
        [--threads 1 2] [--repeats 3] [--naive] [--plot benchmarks/bench_lstm.png]
        [--concurrent 30] [--quick]

``--plot`` saves bar charts (one panel per batch) of the median time per training step of
each implementation at each thread count, labelled with its throughput relative to
torch.nn.LSTM float32. ``--concurrent S`` also runs the training step (bf16 where the CPU
has bf16 units, else float32) for S seconds as one process at 2 threads and as two
processes at 1 thread side by side, and prints the total sequences per second of each
(which uses two cores better). ``--quick`` is a smoke run
(short sequences, small batches, one repeat).
"""

import argparse
import os
import subprocess
import sys
import time

# as `hippo-probe train` runs (training/_cli.py): idle OpenMP workers sleep instead of
# spinning, which made every run ~10x slower when anything else shared the cores. It must
# be set before libgomp loads; set OMP_WAIT_POLICY yourself to compare.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import torch
from torch import nn

from hippo_probe.model.config import native_bf16
from hippo_probe.model.lstm import PeepholeLSTM, _PeepholeLSTMFunction
from hippo_probe.training.memory import reuse_freed_memory

PEER = "torch.nn.LSTM fp32 (peer)"


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


class Unfused(PeepholeLSTM):
    """PeepholeLSTM training through the gate-major float32 Function (its inference path)."""

    def forward(self, x):
        h0 = x.new_zeros(x.shape[1], self.hidden_size)
        return _PeepholeLSTMFunction.apply(x, h0, h0, self.weight_x, self.weight_h, self.bias,
                                           self.weight_peephole)[0], None


def implementations(f, h, naive=False, bf16=True):
    """name -> (core module, autocast?)."""
    rows = {PEER: (nn.LSTM(f, h), False),
            "hippo_probe PeepholeLSTM fp32": (PeepholeLSTM(f, h), False),
            "hippo_probe fp32 unfused": (Unfused(f, h), False)}
    if bf16:
        rows["torch.nn.LSTM autocast bf16"] = (nn.LSTM(f, h), True)
        rows["hippo_probe PeepholeLSTM bf16"] = (PeepholeLSTM(f, h, precision="bf16"), False)
    if naive:
        rows["naive per-step loop (unbind)"] = (NaiveLoop(f, h), False)
    return rows


def make_step(core, readout, x, y, autocast=False):
    params = list(core.parameters()) + list(readout.parameters())
    opt = torch.optim.Adam(params, lr=1e-3)

    def step():
        opt.zero_grad(set_to_none=True)
        with torch.autocast("cpu", dtype=torch.bfloat16, enabled=autocast):
            h, _ = core(x)
            loss = ((readout(h).float() - y) ** 2).mean()
        loss.backward()
        opt.step()

    return step


def time_step(step, repeats):
    step()  # warm-up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        step()
        times.append(time.perf_counter() - t0)
    return min(times), sorted(times)[len(times) // 2]


def step_flops(T, B, F, H):
    """FLOPs of the matmuls of one training step: 2 T B (F+H) 4H forward, twice that
    backward (input/recurrent gradient and weight gradient)."""
    return 3 * 2 * T * B * (F + H) * 4 * H


def matmul_ceiling(T, B, F, H, dtype, repeats):
    """GFLOP/s of plain matmuls of the step's shapes, timed alone: per step one
    (B, F+H) x (F+H, 4H) forward and one (B, 4H) x (4H, H) backward product, then one
    (4H, T B) x (T B, F+H) weight gradient. Counted with the same FLOPs as the step."""
    g = torch.Generator().manual_seed(0)
    xh = torch.randn(T, B, F + H, generator=g).to(dtype)
    w_t = torch.randn(F + H, 4 * H, generator=g).to(dtype)
    w_h = torch.randn(4 * H, H, generator=g).to(dtype)
    dg = torch.randn(T, B, 4 * H, generator=g).to(dtype)
    z = torch.empty(B, 4 * H, dtype=dtype)
    r = torch.empty(B, H, dtype=dtype)

    def run():
        for t in range(T):
            torch.mm(xh[t], w_t, out=z)
        for t in range(T):
            torch.mm(dg[t], w_h, out=r)
        torch.mm(dg.view(T * B, 4 * H).t(), xh.view(T * B, F + H))

    best, _ = time_step(run, repeats)
    return step_flops(T, B, F, H) / best / 1e9


def prepacked_speedup(T, B, F, H, repeats):
    """The step's per-step bf16 products (forward (B, F+H) x (F+H, 4H), backward (B, 4H)
    x (4H, H)) by ``torch.mm`` and by oneDNN with each weight reordered once
    (``torch.ops.mkldnn._reorder_linear_weight`` / ``_linear_pointwise``, private ops):
    returns (seconds by mm, seconds prepacked, whether the products are equal). Where
    oneDNN repacks a weight into its blocked layout on every call (on AMX, tiles), the
    difference is that repacking; the step does not use the private ops."""
    g = torch.Generator().manual_seed(0)
    xh = torch.randn(T, B, F + H, generator=g).bfloat16()
    dg = torch.randn(T, B, 4 * H, generator=g).bfloat16()
    w = torch.randn(4 * H, F + H, generator=g).bfloat16()       # (out, in), as nn.Linear
    w_h = torch.randn(H, 4 * H, generator=g).bfloat16()
    linear = torch.ops.mkldnn._linear_pointwise
    packed = [torch.ops.mkldnn._reorder_linear_weight(m, B) for m in (w, w_h)]

    def by_mm():
        for t in range(T):
            torch.mm(xh[t], w.t())
        for t in range(T):
            torch.mm(dg[t], w_h.t())

    def prepacked():
        for t in range(T):
            linear(xh[t], packed[0], None, "none", [], "")
        for t in range(T):
            linear(dg[t], packed[1], None, "none", [], "")

    equal = torch.equal(linear(xh[0], packed[0], None, "none", [], ""), torch.mm(xh[0], w.t()))
    return time_step(by_mm, repeats)[0], time_step(prepacked, repeats)[0], equal


def plot(results, batches, threads, path, title):
    """Grouped bars per batch: median seconds per step, per implementation and thread
    count, each labelled with its throughput as a multiple of torch.nn.LSTM float32's."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    names = list(results[batches[0]][threads[0]])
    fig, axes = plt.subplots(1, len(batches), figsize=(4.2 * len(batches) + 1, 4.1),
                             constrained_layout=True, squeeze=False)
    width = 0.8 / len(names)
    for ax, batch in zip(axes[0], batches):
        res = results[batch]
        for k, name in enumerate(names):
            xs = np.arange(len(threads)) + (k - (len(names) - 1) / 2) * width
            med = [res[t][name][1] for t in threads]
            bars = ax.bar(xs, med, width, label=name)
            for bar, t, m in zip(bars, threads, med):
                ax.annotate(f"{res[t][PEER][1] / m:.1f}x",
                            (bar.get_x() + bar.get_width() / 2, m),
                            ha="center", va="bottom", fontsize=7)
        ax.set_xticks(np.arange(len(threads)),
                      [f"{t} thread{'s' * (t > 1)}" for t in threads])
        ax.set_title(f"batch {batch}", fontsize=9)
        ax.set_ylim(0, 1.12 * max(r[1] for t in threads for r in res[t].values()))
    axes[0][0].set_ylabel("median time per training step (s)")
    fig.suptitle(title, fontsize=9)
    fig.legend(*axes[0][0].get_legend_handles_labels(), frameon=False, fontsize=8,
               loc="outside lower center", ncol=min(len(names), 3))  # never over a bar
    fig.savefig(path, dpi=130)
    print(f"saved {path}")


def _worker(a):
    """Run the training step for --worker seconds; print the sequences done and the seconds."""
    torch.set_num_threads(a.threads[0])
    x = torch.randn(a.steps, a.batch[0], a.features)
    y = torch.randn(a.steps, a.batch[0], 2)
    step = make_step(PeepholeLSTM(a.features, a.hidden, precision=a.worker_precision),
                     nn.Linear(a.hidden, 2), x, y)
    step()
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < a.worker:
        step()
        n += 1
    print(n * a.batch[0], time.perf_counter() - t0)


def concurrent(a, seconds, batch, precision):
    """Total sequences/s of the training step: one process at 2 threads vs two at 1."""
    def launch(threads):
        env = dict(os.environ, OMP_NUM_THREADS=str(threads), OMP_WAIT_POLICY="PASSIVE")
        cmd = [sys.executable, __file__, "--worker", str(seconds), "--threads",
               str(threads), "--batch", str(batch), "--steps", str(a.steps), "--hidden",
               str(a.hidden), "--features", str(a.features), "--worker-precision", precision]
        return subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, text=True)

    def total(procs):
        out = [p.communicate()[0].split() for p in procs]
        return sum(int(n) / float(s) for n, s in out)

    print(f"\n{precision} training step, batch {batch}, {seconds:g} s each "
          f"(load avg {os.getloadavg()[0]:.2f} before):")
    one = total([launch(2)])
    print(f"  one process at 2 threads:        {one:7.1f} seq/s  "
          f"(load avg {os.getloadavg()[0]:.2f} after)")
    two = total([launch(1), launch(1)])
    print(f"  two processes at 1 thread each:  {two:7.1f} seq/s in total  "
          f"(load avg {os.getloadavg()[0]:.2f} after)  -> {two / one:.2f}x")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, nargs="+", default=[64, 256],
                    help="batch sizes (64: today's training batch)")
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--hidden", type=int, default=256)
    ap.add_argument("--features", type=int, default=9)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--naive", action="store_true", help="also time the naive Python loop")
    ap.add_argument("--plot", default=None, help="save a bar chart here (PNG)")
    ap.add_argument("--concurrent", type=float, default=0, metavar="S",
                    help="also compare 1 process x 2 threads with 2 x 1 for S seconds")
    ap.add_argument("--quick", action="store_true", help="smoke run: T=50, small batches")
    ap.add_argument("--bf16", action="store_true",
                    help="time the bf16 rows even where the CPU emulates bf16 (slow)")
    ap.add_argument("--worker", type=float, default=0, help=argparse.SUPPRESS)
    ap.add_argument("--worker-precision", default="bf16", help=argparse.SUPPRESS)
    a = ap.parse_args()
    reuse_freed_memory()     # as `fit` does: every implementation's activations reused
    if a.worker:
        return _worker(a)
    if a.quick:
        a.steps, a.batch, a.repeats = 50, [16, 32], 1
        a.concurrent = min(a.concurrent, 2)
    torch.manual_seed(0)
    bf16 = a.bf16 or native_bf16()
    if not bf16:
        print("no bf16 units on this CPU (bf16 would be emulated): bf16 rows left out")
    load = os.getloadavg()[0]
    T, F, H = a.steps, a.features, a.hidden
    all_results = {}
    for batch in a.batch:
        x = torch.randn(T, batch, F)
        y = torch.randn(T, batch, 2)
        all_results[batch] = {}
        for threads in a.threads:
            torch.set_num_threads(threads)
            print(f"\nbatch {batch}, {T} steps, {H} units, {F} inputs, {threads} "
                  f"thread{'s' * (threads > 1)}, OMP_WAIT_POLICY "
                  f"{os.environ['OMP_WAIT_POLICY']}, load avg {os.getloadavg()[0]:.2f}")
            results = {}
            for name, (core, autocast) in implementations(F, H, a.naive, bf16).items():
                step = make_step(core, nn.Linear(H, 2), x, y, autocast)
                results[name] = time_step(step, a.repeats)
            ceiling = {d: matmul_ceiling(T, batch, F, H, d, a.repeats)
                       for d in (torch.bfloat16, torch.float32)[not bf16:]}
            flops = step_flops(T, batch, F, H)
            peer = results[PEER][1]
            print(f"{'':32s} {'best s':>7s} {'median s':>8s} {'seq/s':>7s} "
                  f"{'vs peer':>7s} {'matmul GFLOP/s (of ceiling)':>28s}")
            for name, (best, med) in results.items():
                dtype = torch.bfloat16 if "bf16" in name else torch.float32
                gf = "" if not name.startswith("hippo_probe") else \
                    f"{flops / med / 1e9:9.0f} of {ceiling[dtype]:5.0f} " \
                    f"({flops / med / 1e9 / ceiling[dtype]:4.0%})"
                print(f"{name:32s} {best:7.3f} {med:8.3f} {batch / med:7.1f} "
                      f"{peer / med:6.2f}x {gf:>28s}")
            print(f"{'plain matmuls of these shapes':32s} " + ", ".join(
                f"{str(d)[6:]} {c:.0f} GFLOP/s" for d, c in ceiling.items()) + " (the ceilings)")
            if bf16:
                try:
                    mm_s, packed_s, equal = prepacked_speedup(T, batch, F, H, a.repeats)
                    print(f"{'per-step bf16 products':32s} torch.mm {mm_s:.3f} s, weights "
                          f"prepacked once {packed_s:.3f} s ({mm_s / packed_s:.2f}x; "
                          f"products {'equal' if equal else 'NOT equal'})")
                except (RuntimeError, AttributeError) as err:     # no oneDNN build
                    print(f"{'per-step bf16 products':32s} prepacked: not available ({err})")
            all_results[batch][threads] = results
    if a.concurrent:
        concurrent(a, a.concurrent, a.batch[0], "bf16" if bf16 else "fp32")
    if a.plot:
        plot(all_results, a.batch, a.threads, a.plot,
             f"one Adam step: {T} steps x {H} units, {F} inputs "
             f"(load avg {load:.1f} at start)")


if __name__ == "__main__":
    main()
