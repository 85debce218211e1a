"""Every paper figure (hippo_probe.paper) and the network-vs-rodent comparison run end to
end on a tiny configuration (a handful of trials) from the shipped networks, writing only
under the run's --out; the scripts of paper_figures/ and analyses/ stay thin entry
points over the package."""

import json
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _git_status():
    """``git status --porcelain`` of the checkout the tests run from, or None outside one."""
    try:
        run = subprocess.run(["git", "status", "--porcelain", "--untracked-files=all"],
                             capture_output=True, text=True, cwd=ROOT, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return run.stdout if run.returncode == 0 else None


@pytest.fixture(scope="module")
def figures_run(tmp_path_factory):
    """One tiny run of ``hippo-probe main`` (world statistics, then ``figures``: the slow
    part of this module), two runs at once, with the checkout's git status before and
    after it and what it printed."""
    out = tmp_path_factory.mktemp("figures")
    before = _git_status()
    run = subprocess.run([sys.executable, "-m", "hippo_probe.cli", "main", "--size",
                          "tiny", "--jobs", "2", "--out", str(out)], capture_output=True,
                         text=True, cwd=ROOT, timeout=1200)
    assert run.returncode == 0, run.stderr[-4000:]
    return out, before, _git_status(), run.stdout


@pytest.fixture(scope="module")
def figures(figures_run):
    """The folder of the first run's figures (``<world>-seed<k>``)."""
    from hippo_probe.paper.config import shipped_runs

    world, seed = shipped_runs()[0]
    return figures_run[0] / f"{world}-seed{seed}"


def test_figures_write_only_under_out(figures_run):
    """`hippo-probe main --out DIR` leaves the checkout as it was: the tracked copies
    (paper_figures/png, RESULTS.md) are refreshed only by --refresh-tracked CLONE."""
    out, before, after, _ = figures_run
    assert (out / "RESULTS.md").stat().st_size > 1000
    assert (out / "example_trials.png").stat().st_size > 1000
    # a tiny run's verdicts mean nothing, and its RESULTS.md says so first
    assert "every verdict means nothing" in (out / "RESULTS.md").read_text().split("\n")[2]
    assert (out / "network_vs_rodent.json").exists()
    assert (out / "ablation.png").stat().st_size > 1000
    assert not (out / "cache").exists()     # the cached recordings, removed at the end
    # each run's as soon as its figures are made, except the first run's, which the rodent
    # comparison reads after it (and does not have to record again)
    from hippo_probe.paper.config import shipped_runs

    runs = [f"{world}-seed{seed}" for world, seed in shipped_runs()]
    removed = [run for run in runs
               if "removed its cached recordings" in (out / run / "log.txt").read_text()]
    assert removed == runs[1:]
    assert "recorded localization" not in figures_run[3].split("== network vs rodent")[1]
    assert "| darkness-seed0 | " in (out / "timings.md").read_text()
    if before is None:
        pytest.skip("not a git checkout")
    assert after == before


def test_runs_made_at_once_give_the_numbers_of_runs_made_in_turn(figures_run, tmp_path):
    """Two processes of one thread each (main's --jobs 2) write the figures' numbers byte
    for byte as one process running the runs in turn."""
    from hippo_probe.cli import main

    at_once = figures_run[0]
    assert main(["figures", "--size", "tiny", "--only", "fig2", "--jobs", "1",
                 "--no-progress", "--out", str(tmp_path)]) == 0
    made = sorted(tmp_path.glob("*/fig2.json"))
    assert len(made) >= 2
    for path in made:
        run = path.parent.name
        assert path.read_bytes() == (at_once / run / "fig2.json").read_bytes(), run
        assert "fig2 (tiny)" in (at_once / run / "log.txt").read_text()
    # the rodent comparison, made in a worker beside the last runs, as in this process,
    # and what it printed shown under its heading, after RESULTS.md is written
    name = "network_vs_rodent.json"
    assert (tmp_path / name).read_bytes() == (at_once / name).read_bytes()
    printed = figures_run[3]
    heading = printed.index("== network vs rodent")
    assert printed.index("wrote ") < heading < printed.index("| mouse ADn |") \
        < printed.index(f"{name[:-5]}.png")


@pytest.mark.parametrize("extra", [["figures", "--size", "tiny"],
                                   ["figures", "--size", "full"],
                                   ["figures", "--size", "paper", "--only", "fig2"]])
def test_refresh_tracked_needs_every_figure_at_the_paper_size(tmp_path, capsys, extra):
    from hippo_probe.cli import main

    out = tmp_path / "out"
    assert main([*extra, "--refresh-tracked", str(ROOT), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--refresh-tracked needs" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()          # refused before any work


@pytest.mark.parametrize("command", ["figures", "main"])
def test_refresh_tracked_names_a_clone_and_refuses_a_folder_that_is_not_one(tmp_path,
                                                                            capsys, command):
    from hippo_probe.cli import main

    out = tmp_path / "out"
    assert main([command, "--size", "paper", "--refresh-tracked", str(tmp_path),
                 "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "a clone of the hippo_probe repository; none at" in err
    assert not out.exists()


def test_package_boundary():
    """The figure builders are the package's: nothing in it reaches into the repository
    through sys.path, sys.argv or subprocesses."""
    import hippo_probe.paper.fig2 as fig2

    assert callable(fig2.make)
    package = ROOT / "hippo_probe"
    for path in [package / "_main.py", *sorted((package / "paper").glob("*.py"))]:
        text = path.read_text()
        for banned in ("sys.path", "sys.argv =", "subprocess"):
            assert banned not in text, f"{path.relative_to(ROOT)} uses {banned}"


def test_results_notes_missing_is_a_clear_error(tmp_path):
    from hippo_probe.paper.results import write_results

    with pytest.raises(FileNotFoundError, match="missing.md"):
        write_results(tmp_path, tmp_path / "RESULTS.md", tmp_path / "missing.md")
    # without notes the table is written all the same (every claim n/a)
    text = write_results(tmp_path, tmp_path / "RESULTS.md", None).read_text()
    assert "| claim (Kanitscheider & Fiete 2017)" in text


@pytest.mark.parametrize("name", ["fig2", "fig3", "fig4", "fig5"])
def test_figure_written_with_numbers(figures, name):
    for ext in ("png", "pdf", "json"):
        assert (figures / f"{name}.{ext}").stat().st_size > 1000
    data = json.loads((figures / f"{name}.json").read_text())
    assert data["figure"] == name and data["size"]["name"] == "tiny"
    # the figures are of the compass world's networks until the darkness world's finish
    # training; each network is recorded on trials of its own world
    world = data["size"]["world"]
    suffix = "" if world == "darkness" else f"_{world}"
    assert set(data["networks"]) >= {f"{task}{suffix}" for task in
                                     ("localization", "generalized", "specialized")}


def test_fig2_numbers_are_errors_in_metres(figures):
    data = json.loads((figures / "fig2.json").read_text())
    curves = data["euclidean"]
    assert set(curves) == {"network", "particle filter (oracle)", "single hypothesis",
                           "path integration"}
    for values in curves.values():
        finite = [v for v in values if v is not None]
        assert finite and all(0 <= v < 3 for v in finite)   # within a 1 m arena's span


def test_results_table(figures_run, tmp_path):
    from hippo_probe.paper.config import WORLDS, shipped_runs

    out = tmp_path / "RESULTS.md"
    run = subprocess.run([sys.executable, str(ROOT / "paper_figures" / "results.py"),
                          "--figures", str(figures_run[0]), "--out", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    claims, details = out.read_text().split("## Details", 1)

    def table(text):
        return [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]

    rows = table(claims)
    assert len(rows) >= 12
    # a column pair (numbers, verdict) per world; a world with shipped networks has every
    # claim measured, one without says so
    header = [c.strip() for c in rows[0].split("|")[1:-1]]
    assert header[2:] == [x for w in WORLDS for x in (f"{w} world: mean (min–max) over "
                                                      f"seeds", f"verdict, {w}")]
    shipped = {w for w, _ in shipped_runs()}
    for row in rows[1:]:
        cells = [c.strip() for c in row.split("|")[1:-1]]
        for k, world in enumerate(WORLDS):
            numbers, verdict = cells[2 + 2 * k], cells[3 + 2 * k]
            if world in shipped:
                assert "n/a" not in numbers and verdict.split(",")[0] in (
                    "reproduced", "partly", "not reproduced"), row
            else:
                assert numbers == "not trained yet", row
    # each network beside its baselines at 50 / 100 / 200 s: three numbers per cell
    errors = details.split("Mean Euclidean error (m)", 1)[1]
    rows = table(errors)[:4]
    assert [r.split("|")[1].split()[0] for r in rows[1:]] == ["localization", "generalized",
                                                              "specialized"]
    for row in rows[1:]:
        network, pf = row.split("|")[2:4]
        assert len(network.split("/")) == 3 and len(pf.split("/")) == 3
    assert "Arena classification accuracy at 50 / 100 / 200 s" in errors


def test_results_spread_over_seeds(tmp_path):
    """Three seeds of one world: the table shows mean (min–max), the verdict is the rule
    on the seed means, and the seeds that reach it alone are counted."""
    from hippo_probe.paper.results import write_results

    for seed, ratio in enumerate((1.1, 1.3, 1.9)):
        run = tmp_path / f"darkness-seed{seed}"
        run.mkdir()
        (run / "fig2.json").write_text(json.dumps(
            {"figure": "fig2", "size": {"name": "tiny"}, "n_trials": 4,
             "summary": {"network / PF error, t > 100 s": ratio}}))
    text = write_results(tmp_path, tmp_path / "RESULTS.md", None).read_text()
    row = next(line for line in text.splitlines() if line.startswith("| Fig. 2:"))
    # mean 1.43: "partly" by the rule (ratio <= 1.2; partly <= 2); seeds: partly, partly
    # (1.3, 1.9), reproduced (1.1)
    assert "network / PF, t > 100 s 1.43 (1.10–1.90)" in row
    assert "partly, 2 of 3 seeds" in row
    assert "| not trained yet | — |" in row           # no compass run here
    # the ablation figure plots the same headline numbers, one point per seed
    from hippo_probe.paper import ablation

    assert ablation.make(tmp_path, tmp_path).stat().st_size > 1000
    headlines = json.loads((tmp_path / "ablation.json").read_text())["headlines"]
    fig2 = next(v for k, v in headlines.items() if k.startswith("Fig. 2:"))
    assert fig2 == {"darkness": {"network / PF, t > 100 s": [1.1, 1.3, 1.9]}}


def test_error_table_spread_over_seeds(tmp_path):
    """The network's error differs between seeds and reads mean (min–max); the
    baselines, run on the same trials for every seed, read once, also where their last
    bits differ (another CPU); a number not every seed has says over how many it is."""
    from hippo_probe.paper.results import write_results

    for seed, network in enumerate(([0.10, 0.12, 0.14], [0.12, 0.14, 0.18])):
        run = tmp_path / f"darkness-seed{seed}"
        run.mkdir()
        t = [50.0, 100.0, 200.0] if seed == 0 else [0.0, 50.0, 100.0, 200.0]
        pad = [] if seed == 0 else [0.5]          # another time axis: index by its own
        (run / "fig2.json").write_text(json.dumps(
            {"figure": "fig2", "size": {"name": "tiny"}, "n_trials": 4, "trial_time_s": t,
             "euclidean": {"network": pad + network,
                           "particle filter (oracle)": pad + [0.09, 0.1, 0.11 + seed * 1e-9]}}))
        if seed == 0:
            (run / "fig3.json").write_text(json.dumps(
                {"figure": "fig3", "size": {"name": "tiny"},
                 "C_accuracy_at": {"50s": 0.8, "100s": 0.9, "200s": 1.0}}))
    text = write_results(tmp_path, tmp_path / "RESULTS.md", None).read_text()
    row = next(line for line in text.splitlines() if line.startswith("| localization ("))
    assert ("| 0.110 (0.100–0.120) / 0.130 (0.120–0.140) / 0.160 (0.140–0.180) | "
            "0.090 / 0.100 / 0.110 | —") in row
    assert "mean (min–max) over the 2 seeds" in text
    assert "specialized network (1 of 2 seeds) 0.80 / 0.90 / 1.00." in text


def test_results_dimension_without_scaling_range(tmp_path):
    """A network whose C(r) has no scaling range is named as such, not dropped, and the
    verdict rule (each within 20%) cannot call the claim reproduced without it."""
    from hippo_probe.paper.results import write_results

    run = tmp_path / "darkness-seed0"
    run.mkdir()
    (run / "fig5.json").write_text(json.dumps(
        {"figure": "fig5", "size": {"name": "tiny"},
         "C_dimension": {"localization": 5.5, "generalized": None, "specialized": 5.6},
         "C_n_points": {"localization": 1000, "generalized": 1000, "specialized": 1000}}))
    text = write_results(tmp_path, tmp_path / "RESULTS.md", None).read_text()
    detail = [line for line in text.splitlines() if line.startswith("| Fig. 5C:")][-1]
    assert "generalized: no scaling range" in detail
    assert "localization 5.5" in detail and "specialized 5.6" in detail
    assert "| not reproduced" in detail


def test_network_vs_rodent(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "analyses" / "network_vs_rodent.py"),
                          "--size", "tiny", "--out", str(tmp_path)], capture_output=True,
                         text=True, cwd=ROOT, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    table = json.loads((tmp_path / "network_vs_rodent.json").read_text())["table"]
    # the real ADn cells are head-direction tuned, CA1 cells much less (README facts)
    assert table["mouse ADn"]["median_mvl"] > 0.8
    assert table["mouse CA1"]["median_mvl"] < 0.56
    assert table["network (localization)"]["units"] == 256


@pytest.mark.slow
def test_arena_probe(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "analyses" / "arena_probe.py"),
                          "--train-trials", "40", "--test-trials", "10", "--networks",
                          "specialized_compass", "--out", str(tmp_path)], capture_output=True,
                         text=True, cwd=ROOT, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    res = json.loads((tmp_path / "arena_probe.json").read_text())["results"]
    # results[network][training seed][C][time]
    cells = [cell for by_t in res["specialized_compass"]["0"].values()
             for cell in by_t.values()]
    assert len(cells) == 9 and all(0 <= c["test"] <= 1 for c in cells)
    # the positive control: a probe of the specialized network separates the training
    # trials' arenas far above chance (0.01)
    assert max(c["train"] for c in cells) > 0.5


def test_map_ingredients_scores_each_network(tmp_path):
    def scorecard(out, *more):
        run = subprocess.run([sys.executable, "analyses/map_ingredients.py", "--networks",
                              "generalized", *more, "--trials", "8", "--min-per-arena", "1",
                              "--pf-trials", "2", "--readout-trials", "0",
                              "--cache", str(tmp_path / "cache"), "--out", str(out)],
                             capture_output=True, text=True, cwd=ROOT, timeout=900)
        assert run.returncode == 0, run.stderr[-3000:]
        return run.stdout

    assert "from " not in scorecard(tmp_path)
    # a rerun reads the network's row, maps and the filter's estimate from the cache
    # and writes the same scorecard and figure
    assert "generalized: from " in scorecard(tmp_path / "again")
    for name in ("scorecard.json", "map_ingredients.png"):
        assert (tmp_path / name).read_bytes() == (tmp_path / "again" / name).read_bytes()
    # a network new to the cache is scored against the filter's kept estimate
    out = scorecard(tmp_path / "more", "generalized@1")
    assert "particle filter estimate: from " in out and "generalized@1: from" not in out
    first, second = json.loads((tmp_path / "more" / "scorecard.json").read_text())["rows"]
    assert first == json.loads((tmp_path / "scorecard.json").read_text())["rows"][0]
    assert second["network"] == "generalized@1" and second["error_over_pf_after_100s"] > 0
    card = json.loads((tmp_path / "scorecard.json").read_text())
    assert sum(card["trials_per_arena"]) == 8
    (row,) = card["rows"]
    assert row["variant"] == "faithful" and not row["departure_from_study"]
    fractions = [v for k, v in row.items() if k.startswith("fraction_")
                 and k != "fraction_silent"]
    assert {"fraction_place", "fraction_grid", "fraction_head_direction"} <= set(row)
    assert all(0 <= v <= 1 for v in fractions)
    assert row["error_over_pf_after_100s"] > 0 and row["arena_readout_accuracy_200s"] is None
    assert row["steps"] == 40000
    # the Markdown table: a header, its rule and the network's row, yes/no verdicts
    table = (tmp_path / "scorecard.md").read_text().splitlines()
    assert len(table) == 3 and table[2].startswith("| `generalized` (faithful) | 40,000 |")
    assert table[0].count("|") == table[2].count("|")
    assert table[2].endswith("| no | no |")
    assert (tmp_path / "map_ingredients.png").stat().st_size > 1000


def test_main_at_another_size_runs_without_refreshing(capsys):
    import argparse

    from hippo_probe._main import _refresh_of_main

    tiny = argparse.Namespace(size="tiny", refresh_tracked=".")
    assert _refresh_of_main(tiny) is None
    assert "not refreshed" in capsys.readouterr().out
    paper = argparse.Namespace(size="paper", refresh_tracked=".")
    assert _refresh_of_main(paper) == "."


def test_shared_arrays_are_made_once_for_every_run_of_a_world(tmp_path):
    """The reference filters' estimates, which do not depend on the networks, are made
    by a world's first run and read by its others; another world, or other trials, make
    their own."""
    import numpy as np

    from hippo_probe.paper.config import CONFIGS, for_run, shared_arrays, with_cache

    base = with_cache(CONFIGS["tiny"], tmp_path)
    made = []

    def make(value):
        def run():
            made.append(value)
            return {"estimate": np.full(3, value)}
        return run

    first = shared_arrays("pf", for_run(base, "darkness", 0), make(1.0), "trials-a")
    second = shared_arrays("pf", for_run(base, "darkness", 1), make(2.0), "trials-a")
    assert made == [1.0] and np.array_equal(second["estimate"], first["estimate"])
    other_world = shared_arrays("pf", for_run(base, "compass", 0), make(3.0), "trials-a")
    other_trials = shared_arrays("pf", for_run(base, "darkness", 1), make(4.0), "trials-b")
    assert made == [1.0, 3.0, 4.0]
    assert other_world["estimate"][0] == 3.0 and other_trials["estimate"][0] == 4.0


def test_a_data_set_of_anothers_network_and_trials_is_read_from_its_recording(
        tmp_path, monkeypatch):
    """Where fig4's ``specialized_many`` is fig3's ``specialized`` without baselines (the
    same network on the same trials, as at the paper's size), it is read from that
    recording, identical to recording it afresh, without running the network again;
    with other trials, or before the other is recorded, it is recorded."""
    import shutil

    import zarr

    import hippo_probe as hp
    from hippo_probe.paper.config import CONFIGS, recording, with_cache

    same = replace(CONFIGS["tiny"], trials=6, remap_trials=6)
    fresh = recording("specialized_many", with_cache(same, tmp_path / "fresh"))
    shared = with_cache(same, tmp_path / "shared")
    with_baselines = recording("specialized", shared)
    assert "estimate_pf" in with_baselines
    stale = shared.cache / "specialized_many.zarr"     # one made by other code: removed
    shutil.copytree(with_cache(same, tmp_path / "fresh").cache / "specialized_many.zarr",
                    stale)
    zarr.open_group(str(stale), mode="r+").attrs["paper_key"] = "made by other code"

    def no_second_pass(*args, **kwargs):
        raise AssertionError("the network was run again")

    with monkeypatch.context() as patch:
        patch.setattr(hp, "record", no_second_pass)
        derived = recording("specialized_many", shared)
    assert derived.chunks == fresh.chunks
    assert derived.load().identical(fresh.load())
    assert not stale.exists()

    other = with_cache(replace(same, remap_trials=4), tmp_path / "shared")
    assert recording("specialized_many", other).sizes["trial_id"] == 4


def test_runs_made_at_once_wait_for_the_shared_arrays_instead_of_making_them_twice(
        tmp_path):
    import threading
    import time

    import numpy as np

    pytest.importorskip("fcntl")           # without POSIX locks each run makes its own
    from hippo_probe.paper.config import CONFIGS, for_run, shared_arrays, with_cache

    base = with_cache(CONFIGS["tiny"], tmp_path)
    made, results = [], {}

    def run(seed):
        def make():
            made.append(seed)
            time.sleep(0.3)             # long enough for the other run to ask meanwhile
            return {"estimate": np.arange(4.0)}
        results[seed] = shared_arrays("pf_slam", for_run(base, "darkness", seed), make)

    threads = [threading.Thread(target=run, args=(seed,)) for seed in (0, 1)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(made) == 1
    assert np.array_equal(results[0]["estimate"], results[1]["estimate"])


def test_runs_at_once_start_with_each_interleave_worlds():
    from hippo_probe._main import _interleave_worlds
    from hippo_probe.paper.config import CONFIGS, for_run

    runs = [for_run(CONFIGS["tiny"], world, seed) for world, seed in
            [("darkness", 0), ("darkness", 1), ("darkness", 2), ("compass", 0)]]
    assert [cfg.run for cfg in _interleave_worlds(runs)] == [
        "darkness-seed0", "compass-seed0", "darkness-seed1", "darkness-seed2"]


@pytest.mark.parametrize("before,after", [
    (None, "glibc.malloc.hugetlb=1"),
    ("glibc.malloc.arena_max=2", "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1"),
    ("glibc.malloc.hugetlb=0", "glibc.malloc.hugetlb=0")])
def test_figure_workers_ask_for_huge_pages_unless_told_otherwise(monkeypatch, before, after):
    from hippo_probe._main import _huge_pages_for_malloc

    if before is None:
        monkeypatch.delenv("GLIBC_TUNABLES", raising=False)
    else:
        monkeypatch.setenv("GLIBC_TUNABLES", before)
    assert _huge_pages_for_malloc() == after


def test_a_worlds_runs_share_the_filters_of_the_same_trials_only(tmp_path, monkeypatch):
    """The recordings' reference-filter estimates are made once for two networks' runs,
    are those the filters give on the run's own trials, and are made again for other
    trials or another particle count."""
    import numpy as np

    from hippo_probe.paper import config as C
    from hippo_probe.tasks import make_trials, task_config

    real, calls = C.baseline_estimates, []

    def counted(batch, which, n_particles):
        calls.append((batch.position.shape[1], n_particles))
        return real(batch, which, n_particles)

    monkeypatch.setattr(C, "baseline_estimates", counted)
    base = C.with_cache(C.CONFIGS["tiny"], tmp_path)
    for seed in (0, 1):
        C.recording("localization", C.for_run(base, "darkness", seed))
    assert calls == [(base.trials, base.particles)]
    batch = make_trials("localization", base.trials, "test", base.seed,
                        config=task_config("localization", "darkness"))
    direct = real(batch, ("pi", "sh", "pf"), base.particles)
    shared = C.shared_arrays("baselines-localization-pi-sh-pf", C.for_run(base, "darkness", 2),
                             lambda: pytest.fail("made again"), C.batch_digest(batch),
                             ("pi", "sh", "pf"), base.particles)
    assert set(shared) == set(direct)
    for name in direct:
        assert np.array_equal(shared[name], direct[name]), name

    C.recording("localization", C.for_run(replace(base, trials=base.trials + 1),
                                          "darkness", 1))
    C.recording("localization", C.for_run(replace(base, particles=base.particles + 10),
                                          "darkness", 1))
    assert calls[1:] == [(base.trials + 1, base.particles),
                         (base.trials, base.particles + 10)]


def test_a_continued_network_names_its_last_pass_and_the_one_before():
    from hippo_probe.paper.results import _trained
    info = {"steps_done": 3500, "steps_budget": 3500, "finished": True}
    assert _trained("net", info) == "net 3500 of 3500 steps"
    continued = _trained("net", {**info, "base_network": "generalized",
                                 "base_network_steps": 6000})
    assert continued == ("net 3500 of 3500 steps (its last pass; the one before: 6000 "
                         "steps of generalized)")
