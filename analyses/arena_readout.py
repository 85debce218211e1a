"""Fit the arena readout of the frozen generalized networks to convergence (Fig. 3F).

The protocol is :mod:`hippo_probe.paper.readout`'s: features of each frozen network on
specialized-task trials, a multinomial logistic regression (L2 strength chosen on
validation trials) at each training-set size, scored on test trials every 10 s. The
study's readout reads the units ``h``; the variant (labelled as one) reads a leaky
average of them, its time constant chosen on validation trials at ``--tau-size`` trials
and ``C = --tau-c``, then fitted like the study's readout.

    python analyses/arena_readout.py [--world darkness] [--seeds 0 1 2]
        [--sizes 4000 16000 64000] [--c-grid 0.01 0.1 1 10] [--features cache/readout]
        [--out analyses/data/arena_readout] [--export hippo_probe/pretrained]

The arena probe of a training run along its steps (its snapshots, 2,000 training trials):

    python analyses/arena_readout.py --networks runs/RUN/snapshots/step_*.pt
        --sizes 2000 --tau-size 2000 --out analyses/data/arena_probe_steps

Writes ``<out>/<network>_seed<k>.json`` (learning curves, L2 paths, test curves; a later
run of other sizes or kinds on the same features is added to it) and,
with ``--export``, the study's readout at the largest size as
``<export>/generalized_readout[_seed<k>].pt`` (the compass world's as
``generalized_compass_readout.pt``).
"""

import argparse
import json
import sys
import time
from dataclasses import asdict, replace
from pathlib import Path

import hippo_probe as hp
from hippo_probe._threads import limit_threads
from hippo_probe.model.checkpoint import save_atomic
from hippo_probe.paper import readout as R
from hippo_probe.paper.config import network_name

ROOT = Path(__file__).resolve().parents[1]


def shipped_name(base: str, seed: int) -> str:
    return base if seed == 0 else f"{base}_seed{seed}"


def ship_log(file: Path, res: dict, row: dict, folder, target: str,
             command: str | None = None) -> None:
    """Write ``<target>.log.json`` beside the exported readout ``file``: the fit's record
    and its test metrics measured anew (:func:`~hippo_probe.paper.readout.readout_log`),
    keeping the log of the readout it replaces in ``folder`` (or the shipped one)."""
    from hippo_probe._atomic import write_text
    from hippo_probe.pretrained import HERE

    old = next((p for p in (Path(folder) / f"{target}.log.json", HERE / f"{target}.log.json")
                if p.exists()), None)
    previous = json.loads(old.read_text()) if old else None
    h = res["kinds"]["h"]
    log = R.readout_log(file, row, h["times"], fit_seconds=res.get("fit_seconds"),
                        command=command or ("python analyses/arena_readout.py "
                                            + " ".join(sys.argv[1:])),
                        previous=previous)
    write_text(Path(folder) / f"{target}.log.json", json.dumps(log, indent=1), what="export")


