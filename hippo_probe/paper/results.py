"""RESULTS.md: each quantitative claim of the study beside our value.

Reads the JSON files the figure builders wrote for every run
(``<figures>/<world>-seed<k>/fig*.json``) and appends the hand-written notes (``paper_figures/RESULTS_notes.md`` of the repository by default).
:func:`write_results` is called by ``hippo-probe figures`` and by the script
``paper_figures/results.py``.
"""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import NamedTuple

from ._repository import repository_file

#: The notes appended to the table, inside the repository.
NOTES = "paper_figures/RESULTS_notes.md"


class _RepositoryNotes:
    """The default of ``notes_path``: the repository's notes."""

    def __repr__(self):
        return f"<the repository's {NOTES}>"


_REPOSITORY_NOTES = _RepositoryNotes()


def _get(d, *keys):
    for k in keys:
        if not isinstance(d, dict) or k not in d:
            return None
        d = d[k]
    return d


def _fmt(x, spec=".2f"):
    return "n/a" if x is None else format(x, spec)


def _verdict(ok, partly=False, rule=""):
    """A claim's verdict by a stated rule (the rules are ours: the paper gives no
    tolerances)."""
    word = "reproduced" if ok else ("partly" if partly else "not reproduced")
    return f"{word} ({rule})" if rule else word


def _ratio(a, b):
    return None if a is None or b is None or b == 0 else a / b


def _difference(a, b):
    return None if a is None or b is None else a - b


class Claim(NamedTuple):
    """One quantitative claim of the study and what one set of figures says of it."""

    claim: str
    paper: str
    measured: str                   # the numbers, in words
    verdict: str                    # by the rule printed with it
    headline: dict                  # label -> number: what the table shows per seed
    study: dict = {}                # label -> the study's number, where it gives one
    title: str = ""                 # a short panel title for the ablation figure
    ylabel: str = ""                # what the headline numbers are, with units


def rows(fig):
    """A :class:`Claim` for every quantitative claim of the study, from one run's figures
    (``fig["fig2"]`` ... ``fig["fig5"]``: their JSON), in RESULTS.md's order."""
    f2, f3, f4, f5 = (fig.get(k, {}) for k in ("fig2", "fig3", "fig4", "fig5"))
    yield _fig2_claim(f2)
    yield _fig3a_claim(f3)
    yield _fig3c_claim(f3)
    yield _fig3f_claim(f3)
    yield _fig3de_claim(f3)
    yield _fig5c_claim(f5)
    yield _fig5a_claim(f5)
    yield _fig4e_claim(f4)
    yield _fig4c_claim(f4)
    yield _fig4ab_claim(f4)
    yield _fig4d_claim(f4)


def _fig2_claim(f2):
    """Fig. 2: the localization network against the optimal particle filter."""
    n2 = f2.get("n_trials")
    pf_loc = _get(f2, "summary", "particle filter (oracle)", "200s")
    net_loc = _get(f2, "summary", "network", "200s")
    r = _get(f2, "summary", "network / PF error, t > 100 s")
    return Claim("Fig. 2: the localization network is about as good as the optimal (oracular) "
            "particle filter in its familiar arena",
            "network ≈ PF",
            f"network / PF error (mean over t > 100 s) = {_fmt(r)}; at 200 s: network "
            f"{_fmt(net_loc, '.3f')} m, PF {_fmt(pf_loc, '.3f')} m ({n2} test trials)",
            _verdict(r is not None and r <= 1.2, r is not None and r <= 2,
                     "ratio ≤ 1.2; partly ≤ 2"),
            {"network / PF, t > 100 s": r}, {"network / PF, t > 100 s": 1.0},
            "Fig. 2: localization network vs the optimal PF", "error ratio")


