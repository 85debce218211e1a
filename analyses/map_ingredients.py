"""Which ingredient makes place fields and global remapping emerge? The scorecard per network.

Every network named is recorded on the same trials: ``--trials`` test trials in two fixed
arenas that none of them trained in (the first two of the specialized task's arenas,
started at the centre, so the generalized networks' start-relative estimate is in the
arena frame; at least ``--min-per-arena`` trials in each, the default 140 giving 80 and
60), and scored by :func:`hippo_probe.map_scorecard` (rules fixed in
``ScorecardConfig``), beside its localization error against the oracular particle filter
on ``--pf-trials`` generalized test trials, the median Skaggs information of its units as
spikes (``hp.poisson_spikes`` at 5 Hz) and the fraction of them in each class of
:func:`hippo_probe.classify_cells`, their TwoNN dimension, and the accuracy at 200 s of
the study's arena readout (Fig. 3F: a linear readout of the units fitted to convergence
on ``--readout-trials`` specialized-task trials, :mod:`hippo_probe.paper.readout`, the
same size for every network). The variants
(``generalized_nonneg``, ``generalized_dale``, ``generalized_placecells``) are departures
from the study; ``generalized`` is the study's network and ``generalized_faithful`` the
same trained the variants' 20,000 steps.

    python analyses/map_ingredients.py [--networks generalized ...] [--trials 140]
        [--min-per-arena 60] [--pf-trials 1000] [--readout-trials 1000]
        [--features cache/readout]
        [--out analyses/data/map_ingredients]

A network named at several seeds (``generalized_nonneg@1``, ...) gets each seed's row and
a summary across them: each measure's mean and range, each verdict's count of seeds.

Writes ``<out>/scorecard.json``, ``scorecard.csv`` (every measure), ``scorecard.md`` (the
headline measures as a Markdown table, and across seeds where given) and
``map_ingredients.png`` (per network, its first seed's rate maps of its 16 most spatially
informative units in the two arenas, and its scorecard beside them).
"""

import argparse
import dataclasses
import functools
import hashlib
import json
import time
import warnings
import zipfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from localization_vs_pf import errors, load, pf_estimate

import hippo_probe as hp
from hippo_probe._atomic import atomic_path, save_figure, write_text
from hippo_probe._threads import limit_threads
from hippo_probe.paper import readout as R
from hippo_probe.paper.config import code_version
from hippo_probe.tasks import make_trials, task_config

ROOT = Path(__file__).resolve().parents[1]
MEAN_RATE_HZ = 5.0          # the mouse session's median firing rate, rounded
N_SHOWN = 16


def two_arena_trials(n_trials, world, min_per_arena):
    """Test trials in the specialized task's first two arenas, started at the centre (each
    trial's arena drawn at random); refused if an arena gets fewer than ``min_per_arena``."""
    cfg = dataclasses.replace(task_config("specialized", world), n_arenas=2, classify=False)
    batch = make_trials("specialized", n_trials, "test", 0, config=cfg)
    per_arena = np.bincount(np.asarray(batch.environment), minlength=2)
    if per_arena.min() < min_per_arena:
        raise SystemExit(f"--trials {n_trials} gives {per_arena.tolist()} trials in the two "
                         f"arenas; --min-per-arena asks for at least {min_per_arena} in each")
    return batch


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


def most_informative_units(information, n):
    """Indices (ascending) of the ``n`` units with the most spatial information; a silent
    unit (NaN) comes last. The most informative are not the typical units: compare the
    scorecard's medians over all active units."""
    order = np.argsort(np.nan_to_num(information, nan=-np.inf), kind="stable")[::-1]
    return np.sort(order[:n])


#: The scorecard's headline measures, printed beside each network's maps and as the
#: columns of ``scorecard.md``: (label, key, format).
SCORE_LINES = (("steps", "steps", "{:,}"),
               ("error / PF after 100 s", "error_over_pf_after_100s", "{:.2f}"),
               ("place-like units", "fraction_place_like", "{:.2f}"),
               ("median field area (m²)", "median_field_area", "{:.3f}"),
               ("map corr. within", "within_map_correlation", "{:.2f}"),
               ("map corr. across", "across_map_correlation", "{:.2f}"),
               ("pop. vector corr. across", "population_vector_correlation", "{:.2f}"),
               ("silent units", "fraction_silent", "{:.2f}"),
               ("active in one arena only", "fraction_active_in_one_environment", "{:.3f}"),
               ("bits / spike (median)", "median_information_bits_per_spike", "{:.3f}"),
               ("TwoNN dimension", "twonn_dimension", "{:.1f}"),
               ("arena readout at 200 s", "arena_readout_accuracy_200s", "{:.3f}"),
               ("place fields", "place_fields", "{}"),
               ("global remapping", "global_remapping", "{}"))


