"""Which ingredient makes place fields and global remapping emerge? The scorecard per network.

Every network named is recorded on the same trials: ``--trials`` test trials in two fixed
arenas that none of them trained in (the first two of the specialized task's arenas,
started at the centre, so the generalized networks' start-relative estimate is in the
arena frame), and scored by :func:`hippo_probe.map_scorecard` (rules fixed in
``ScorecardConfig``), beside its localization error against the oracular particle filter
on ``--pf-trials`` generalized test trials, the median Skaggs information of its units as
spikes (``hp.poisson_spikes`` at 5 Hz) and the fraction of them in each class of
:func:`hippo_probe.classify_cells`, their TwoNN dimension, and the accuracy at 200 s of
the study's arena readout (Fig. 3F: a linear readout of the units fitted to convergence
on ``--readout-trials`` specialized-task trials, :mod:`hippo_probe.paper.readout`, the
same size for every network). The variants
(``generalized_nonneg``, ``generalized_dale``, ``generalized_placecells``) are departures
from the study; ``generalized`` is the study's network.

    python analyses/map_ingredients.py [--networks generalized ...] [--trials 120]
        [--pf-trials 200] [--readout-trials 4000] [--features cache/readout]
        [--out analyses/data/map_ingredients]

Writes ``<out>/scorecard.json``, ``scorecard.csv`` and ``map_ingredients.png`` (rate maps of
the same 16 units in the two arenas, per network).
"""

import argparse
import dataclasses
import json
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
from localization_vs_pf import errors, load, pf_estimate

import hippo_probe as hp
from hippo_probe._atomic import save_figure, write_text
from hippo_probe._threads import limit_threads
from hippo_probe.paper import readout as R
from hippo_probe.tasks import make_trials, task_config

ROOT = Path(__file__).resolve().parents[1]
MEAN_RATE_HZ = 5.0          # the mouse session's median firing rate, rounded
N_SHOWN = 16


def two_arena_trials(n_trials, world):
    """Test trials in the specialized task's first two arenas, started at the centre."""
    cfg = dataclasses.replace(task_config("specialized", world), n_arenas=2, classify=False)
    return make_trials("specialized", n_trials, "test", 0, config=cfg)


def arena_readout_accuracy(name, net, n_trials, folder):
    """Test accuracy at 200 s of the study's readout (units h, fitted to convergence on
    ``n_trials`` training trials; the L2 strength chosen on validation trials)."""
    cfg = dataclasses.replace(R.READOUT, sizes=(n_trials,), taus=())
    key = name.replace("/", "_").replace("@", "_seed")
    for split, n in (("validation", cfg.n_validation), ("test", cfg.n_test),
                     ("train", n_trials)):
        keys = R.extract_features({key: net}, split, n, folder, world=net.world, cfg=cfg,
                                  progress=False)
    curve = R.learning_curve(folder, keys[key], ["h"], cfg, progress=False)["kinds"]["h"]
    return curve["rows"][-1]["test_accuracy"][curve["times"].index(200.0)]


def cell_class_fractions(spikes):
    """The fraction of units in each class of :func:`hippo_probe.classify_cells` (a unit
    may be in several), on the units as spikes: noise-free activity beats every shuffle,
    so its classes would say nothing."""
    table = hp.classify_cells(spikes, seed=0)
    return {f"fraction_{name[3:]}": float(table[name].mean())
            for name in table.data_vars if name.startswith("is_")}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--networks", nargs="+", default=["generalized"],
                    help="shipped names (name@seed) or network files / run folders")
    ap.add_argument("--trials", type=int, default=120)
    ap.add_argument("--pf-trials", type=int, default=200)
    ap.add_argument("--readout-trials", type=int, default=4000,
                    help="training trials of the arena readout, the same for every network "
                         "(0: no readout, for a quick look)")
    ap.add_argument("--features", default=str(ROOT / "cache" / "readout"),
                    help="the readout's feature cache (resumable)")
    ap.add_argument("--out", default=str(ROOT / "analyses" / "data" / "map_ingredients"))
    a = ap.parse_args()
    limit_threads(1)          # one process per core: BLAS too, not only torch
    out = Path(a.out)
    rows, maps, pf = [], {}, {}
    for name in a.networks:
        t0 = time.time()
        net = load(name)
        if net.world not in pf:          # one particle filter per world, for every network
            batch = make_trials("generalized", a.pf_trials, "test", 0,
                                config=task_config("generalized", net.world))
            pf[net.world] = batch, pf_estimate(batch)
        variant = (net.info.get("config") or {}).get("variant", "faithful")
        rec = hp.record(net, two_arena_trials(a.trials, net.world))
        card = hp.map_scorecard(rec, bin_size=0.03)
        spikes = hp.poisson_spikes(rec, MEAN_RATE_HZ, seed=0)
        info = hp.spatial_information(spikes, bin_size=0.03, n_shuffles=0)
        dim = hp.intrinsic_dimension(rec, estimators="TwoNN")
        row = {"network": name, "variant": variant,
               "departure_from_study": variant != "faithful",
               "error_over_pf_after_100s":
                   errors(net, *pf[net.world])["ratio_to_pf_t_gt_100s"],
               **{k: float(card[k]) for k in card.data_vars if card[k].ndim == 0},
               "place_fields": card.attrs["place_fields"],
               "global_remapping": card.attrs["global_remapping"],
               "median_information_bits_per_spike": float(info.information.median()),
               **cell_class_fractions(spikes),
               "twonn_dimension": float(dim.dimension.sel(estimator="TwoNN")),
               "arena_readout_accuracy_200s": arena_readout_accuracy(
                   name, net, a.readout_trials, a.features) if a.readout_trials else None,
               "seconds": round(time.time() - t0)}
        rows.append(row)
        maps[name] = hp.ratemaps(rec, bin_size=0.03, by="environment")
        print(json.dumps(row), flush=True)
    out.mkdir(parents=True, exist_ok=True)
    write_text(out / "scorecard.json", json.dumps(
        {"trials": a.trials, "pf_trials": a.pf_trials, "readout_trials": a.readout_trials,
         "rules": card.attrs["place_rule"]
         + "; " + card.attrs["remapping_rule"], "rows": rows}, indent=1), what="out")
    keys = list(rows[0])
    write_text(out / "scorecard.csv", "\n".join(
        [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n",
        what="out")
    fig, axes = plt.subplots(2 * len(maps), N_SHOWN, figsize=(N_SHOWN * 0.9,
                                                               2 * len(maps) * 0.95),
                             squeeze=False)
    for k, (name, m) in enumerate(maps.items()):
        for e in range(2):
            for u in range(N_SHOWN):
                ax = axes[2 * k + e, u]
                ax.imshow(m.isel(unit=u, environment=e).values, origin="lower",
                          cmap="viridis")
                ax.set_xticks([])
                ax.set_yticks([])
                if u == 0:
                    label = Path(name).name if Path(name).exists() else name
                    ax.set_ylabel(f"{label}\narena {e}", fontsize=6)
    fig.suptitle("rate maps of units 0-15 in two arenas (rows), per network", fontsize=8)
    save_figure(fig, out / "map_ingredients.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
