"""The ``hippo-probe`` command: ``world-stats``."""

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from hippo_probe.cli import main
from hippo_probe.tasks import TASKS, task_config


@pytest.fixture(scope="module")
def world_stats(tmp_path_factory):
    """Run ``hippo-probe world-stats`` once (in process) and keep what it printed and saved."""
    out = tmp_path_factory.mktemp("world-stats")
    capture = pytest.MonkeyPatch()
    printed = io.StringIO()
    capture.setattr(sys, "stdout", printed)
    try:
        code = main(["world-stats", "--trials", "120", "--split", "validation", "--seed", "1",
                     "--json", str(out / "stats.json"), "--plot", str(out / "trials.png")])
    finally:
        capture.undo()
    return code, printed.getvalue(), json.loads((out / "stats.json").read_text()), out


def test_world_stats_prints_a_row_per_task_and_saves_numbers_and_picture(world_stats):
    code, printed, stats, out = world_stats
    assert code == 0
    lines = printed.splitlines()
    for column in ("mean speed", "between contacts", "PI err 50 s", "PI err 100 s",
                   "PI err 200 s"):
        assert column in lines[0]
    for task in TASKS:
        row, drift_row = [line for line in lines if line.startswith(task)]
        numbers = [float(x) for x in row.split()[1:]]
        assert float(drift_row.split()[1]) == pytest.approx(
            stats[task]["drift_rate_median_deg_per_min"], abs=0.05)
        assert stats[task]["world"] == "darkness"
        assert numbers[0] == pytest.approx(stats[task]["mean_speed_m_per_s"], abs=1e-3)
        assert numbers[4] == pytest.approx(stats[task]["pi_error_200s_m"], abs=1e-3)
        assert stats[task]["n_trials"] == 120
    png = (out / "trials.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 20_000


@pytest.mark.parametrize("task", TASKS)
def test_world_stats_are_those_the_study_needs(world_stats, task):
    """Contacts seconds apart; PI drift growing like a random walk; speed as configured."""
    stats = world_stats[2][task]
    motion = task_config(task).world.motion
    assert 0.7 * motion.mean_speed < stats["mean_speed_m_per_s"] < 1.3 * motion.mean_speed
    assert 1.0 < stats["mean_time_between_contacts_s"] < 20.0
    pi = [stats[f"pi_error_{t}s_m"] for t in (50, 100, 200)]
    assert 0 < pi[0] < pi[1] < pi[2]
    assert 1.5 < pi[2] / pi[0] < 2.5          # ~ sqrt(200 / 50): independent noise per step


def test_generalized_pi_error_after_200_s_is_of_the_order_of_the_arena_radius(world_stats):
    """Otherwise boundaries would not matter and the study would be trivial."""
    radius = task_config("generalized").world.arena.mean_radius
    stats = world_stats[2]["generalized"]
    assert stats["arena_mean_radius_m"] == pytest.approx(radius, rel=1e-9)
    assert 0.5 * radius < stats["pi_error_200s_m"] < 2.0 * radius


def test_world_stats_of_the_compass_world_have_no_drift(capsys):
    assert main(["world-stats", "--world", "compass", "--trials", "10"]) == 0
    printed = capsys.readouterr().out
    assert "heading drift" not in printed          # the compass world's table, as it was
    rows = [line for line in printed.splitlines() if line.startswith("generalized")]
    assert len(rows) == 1


@pytest.mark.parametrize("argv, words", [
    (["--trials", "-1"], ["argument --trials", ">= 1", "-1"]),
    (["--trials", "0"], ["argument --trials", ">= 1", "0"]),
    (["--trials", "ten"], ["argument --trials", "whole number", "'ten'"]),
    (["--world", "moon"], ["`world`", "'moon'", "'darkness'"]),
    (["--split", "dev"], ["`split`", "'dev'"]),
    (["--seed", "-2"], ["`seed`", "-2"]),
])
def test_world_stats_bad_input_is_one_clear_line(argv, words, capsys):
    assert main(["world-stats", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("hippo-probe world-stats: error:")
    for word in words:
        assert word in err


def test_the_console_command_offers_world_stats():
    script = Path(sys.executable).with_name("hippo-probe")       # installed by pip
    command = [str(script)] if script.exists() else [sys.executable, "-m", "hippo_probe.cli"]
    done = subprocess.run([*command, "world-stats", "--help"], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    for option in ("--trials", "--split", "--seed", "--plot", "--json"):
        assert option in done.stdout