def _fig3a_claim(f3):
    """Fig. 3A: the generalized network in novel arenas."""
    n3 = f3.get("size", {}).get("trials")
    gen = _get(f3, "A_generalized_error") or {}
    r = _get(f3, "A_ratio_network_to_pf_t_gt_100s")
    net_200 = (gen.get("network") or [None])[-1]
    pi_200 = (gen.get("path integration") or [None])[-1]
    beats_pi = None if net_200 is None or pi_200 is None else net_200 < 0.75 * pi_200
    return Claim("Fig. 3A: in novel arenas the generalized network is within ~1.5x of the "
            "oracular PF and far better than path integration",
            "≈ 1.5x PF (read from the main text); << PI",
            f"network / PF error (t > 100 s) = {_fmt(r)}; at 200 s: network "
            f"{_fmt(net_200, '.3f')} m, PF "
            f"{_fmt((gen.get('particle filter (oracle)') or [None])[-1], '.3f')} m, PI "
            f"{_fmt(pi_200, '.3f')} m, naive Bayes "
            f"{_fmt((gen.get('naive Bayes') or [None])[-1], '.3f')} m ({n3} trials)",
            _verdict(bool(beats_pi) and r is not None and r <= 2, bool(beats_pi),
                     "ratio ≤ 2 and error < 0.75 PI at 200 s; partly: only the latter"),
            {"network / PF, t > 100 s": r, "network / PI, 200 s": _ratio(net_200, pi_200)},
            {"network / PF, t > 100 s": 1.5},
            "Fig. 3A: generalized network, novel arenas", "error ratio")


def _fig3c_claim(f3):
    """Fig. 3C: the specialized network names its arena."""
    n3 = f3.get("size", {}).get("trials")
    acc = _get(f3, "C_accuracy_at") or {}
    a200 = acc.get("200s")
    return Claim("Fig. 3C: the specialized network identifies its arena (of 100) with accuracy "
            "near 100% within 200 s",
            "≈ 100% by 200 s",
            "accuracy at 50/100/200 s = " + (", ".join(_fmt(v, ".3f") for v in acc.values())
                                              if acc else "n/a") + f" (chance 0.01; {n3} trials)",
            _verdict(a200 is not None and a200 >= 0.9, a200 is not None and a200 >= 0.5,
                     "≥ 0.9 at 200 s; partly ≥ 0.5"),
            {"accuracy, 200 s": a200}, {"accuracy, 200 s": 1.0},
            "Fig. 3C: specialized network names its arena",
            "classification accuracy (chance 0.01)")


def _fig3f_claim(f3):
    """Fig. 3F: the retrained readout of the frozen generalized network."""
    n3 = f3.get("size", {}).get("trials")
    ro = _get(f3, "F_readout_accuracy_at") or {}
    r200 = ro.get("200s")
    return Claim("Fig. 3F: retraining only the readout of the generalized network classifies "
            "the arenas at about 85%",
            "≈ 85%",
            "accuracy at 50/100/200 s = " + (", ".join(_fmt(v) for v in ro.values())
                                              if ro else "n/a") + f" ({n3} trials)",
            _verdict(r200 is not None and r200 >= 0.7, r200 is not None and r200 >= 0.3,
                     "≥ 0.7 at 200 s; partly ≥ 0.3"),
            {"accuracy, 200 s": r200}, {"accuracy, 200 s": 0.85},
            "Fig. 3F: generalized network, retrained readout",
            "classification accuracy (chance 0.01)")


def _fig3de_claim(f3):
    """Fig. 3D-E: the specialized network against PF-SLAM."""
    slam_n = f3.get("size", {}).get("slam_trials")
    slam = sorted((int(k.split("_")[2]), v) for k, v in f3.items()
                  if k.startswith("E_pfslam_"))
    slam_err = {int(k.split("_")[2]): v for k, v in f3.items() if k.startswith("D_pfslam_")}
    slam_txt = "; ".join(f"{n:,} particles: accuracy {_fmt(v.get('200s'))}, error "
                         f"{_fmt(slam_err.get(n, {}).get('200s'), '.3f')} m"
                         for n, v in slam)
    # 180-200 s means on the PF-SLAM trials: 50 trials make single-sample accuracies
    # move in steps of 0.02
    net = _get(f3, "last20s_network_on_slam_trials") or {}
    top = _get(f3, f"last20s_pfslam_{slam[-1][0]}") if slam else None
    acc_ok = bool(net and top) and net["accuracy"] >= 0.8 * top["accuracy"]
    err_ok = bool(net and top) and net["error"] <= 1.25 * top["error"]
    return Claim("Fig. 3D-E: the specialized network is comparable to a PF-SLAM with 10,000 "
            "particles",
            "≈ PF-SLAM 10k",
            f"mean over 180-200 s, on {slam_n} trials — network: accuracy "
            f"{_fmt(net.get('accuracy'))}, error {_fmt(net.get('error'), '.3f')} m; "
            f"PF-SLAM 10k: accuracy {_fmt((top or {}).get('accuracy'))}, error "
            f"{_fmt((top or {}).get('error'), '.3f')} m. At 200 s: PF-SLAM {slam_txt or 'n/a'}",
            _verdict(acc_ok and err_ok, acc_ok or err_ok,
                     "accuracy ≥ 0.8 × and error ≤ 1.25 × PF-SLAM 10k's; partly: one of "
                     "the two"),
            # accuracy as a difference: PF-SLAM's accuracy may be 0 (few particles for 100
            # arenas in darkness), where a ratio is undefined; errors are never 0
            {"accuracy − PF-SLAM's": _difference(net.get("accuracy"),
                                                 (top or {}).get("accuracy")),
             "error / PF-SLAM's": _ratio(net.get("error"), (top or {}).get("error"))},
            {"accuracy − PF-SLAM's": 0.0, "error / PF-SLAM's": 1.0},
            "Fig. 3D-E: specialized network vs PF-SLAM 10k",
            "accuracy difference; error ratio")


