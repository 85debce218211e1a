"""The core install (no torch) is a complete lab toolkit: the README's Jupyter example on
the mouse session runs in an interpreter where torch cannot be imported at all, and what
needs torch says which extra brings it."""

import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

ROOT = Path(__file__).parents[1]

# every `import torch` (and of its submodules) fails, as on a machine without it
NO_TORCH = textwrap.dedent("""
    import sys
    class _NoTorch:
        def find_spec(self, name, path=None, target=None):
            if name == "torch" or name.startswith("torch."):
                raise ModuleNotFoundError(f"No module named {name!r}", name=name)
    sys.meta_path.insert(0, _NoTorch())
""")


def run_without_torch(code: str):
    done = subprocess.run([sys.executable, "-c", NO_TORCH + textwrap.dedent(code)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_the_core_dependencies_do_not_include_torch():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    names = [d.split(">")[0].split("=")[0].split("[")[0].strip().lower()
             for d in project["dependencies"]]
    assert "torch" not in names
    assert any(d.startswith("torch") for d in project["optional-dependencies"]["model"])


def test_the_readme_jupyter_example_on_the_mouse_session_runs_without_torch():
    out = run_without_torch("""
        import matplotlib
        matplotlib.use("Agg")
        import hippo_probe as hp
        mouse = hp.from_nwb("tests/data/A2929-200711.nwb", epoch="wake", position_units="m")
        maps = hp.ratemaps(mouse)
        maps.hp.plot()
        hd = hp.head_direction_tuning(mouse, n_bins=60)
        hd.hp.plot()
        info = hp.spatial_information(mouse)
        assert "torch" not in sys.modules
        print(maps.sizes["unit"], hd.sizes["unit"], info.sizes["unit"])
    """)
    assert out.split() == ["15", "15", "15"]


def test_what_needs_torch_names_the_extra():
    out = run_without_torch("""
        import hippo_probe as hp
        for call in (lambda: hp.record, lambda: hp.load_pretrained("localization_compass")):
            try:
                call()
            except ModuleNotFoundError as err:
                print(err)
    """)
    lines = out.strip().splitlines()
    assert len(lines) == 2
    assert all("pip install 'hippo_probe[model]'" in line for line in lines)
