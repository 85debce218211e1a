"""
Cell classes of a mouse session
===============================

:func:`hippo_probe.classify_cells` scores every unit as a place, grid, border,
head-direction and speed cell against its own time-shifted shuffles, as a
hippocampal-entorhinal lab does. The classes depend on the bin size (coarser bins smooth
fields together), so it is stated and can be varied.
"""

# %%
import warnings

import hippo_probe as hp
from _paths import MOUSE_NWB

mouse = hp.from_nwb(MOUSE_NWB, position_units="m")

# %%
# Twenty shuffles keep the example quick (the papers use 100 or more). The scores that
# cannot be computed say why, with a warning: a grid score needs a ring of peaks in the
# autocorrelogram, which a single field or a maze's arm does not have, and the
# position x direction model of the conjunctive score may stop before converging on a
# short session. They are recorded in the result's attrs; here they are silenced.
# One warning matters for reading the classes: this mouse ran on a Y-maze, not in an
# open field. Without ``walls=`` the border score takes the arena's walls to be the
# convex hull of the visited bins, which the maze fills only 28% of, so its walls cross
# space the mouse never entered; the border and grid classes of this session are not the
# open-field classes those scores were defined for (``classify_cells`` warns so).
with warnings.catch_warnings():
    warnings.simplefilter("ignore", hp.AnalysisWarning)
    cells = hp.classify_cells(mouse, n_shuffles=20, bin_size=0.04, seed=0)
cells.hp.plot()
print(cells["cell_class"].to_series().value_counts())

# %%
# The bin size matters. By default the maps' bins follow the session (here about 2.4 cm);
# at 4 cm, neighbouring fields and a field's edge merge differently, and a few CA1 units
# change class. A lab states the bin size with its classes; so does the result
# (``cells.attrs["bin_size"]``).
import pandas as pd

with warnings.catch_warnings():
    warnings.simplefilter("ignore", hp.AnalysisWarning)
    default = hp.classify_cells(mouse, n_shuffles=20, seed=0)
table = pd.DataFrame({
    "region": cells["region"].values,
    f"{default.attrs['bin_size'] * 100:.1f} cm bins": default["cell_class"].values,
    f"{cells.attrs['bin_size'] * 100:.1f} cm bins": cells["cell_class"].values,
}, index=cells["unit"].values)
print(table[table.iloc[:, 1] != table.iloc[:, 2]])
