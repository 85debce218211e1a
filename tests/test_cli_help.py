"""The ``hippo-probe`` command explains itself: every option has help text and shows its
default, the task, world and split options offer exactly their names, an output path is
refused before any work, the long steps show progress, and ``--help`` never imports torch.
"""

import argparse
import json
import subprocess
import sys
import textwrap
import time
import warnings

import pytest

from hippo_probe.cli import build_parser, main
from hippo_probe.tasks import SPLITS, TASKS
from hippo_probe.world.config import WORLDS


def subcommands(parser) -> dict:
    """name -> parser of every subcommand (argparse has no public way to list them)."""
    found = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(found[0].choices)


def options(parser) -> list:
    """The parser's arguments, less --help, --version and the subcommands."""
    skip = (argparse._HelpAction, argparse._VersionAction, argparse._SubParsersAction)
    return [a for a in parser._actions if not isinstance(a, skip)]


def squeeze(text: str) -> str:
    """``text`` without whitespace, so line wrapping (even at a hyphen) does not matter."""
    return "".join(text.split())


PARSER = build_parser()
COMMANDS = subcommands(PARSER)
RESTRICTED = {"--task": TASKS, "--world": WORLDS, "--split": SPLITS}
LONG_COMMANDS = ("train", "evaluate", "record", "baselines", "figures", "main")


def test_every_command_is_there():
    assert {"world-stats", "train", "evaluate", "record", "export-network", "baselines",
            "import-nwb", "main", "figures"} <= set(COMMANDS)


@pytest.mark.parametrize("name", ["hippo-probe", *COMMANDS])
def test_every_option_has_help_and_its_default_is_shown(name):
    parser = PARSER if name == "hippo-probe" else COMMANDS[name]
    assert issubclass(parser.formatter_class, argparse.ArgumentDefaultsHelpFormatter)
    shown = squeeze(parser.format_help())
    for action in options(parser):
        flag = "/".join(action.option_strings) or action.metavar or action.dest
        assert action.help and action.help.strip(), f"{name} {flag}: no help text"
        if action.default is not None and action.default is not argparse.SUPPRESS:
            text = action.help.replace("%%", "%")
            assert squeeze(f"{text} (default: {action.default})") in shown, \
                f"{name} {flag}: its default {action.default!r} is not shown"


def test_task_world_and_split_offer_exactly_their_names():
    seen = set()
    for name, parser in COMMANDS.items():
        for action in options(parser):
            for flag, allowed in RESTRICTED.items():
                if flag in action.option_strings:
                    assert action.choices is not None and tuple(action.choices) == allowed, \
                        f"{name} {flag}: choices {action.choices}"
                    seen.add((name, flag))
    for name in ("train", "evaluate", "record", "baselines"):
        assert (name, "--task") in seen and (name, "--world") in seen
    for name in ("world-stats", "evaluate", "record", "baselines"):
        assert (name, "--split") in seen


@pytest.mark.parametrize("name, flag", [
    (name, flag) for name, parser in COMMANDS.items() for flag in RESTRICTED
    if any(flag in a.option_strings for a in options(parser))])
