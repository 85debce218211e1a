"""The documentation builds with warnings as errors, executing every gallery example."""

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).parents[1]


def test_the_documentation_builds_without_a_warning(tmp_path):
    # a fresh output folder, and every example run again (not taken from the gallery's
    # cache of unchanged examples)
    done = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-D", "sphinx_gallery_conf.run_stale_examples=1",
         "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(tmp_path / "html")],
        capture_output=True, text=True, timeout=600,
        env={**__import__("os").environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-3000:]
    html = tmp_path / "html"
    for page in ("index.html", "api.html", "auto_examples/index.html",
                 "generated/hippo_probe.ratemaps.html"):
        assert (html / page).is_file(), page
    # the seven examples ran and drew their figures
    pictures = list((html / "_images").glob("sphx_glr_plot_*_001.png"))
    assert len(pictures) >= 7, sorted(p.name for p in pictures)
