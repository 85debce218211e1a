"""Which of the brain's cell types emerge in networks trained to navigate? Cell classes of
every shipped network beside a real mouse session, with the same calls.

Each network is recorded in one arena (its task's arena; the generalized and specialized
networks in one fixed arena of their task, so that walls and maps are those of one
environment, as in an open-field session), on ``--trials`` test trials; the mouse session
is tests/data/A2929-200711.nwb (ADn head-direction cells and CA1 cells), imported with
``hippo_probe.from_nwb``. ``hippo_probe.classify_cells`` gives every unit's grid, border,
place, head-direction, speed and conjunctive scores against time-shift shuffles; the
figure shows the fraction of units in each class, side by side.

The networks' units are noise-free: with ~100,000 samples any tuning at all beats the
shuffles, so on their activity as recorded almost every unit passes almost every test.
Each network is therefore also classified as spikes (``hippo_probe.poisson_spikes``: each
unit's activity, minus its minimum, as a Poisson rate whose mean is the mouse session's
median firing rate) over the first whole trials that cover the mouse session's duration
(600 s of trials for its 530 s): about the same counting noise and power as the mouse's
cells. Every network unit gets the median rate, while the mouse's units range from 0.2
to 20 Hz. It also times
``classify_cells`` on one network's 256 units beside opexebo's grid and border scores on
the same rate maps (opexebo has no shuffles: its time is for the observed maps only).

    python analyses/cell_classes.py [--networks NAME ...] [--trials 200] [--shuffles 100]
                                    [--opexebo-units 256] [--out figures/]

``--networks`` defaults to every shipped network (both worlds, readout variants aside:
they share their base network's units). Writes ``cell_classes.png/.pdf``,
``cell_classes.md`` (the table) and ``cell_classes.json`` (every number) to ``--out``.
"""

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import hippo_probe as hp  # noqa: E402
from hippo_probe._atomic import save_figure, write_text  # noqa: E402
from hippo_probe.analysis import AnalysisWarning  # noqa: E402
from hippo_probe.paper.config import jsonable  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
SESSION = ROOT / "tests" / "data" / "A2929-200711.nwb"
#: The shipped networks whose units are their own (readout variants share them).
CANDIDATES = ("localization", "generalized", "specialized",
              "localization_compass", "generalized_compass", "specialized_compass")
#: One fixed arena per task, so every recording is one environment.
ONE_ARENA = {"localization": {}, "generalized": {"arenas": "fixed", "n_arenas": 1},
             "specialized": {"n_arenas": 1}}
CLASSES = ("grid", "border", "place", "head_direction", "speed", "conjunctive")
BIN_ANIMAL = 0.04     # m: the mouse's arena is ~0.55 x 0.75 m (14 x 19 bins)
REGIONS = {"adn": "ADn", "ca1": "CA1"}
SEED = 0


def shipped_networks():
    from hippo_probe.pretrained import available
    shipped = set(available())
    return [n for n in CANDIDATES if n in shipped]


def record_network(name, n_trials):
    """A recording of the shipped network ``name`` in one arena of its task."""
    import torch

    from hippo_probe.tasks import make_trials, task_config

    torch.set_num_threads(int(os.environ.get("OMP_NUM_THREADS", "1")))
    net = hp.load_pretrained(name)
    config = task_config(net.task, net.world, **ONE_ARENA[net.task])
    batch = make_trials(net.task, n_trials, "test", SEED, config=config)
    with torch.no_grad():
        return hp.record(net, batch, checkpoint=name, config=config,
                         session_id=f"cell-classes-{name}")


def fractions(table, mask=None):
    """Fraction of units in each class (a unit may be in several) and unclassified."""
    mask = np.ones(table.sizes["unit"], bool) if mask is None else mask
    out = {c: float(table[f"is_{c}"].values[mask].mean()) for c in CLASSES}
    out["unclassified"] = float((table.cell_class.values[mask] == "unclassified").mean())
    out["n_units"] = int(mask.sum())
    return out