def _fig5c_claim(f5):
    """Fig. 5C: the correlation dimension of the hidden states."""
    measured = _get(f5, "C_dimension") or {}
    dims = {k: v for k, v in measured.items() if v is not None}
    # D is None where C(r) has no scaling range: the local slope never plateaus
    # the study's text: "The localization-only network has a dimension D=5.5 ... the
    # specialized network states ... D=5.6. The generalized network states ... D=8.5."
    paper = {"localization": 5.5, "specialized": 5.6, "generalized": 8.5}
    # the rule needs all three: a network without a dimension can be neither within 20%
    # nor the highest
    complete = dims.keys() >= paper.keys()
    close = [complete and abs(dims[k] / v - 1) <= 0.2 for k, v in paper.items()]
    ordered = complete and max(dims, key=dims.get) == max(paper, key=paper.get)
    n_dim = min((_get(f5, "C_n_points") or {}).values(), default=None)
    bound = 2 * math.log10(n_dim) if n_dim else None
    return Claim("Fig. 5C: correlation dimension of the hidden-state trajectories",
            "5.5 / 5.6 / 8.5 (localization / specialized / generalized, the study's text)",
            (" / ".join(f"{k} {_fmt(v, '.1f')}" if v is not None else
                        f"{k}: no scaling range (the local slope never plateaus)"
                        for k, v in measured.items()) or "n/a")
            + (f" ({n_dim:,} states each; values near 2 log10 N = {bound:.1f} "
               "(Eckmann & Ruelle 1992) are lower bounds)" if bound else "")
            + "".join(f"; {e} (same states): " + " / ".join(
                f"{k} {_fmt(v, '.1f')}" for k, v in (_get(f5, f"C_dimension_{e}") or {}).items())
                for e in ("TwoNN", "MLE") if _get(f5, f"C_dimension_{e}")),
            _verdict(bool(close) and all(close), ordered,
                     "each within 20%; partly: the generalized network highest"),
            {f"D {k}": dims.get(k) for k in paper}, {f"D {k}": v for k, v in paper.items()},
            "Fig. 5C: correlation dimension of hidden states",
            "dimension D (Grassberger-Procaccia)")


def _fig5a_claim(f5):
    """Fig. 5A: the particle filter's covariance decoded from the units."""
    r2 = _get(f5, "A_r2") or {}
    r2_t = _get(f5, "A_r2_time_in_trial_alone") or {}
    gain = [r2[k] - r2_t.get(k, 0.0) for k in ("xx", "yy") if k in r2]
    return Claim("Fig. 5A: the PF's posterior covariance is linearly decodable from the "
            "localization network's units",
            "decodable",
            "cross-validated R² (xx, yy, xy) = " + ", ".join(_fmt(v) for v in r2.values())
            + ("; from time in trial alone: " + ", ".join(_fmt(v) for v in r2_t.values())
               if r2_t else ""),
            _verdict(bool(gain) and min(r2.get("xx", 0), r2.get("yy", 0)) >= 0.5
                     and min(gain) >= 0.1,
                     any(r2[k] - r2_t.get(k, 0.0) >= 0.05 for k in r2),
                     "R² ≥ 0.5 for xx and yy, ≥ 0.1 above time in trial alone; partly: "
                     "≥ 0.05 above it for one component"),
            {f"R² {k} − time alone": r2[k] - r2_t.get(k, 0.0) if k in r2 else None
             for k in ("xx", "yy", "xy")}, {},
            "Fig. 5A: PF covariance decoded from units", "cross-validated R² gain")


