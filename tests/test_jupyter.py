"""In Jupyter, a plot is drawn once: ending a cell with ``result.hp.plot()``, assigning
it, or showing the Figure again in a later cell."""

import pytest

nbformat = pytest.importorskip("nbformat")
nbclient = pytest.importorskip("nbclient")
pytest.importorskip("ipykernel")

CELLS = [
    "%matplotlib inline\n"
    "import numpy as np\n"
    "import hippo_probe as hp\n"
    "rng = np.random.default_rng(0)\n"
    "n = 3000\n"
    "rec = hp.from_arrays(np.arange(1, n + 1) * 0.1, rng.uniform(-0.5, 0.5, (n, 2)),\n"
    "                     activity=rng.random((n, 4)))\n"
    "maps = hp.ratemaps(rec, bin_size=0.1)",
    "maps.hp.plot()",                  # the cell's value
    "fig = maps.hp.plot()",            # drawn by pyplot at the cell's end
    "fig",                             # the same Figure, shown again later
    "rec.hp.plot()",                   # a recording's overview
    "fig = maps.hp.plot()\nfig.savefig('maps.png')\nfig",
]


def test_each_plot_is_drawn_once_in_a_notebook(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(source) for source in CELLS]
    nbclient.NotebookClient(nb, timeout=300, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    images = [sum("image/png" in out.get("data", {}) for out in cell.outputs)
              for cell in nb.cells]
    assert images == [0, 1, 1, 1, 1, 1]
    assert (tmp_path / "maps.png").stat().st_size > 1000