def earlier_tau_choice(before, key: str, tau_size: int, tau_c: float, cfg):
    """The variant's time constant as an earlier run chose it on these features, at the
    same size and C among the same candidates (the scan is then not repeated), or None."""
    choice = (before or {}).get("leaky_tau_choice")
    if (choice is None or before.get("features") != key
            or choice["train_trials"] != tau_size or choice["c"] != tau_c
            or set(choice["validation_accuracy_late"]) != set(R.feature_kinds(cfg)[1:])):
        return None
    return choice


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", default="darkness", choices=("darkness", "compass"))
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--networks", nargs="+", default=None, metavar="FILE",
                    help="network files to read instead of the shipped generalized "
                         "networks (e.g. a run's snapshots/step_*.pt; named by the run "
                         "folder and the file's name)")
    ap.add_argument("--sizes", type=int, nargs="+", default=list(R.READOUT.sizes))
    ap.add_argument("--taus", type=float, nargs="+", default=list(R.READOUT.taus),
                    help="time constants (s) of the leaky-average variant tried "
                         "('inf': the running mean)")
    ap.add_argument("--tau-size", type=int, default=4000,
                    help="training trials at which the variant's time constant is chosen")
    ap.add_argument("--tau-c", type=float, default=1.0,
                    help="the L2 strength C at which the time constant is chosen")
    ap.add_argument("--c-grid", type=float, nargs="+", default=list(R.READOUT.c_grid),
                    help="inverse L2 strengths tried, in increasing order (default: the "
                         "protocol's; a narrower grid for the largest sizes, whose fits "
                         "take hours, e.g. the two best at the size below)")
    ap.add_argument("--kinds", nargs="+", default=["h", "leaky"],
                    choices=("h", "leaky"))
    ap.add_argument("--features", default=str(ROOT / "cache" / "readout"))
    ap.add_argument("--out", default=str(ROOT / "analyses" / "data" / "arena_readout"))
    ap.add_argument("--export", default=None, metavar="FOLDER")
    ap.add_argument("--extract-only", action="store_true",
                    help="only write the features (to fit later, e.g. on another core)")
    ap.add_argument("--threads", type=int, default=1,
                    help="threads of the network's forward pass and of the fits' BLAS "
                         "(default 1: one process per core, e.g. one per seed)")
    ap.add_argument("--no-progress", action="store_true")
    ap.add_argument("--plot-only", action="store_true",
                    help="only draw <out>/arena_readout.png and tabulate arena_readout.md "
                         "from the JSON files in --out")
    a = ap.parse_args()
    if a.export and a.networks:
        ap.error("--export ships the shipped networks' readouts; it cannot be combined "
                 "with --networks")
    if a.plot_only:
        from hippo_probe._atomic import save_figure, write_text

        files = sorted(Path(a.out).glob("*.json"))
        results = [json.loads(f.read_text()) for f in files]
        fig = R.plot_readout(results)
        save_figure(fig, Path(a.out) / "arena_readout.png", dpi=130)
        write_text(Path(a.out) / "arena_readout.md",
                   R.readout_table(results) + "\nAcross networks:\n\n"
                   + R.seed_summary(results), what="out")
        print(f"saved {Path(a.out) / 'arena_readout.png'} and arena_readout.md from "
              f"{len(files)} networks")
        return
    limit_threads(a.threads)
    cfg = replace(R.READOUT, sizes=tuple(sorted(set(a.sizes))), taus=tuple(a.taus),
                  c_grid=tuple(sorted(set(a.c_grid))))
    base = network_name("generalized", a.world)
    if a.networks:
        nets = {f"{Path(f).resolve().parents[1].name}_{Path(f).stem}": hp.load_pretrained(f)
                for f in a.networks}
    else:
        nets = {shipped_name(base, s): hp.load_pretrained(base, seed=s) for s in a.seeds}
    for net in nets.values():
        net.eval()
    t0 = time.time()
    n_train = max(max(cfg.sizes), a.tau_size if "leaky" in a.kinds else 0)
    for split, n in (("validation", cfg.n_validation), ("test", cfg.n_test),
                     ("train", n_train)):
        keys = R.extract_features(nets, split, n, a.features, world=a.world, cfg=cfg,
                                  progress=not a.no_progress)
    print(f"features: {time.time() - t0:.0f} s", flush=True)
    if a.extract_only:
        return
    for name, net in nets.items():
        t1, key = time.time(), keys[name]
        out_file = Path(a.out) / f"{name}.json"
        before = json.loads(out_file.read_text()) if out_file.exists() else None
        res = R.learning_curve(a.features, key, ["h"] if "h" in a.kinds else [], cfg)
        decoders = res.pop("decoders")
        if "leaky" in a.kinds:
            choice = earlier_tau_choice(before, key, a.tau_size, a.tau_c, cfg)
            if choice is None:
                # the time constant is chosen at one size and one C (each fit of the
                # scan is as costly as the study's readout), then fitted along the C grid
                scan = R.learning_curve(a.features, key, R.feature_kinds(cfg)[1:],
                                        replace(cfg, c_grid=(a.tau_c,)),
                                        sizes=(a.tau_size,))
                scan.pop("decoders")
                at = {k: v["rows"][-1]["validation_accuracy_late"]
                      for k, v in scan["kinds"].items()}
                choice = {"train_trials": a.tau_size, "c": a.tau_c,
                          "validation_accuracy_late": at, "chosen": max(at, key=at.get)}
            else:
                print(f"{key}: time constant chosen before on the same features and "
                      f"candidates: {choice['chosen']}", flush=True)
            res["leaky_tau_choice"] = choice
            chosen = R.learning_curve(a.features, key, [choice["chosen"]], cfg)
            chosen.pop("decoders")
            res["kinds"].update(chosen["kinds"])
        res.update(network=name, features=key, world=a.world,
                   config=dict(asdict(cfg), taus=[str(t) for t in cfg.taus]),
                   fit_seconds=round(time.time() - t1))
        if before is not None:
            # another size or kind of the same features extends the learning curve
            res = R.merge_results(before, res)
            print(f"added to {out_file}", flush=True)
        R.write_json(out_file, res)
        if a.export and "h" in decoders:
            seed = int(name.rsplit("seed", 1)[1]) if "_seed" in name else 0
            # the decoder is this run's largest size (the merged results may hold others)
            row = next(r for r in res["kinds"]["h"]["rows"]
                       if r["train_trials"] == max(cfg.sizes))
            target = shipped_name(f"{base}_readout", seed)
            desc = {"task": "specialized", "world": a.world, "train_only": "classifier",
                    "init_from": name, "readout": "convex", "features": "h",
                    "fit_times_s": list(cfg.fit_times),
                    "train_trials": row["train_trials"],
                    "c": row["c"],
                    "precision": "fp32"}
            file = Path(a.export) / f"{target}.pt"
            save_atomic(R.readout_network(net.info["file"], decoders["h"],
                                          description=desc), file)
            ship_log(file, res, row, a.export, target)
            print(f"exported {target}", flush=True)


if __name__ == "__main__":
    main()