def _fig4e_claim(f4):
    """Fig. 4E: classifier weight against spatial selectivity."""
    rho, p = _get(f4, "E", "rank_correlation"), _get(f4, "E", "rank_correlation_p")
    return Claim("Fig. 4E: units projecting strongly onto the classifier are less spatially "
            "selective (negative correlation)",
            "negative",
            f"Spearman rho = {_fmt(rho)} (p = {_fmt(p, '.2g')})",
            _verdict(rho is not None and rho < 0 and p is not None and p < 0.05,
                     rho is not None and rho < 0, "rho < 0 with p < 0.05; partly: rho < 0"),
            {"Spearman rho": rho}, {},
            "Fig. 4E: classifier weight vs spatial selectivity", "Spearman ρ")


def _fig4c_claim(f4):
    """Fig. 4C: head-direction tuning."""
    mvl = _get(f4, "C_mean_vector_length", "median_all_units")
    sig = _get(f4, "C_mean_vector_length", "fraction_significant_p_lt_0.01")
    return Claim("Fig. 4C: head-direction tuning is weak",
            "weak",
            f"specialized network: median mean vector length {_fmt(mvl)}, max "
            f"{_fmt(_get(f4, 'C_mean_vector_length', 'max'))}; "
            f"{_fmt(sig)} of units significant (p < 0.01, time-shift shuffles): tuned, "
            "but weakly (mouse ADn cells: median R 0.84, see the network-vs-rodent table)",
            _verdict(mvl is not None and mvl < 0.2, rule="median R < 0.2"),
            {"median R": mvl}, {},
            "Fig. 4C: head-direction tuning", "median mean vector length R")


def _fig4ab_claim(f4):
    """Fig. 4A-B: rate-map stability within an arena."""
    same_a, same_b = (_get(f4, k, "stability_same_arena_median") for k in "AB")
    across_a, across_b = (_get(f4, k, "correlation_across_arenas_median") for k in "AB")
    return Claim("Fig. 4A-B: place fields are stable across trajectories in the same arena",
            "stable",
            f"median rate-map correlation, same arena vs other arena: specialized "
            f"{_fmt(same_a)} vs {_fmt(across_a)}, generalized {_fmt(same_b)} vs "
            f"{_fmt(across_b)}",
            _verdict(same_a is not None and same_a >= 0.7 and (same_b or 0) >= 0.7
                     and across_a is not None and same_a - across_a >= 0.1,
                     same_a is not None and same_a >= 0.7,
                     "same-arena median ≥ 0.7 and ≥ 0.1 above the other arena's for the "
                     "specialized network; partly: stable only. Smooth gradient-like maps "
                     "are stable trivially (notes)"),
            {"same arena": same_a, "other arena": across_a}, {},
            "Fig. 4A-B: rate-map stability (specialized)", "median rate-map correlation")


def _fig4d_claim(f4):
    """Fig. 4D: remapping between arenas."""
    across_a = _get(f4, "A", "correlation_across_arenas_median")
    d = _get(f4, "D_similarity") or {}
    dc = _get(f4, "D_similarity_units_centred") or {}
    within, across = dc.get("same"), dc.get("different")
    # global remapping = units' maps unrelated across arenas, not only the population
    # vectors: the per-unit rate-map correlation across arenas (Fig. 4A) must be low too
    pv_ok = across is not None and within is not None and across < 0.3 and within > 0.7
    maps_ok = across_a is not None and across_a < 0.5
    return Claim("Fig. 4D: global remapping between arenas",
            "across ≈ 0, within high",
            f"mean population-vector correlation, each unit's mean removed: within "
            f"{_fmt(within)}, across {_fmt(across)} (labels shuffled: "
            f"{_fmt(dc.get('same_permuted'))} / {_fmt(dc.get('different_permuted'))}); "
            f"pooled without centring: {_fmt(d.get('same'))} / {_fmt(d.get('different'))}; "
            f"but single units' rate maps across arenas correlate {_fmt(across_a)} (median)",
            _verdict(pv_ok and maps_ok, pv_ok,
                     "population vectors across < 0.3 and within > 0.7, and units' maps "
                     "across arenas < 0.5; partly: population vectors only, i.e. rate "
                     "remapping (units change their mean rate by arena, keep their map)"),
            {"PV across": across, "maps across": across_a}, {},
            "Fig. 4D: remapping between arenas", "correlation across arenas")