def test_another_name_is_refused_in_one_line_naming_the_choices(name, flag, capsys):
    assert main([name, flag, "maze"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"hippo-probe {name}: error:")
    assert f"argument {flag}: `{flag[2:]}` must be one of" in err and "got 'maze'" in err
    assert repr(RESTRICTED[flag][0]) in err


@pytest.mark.parametrize("name", LONG_COMMANDS)
def test_every_long_command_can_hide_its_progress(name):
    flags = {f for a in options(COMMANDS[name]) for f in a.option_strings}
    assert "--no-progress" in flags


def test_baselines_refuses_an_existing_out_before_making_any_trial(tmp_path, capsys,
                                                                    monkeypatch):
    import hippo_probe.tasks

    def no_trials(*args, **kwargs):
        raise AssertionError("a trial was made before the output was checked")

    monkeypatch.setattr(hippo_probe.tasks, "make_trials", no_trials)
    existing = tmp_path / "b.zarr"
    existing.mkdir()
    began = time.perf_counter()
    code = main(["baselines", "--task", "generalized", "--out", str(existing)])
    elapsed = time.perf_counter() - began
    assert code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"--out {existing} already exists; pass --overwrite to replace it" in err
    assert elapsed < 0.5, f"took {elapsed:.2f} s to refuse"
    assert not any(existing.iterdir())


@pytest.mark.parametrize("argv, words", [
    (["baselines", "--task", "localization", "--out", "NEW", "--plot", "FOLDER"],
     "--plot {folder} is a folder; give a file name (e.g. {folder}/errors.png)"),
    (["world-stats", "--plot", "FOLDER"],
     "--plot {folder} is a folder; give a file name (e.g. {folder}/example_trials.png)"),
    (["world-stats", "--json", "FOLDER"],
     "--json {folder} is a folder; give a file name (e.g. {folder}/numbers.json)"),
    (["baselines", "--task", "localization", "--out", "FILE/b.zarr"],
     "--out {file}/b.zarr: {file} is a file, not a folder"),
    (["import-nwb", "session.nwb", "FOLDER"], "DEST {folder} already exists; pass --overwrite"),
    (["figures", "--out", "FILE"], "--out {file} is a file; give a folder"),
    (["main", "--out", "FILE"], "--out {file} is a file; give a folder"),
    (["train", "--task", "localization", "--out", "FILE"],
     "--out {file} is a file; give a folder"),
    (["world-stats", "--json", "FILE"],
     "--json {file} exists and is not a json file (.json) this command writes; pass "
     "--overwrite"),
    (["world-stats", "--plot", "FILE"],
     "--plot {file} exists and is not a figure file (.png, .pdf, .svg)"),
    (["baselines", "--task", "localization", "--out", "NEW", "--plot", "FILE"],
     "--plot {file} exists and is not a figure file"),
    (["baselines", "--task", "localization", "--out", "NEW", "--first", "1000000000"],
     "--first 1000000000: the test split of the localization task holds trials 0 to 999"),
    (["baselines", "--task", "localization", "--out", "NEW", "--first", "990",
      "--trials", "20"],
     "--first 990 --trials 20: the test split of the localization task holds trials 0 to "
     "999"),
])
def test_outputs_are_refused_before_the_work_naming_the_flag(argv, words, tmp_path, capsys,
                                                             monkeypatch):
    import hippo_probe.tasks

    monkeypatch.setattr(hippo_probe.tasks, "make_trials", None)     # any use would fail
    folder, file = tmp_path / "folder", tmp_path / "file"
    folder.mkdir()
    file.write_text("")
    places = {"NEW": str(tmp_path / "new.zarr"), "FOLDER": str(folder), "FILE": str(file),
              "FILE/b.zarr": str(file / "b.zarr")}
    assert main([places.get(a, a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words.format(folder=folder, file=file) in err
    assert not (tmp_path / "new.zarr").exists()


def test_help_does_not_import_torch():
    """``hippo-probe --help`` (and every command's) is fast: no torch, in a fresh process."""
    argvs = [["--help"], *[[name, "--help"] for name in sorted(COMMANDS)]]
    script = textwrap.dedent(f"""
        import contextlib, io, json, sys
        from hippo_probe.cli import main
        with contextlib.redirect_stdout(io.StringIO()) as shown:
            codes = [main(argv) for argv in {argvs!r}]
        print(json.dumps({{"codes": codes, "torch": "torch" in sys.modules,
                           "shown": shown.getvalue().count("usage: hippo-probe")}}))
        """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["codes"] == [0] * (len(COMMANDS) + 1)
    assert result["shown"] == len(COMMANDS) + 1
    assert not result["torch"], "`hippo-probe --help` imported torch"


@pytest.fixture(scope="module")
def two_trials():
    pytest.importorskip("torch")
    from hippo_probe.model.load import load_pretrained
    from hippo_probe.tasks import make_trials

    net = load_pretrained("localization_compass")
    return net, make_trials("localization", 2, "test", 0, world=net.world)


def test_record_shows_progress_only_when_asked_and_records_the_same(two_trials, capsys):
    from hippo_probe.model.record import record

    net, batch = two_trials
    quiet = record(net, batch)
    assert capsys.readouterr().err == ""                      # library calls stay quiet
    shown = record(net, batch, progress=True)
    assert "record localization" in capsys.readouterr().err
    assert (quiet.activity.values == shown.activity.values).all()
    assert (quiet.estimate.values == shown.estimate.values).all()


def test_evaluate_shows_progress_and_prints_the_same_numbers(two_trials, capsys):
    argv = ["evaluate", "localization_compass", "--trials", "2", "--world", "compass"]
    assert main([*argv, "--no-progress"]) == 0
    quiet = capsys.readouterr()
    assert "evaluate" not in quiet.err
    assert main(argv) == 0
    shown = capsys.readouterr()
    assert "evaluate localization" in shown.err and "2/2" in shown.err
    assert json.loads(shown.out) == json.loads(quiet.out)


def test_the_toolkit_s_warnings_print_as_one_line_naming_the_command(tmp_path):
    from hippo_probe._cli_common import PACKAGE, plain_warnings

    ours = str(PACKAGE / "model" / "_cli.py")
    with plain_warnings("record"):
        assert warnings.formatwarning("arenas differ", UserWarning, ours, 58) == \
            "hippo-probe record: warning: arenas differ\n"
        # another library's warning keeps Python's form (its file and line)
        assert warnings.formatwarning("old", FutureWarning, "/lib/other.py", 3).startswith(
            "/lib/other.py:3: FutureWarning: old")
        with pytest.warns(UserWarning, match="still recorded"):   # recording is untouched
            warnings.warn_explicit("still recorded", UserWarning, ours, 1)
    assert warnings.formatwarning("x", UserWarning, ours, 58).startswith(ours)   # restored


def test_a_command_prints_the_toolkit_s_warnings_as_one_line():
    """End to end, in a fresh process (pytest records warnings instead of printing them)."""
    script = textwrap.dedent("""
        import sys, warnings
        import hippo_probe.pretrained.summary as summary
        from hippo_probe.cli import main

        def warn_then_fail(*args, **kwargs):
            warnings.warn_explicit("a warning of ours", UserWarning, summary.__file__, 1)
            raise FileNotFoundError("stop here")

        summary.shipped_table = warn_then_fail
        sys.exit(main(["networks"]))
    """)
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          check=False)
    assert done.returncode == 2
    assert done.stderr == ("hippo-probe networks: warning: a warning of ours\n"
                           "hippo-probe networks: error: stop here\n")
