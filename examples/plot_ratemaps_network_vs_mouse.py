"""
Rate maps of a network beside a mouse session
=============================================

A trained network is recorded like an electrophysiology session, a real mouse session
(NWB) loads into the same layout, and :func:`hippo_probe.ratemaps` runs unchanged on both.
"""

# %%
# Record the generalized network on 40 test trials in one arena it never trained in
# (a fixed random polygon; the task's trials are otherwise each in a new arena, and maps
# pooled over arenas would mix their shapes: ``by="environment"`` separates them).
import hippo_probe as hp

net = hp.load_pretrained("generalized")
one_arena = hp.tasks.task_config("generalized", arenas="fixed", n_arenas=1)
batch = hp.tasks.make_trials("generalized", n_trials=40, split="test", seed=0,
                             config=one_arena)
network = hp.record(net, batch)
network

# %%
# Load the mouse session: anterodorsal thalamus and CA1 units, position, head direction.
from _paths import MOUSE_NWB

mouse = hp.from_nwb(MOUSE_NWB, position_units="m")
minutes = float(mouse.time[-1] - mouse.time[0]) / 60
print(f"{mouse.sizes['unit']} units, {minutes:.1f} min")

# %%
# The same call on both: occupancy-normalized maps, smoothed by normalized convolution.
# The maps are labelled xarray objects; ``.hp.plot()`` draws a grid of them. The
# network's units, in a novel arena, are smooth gradients ...
net_maps = hp.ratemaps(network, bin_size=0.04)
net_maps.isel(unit=slice(0, 8)).hp.plot()

# %%
# ... and the mouse's CA1 cells, in their maze, fire in fields (the ``region``
# coordinate tells them from the anterodorsal thalamus's head-direction cells), outlined
# here as :func:`hippo_probe.place_fields` detects them.
mouse_maps = hp.ratemaps(mouse, bin_size=0.04)
ca1 = mouse_maps.isel(unit=mouse_maps.region.values == "ca1")
ca1.hp.plot(fields=hp.place_fields(ca1))
# sphinx_gallery_thumbnail_number = 2

# %%
# Skaggs information of each unit, from the recordings: on unsmoothed maps (its
# default; smoothing spreads a field and lowers it). It needs a non-negative rate: the
# network's signed units are shifted by their minimum, as the result's attrs say.
net_info = hp.spatial_information(network, bin_size=0.04)
print(net_info.attrs["rate_offset"])
print("network:", net_info.information.round(3).values[:8])
print("mouse:  ", hp.spatial_information(mouse, bin_size=0.04).information.round(3).values)
