import subprocess
import sys


def test_analyses_and_plots_never_import_torch():
    code = ("import sys, hippo_probe as hp\n"
            "import hippo_probe.analysis, hippo_probe.plot\n"
            "[getattr(hp, n) for n in hippo_probe.analysis.__all__ if n[0].islower()]\n"
            "assert 'torch' not in sys.modules, 'torch was imported'\n"
            "assert 'matplotlib' not in sys.modules, 'matplotlib imported before a plot'\n")
    subprocess.run([sys.executable, "-c", code], check=True)
