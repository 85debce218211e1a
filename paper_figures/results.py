"""Write paper_figures/RESULTS.md: each quantitative claim of the study beside our value.

Reads the JSON files the figure scripts wrote (``figures/fig*.json``).

    python paper_figures/results.py [--figures figures/] [--out paper_figures/RESULTS.md]
"""

import argparse
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _get(d, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def _fmt(x, spec=".2f"):
    return "n/a" if x is None else format(x, spec)


def rows(fig):
    f2, f3, f4, f5 = (fig.get(k, {}) for k in ("fig2", "fig3", "fig4", "fig5"))
    pf_loc = _get(f2, "summary", "particle filter (oracle)", "200s")
    net_loc = _get(f2, "summary", "network", "200s")
    gen = _get(f3, "A_generalized_error")
    yield ("Fig. 2: the localization network is about as good as the optimal (oracular) "
           "particle filter in its familiar arena",
           "network ≈ PF",
           f"network / PF error (t > 100 s) = "
           f"{_fmt(_get(f2, 'summary', 'network / PF error, t > 100 s'))}; at 200 s: "
           f"network {_fmt(net_loc, '.3f')} m, PF {_fmt(pf_loc, '.3f')} m")
    pi_200 = gen and gen.get("path integration") and gen["path integration"][-1]
    yield ("Fig. 3A: in novel arenas the generalized network is within ~1.5x of the "
           "oracular PF and far better than path integration",
           "≈ 1.5x PF (approximate, read from the main text); << PI",
           f"network / PF error (t > 100 s) = {_fmt(_get(f3, 'A_ratio_network_to_pf_t_gt_100s'))}; "
           f"at 200 s: network {_fmt(gen and gen['network'][-1], '.3f')} m, PF "
           f"{_fmt(gen and gen['particle filter (oracle)'][-1], '.3f')} m, PI "
           f"{_fmt(pi_200, '.3f')} m")
    acc = _get(f3, "C_accuracy_at")
    yield ("Fig. 3C: the specialized network identifies its arena (of 100) with accuracy "
           "near 100% within 200 s",
           "≈ 100% by 200 s",
           "accuracy at 50/100/200 s = " + (", ".join(_fmt(v) for v in acc.values())
                                             if acc else "n/a"))
    ro = _get(f3, "F_readout_accuracy_at")
    yield ("Fig. 3F: retraining only the readout of the generalized network classifies "
           "the arenas at about 85%",
           "≈ 85%",
           "accuracy at 50/100/200 s = " + (", ".join(_fmt(v) for v in ro.values())
                                             if ro else "n/a"))
    slam = {k: v for k, v in f3.items() if k.startswith("E_pfslam_")}
    slam_txt = "; ".join(f"{k.split('_')[2]} particles: {_fmt(v.get('200s'))}"
                         for k, v in slam.items())
    yield ("Fig. 3D-E: the specialized network is comparable to a PF-SLAM with 10,000 "
           "particles",
           "≈ PF-SLAM 10k",
           f"accuracy at 200 s — network {_fmt(_get(f3, 'E_network_accuracy_at', '200s'))}; "
           f"PF-SLAM {slam_txt or 'n/a'}; error at 200 s — network "
           f"{_fmt(_get(f3, 'D_network_error_at', '200s'), '.3f')} m")
    dims = _get(f5, "C_dimension") or {}
    yield ("Fig. 5C: correlation dimension of the hidden-state trajectories",
           "5.5 / 5.6 / 8.5 (three networks; the mapping to networks is taken from the "
           "project brief, the SI is unavailable)",
           " / ".join(f"{k} {_fmt(v, '.1f')}" for k, v in dims.items()) or "n/a")
    yield ("Fig. 5A: the PF's posterior covariance is linearly decodable from the units",
           "decodable",
           "R² (xx, yy, xy) = " + ", ".join(_fmt(v) for v in (_get(f5, "A_r2") or {}).values()))
    yield ("Fig. 4E: units projecting strongly onto the classifier are less spatially "
           "selective (negative correlation)",
           "negative",
           f"Spearman rho = {_fmt(_get(f4, 'E', 'rank_correlation'))} "
           f"(p = {_fmt(_get(f4, 'E', 'rank_correlation_p'), '.2g')})")
    yield ("Fig. 4C: head-direction tuning is weak",
           "weak",
           f"median mean vector length {_fmt(_get(f4, 'C_mean_vector_length', 'median_all_units'))}, "
           f"max {_fmt(_get(f4, 'C_mean_vector_length', 'max'))}")
    yield ("Fig. 4A-B: place fields are stable across trajectories in the same arena",
           "stable",
           f"median rate-map correlation A vs A: specialized "
           f"{_fmt(_get(f4, 'A', 'stability_same_arena_median'))}, generalized "
           f"{_fmt(_get(f4, 'B', 'stability_same_arena_median'))}")
    d = _get(f4, "D_similarity") or {}
    yield ("Fig. 4D: global remapping between arenas",
           "across ≈ 0, within high",
           f"mean PV correlation within {_fmt(d.get('same'))}, across "
           f"{_fmt(d.get('different'))} (shuffled labels: {_fmt(d.get('same_permuted'))} / "
           f"{_fmt(d.get('different_permuted'))})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--figures", default=str(ROOT / "figures"))
    ap.add_argument("--out", default=str(ROOT / "paper_figures" / "RESULTS.md"))
    ap.add_argument("--notes", default=str(ROOT / "paper_figures" / "RESULTS_notes.md"),
                    help="hand-written explanations appended to the table")
    a = ap.parse_args()
    figs = {p.stem: json.loads(p.read_text()) for p in Path(a.figures).glob("fig*.json")}
    size = next((f["size"]["name"] for f in figs.values()), "?")
    # the newest figure's record of the shipped networks
    newest = max(Path(a.figures).glob("fig*.json"), key=lambda p: p.stat().st_mtime,
                 default=None)
    nets = (figs[newest.stem].get("networks") if newest else None) or {}
    lines = ["# The paper's claims beside this project's measurements", "",
             f"Generated by `python paper_figures/results.py` from the figure data "
             f"(`figures/fig*.json`, data size `{size}`).", "",
             "Shipped networks used: " + "; ".join(
                 f"{k}: {v['steps_done']} of {v['steps_budget']} steps"
                 f"{'' if v.get('finished') else ' (training not finished)'}"
                 f"{'' if not v.get('base_network_steps') else ' on a base network of ' + str(v['base_network_steps']) + ' steps'}"
                 for k, v in nets.items()), "",
             "| claim (Kanitscheider & Fiete 2017) | paper | this project |",
             "| --- | --- | --- |"]
    lines += [f"| {c} | {p} | {m} |" for c, p, m in rows(figs)]
    notes = Path(a.notes)
    if notes.exists():
        lines += ["", notes.read_text()]
    Path(a.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