def error_table(figs):
    """Markdown rows: each network's mean Euclidean error at 50 / 100 / 200 s beside the
    baselines' on the same test trials (Fig. 2, 3A, 3B).

    ``figs`` is one run's figures (``{figN: data}``) per training seed. A number that
    differs between seeds (the network's) reads ``mean (min–max)``; the baselines, run
    on the same trials for every seed, read once. A row that not every seed has says how
    many it is over.
    """
    cols = ["network", "particle filter (oracle)", "single hypothesis", "path integration",
            "naive Bayes"]
    panels = [("localization (familiar 1 m arena, start unknown)", "fig2", "euclidean"),
              ("generalized (novel 0.33 m arenas)", "fig3", "A_generalized_error"),
              ("specialized (100 familiar 0.33 m arenas)", "fig3", "B_specialized_error")]
    lines = ["| network (task) | " + " | ".join(cols) + " |",
             "| --- |" + " --- |" * len(cols)]
    for label, f, key in panels:
        # each seed's values at 50 / 100 / 200 s, on its own time axis
        at = []
        for fig in figs:
            curves, t = _get(fig, f, key), _get(fig, f, "trial_time_s")
            if curves and t is not None:
                index = [min(range(len(t)), key=lambda i: abs(t[i] - s))
                         for s in (50, 100, 200)]
                at.append({c: [v[i] for i in index] for c, v in curves.items()})
        if not at:
            continue
        cells = [" / ".join(_spread([a[c][k] for a in at if c in a], ".3f") for k in range(3))
                 if any(c in a for a in at) else "—" for c in cols]
        lines.append(f"| {label}{_over(len(at), len(figs))} | " + " | ".join(cells) + " |")
    return lines


def _over(n: int, of: int) -> str:
    """Where a number is over only some of the seeds, how many: `` (n of N seeds)``."""
    return "" if n == of else f" ({n} of {of} seeds)"


#: A run's folder under the figures' output: ``<world>-seed<k>``.
_RUN = re.compile(r"(?P<world>[a-z]+)-seed(?P<seed>\d+)")


def read_runs(figures_dir, runs=None) -> dict:
    """The figures' JSON of the runs under ``figures_dir``: ``{world: {seed: {figN:
    data}}}``, worlds in the order of :data:`~hippo_probe.paper.config.WORLDS`.

    ``runs`` (folder names, ``<world>-seed<k>``) limits it to those: the runs just made,
    not a folder an earlier run of another size or seed left there. Default: every run
    folder found.
    """
    from .config import WORLDS

    found = {}
    for folder in sorted(Path(figures_dir).iterdir()) if Path(figures_dir).is_dir() else ():
        if runs is not None and folder.name not in runs:
            continue
        m = _RUN.fullmatch(folder.name)
        figs = {p.stem: json.loads(p.read_text()) for p in sorted(folder.glob("fig*.json"))}
        if m and folder.is_dir() and figs:
            found.setdefault(m["world"], {})[int(m["seed"])] = figs
    order = [w for w in WORLDS if w in found] + sorted(set(found) - set(WORLDS))
    return {w: dict(sorted(found[w].items())) for w in order}


