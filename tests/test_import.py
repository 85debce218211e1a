"""``import hippo_probe`` stays light: no torch until a part that needs it is used."""

import json
import subprocess
import sys


def torch_loaded_after(*steps):
    """Run ``steps`` (Python statements) in a fresh interpreter; for each, whether torch
    had been imported by then."""
    lines = ["import json, sys", "loaded = []"]
    for step in steps:
        lines += [step, "loaded.append('torch' in sys.modules)"]
    lines.append("print(json.dumps(loaded))")
    done = subprocess.run([sys.executable, "-c", "\n".join(lines)], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return dict(zip(steps, json.loads(done.stdout.strip().splitlines()[-1])))


def test_import_hippo_probe_and_making_trials_do_not_load_torch():
    loaded = torch_loaded_after(
        "import hippo_probe",
        "hippo_probe.__version__, hippo_probe.HippoProbeError",
        "hippo_probe.tasks.make_trials('generalized', 2, 'train', 0)",
    )
    assert not any(loaded.values()), f"torch was imported by: {loaded}"


def test_the_command_line_parser_does_not_load_torch():
    """``hippo-probe --help`` stays fast: each subsystem's ``_cli`` imports nothing heavy."""
    step = "hippo_probe.cli.build_parser()"
    loaded = torch_loaded_after("import hippo_probe", step)
    assert not loaded[step], f"torch was imported by {step}"


def test_public_names_resolve():
    import hippo_probe

    assert callable(hippo_probe.world.random_arena)
    assert callable(hippo_probe.tasks.make_trials)
    assert {"world", "tasks"} <= set(dir(hippo_probe))
    # every advertised name exists (a name in __all__ without a module behind it would
    # show in tab completion and then fail)
    for name in hippo_probe.__all__:
        assert getattr(hippo_probe, name) is not None, name
