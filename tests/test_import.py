"""``import hippo_probe`` stays light: no torch until a part that needs it is used."""

import json
import subprocess
import sys

CHECK = """
import json, sys
loaded = {}
import hippo_probe
loaded["import hippo_probe"] = "torch" in sys.modules
hippo_probe.__version__, hippo_probe.HippoProbeError
loaded["version and errors"] = "torch" in sys.modules
hippo_probe.tasks.make_trials("generalized", 2, "train", 0)
loaded["world and tasks (make_trials)"] = "torch" in sys.modules
hippo_probe.cli.build_parser()
loaded["the command line parser"] = "torch" in sys.modules
print(json.dumps(loaded))
"""


def test_import_hippo_probe_does_not_load_torch():
    done = subprocess.run([sys.executable, "-c", CHECK], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0, done.stderr
    loaded = json.loads(done.stdout.strip().splitlines()[-1])
    assert list(loaded) == ["import hippo_probe", "version and errors",
                            "world and tasks (make_trials)", "the command line parser"]
    assert not any(loaded.values()), f"torch was imported by: {loaded}"


def test_public_names_resolve():
    import hippo_probe

    assert hippo_probe.world.random_arena is not None
    assert hippo_probe.tasks.make_trials is not None
    assert {"world", "tasks"} <= set(dir(hippo_probe))