def seed_mean(values: list):
    """The leafwise mean over seeds of the same JSON structure: numbers are averaged
    (None, i.e. NaN, left out), lists of equal length element by element; anything else
    is the first seed's."""
    first = values[0]
    if isinstance(first, dict):
        return {k: seed_mean([v[k] for v in values if isinstance(v, dict) and k in v])
                for k in first}
    if isinstance(first, list) and all(isinstance(v, list) and len(v) == len(first)
                                       for v in values):
        return [seed_mean(list(col)) for col in zip(*values)]
    if _is_number(first) or first is None:
        numbers = [v for v in values if _is_number(v)]
        if numbers and all(v == numbers[0] for v in numbers):
            return numbers[0]              # a size, a count: kept as it was
        return sum(numbers) / len(numbers) if numbers else None
    return first


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _spread(values: list, spec: str = ".2f") -> str:
    """``mean (min–max)`` of one number over seeds, or the number alone where the seeds
    agree to the printed digits (one seed; a baseline run on the same trials, whose last
    bits may differ between CPUs); ``n/a`` if none."""
    values = [v for v in values if v is not None and math.isfinite(v)]
    if not values:
        return "n/a"
    mean, lo, hi = (format(v, spec) for v in (sum(values) / len(values), min(values),
                                             max(values)))
    return mean if lo == hi else f"{mean} ({lo}–{hi})"


def _trained(name: str, info: dict) -> str:
    """How a network of the run was made, for the header of RESULTS.md."""
    if info.get("fit_trials"):
        return (f"{name} fitted to convergence on {info['fit_trials']:,} training trials "
                f"(C = {info['fit_c']:g})")
    # a network continued from another (--init-from) counts its last pass only
    before = (f" (its last pass; the one before: {info['base_network_steps']} steps of "
              f"{info['base_network']})" if info.get("base_network") else "")
    return (f"{name} {info['steps_done']} of {info['steps_budget']} steps" + before
            + ("" if info.get("finished") else " (training not finished)")
            + _stopped(info.get("stopped")))


def _stopped(stopped) -> str:
    """How a run that ended before its budget ended, in words (``log["stopped"]``)."""
    if not stopped:
        return ""
    rule = str(stopped.get("reason", "")).split(":")[0]
    return {"stop_improvement": " (ended early: validation improved < 1% over its last "
                                "fifth)",
            "max_hours": " (ended early: the 10-hour cap)"}.get(rule, " (ended early)")


def _word(verdict: str) -> str:
    return verdict.split(" (")[0]


def world_columns(by_seed: dict) -> list[dict]:
    """Per claim of one world: its headline numbers over seeds, the verdict on the seed
    means and how many seeds meet it alone."""
    seeds = list(by_seed)
    mean = rows({name: seed_mean([by_seed[k].get(name, {}) for k in seeds])
                 for name in ("fig2", "fig3", "fig4", "fig5")})
    per_seed = [list(rows(by_seed[k])) for k in seeds]
    out = []
    for i, claim in enumerate(mean):
        numbers = "; ".join(
            f"{label} {_spread([r[i].headline.get(label) for r in per_seed])}"
            for label in claim.headline)
        agree = sum(_word(r[i].verdict) == _word(claim.verdict) for r in per_seed)
        verdict = _word(claim.verdict) + (f", {agree} of {len(seeds)} seeds"
                                          if len(seeds) > 1 else "")
        out.append({"claim": claim, "numbers": numbers, "verdict": verdict})
    return out