def score_text(row, key, fmt):
    """One measure of a scorecard row as text: "—" if not measured or undefined (no unit
    with a field has no median field area), verdicts as yes/no."""
    value = row[key]
    if value is None or (isinstance(value, float) and np.isnan(value)):
        return "—"
    return "yes" if value is True else "no" if value is False else fmt.format(value)


def markdown_table(rows):
    """The scorecard's headline measures, one row per network, as a Markdown table."""
    lines = ["| network (variant) | " + " | ".join(h for h, _, _ in SCORE_LINES) + " |",
             "|---" * (len(SCORE_LINES) + 1) + "|"]
    for row in rows:
        name = Path(row["network"]).name if Path(row["network"]).exists() else row["network"]
        lines.append(f"| `{name}` ({row['variant']}) | "
                     + " | ".join(score_text(row, k, f) for _, k, f in SCORE_LINES) + " |")
    return "\n".join(lines) + "\n"


def network_of(name):
    """The network a scorecard row is a seed of: ``name@k`` -> ``name``; a file or run
    folder is its own network."""
    return name if Path(name).exists() else name.partition("@")[0]


def check_distinct(names):
    """Refuse a network named twice (``name`` is ``name@0``: seed 0 is the default)."""
    seen = {}
    for name in names:
        seed = "" if Path(name).exists() else (name.partition("@")[2] or "0")
        key = (network_of(name), int(seed) if seed.isdigit() else seed)
        if key in seen:
            raise SystemExit(f"--networks names one network twice: {seen[key]!r} and "
                             f"{name!r}")
        seen[key] = name


def across_seeds(rows):
    """Per network given at two or more seeds: each headline measure's mean, minimum and
    maximum over the seeds (NaN and unmeasured values left out), and each verdict's
    count of seeds that reach it."""
    groups = {}
    for row in rows:
        groups.setdefault(network_of(row["network"]), []).append(row)
    out = {}
    for network, group in groups.items():
        if len(group) < 2:
            continue
        summary = {"seeds": [r["network"] for r in group]}
        for _, key, _ in SCORE_LINES:
            values = [r[key] for r in group]
            if all(isinstance(v, bool) for v in values):
                summary[key] = {"yes": sum(values), "of": len(values)}
                continue
            numbers = [v for v in values if v is not None and np.isfinite(v)]
            if not numbers:
                summary[key] = None
                continue
            mean = float(np.mean(numbers))
            if all(isinstance(v, int) for v in numbers) and mean.is_integer():
                mean = int(mean)                # steps stay a count
            summary[key] = {"mean": mean, "min": min(numbers), "max": max(numbers),
                            "n": len(numbers)}
        out[network] = summary
    return out


