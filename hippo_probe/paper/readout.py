"""The arena readout of a frozen network, fitted as the convex problem it is (Fig. 3F).

The study retrains only the softmax readout of the generalized network on the specialized
task's 100 familiar arenas and reads its classification late in each trial ("close to
85%"). With the network frozen this is a multinomial logistic regression on the units:
convex, with one optimum, so it is fitted to convergence rather than trained by gradient
steps that stop on a budget. The protocol, with its numbers in :class:`ReadoutConfig`:

1. Features. The frozen network runs on specialized-task trials (train split for the fit,
   validation split to choose the L2 strength, test split to score) in its own world;
   its hidden units ``h_t`` are kept at the fit times (every 20 s from 100 s: "late in
   each trial") on training trials and every 10 s on the others. Features stream to disk
   in blocks of 1,000 trials (resumable), so memory holds one block at a time while
   extracting and one training set while fitting.
2. The study's readout: one linear readout of ``h_t``, trained on the fit times of every
   training trial at once, scored on each test trial at each time: the Fig. 3F curve.
3. A labelled variant: the same on a leaky average of the units, the output of a
   downstream cell integrating them, ``a_t = sum_{s<=t} w_{t-s} h_s / sum_{s<=t}
   w_{t-s}`` with ``w_k = exp(-k dt / tau)``; ``tau`` chosen on validation trials.
4. A learning curve over the training-set size (4k, 16k, 64k, ... trials): the readout's
   accuracy is a property of the network only once it stops rising with more data.
5. The study's readout at the largest size is shipped as the network's classifier
   weights (:func:`readout_network`): the standardization folded into one linear layer,
   so :func:`hippo_probe.record` and the figures use it unchanged.

References
----------
Kanitscheider & Fiete (2017), NIPS 30, Fig. 3F. Hastie, Tibshirani & Friedman (2009),
The Elements of Statistical Learning, 2nd ed., Sect. 4.4.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._atomic import atomic_path, write_text
from .._validators import check_positive
from ..analysis.decode_environment import decoder_weights, fit_linear_decoder


@dataclass(frozen=True)
class ReadoutConfig:
    """The readout protocol's numbers.

    Attributes
    ----------
    fit_times : tuple of float
        Times in trial (s) whose states train the readout: 100-200 s every 20 s, "late in
        each trial" (the study trains its readout for the late part; 6 states a trial,
        20 s apart, are far less correlated than consecutive 0.4-s steps).
    curve_times : tuple of float
        Times (s) at which validation and test trials are scored: every 10 s, 10-200 s
        (the Fig. 3F curve).
    taus : tuple of float
        Time constants (s) of the leaky-average variant tried on validation trials:
        10-400 s and ``inf`` (the running mean of the trial so far), from a few contacts
        apart to twice a trial, so that the chosen one is not at the grid's edge unless
        it is the running mean.
    sizes : tuple of int
        Training-set sizes of the learning curve (trials of the train split).
    c_grid : tuple of float
        Inverse L2 strengths tried at every training-set size, in increasing order (each
        fit starts from the last); the path stops once validation accuracy falls.
    tol : float
        The solver's tolerance on the largest gradient component of scikit-learn's
        objective, which is the *mean* log-loss plus ``|W|^2 / (2 C n)``: the L2 term's
        gradient is of order ``1 / (C n)``, so the tolerance must be well below that for
        the fits at different C to differ at all (at ``n`` = 80,000 samples and C = 10,
        ``1 / (C n)`` is about 1e-6).
    n_validation, n_test : int
        Trials of the validation and test splits.
    max_iter : int
        L-BFGS iterations per fit; a fit that needs more is reported as unconverged.
    block : int
        Trials per feature file (the trial cache's block).
    """

    fit_times: tuple = (100.0, 120.0, 140.0, 160.0, 180.0, 200.0)
    curve_times: tuple = tuple(float(t) for t in range(10, 201, 10))
    taus: tuple = (10.0, 25.0, 50.0, 100.0, 200.0, 400.0, float("inf"))
    sizes: tuple = (4000, 16000, 64000)
    c_grid: tuple = (0.01, 0.1, 1.0, 10.0)
    tol: float = 1e-8
    n_validation: int = 1000
    n_test: int = 1000
    max_iter: int = 2000
    block: int = 1000


READOUT = ReadoutConfig()


# ----------------------------------------------------------------------- features
def leaky_average(h: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """Normalized exponential moving average over time of ``h`` (T, ...).

    ``a_t = sum_{s<=t} exp(-(t - s) dt / tau) h_s / sum_{s<=t} exp(-(t - s) dt / tau)``:
    a weighted mean of the past, so ``a_0 = h_0`` and a constant input is returned
    unchanged (no start-up bias); ``tau -> 0`` gives ``h``, ``tau = inf`` the running
    mean. Numerator and denominator follow ``y_t = decay * y_{t-1} + u_t`` in float64,
    one vectorized step at a time (along time, a per-series recursive filter such as
    :func:`scipy.signal.lfilter` is an order of magnitude slower on these shapes).
    """
    if not tau > 0:
        raise ValueError(f"`tau` must be > 0 s; got {tau!r}")
    decay = np.exp(-dt / tau)
    out = np.empty(h.shape, np.float32)
    num = np.zeros(h.shape[1:], np.float64)
    den = 0.0
    for t in range(h.shape[0]):
        num *= decay
        num += h[t]
        den = decay * den + 1.0
        out[t] = num / den
    return out


def describe_kind(kind: str) -> str:
    """A feature kind in words, for tables and legends."""
    if kind == "h":
        return "units h (the study's readout)"
    tau = kind.split("_", 1)[1]
    return "running mean of h (variant)" if tau == "inf" else \
        f"leaky average of h, tau {tau} s (variant)"


def feature_kinds(cfg: ReadoutConfig = READOUT) -> tuple[str, ...]:
    """``"h"`` (the units) and ``"leaky_<tau>"`` (the variant) for every tau."""
    return ("h", *(f"leaky_{tau:g}" for tau in cfg.taus))


def _steps(times, dt, n_steps: int) -> np.ndarray:
    """0-based step index of each time in trial (step s ends at (s + 1) dt)."""
    times = np.asarray(times, float)
    steps = np.rint(times / dt).astype(int) - 1
    bad = (steps < 0) | (steps >= n_steps) | ~np.isclose((steps + 1) * dt, times)
    if bad.any():
        raise ValueError(f"times in trial must be multiples of dt = {dt:g} s within "
                         f"(0, {n_steps * dt:g}] s; got {times[bad].tolist()}")
    return steps


def network_features(net, inputs, dt, times, cfg: ReadoutConfig = READOUT,
                     chunk: int = 250) -> dict[str, np.ndarray]:
    """Each feature kind of a frozen network at ``times``: ``{kind: (B, S, H) float32}``."""
    import torch

    steps = _steps(times, dt, inputs.shape[0])
    out = {k: [] for k in feature_kinds(cfg)}
    with torch.no_grad():
        for lo in range(0, inputs.shape[1], chunk):
            # the whole trajectory of each trial (the leaky averages need every step)
            _, _, h = net(torch.from_numpy(np.ascontiguousarray(inputs[:, lo:lo + chunk])))
            h = h.numpy()
            out["h"].append(h[steps].transpose(1, 0, 2))
            for tau in cfg.taus:
                out[f"leaky_{tau:g}"].append(
                    leaky_average(h, dt, tau)[steps].transpose(1, 0, 2))
    return {k: np.concatenate(v).astype(np.float32) for k, v in out.items()}


def _block_path(folder, key, split, block) -> Path:
    return Path(folder) / key / split / f"block_{block:05d}.npz"


def feature_key(name: str, net, world: str, cfg: ReadoutConfig = READOUT) -> str:
    """The cache folder of a network's features: ``<name>-<digest>``.

    The digest covers everything the stored numbers depend on (the network's parameters,
    the world, the times, the time constants and the block size), so a retrained network
    or another protocol never reads features of the old one.
    """
    import hashlib

    digest = hashlib.sha256()
    for k, v in sorted(net.state_dict().items()):
        digest.update(k.encode())
        digest.update(np.ascontiguousarray(v.detach().cpu().float().numpy()).tobytes())
    protocol = {"world": world, "fit_times": list(cfg.fit_times),
                "curve_times": list(cfg.curve_times), "taus": [str(t) for t in cfg.taus],
                "block": cfg.block}
    digest.update(json.dumps(protocol, sort_keys=True).encode())
    return f"{name}-{digest.hexdigest()[:12]}"


def extract_features(nets: dict, split: str, n_trials: int, folder, *, world: str,
                     cfg: ReadoutConfig = READOUT, progress: bool = True) -> dict:
    """Write the features of every network in ``nets`` on the first ``n_trials``
    specialized-task trials of ``split`` (world ``world``) under ``folder``; return
    ``{name: key}``, the cache folder of each (:func:`feature_key`).

    One file per network and block of ``cfg.block`` trials, written atomically and
    skipped when present: an interrupted extraction resumes where it stopped, and the
    trials of a block are simulated once for all networks. Blocks are always whole (the
    last may hold trials beyond ``n_trials``), so a later, larger request reuses them.
    """
    from tqdm.auto import tqdm

    from ..tasks import make_trials

    check_positive("n_trials", n_trials, integer=True)
    keys = {name: feature_key(name, net, world, cfg) for name, net in nets.items()}
    times = cfg.fit_times if split == "train" else cfg.curve_times
    n_blocks = -(-n_trials // cfg.block)
    for block in tqdm(range(n_blocks), desc=f"features {split}", unit="block",
                      disable=not progress):
        todo = {name: net for name, net in nets.items()
                if not _block_path(folder, keys[name], split, block).exists()}
        if not todo:
            continue
        batch = make_trials("specialized", cfg.block, split, 0, first=block * cfg.block,
                            world=world)
        for name, net in todo.items():
            feats = network_features(net, batch.inputs, batch.dt, times, cfg)
            with atomic_path(_block_path(folder, keys[name], split, block),
                             overwrite=True, what="features") as tmp:
                with open(tmp, "wb") as f:
                    np.savez(f, environment=batch.environment.astype(np.int16),
                             times=np.asarray(times), **feats)
    return keys


def load_features(folder, key: str, split: str, n_trials: int, kind: str,
                  cfg: ReadoutConfig = READOUT) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x (n_trials, S, H), labels (n_trials,), times (S,)) of one feature kind of the
    network whose cache folder is ``key`` (:func:`extract_features`)."""
    xs, ys, times = [], [], None
    for block in range(-(-n_trials // cfg.block)):
        path = _block_path(folder, key, split, block)
        if not path.exists():
            raise FileNotFoundError(f"features of {key!r} on {split} trials, block "
                                    f"{block}, are missing ({path}); extract them first")
        with np.load(path, allow_pickle=False) as f:
            xs.append(f[kind])
            ys.append(f["environment"])
            times = f["times"]
    x, y = np.concatenate(xs)[:n_trials], np.concatenate(ys)[:n_trials]
    return x, y.astype(np.int64), times


# ----------------------------------------------------------------------- fits
def accuracy_by_time(decoder, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Accuracy of ``decoder`` on trials ``x`` (N, S, H) at each of the S times."""
    n, s, h = x.shape
    pred = decoder.predict(x.reshape(n * s, h)).reshape(n, s)
    return (pred == y[:, None]).mean(axis=0)


def fit_path(x_train, y_train, x_val, y_val, val_times, cfg: ReadoutConfig = READOUT):
    """Fit along ``cfg.c_grid``; return (best decoder, its C, [path entries]).

    Each entry records C, the validation accuracy (the mean over the validation times
    within the fit times' range, late in the trial), the solver's iterations and whether
    it converged (with scikit-learn's report if not). The path runs in increasing C, each
    fit warm-started from the last converged one (the same optimum, fewer iterations), and
    stops once validation accuracy falls. A fit that did not converge is recorded but
    never chosen: its weights are not the optimum its C defines.
    """
    late = np.asarray(val_times) >= min(cfg.fit_times)
    n, s, h = x_train.shape
    x = x_train.reshape(n * s, h)
    y = np.repeat(y_train, s)
    best, best_c, best_acc, path, prev = None, None, -1.0, [], None
    for c in sorted(cfg.c_grid):
        model = fit_linear_decoder(x, y, c=c, max_iter=cfg.max_iter, tol=cfg.tol,
                                   warm_from=prev)
        acc = float(accuracy_by_time(model, x_val, y_val)[late].mean())
        path.append({"c": c, "validation_accuracy": acc, "n_iter": model.n_iter,
                     "converged": bool(model.converged)})
        if model.solver_message:
            path[-1]["solver_message"] = model.solver_message
        if not model.converged:
            continue
        if acc > best_acc:
            best, best_c, best_acc = model, c, acc
        elif acc < best_acc:
            break                      # past the optimum of the L2 strength
        prev = model
    if best is None:
        raise RuntimeError(f"no fit along C = {sorted(cfg.c_grid)} converged (max_iter = "
                           f"{cfg.max_iter}): {path}")
    return best, best_c, path


def learning_curve(folder, key: str, kinds, cfg: ReadoutConfig = READOUT,
                   sizes=None, progress: bool = True) -> dict:
    """The readout fitted at each training-set size for each feature kind.

    ``key`` is the network's cache folder (:func:`extract_features`). Returns a JSON-able
    dict: per kind and size, the L2 path on validation trials, the chosen C, test
    accuracy at every curve time, and the fitted decoder of the largest size (under
    ``"decoders"``, not JSON-able; popped by the caller).
    """
    sizes = sorted(set(cfg.sizes if sizes is None else sizes))
    for n in sizes:
        check_positive("sizes", n, integer=True)
    out = {"sizes": sizes, "kinds": {}, "decoders": {}}
    for kind in kinds:
        x_val, y_val, val_times = load_features(folder, key, "validation",
                                                cfg.n_validation, kind, cfg)
        x_test, y_test, test_times = load_features(folder, key, "test", cfg.n_test,
                                                   kind, cfg)
        rows = []
        for n in sizes:
            x_tr, y_tr, _ = load_features(folder, key, "train", n, kind, cfg)
            decoder, c, path = fit_path(x_tr, y_tr, x_val, y_val, val_times, cfg)
            del x_tr
            acc = accuracy_by_time(decoder, x_test, y_test)
            rows.append({"train_trials": n, "c": c, "path": path,
                         "test_accuracy": acc.tolist(),
                         "validation_accuracy_late": max(p["validation_accuracy"]
                                                         for p in path if p["converged"])})
            out["decoders"][kind] = decoder
            if progress:
                print(f"{key} {kind} {n} trials: C={c:g}, test accuracy at "
                      f"{test_times[-1]:g} s {acc[-1]:.3f}", flush=True)
        out["kinds"][kind] = {"rows": rows, "times": test_times.tolist()}
    return out


def readout_network(base_file, decoder, *, description: dict) -> dict:
    """A readout file's content: the decoder's weights (standardization folded in) as
    the arena classifier of the frozen network of ``base_file``.

    The file holds the classifier alone and names its network by the base file's name
    (``<name>[_seed<k>].pt``) and parameters' digest
    (:data:`~hippo_probe.model.load.READOUT_OF`); :func:`hippo_probe.load_pretrained`
    reads that network beside the readout file, or the shipped one, and refuses other
    parameters than those the readout was fitted on.
    """
    import torch

    from ..model.checkpoint import load
    from ..model.load import as_readout
    from ..pretrained import checkpoint_world
    from ..tasks import task_config

    base_file = Path(base_file)
    base = load(base_file)
    w, b = decoder_weights(decoder)
    classes = np.asarray(decoder.classes_)
    n_classes = task_config("specialized").n_arenas
    if classes.min() < 0 or classes.max() >= n_classes:
        raise ValueError(f"`decoder` classes must be arena ids 0..{n_classes - 1}; got "
                         f"{classes.min()}..{classes.max()}")
    # row e of the classifier is arena e; an arena absent from the training trials can
    # never be predicted (its logit far below any other)
    weight = np.zeros((n_classes, w.shape[1]), np.float32)
    bias = np.full(n_classes, -1e4, np.float32)
    weight[classes], bias[classes] = w, b
    state = {**(base.get("best_model") or base["model"]),
             "classifier.weight": torch.from_numpy(weight),
             "classifier.bias": torch.from_numpy(bias)}
    model_config = dict(base["model_config"], n_classes=n_classes)
    network = {"model": state, "model_config": model_config, "task": "specialized",
               "world": checkpoint_world(base), "config": description,
               "class_weight": None, "test": None, "steps_done": None, "finished": True,
               "base_network": {"file": base_file.name, "steps_done": base.get("steps_done"),
                                "finished": base.get("finished")}}
    return as_readout(network, base, base_file)


def readout_log(readout_file, row: dict, times, *, fit_seconds=None, command=None,
                previous: dict | None = None, n_test: int = 1000) -> dict:
    """The log shipped beside a convex readout (``<name>.log.json``), in the shape of a
    training log so that :mod:`hippo_probe.pretrained.summary` and the figures read it.

    ``test`` is measured anew: the readout file (``readout_file``, from
    :func:`readout_network`) runs on the specialized task's first ``n_test`` test trials
    through the trainer's own evaluation, so its accuracy is that of the shipped weights
    (it must equal the fit's ``row["test_accuracy"]`` on the same trials up to float32
    rounding) and its errors are the frozen network's. ``fit`` keeps the fit's record
    (training trials, C, the L2 path, the Fig. 3F curve at ``times``); ``config["steps"]``
    is None (no gradient steps). ``previous``, the log of the readout it replaces, is kept
    under ``replaces`` (a gradient-trained readout's steps and test metrics; what a
    convex one itself replaced).
    """
    from ..model.load import load_pretrained
    from ..tasks import make_trials
    from ..training.trainer import evaluate_network, summarize

    net = load_pretrained(readout_file)
    batch = make_trials("specialized", n_test, "test", 0, world=net.world)
    test = summarize(evaluate_network(net, batch), batch.dt)
    log = {"config": {**net.info["config"], "steps": None}, "world": net.world,
           "fit": {"train_trials": row["train_trials"], "c": row["c"], "path": row["path"],
                   "validation_accuracy_late": row["validation_accuracy_late"],
                   "times": [float(t) for t in times],
                   "test_accuracy": row["test_accuracy"]},
           "test": test, "steps_done": None, "finished": True, "wall_time_s": fit_seconds,
           "command": command, "base_network": net.info.get("base_network")}
    if previous is not None and "fit" in previous:   # a convex readout: keep its record
        log["replaces"] = previous.get("replaces")
    elif previous is not None:
        log["replaces"] = {"readout": "gradient-trained",
                           "steps_done": previous.get("steps_done"),
                           "stopped": previous.get("stopped"), "test": previous.get("test")}
    return log


def write_json(path, obj) -> None:
    write_text(Path(path), json.dumps(obj, indent=1), what="out")


def merge_results(old: dict, new: dict) -> dict:
    """``new`` fitted readouts added to ``old`` ones of the same network's features.

    A later run at another training-set size or of another feature kind extends the
    learning curve instead of replacing it: per kind, the rows of ``new`` replace those
    of ``old`` at the same size, the others are kept, sorted by size. Each row's L2 path
    records the strengths it tried, so rows fitted with different ``c_grid`` stay
    self-describing; ``config`` is the latest run's and ``runs`` lists every run's.
    Results of other features (another network, world or protocol) are refused.
    """
    if old.get("features") != new.get("features"):
        raise ValueError(f"cannot merge readouts of features {new.get('features')!r} into "
                         f"those of {old.get('features')!r}: another network or protocol")
    merged = {**old, **{k: v for k, v in new.items() if k != "kinds"}}
    kinds = {k: dict(v) for k, v in old["kinds"].items()}
    for kind, v in new["kinds"].items():
        rows = {r["train_trials"]: r for r in kinds.get(kind, {}).get("rows", [])}
        rows.update({r["train_trials"]: r for r in v["rows"]})
        kinds[kind] = {**v, "rows": [rows[n] for n in sorted(rows)]}
    merged["kinds"] = kinds
    merged["sizes"] = sorted({r["train_trials"] for v in kinds.values() for r in v["rows"]})
    merged["runs"] = [*old.get("runs", [{"config": old.get("config"),
                                        "fit_seconds": old.get("fit_seconds")}]),
                      {"config": new.get("config"), "fit_seconds": new.get("fit_seconds")}]
    merged["fit_seconds"] = sum(r["fit_seconds"] or 0 for r in merged["runs"])
    return merged


def seed_summary(results: list) -> str:
    """A Markdown table across networks (seeds): per world, feature kind and training-set
    size, the test accuracy at 100 s and 200 s as mean (min-max) and the number of
    networks.

    The variant's rows pool each network's chosen time constant (named per network in
    :func:`readout_table`)."""
    groups: dict = {}
    for res in results:
        chosen = (res.get("leaky_tau_choice") or {}).get("chosen")
        for kind, v in res["kinds"].items():
            if kind != "h" and kind != chosen:
                continue
            label = describe_kind("h") if kind == "h" else \
                "leaky average of h, tau chosen per network (variant)"
            times = v["times"]
            for row in v["rows"]:
                acc = row["test_accuracy"]
                groups.setdefault((res.get("world", ""), kind == "h", label,
                                   row["train_trials"]), []).append(
                    (acc[times.index(100.0)], acc[times.index(200.0)]))

    def spread(values):
        return f"{np.mean(values):.3f} ({min(values):.3f}–{max(values):.3f})"

    lines = ["| world | features | training trials | networks | accuracy at 100 s | "
             "accuracy at 200 s |", "| --- | --- | --- | --- | --- | --- |"]
    # per world: the study's readout first, then the variant, each by training-set size
    for key in sorted(groups, key=lambda g: (g[0], not g[1], g[3])):
        world, _, label, n = key
        a100, a200 = zip(*groups[key])
        lines.append(f"| {world} | {label} | {n:,} | {len(a100)} | {spread(a100)} | "
                     f"{spread(a200)} |")
    return "\n".join(lines) + "\n"


def readout_table(results: list) -> str:
    """A Markdown table of fitted readouts: per network, feature kind and training-set
    size, the chosen C and the test accuracy at 100 s and 200 s (the variant's time
    constant named; ``*`` marks the time constant chosen on validation trials)."""
    lines = ["| network | features | training trials | C | accuracy at 100 s | "
             "accuracy at 200 s |", "| --- | --- | --- | --- | --- | --- |"]
    for res in results:
        chosen = (res.get("leaky_tau_choice") or {}).get("chosen")
        for kind, v in res["kinds"].items():
            times = v["times"]
            i100, i200 = times.index(100.0), times.index(200.0)
            what = describe_kind(kind) + (" *" if kind == chosen else "")
            for row in v["rows"]:
                acc = row["test_accuracy"]
                lines.append(f"| {res['network']} | {what} | {row['train_trials']:,} | "
                             f"{row['c']:g} | {acc[i100]:.3f} | {acc[i200]:.3f} |")
    return "\n".join(lines) + "\n"


def plot_readout(results: list, *, study: float = 0.85, chance: float = 0.01):
    """The Fig. 3F curves of fitted readouts and their learning curves, as one Figure.

    ``results`` are :func:`learning_curve` outputs (with ``network`` and, for the
    variant, ``leaky_tau_choice``), one per network. Left: accuracy against time in trial
    of the study's readout (``h``, solid) and of the leaky-average variant (dashed), each
    at its largest training set. Right: accuracy at the last time against the number of
    training trials.
    """
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_n) = plt.subplots(1, 2, figsize=(9.5, 3.6))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, res in enumerate(results):
        color = colors[k % len(colors)]
        kinds = [("h", "-")]
        leaky = (res.get("leaky_tau_choice") or {}).get("chosen")
        if leaky:
            kinds.append((leaky, "--"))
        for kind, style in kinds:
            if kind not in res["kinds"]:
                continue
            what = describe_kind(kind)
            rows = res["kinds"][kind]["rows"]
            times = res["kinds"][kind]["times"]
            ax_t.plot(times, rows[-1]["test_accuracy"], style, color=color,
                      label=f"{res['network']}: {what}, {rows[-1]['train_trials']:,} trials")
            ax_n.plot([r["train_trials"] for r in rows],
                      [r["test_accuracy"][-1] for r in rows], style, marker="o",
                      color=color, label=f"{res['network']}: {what}")
    for ax in (ax_t, ax_n):
        ax.axhline(study, color="gray", ls=":", lw=1)
        ax.axhline(chance, color="gray", ls="-", lw=0.5)
        ax.set_ylim(0, 1)
        ax.set_ylabel("arena accuracy (test trials)")
    ax_t.text(5, study + 0.02, "the study, late in the trial", fontsize=7, color="gray")
    ax_t.set_xlabel("time in trial (s)")
    ax_t.set_title("F  readout of the frozen generalized network", fontsize=9)
    ax_n.set_xscale("log")
    # the sizes themselves as ticks: log-scale minor labels overlap at these ranges
    sizes = sorted({r["train_trials"] for res in results for v in res["kinds"].values()
                    for r in v["rows"]})
    ax_n.set_xticks(sizes, [f"{n:,}" for n in sizes])
    ax_n.xaxis.set_minor_formatter(plt.NullFormatter())
    ax_n.set_xlabel("training trials")
    ax_n.set_title(f"accuracy at {int(results[0]['kinds']['h']['times'][-1])} s vs "
                   "training-set size", fontsize=9)
    ax_n.legend(fontsize=5.5, loc="upper left")
    fig.tight_layout()
    return fig