def opexebo_scores(maps, n_units):
    """opexebo's grid score and border score (its own field detection, square arena) on
    the first ``n_units`` maps; returns (seconds, grid scores, border scores)."""
    import opexebo

    # opexebo 0.7.2 returns a 1-element array from _findCentreRadius, which int() refuses
    # under numpy >= 2.3: take its one value
    module = sys.modules["opexebo.analysis.grid_score"]
    original = module._findCentreRadius
    module._findCentreRadius = lambda *a, **k: float(np.ravel(original(*a, **k))[0])
    values = maps.values[:n_units]
    grid, border = [], []
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for m in values:
            m = m - np.nanmin(m)            # opexebo expects non-negative rates
            grid.append(opexebo.analysis.grid_score(opexebo.analysis.autocorrelation(m))[0])
            fields, fields_map = opexebo.analysis.place_field(m, min_peak=0, min_mean=0)
            as_walls = [{"field_map": f["map"]} for f in fields]
            border.append(opexebo.analysis.border_score(m, fields_map, as_walls, "square")[0]
                          if as_walls else -1.0)
    seconds = time.perf_counter() - t0
    module._findCentreRadius = original
    return seconds, np.array(grid, float), np.array(border, float)


def _range(pair):
    return "n/a" if pair is None else f"{pair[0]:.2f} to {pair[1]:.2f}"


def timing(rec, t_classify, n_shuffles, opexebo_units):
    """Seconds for classify_cells (``t_classify``: all scores, with shuffles), for our grid
    + border scores on the observed maps, and for opexebo's on the same maps."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AnalysisWarning)
        maps = hp.ratemaps(rec)
        t0 = time.perf_counter()
        ours_g = hp.grid_score(maps).grid_score.values
        hp.border_score(maps)
        t_ours = time.perf_counter() - t0
    n_units = min(opexebo_units, maps.sizes["unit"])
    t_op, op_g, _ = opexebo_scores(maps, n_units)
    ok = np.isfinite(ours_g[:n_units]) & np.isfinite(op_g)
    return {
        "units": int(maps.sizes["unit"]), "samples": int(rec.sizes["time"]),
        "map_bins": [int(maps.sizes["y"]), int(maps.sizes["x"])],
        "n_shuffles": n_shuffles,
        "classify_cells_s": t_classify,
        "ours_grid_border_observed_s": t_ours,
        "opexebo_units_timed": n_units,
        "opexebo_grid_border_observed_s": t_op,
        "opexebo_grid_border_observed_per_256_units_s": t_op * 256 / n_units,
        "opexebo_with_shuffles_estimate_s": t_op * 256 / n_units * (1 + n_shuffles),
        "grid_score_correlation_with_opexebo": float(np.corrcoef(ours_g[:n_units][ok],
                                                                 op_g[ok])[0, 1])
        if ok.sum() > 2 else None,
        "grid_scores_compared": int(ok.sum()),
        "grid_scores_ours_range": [float(ours_g[:n_units][ok].min()),
                                   float(ours_g[:n_units][ok].max())] if ok.any() else None,
        "grid_scores_opexebo_range": [float(op_g[ok].min()), float(op_g[ok].max())]
        if ok.any() else None,
    }


def _label(name, group):
    """A network's bar label: its name, with its world where the name does not say it."""
    world = group.get("world")
    return name if not world or world in name else f"{name} ({world})"


def _class_bars(ax, bars_of, title):
    """Grouped bars: one group per class, one bar per recording (``bars_of``)."""
    labels = list(bars_of)
    classes = (*CLASSES, "unclassified")
    width = 0.8 / len(labels)
    colors = plt.get_cmap("tab10")
    for k, name in enumerate(labels):
        f = bars_of[name]
        x = np.arange(len(classes)) + (k - (len(labels) - 1) / 2) * width
        ax.bar(x, [f[c] for c in classes], width, color=colors(k),
               label=f"{name} (n={f['n_units']})")
    ax.set_xticks(np.arange(len(classes)), [c.replace("_", "\n") for c in classes])
    ax.set_ylabel("fraction of units")
    ax.set_ylim(0, 1.3)
    ax.set_yticks(np.linspace(0, 1, 6))
    ax.legend(fontsize=7, loc="upper center", ncols=3)      # above the bars (y > 1)
    ax.set_title(title, fontsize=10)