def write_results(figures_dir, out_path, notes_path=_REPOSITORY_NOTES, *, runs=None) -> Path:
    """Write RESULTS.md: the study's claims beside the numbers of the figures' JSON.

    One column per world (the darkness world, the study's, first): each claim's headline
    numbers as the mean over the networks' training seeds with their range, ``mean
    (min–max)``; the verdict by the claim's rule applied to the seed means of every
    number (:func:`seed_mean`), with how many seeds meet that verdict on their own. The
    details (every number behind a verdict) follow per world, as seed means.

    Parameters
    ----------
    figures_dir : str or os.PathLike
        Folder of the runs, ``<world>-seed<k>/fig*.json`` (a missing figure's claims
        read "n/a").
    out_path : str or os.PathLike
        The Markdown file written (replaced, atomically).
    notes_path : str or os.PathLike or None, optional
        Hand-written explanations appended to the table; default the repository's
        ``paper_figures/RESULTS_notes.md``; ``None``: no notes.
    runs : sequence of str, optional
        The run folders to read (default: every ``<world>-seed<k>`` found).

    Returns
    -------
    pathlib.Path
        ``out_path``.

    Raises
    ------
    FileNotFoundError
        The notes are not found (the default outside a clone of the repository).
    ValueError
        The notes hold unfilled ``{PLACEHOLDERS}``.
    """
    from .._atomic import write_text
    from .config import WORLDS

    figures_dir, out_path = Path(figures_dir), Path(out_path)
    if notes_path is _REPOSITORY_NOTES:
        notes_path = repository_file(NOTES, argument="notes_path")
    elif notes_path is not None:
        notes_path = Path(notes_path)
        if not notes_path.is_file():
            raise FileNotFoundError(f"notes {notes_path} not found")
    runs = read_runs(figures_dir, runs)
    worlds = list(dict.fromkeys([*WORLDS, *runs]))
    columns = {w: world_columns(runs[w]) if w in runs else None for w in worlds}
    any_figs = next((f for by_seed in runs.values() for f in by_seed.values()), {})
    size = next((f["size"]["name"] for f in any_figs.values()), "?")
    lines = ["# The paper's claims beside this project's measurements", ""]
    if size == "tiny":
        # the tests' size: every code path on a handful of trials
        lines += ["**Data size `tiny`: every number below rests on a handful of trials and "
                  "every verdict means nothing; this file only shows that the pipeline "
                  "runs. `hippo-probe figures --size paper` makes the real one.**", ""]
    lines += [f"Generated by `hippo-probe figures` (data size `{size}`) from the figures of "
             "every shipped run: the networks of each world, one run per training seed "
             "(`<world>-seed<k>/fig*.json`).", ""]
    for w in worlds:
        if w not in runs:
            lines.append(f"- {w} world: no networks shipped yet.")
            continue
        for seed, figs in runs[w].items():
            nets = next((f.get("networks") for f in figs.values() if f.get("networks")), {})
            lines.append(f"- {w} world, seed {seed}: " + ("; ".join(
                _trained(k, v) for k, v in nets.items()) or "networks n/a"))
    head = ["claim (Kanitscheider & Fiete 2017)", "paper"]
    for w in worlds:
        head += [f"{w} world: mean (min–max) over seeds", f"verdict, {w}"]
    lines += ["", "| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for i, claim in enumerate(rows({})):
        cells = [claim.claim, claim.paper]
        for w in worlds:
            col = columns[w]
            cells += ["not trained yet", "—"] if col is None else \
                [col[i]["numbers"], col[i]["verdict"]]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Verdicts apply each claim's rule (below) to the seed means; \"k of n "
              "seeds\" counts the seeds that reach the same verdict on their own."]
    for w in worlds:
        if columns[w] is None:
            continue
        mean = {name: seed_mean([f.get(name, {}) for f in runs[w].values()])
                for name in ("fig2", "fig3", "fig4", "fig5")}
        lines += ["", f"## Details, {w} world (means over {len(runs[w])} seed"
                      f"{'s' if len(runs[w]) > 1 else ''})", "",
                  "| claim | this project | verdict (rule) |", "| --- | --- | --- |"]
        lines += [f"| {c['claim'].claim} | {c['claim'].measured} | {c['claim'].verdict} |"
                  for c in columns[w]]
        figs = list(runs[w].values())
        spread = "" if len(figs) == 1 else f"; mean (min–max) over the {len(figs)} seeds"
        table = error_table(figs)
        if len(table) > 2:
            lines += ["", "Mean Euclidean error (m) at 50 / 100 / 200 s on the same test "
                      f"trials ({_get(mean, 'fig2', 'n_trials')} per network{spread}):", "",
                      *table]
        acc = []
        for name, key in (("specialized network", "C_accuracy_at"),
                          ("generalized network, retrained readout", "F_readout_accuracy_at")):
            by_seed = [a for fig in figs if (a := _get(fig, "fig3", key))]
            if by_seed:
                acc.append((name + _over(len(by_seed), len(figs)), by_seed))
        if acc:
            lines += ["", "Arena classification accuracy at 50 / 100 / 200 s (chance "
                      f"0.01{spread}): " + "; ".join(f"{n} " + " / ".join(
                          _spread([a[k] for a in by_seed]) for k in ("50s", "100s", "200s"))
                          for n, by_seed in acc) + "."]
    if notes_path is not None:
        text = notes_path.read_text()
        unfilled = sorted(set(re.findall(r"\{[A-Z_]+\}", text)))
        if unfilled:
            raise ValueError(f"{notes_path} has unfilled placeholders {unfilled}")
        lines += ["", text]
    out_path.parent.mkdir(parents=True, exist_ok=True)
    write_text(out_path, "\n".join(lines) + "\n", what="results table")
    return out_path
