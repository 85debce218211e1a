"""
Cell classes of a mouse session
===============================

:func:`hippo_probe.classify_cells` scores every unit as a place, grid, border,
head-direction and speed cell against its own time-shifted shuffles, as a
hippocampal-entorhinal lab does. The classes depend on the bin size (coarser bins smooth
fields together), so it is stated and can be varied.
"""

# %%
import hippo_probe as hp
from _paths import MOUSE_NWB

mouse = hp.from_nwb(MOUSE_NWB)
cells = hp.classify_cells(mouse, n_shuffles=20, bin_size=0.04, seed=0)
cells.hp.plot()
print(cells["cell_class"].to_series().value_counts() if "cell_class" in cells else cells)
