"""Sphinx configuration of the hippo_probe documentation.

Build: ``sphinx-build -W -b html docs docs/_build/html`` (the tests do, warnings as
errors). The gallery executes every ``examples/plot_*.py`` on small data.
"""

import os
import sys
import warnings
from pathlib import Path

import hippo_probe

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "examples"))     # the examples' shared _paths.py
os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("TQDM_DISABLE", "1")

project = "hippo_probe"
author = "the hippo_probe developers"
copyright = "2026, the hippo_probe developers"
release = version = hippo_probe.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
    "myst_parser",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "generated/*.examples", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.md5", "auto_examples/*.json"]
autosummary_generate = True
# classes: their own documented members, not those inherited (torch.nn.Module has ~50)
templates_path = ["_templates"]
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_show_inherited_class_members = False
numpydoc_class_members_toctree = False
numpydoc_validation_checks = set()
# docstrings cite their own modules in prose; only the pages below are cross-referenced
numpydoc_xref_param_type = False
myst_heading_anchors = 3
suppress_warnings = ["myst.header", "ref.python",
                     "autosummary.import_cycle"]

sphinx_gallery_conf = {
    "examples_dirs": str(HERE.parent / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "reset_modules": ("matplotlib",),
    "ignore_pattern": r"(__init__|_paths)\.py",
    "capture_repr": ("_repr_html_",),     # datasets as tables; figures only as pictures
}

html_theme = "pydata_sphinx_theme"
html_title = "hippo_probe"
html_theme_options = {
    "navigation_with_keys": False,
    "show_prev_next": False,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path = ["_static"]
html_css_files = ["hippo_probe.css"]
warnings.filterwarnings("ignore", category=UserWarning,
                        message="Matplotlib is currently using agg")