def figure(groups, time_info, out, subtitle="", spike_rate=None, mouse_s=None):
    """Bars of class fractions, networks as recorded and as spikes (the mouse, by region,
    in both), and of the timings."""
    mouse, recorded, spiking = {}, {}, {}
    for name, g in groups.items():
        if "by_region" in g:
            for region, f in g["by_region"].items():
                mouse[f"{name} {REGIONS.get(region, region)}"] = f
        elif g.get("spikes"):
            spiking[_label(name.removesuffix(" spikes"), g)] = g["fractions"]
        else:
            recorded[_label(name, g)] = g["fractions"]
    panels = [(recorded, "networks' activity as recorded (noise-free)")]
    n_seconds = max((g["seconds"] for g in groups.values() if g.get("spikes")), default=0)
    if spiking:
        panels.append((spiking, (f"networks as Poisson spikes at {spike_rate:.2g} Hz "
                                  f"(the mouse's median rate), "
                                  f"{n_seconds:.0f} s (the mouse: {mouse_s:.0f} s)")))
    fig = plt.figure(figsize=(13, 4.2 * len(panels)), layout="constrained")
    grid = fig.add_gridspec(len(panels), 2, width_ratios=[3, 1])
    for row, (bars, title) in enumerate(panels):
        _class_bars(fig.add_subplot(grid[row, 0]), {**bars, **mouse}, title)
    ax_t = fig.add_subplot(grid[:, 1])
    fig.suptitle("cell classes (a unit may be in several; thresholds from each unit's "
                 f"time-shift shuffles){subtitle}", fontsize=10)
    if time_info:
        bars = {f"classify_cells\n(all scores,\n{time_info['n_shuffles']} shuffles)":
                time_info["classify_cells_s"],
                "ours: grid +\nborder, maps": time_info["ours_grid_border_observed_s"],
                "opexebo: grid +\nborder, maps": time_info[
                    "opexebo_grid_border_observed_per_256_units_s"]}
        ax_t.bar(range(len(bars)), list(bars.values()), color=["k", "tab:gray", "tab:red"])
        for i, v in enumerate(bars.values()):
            ax_t.text(i, v, f"{v:.3g} s", ha="center", va="bottom", fontsize=8)
        ax_t.set_xticks(range(len(bars)), list(bars), fontsize=7)
        ax_t.set_yscale("log")
        ax_t.set_ylabel("seconds (256 units)")
        note = "" if time_info["opexebo_units_timed"] == 256 else \
            f"\n(opexebo timed on {time_info['opexebo_units_timed']} units, scaled)"
        ax_t.set_title(f"{time_info['network']}: {time_info['samples']} samples{note}",
                       fontsize=8)
    out.mkdir(parents=True, exist_ok=True)
    save_figure(fig, out / "cell_classes.png", dpi=130)
    save_figure(fig, out / "cell_classes.pdf")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--networks", nargs="+", default=None,
                    help=f"shipped networks (default: those of {CANDIDATES} shipped)")
    ap.add_argument("--trials", type=int, default=200, help="test trials per network")
    ap.add_argument("--shuffles", type=int, default=100, help="time-shift shuffles")
    ap.add_argument("--opexebo-units", type=int, default=256,
                    help="units timed with opexebo (scaled to 256)")
    ap.add_argument("--no-timing", action="store_true")
    ap.add_argument("--out", default=str(ROOT / "figures"))
    a = ap.parse_args()
    names = a.networks or shipped_networks()
    out = Path(a.out)
    groups, tables, time_info = {}, {}, None
    mouse = hp.from_nwb(SESSION, epoch="wake")
    # the mouse's units' median rate, in Hz (counts per sample / dt)
    spike_rate = float(np.median(mouse.activity.values.mean(axis=0)) / mouse.attrs["dt"])
    mouse_s = float(mouse.sizes["time"] * mouse.attrs["dt"])
    print(f"mouse: {mouse.sizes['unit']} units over {mouse_s:.0f} s, median rate "
          f"{spike_rate:.2f} Hz")
    for name in names:
        t0 = time.perf_counter()
        rec = record_network(name, a.trials)
        t_rec = time.perf_counter() - t0
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AnalysisWarning)
            table = hp.classify_cells(rec, n_shuffles=a.shuffles, seed=SEED)
        t_cls = time.perf_counter() - t0
        tables[name] = table
        groups[name] = {"fractions": fractions(table), "record_s": t_rec,
                        "classify_s": t_cls, "samples": int(rec.sizes["time"]),
                        "world": rec.attrs.get("world", ""), "task": rec.attrs.get("task")}
        print(f"{name}: {rec.sizes['time']} samples, recorded in {t_rec:.0f} s, classified "
              f"in {t_cls:.0f} s: {groups[name]['fractions']}")
        if time_info is None and not a.no_timing and rec.sizes["unit"] >= 256:
            time_info = dict(timing(rec, t_cls, a.shuffles, a.opexebo_units), network=name)
            print(f"timing ({name}): {time_info}")
        # as spikes, over the mouse session's duration (its first whole trials covering
        # it): the same rate and duration give the same counts, so the same power
        trial_s = np.diff(rec.trial_start.values[:2])[0] if rec.sizes["trial_id"] > 1 \
            else rec.sizes["time"] * rec.attrs["dt"]
        n_first = int(np.ceil(mouse_s / trial_s))
        spikes = hp.poisson_spikes(
            hp.select_trials(rec, trials=rec.trial_id.values[:n_first]),
            mean_rate=spike_rate, seed=SEED)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", AnalysisWarning)
            table = hp.classify_cells(spikes, n_shuffles=a.shuffles, seed=SEED)
        tables[f"{name} spikes"] = table
        groups[f"{name} spikes"] = {"fractions": fractions(table), "spikes": True,
                                    "mean_rate_hz": spike_rate, "trials": n_first,
                                    "world": groups[name]["world"],
                                    "seconds": float(spikes.sizes["time"] * rec.attrs["dt"])}
        print(f"{name} as spikes at {spike_rate:.2f} Hz: "
              f"{groups[f'{name} spikes']['fractions']}")

    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AnalysisWarning)
        table = hp.classify_cells(mouse, n_shuffles=a.shuffles, seed=SEED,
                                  bin_size=BIN_ANIMAL)
    region = mouse.region.values.astype(str)
    groups["mouse A2929"] = {
        "fractions": fractions(table), "classify_s": time.perf_counter() - t0,
        "samples": int(mouse.sizes["time"]),
        "by_region": {r: fractions(table, region == r) for r in np.unique(region)},
        "cell_class": dict(zip(map(str, mouse.unit.values), table.cell_class.values.tolist(),
                               strict=True)),
        "walls_source": table.attrs.get("walls_source")}
    tables["mouse A2929"] = table
    print(f"mouse: {groups['mouse A2929']['fractions']}; by region "
          f"{groups['mouse A2929']['by_region']}")

    figure(groups, time_info, out, spike_rate=spike_rate, mouse_s=mouse_s,
           subtitle=f"; {a.trials} trials per network, {a.shuffles} shuffles")
    lines = ["| recording | units | " + " | ".join(CLASSES) + " | unclassified |",
             "|---" * (len(CLASSES) + 3) + "|"]
    for name, g in groups.items():
        f = g["fractions"]
        lines.append(f"| {name} | {f['n_units']} | "
                     + " | ".join(f"{f[c]:.2f}" for c in (*CLASSES, "unclassified")) + " |")
    if time_info:
        lines += ["", (f"Timing on {time_info['network']} ({time_info['units']} units, "
                  f"{time_info['samples']} samples, maps {time_info['map_bins']}): "
                  f"classify_cells with {time_info['n_shuffles']} shuffles "
                  f"{time_info['classify_cells_s']:.1f} s; our grid + border scores of the "
                  f"observed maps {time_info['ours_grid_border_observed_s']:.2f} s; "
                  f"opexebo's on the same maps "
                  f"{time_info['opexebo_grid_border_observed_per_256_units_s']:.1f} s "
                  f"(timed on {time_info['opexebo_units_timed']} units). Grid scores beside "
                  f"opexebo's on these maps: r = "
                  f"{time_info['grid_score_correlation_with_opexebo']:.2f} over the "
                  f"{time_info['grid_scores_compared']} maps both score (ours "
                  f"{_range(time_info['grid_scores_ours_range'])}, opexebo's "
                  f"{_range(time_info['grid_scores_opexebo_range'])}; ours is NaN for "
                  "maps whose central peak is wider than half the largest annulus). These "
                  "maps have no hexagonal autocorrelogram, and on such maps the score "
                  "depends on the annulus each rule picks (the central-radius convention, "
                  "tests/analysis/test_grid_score.py); on grid-like maps the two agree "
                  "(r > 0.95, the same maps above 0.5)."),
                  "", (f"'spikes': the network's units as Poisson spikes at {spike_rate:.2f} Hz "
                       "(hp.poisson_spikes), the mouse's median rate, on the first whole trials "
                       f"covering the mouse session's {mouse_s:.0f} s (" + ", ".join(
                           f"{n}: {g['seconds']:.0f} s" for n, g in groups.items()
                           if g.get("spikes")) + "); as recorded: "
                       f"{a.trials} trials.")]
    write_text(out / "cell_classes.md", "\n".join(lines) + "\n", what="class table")
    write_text(out / "cell_classes.json", json.dumps(jsonable({
        "trials": a.trials, "n_shuffles": a.shuffles, "seed": SEED,
        "spike_rate_hz": spike_rate,
        "hippo_probe": hp.__version__, "groups": groups, "timing": time_info,
        "rules": tables[names[0]].attrs["rules"] if names else None}), indent=1))
    print(f"wrote {out}/cell_classes.png/.pdf/.md/.json")


if __name__ == "__main__":
    main()
