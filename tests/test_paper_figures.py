"""Every paper-figure script and the network-vs-rodent comparison run end to end on a
tiny configuration (a handful of trials) from the shipped networks."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def figures(tmp_path_factory):
    out = tmp_path_factory.mktemp("figures")
    run = subprocess.run([sys.executable, "-m", "hippo_probe.cli", "figures", "--size",
                          "tiny", "--out", str(out)], capture_output=True, text=True,
                         cwd=ROOT, timeout=1200)
    assert run.returncode == 0, run.stderr[-4000:]
    return out


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


def test_results_table(figures, tmp_path):
    out = tmp_path / "RESULTS.md"
    run = subprocess.run([sys.executable, str(ROOT / "paper_figures" / "results.py"),
                          "--figures", str(figures), "--out", str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    claims, errors = out.read_text().split("Mean Euclidean error (m)")

    def table(text):
        return [line for line in text.splitlines() if line.startswith("| ") and "---" not in line]

    rows = table(claims)
    assert len(rows) >= 11
    measured = [row.rsplit("|", 2)[-2] for row in rows[1:]]
    assert not [m for m in measured if "n/a" in m], measured
    # each network beside its baselines at 50 / 100 / 200 s: three numbers per cell
    rows = table(errors)
    assert [r.split("|")[1].split()[0] for r in rows[1:]] == ["localization", "generalized",
                                                              "specialized"]
    for row in rows[1:]:
        network, pf = row.split("|")[2:4]
        assert len(network.split("/")) == 3 and len(pf.split("/")) == 3
    assert "Arena classification accuracy at 50 / 100 / 200 s" in errors


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
                          "specialized", "--out", str(tmp_path)], capture_output=True,
                         text=True, cwd=ROOT, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    res = json.loads((tmp_path / "arena_probe.json").read_text())["results"]
    cells = [cell for by_c in res["specialized"].values() for cell in by_c.values()]
    assert len(cells) == 9 and all(0 <= c["test"] <= 1 for c in cells)
    # the positive control: a probe of the specialized network separates the training
    # trials' arenas far above chance (0.01)
    assert max(c["train"] for c in cells) > 0.5
