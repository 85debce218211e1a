"""Network units vs real rodent cells, with the same analyses on the same layout.

The real session (tests/data/A2929-200711.nwb: head-direction cells of the anterodorsal
thalamus and CA1 cells of a mouse, from the pynapple project) is imported with
``hippo_probe.from_nwb``; the network session is a recording of the shipped localization
network in its familiar 1 m arena (the closest analogue of the mouse's open field). Both go
through the very same calls: head-direction tuning (60 bins, no smoothing), Skaggs
spatial information and spatial selectivity.

Called by ``hippo-probe figures`` and by the script ``analyses/network_vs_rodent.py``.
Writes ``network_vs_rodent.png/.pdf`` (one figure), ``network_vs_rodent.md`` (one table)
and ``network_vs_rodent.json``.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import hippo_probe as hp
from hippo_probe._atomic import save_figure, write_text

from . import config as C

#: The mouse session inside the repository (the default of ``make(session=)``).
SESSION = "tests/data/A2929-200711.nwb"
BIN_ANIMAL = 0.04     # m: the mouse's arena is ~0.5 m across (~12 x 12 bins)
BIN_NETWORK = 0.16    # m: the network's arena is ~2 m across (~13 x 13 bins)
HD_BINS = 60


def summarize(rec, groups, bin_size):
    """Per-unit HD mean vector length, Skaggs information and selectivity, by group."""
    hd = hp.head_direction_tuning(rec, n_bins=HD_BINS, sigma=0.0)
    info = hp.spatial_information(rec, bin_size=bin_size, sigma=0.0)
    sel = hp.spatial_selectivity(rec, bin_size=bin_size)
    out = {}
    for name, mask in groups.items():
        out[name] = {
            "n_units": int(mask.sum()),
            "mean_vector_length": hd.mean_vector_length.values.ravel()[mask],
            "hd_p_value": hd.p_value.values.ravel()[mask],
            "spatial_information": info.information.values.ravel()[mask],
            "information_units": info.information.attrs.get("units", ""),
            "selectivity": sel.selectivity.values.ravel()[mask],
        }
    return hd, out


def make(cfg, out, session=None):
    """The comparison into ``out``; returns the numbers written to its JSON.

    Parameters
    ----------
    cfg : FigureConfig
        Sizes of the network's recording (the localization data set of the figures).
    out : str or os.PathLike
        Folder of ``network_vs_rodent.png/.pdf/.md/.json``.
    session : str or os.PathLike, optional
        The mouse's NWB session; default the repository's ``tests/data/A2929-200711.nwb``.

    Raises
    ------
    FileNotFoundError
        The session is not found (the default outside a clone of the repository).
    """
    session = C.repository_file(SESSION, argument="session") if session is None \
        else Path(session)
    if not session.is_file():
        raise FileNotFoundError(f"NWB session {session} not found")
    cfg, out = C.cached_under(cfg, out), Path(out)

    mouse = hp.from_nwb(session, epoch="wake")
    region = mouse.region.values.astype(str)
    _, mouse_sum = summarize(mouse, {"mouse ADn": region == "adn",
                                     "mouse CA1": region == "ca1"}, BIN_ANIMAL)
    net = C.recording("localization", cfg)
    _, net_sum = summarize(net, {"network (localization)":
                                 np.ones(net.sizes["unit"], bool)}, BIN_NETWORK)
    groups = {**mouse_sum, **net_sum}

    fig, axes = plt.subplots(1, 4, figsize=(16, 3.8), constrained_layout=True)
    colors = {"mouse ADn": "tab:red", "mouse CA1": "tab:blue",
              "network (localization)": "k"}
    mice = [n for n in groups if n.startswith("mouse")]
    # Skaggs information is in bits per spike for spike counts and in bits per unit of
    # activity for the network's hidden state: not one scale, so two axes
    panels = [("mean_vector_length", "head-direction mean vector length R", list(groups)),
              ("spatial_information", "Skaggs information (bits/spike)", mice),
              ("spatial_information", "Skaggs information (bits per unit of activity)",
               [n for n in groups if n not in mice]),
              ("selectivity", "spatial selectivity (variance explained)", list(groups))]
    for k, (ax, (key, label, names)) in enumerate(zip(axes, panels)):
        hp.plot.cumulative({name: groups[name][key] for name in names}, ax=ax,
                           styles={name: {"color": colors[name]} for name in names},
                           xlabel=label, ylabel="cumulative fraction of units")
        ax.get_legend().remove()
    # one legend, below the panels (the first panel names every group; its corners hold
    # curves)
    fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center",
               ncols=len(groups), frameon=False, fontsize=9)
    fig.suptitle("Same analyses, same recording layout: mouse cells vs network units")
    out.mkdir(parents=True, exist_ok=True)
    save_figure(fig, out / "network_vs_rodent.png", dpi=130)
    save_figure(fig, out / "network_vs_rodent.pdf")
    plt.close(fig)

    def med(x):
        x = x[np.isfinite(x)]
        return float(np.median(x)) if len(x) else float("nan")

    lines = ["| group | units | median HD mean vector length | fraction R > 0.5 | "
             "fraction HD-significant (p < 0.01) | median Skaggs information | "
             "median selectivity |",
             "| --- | --- | --- | --- | --- | --- | --- |"]
    table = {}
    for name, g in groups.items():
        mvl = g["mean_vector_length"]
        row = {"units": g["n_units"], "median_mvl": med(mvl),
               "fraction_mvl_gt_0.5": float(np.mean(mvl[np.isfinite(mvl)] > 0.5)),
               "fraction_hd_significant": float(np.mean(g["hd_p_value"] < 0.01)),
               "median_information": med(g["spatial_information"]),
               "information_units": g["information_units"],
               "median_selectivity": med(g["selectivity"])}
        table[name] = row
        lines.append(f"| {name} | {row['units']} | {row['median_mvl']:.3f} | "
                     f"{row['fraction_mvl_gt_0.5']:.2f} | {row['fraction_hd_significant']:.2f} | "
                     f"{row['median_information']:.3f} "
                     f"{row['information_units']} | {row['median_selectivity']:.3f} |")
    lines += ["", "Read across rows with care. Head-direction R comes from 60-bin tuning "
              "curves in both, but spikes have a true zero while the network's signed "
              "activity is measured from each unit's minimum, so R is comparable within a "
              "row; the fraction significant against 100 circular time-shift shuffles is "
              "the comparison across rows. Skaggs information is in bits per spike for the "
              "mouse and bits per unit of (min-shifted) activity for the network, and "
              "selectivity (variance explained by position) of ~8 ms spike counts (120 Hz "
              "samples) is capped by Poisson noise while the network's h is noise-free — "
              "a higher value for the network does not make its units 'more spatial' than CA1 cells."]
    write_text(out / "network_vs_rodent.md", "\n".join(lines) + "\n", what="table")
    numbers = {"size": cfg.name, "table": table,
               "per_unit": {n: {k: v for k, v in g.items() if isinstance(v, np.ndarray)}
                            for n, g in groups.items()}}
    write_text(out / "network_vs_rodent.json", json.dumps(C.jsonable(numbers), indent=1),
               what="figure data")
    print("\n".join(lines))
    print(f"wrote {out}/network_vs_rodent.png/.pdf/.md/.json")
    return numbers