def seeds_table(summary):
    """:func:`across_seeds` as a Markdown table: mean (min–max) over the seeds, verdicts
    as the number of seeds that reach them."""
    lines = ["| network | seeds | " + " | ".join(h for h, _, _ in SCORE_LINES) + " |",
             "|---" * (len(SCORE_LINES) + 2) + "|"]
    for network, by_key in summary.items():
        cells = []
        for _, key, fmt in SCORE_LINES:
            v = by_key[key]
            if v is None:
                cells.append("—")
            elif "yes" in v:
                cells.append(f"{v['yes']} of {v['of']}")
            else:
                cells.append(fmt.format(v["mean"]) + (
                    "" if v["min"] == v["max"] else
                    f" ({fmt.format(v['min'])}–{fmt.format(v['max'])})"))
        lines.append(f"| `{network}` | {len(by_key['seeds'])} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def scorecard_figure(maps, shown, rows, n_seeds=None):
    """Per network two rows of rate maps (its ``N_SHOWN`` most informative units, the
    same units in arena 0 and arena 1, each unit's colours spanning its range over both
    arenas) and its scorecard beside them."""
    fig = plt.figure(figsize=(N_SHOWN * 0.75 + 3.2, 1.9 * len(maps) + 0.5),
                     layout="constrained")
    grid = fig.add_gridspec(2 * len(maps), N_SHOWN + 1,
                            width_ratios=[1] * N_SHOWN + [4.2])
    for k, ((name, m), row) in enumerate(zip(maps.items(), rows)):
        label = Path(name).name if Path(name).exists() else name
        for u_pos, (unit, pair) in enumerate(zip(shown[name], m, strict=True)):
            low, top = float(np.nanmin(pair)), float(np.nanmax(pair))
            if not low < top:           # a silent unit: any range shows it flat
                low, top = 0.0, 1.0
            for e in range(2):
                ax = fig.add_subplot(grid[2 * k + e, u_pos])
                ax.imshow(pair[e], origin="lower",
                          cmap="viridis", vmin=low, vmax=top)
                ax.set_xticks([])
                ax.set_yticks([])
                if e == 0:
                    ax.set_title(f"{int(unit)}", fontsize=6, pad=1)
                if u_pos == 0:
                    ax.set_ylabel(f"arena {e}", fontsize=6)
        text = fig.add_subplot(grid[2 * k:2 * k + 2, N_SHOWN])
        text.axis("off")
        lines = [f"{label} ({row['variant']}"
                 + (", a departure)" if row["departure_from_study"] else ", the study's)")]
        given = (n_seeds or {}).get(network_of(name), 1)
        if given > 1:
            lines[0] += f", the first of {given} seeds"
        lines += [f"{what:<25}" + score_text(row, key, fmt)
                  for what, key, fmt in SCORE_LINES]
        text.text(0.0, 1.0, "\n".join(lines), va="top", ha="left", family="monospace",
                  fontsize=6, transform=text.transAxes)
    fig.suptitle(f"each network's {N_SHOWN} most spatially informative units (numbered; "
                 f"information of their 5 Hz Poisson spikes, both arenas pooled), the same "
                 f"units in two arenas; colours span each unit's range over both",
                 fontsize=8)
    return fig


@functools.cache
def code_digest():
    """A digest of the code a scorecard row depends on: the package's sources
    (``code_version``) and the scripts that score, so a cached row is never read by other
    code. Read once per process: a run names what it writes by the code it loaded."""
    digest = hashlib.sha256(code_version().encode())
    for path in (Path(__file__).resolve(), ROOT / "analyses" / "localization_vs_pf.py"):
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


def cache_file(cache, name, file_digest, options):
    """The cache file of a network's row: a readable prefix of its name, then a digest of
    the whole name, its file's digest and the options (names differing only in the
    characters the prefix drops, or very long paths, cannot collide or overflow)."""
    key = hashlib.sha256(f"{name}\0{file_digest}\0{options}".encode()).hexdigest()[:20]
    prefix = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[-40:]
    return Path(cache) / f"{prefix}-{key}.npz"


def keep(path, save, *args, **kwargs):
    """Write a NumPy file into the cache with ``save`` (``np.save``, ``np.savez``)
    atomically: a run stopped midway leaves no half-written file to be read later."""
    with atomic_path(path, overwrite=True, what="--cache") as tmp, open(tmp, "wb") as f:
        save(f, *args, **kwargs)


def read_cached(path, name):
    """A cached row, its shown units, their maps and the rules; None (with a warning)
    where the file cannot be read, so the row is computed again."""
    try:
        with np.load(path, allow_pickle=False) as kept:
            row, rules = json.loads(str(kept["row"])), str(kept["rules"])
            units, maps = kept["units"], kept["maps"]
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as err:
        warnings.warn(f"the cached scorecard row {path} cannot be read ({err}); "
                      f"computing it again", stacklevel=2)
        return None
    row["network"] = name
    return row, units, maps, rules


def score(name, net, a, arenas, reference):
    """One network's scorecard row, its ``N_SHOWN`` most informative units, their rate
    maps in the two arenas (unit, environment, y, x) and the scorecard's verdict rules."""
    t0 = time.time()
    config = net.info.get("config") or {}
    variant = config.get("variant", "faithful")
    rec = hp.record(net, arenas)
    card = hp.map_scorecard(rec, bin_size=0.03)
    spikes = hp.poisson_spikes(rec, MEAN_RATE_HZ, seed=0)
    with warnings.catch_warnings():
        # both arenas pooled on purpose: the scorecard's information and the units
        # the figure shows are the pooled maps' (its title says so)
        warnings.filterwarnings("ignore", "the recording spans", hp.AnalysisWarning)
        info = hp.spatial_information(spikes, bin_size=0.03, n_shuffles=0)
    dim = hp.intrinsic_dimension(rec, estimators="TwoNN")
    row = {"network": name, "variant": variant,
           "departure_from_study": variant != "faithful",
           "steps": net.info.get("steps_done") or config.get("steps"),
           "error_over_pf_after_100s":
               errors(net, *reference(net.world))["ratio_to_pf_t_gt_100s"],
           **{k: float(card[k]) for k in card.data_vars if card[k].ndim == 0},
           "place_fields": card.attrs["place_fields"],
           "global_remapping": card.attrs["global_remapping"],
           "median_information_bits_per_spike": float(info.information.median()),
           **cell_class_fractions(spikes),
           "twonn_dimension": float(dim.dimension.sel(estimator="TwoNN")),
           "arena_readout_accuracy_200s": arena_readout_accuracy(
               name, net, a.readout_trials, a.features) if a.readout_trials else None,
           "seconds": round(time.time() - t0)}
    units = most_informative_units(info.information.values, N_SHOWN)
    maps = hp.ratemaps(rec, bin_size=0.03, by="environment").isel(unit=units)
    rules = card.attrs["place_rule"] + "; " + card.attrs["remapping_rule"]
    return row, units, maps.transpose("unit", "environment", "y", "x").values, rules


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--networks", nargs="+", default=["generalized"],
                    help="shipped names (name@seed) or network files / run folders")
    ap.add_argument("--trials", type=int, default=140)
    ap.add_argument("--min-per-arena", type=int, default=60,
                    help="trials each arena's rate maps need at least (refused if fewer)")
    ap.add_argument("--pf-trials", type=int, default=1000)
    ap.add_argument("--readout-trials", type=int, default=1000,
                    help="training trials of the arena readout, the same for every network "
                         "(0: no readout, for a quick look)")
    ap.add_argument("--features", default=str(ROOT / "cache" / "readout"),
                    help="the readout's feature cache (resumable)")
    ap.add_argument("--cache", default=str(ROOT / "cache" / "map_ingredients"),
                    help="each network's row and shown maps, and the particle filter's "
                         "estimate, kept so that a rerun computes only what is new to it "
                         "(keyed by the network file's digest, the trial options and a "
                         "digest of the code, so a row is never read by other code)")
    ap.add_argument("--out", default=str(ROOT / "analyses" / "data" / "map_ingredients"))
    a = ap.parse_args()
    check_distinct(a.networks)
    limit_threads(1)          # one process per core: BLAS too, not only torch
    out = Path(a.out)
    cache = Path(a.cache)
    options = (f"t{a.trials}-m{a.min_per_arena}-p{a.pf_trials}-r{a.readout_trials}"
               f"-code{code_digest()}")
    rows, maps, shown, pf, arenas = [], {}, {}, {}, {}

    def reference(world):
        """The oracular particle filter on the world's generalized test trials, made once
        (and kept in the cache: the same trials and filter for every network)."""
        if world not in pf:
            batch = make_trials("generalized", a.pf_trials, "test", 0,
                                config=task_config("generalized", world))
            path = cache / f"pf-{world}-{a.pf_trials}-code{code_digest()}.npy"
            if path.exists():
                estimate = np.load(path, allow_pickle=False)
                print(f"particle filter estimate: from {path}", flush=True)
            else:
                estimate = np.asarray(pf_estimate(batch))
                keep(path, np.save, estimate, allow_pickle=False)
            pf[world] = batch, estimate
        return pf[world]

    for name in a.networks:
        net = load(name)
        if net.world not in arenas:
            arenas[net.world] = two_arena_trials(a.trials, net.world, a.min_per_arena)
        digest = hashlib.sha256(Path(net.info["file"]).read_bytes()).hexdigest()
        path = cache_file(cache, name, digest, options)
        kept = read_cached(path, name) if path.exists() else None
        if kept is not None:
            row, shown[name], maps[name], rules = kept
            print(f"{name}: from {path}", flush=True)
        else:
            row, shown[name], maps[name], rules = score(name, net, a, arenas[net.world],
                                                        reference)
            keep(path, np.savez, row=np.array(json.dumps(row)), units=shown[name],
                 maps=maps[name], rules=np.array(rules))
        rows.append(row)
        print(json.dumps(row), flush=True)
    out.mkdir(parents=True, exist_ok=True)
    per_arena = np.bincount(np.asarray(next(iter(arenas.values())).environment)).tolist()
    seeds = across_seeds(rows)
    write_text(out / "scorecard.json", json.dumps(
        {"trials": a.trials, "trials_per_arena": per_arena, "pf_trials": a.pf_trials,
         "readout_trials": a.readout_trials,
         "rules": rules, "rows": rows, "across_seeds": seeds},
        indent=1), what="out")
    keys = list(rows[0])
    write_text(out / "scorecard.csv", "\n".join(
        [",".join(keys)] + [",".join(str(r[k]) for k in keys) for r in rows]) + "\n",
        what="out")
    write_text(out / "scorecard.md", markdown_table(rows) + (
        "\nAcross seeds: mean (min–max); verdicts, the seeds that reach them.\n\n"
        + seeds_table(seeds) if seeds else ""), what="out")
    # one seed of each network in the figure (its first given): the maps of every seed
    # would not fit a page
    first = {}
    for row in rows:
        first.setdefault(network_of(row["network"]), row)
    drawn = [row["network"] for row in first.values()]
    fig = scorecard_figure({n: maps[n] for n in drawn}, shown, list(first.values()),
                           n_seeds={k: len(v["seeds"]) for k, v in seeds.items()})
    save_figure(fig, out / "map_ingredients.png", dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
