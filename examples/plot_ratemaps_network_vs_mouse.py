"""
Rate maps of a network beside a mouse session
=============================================

A trained network is recorded like an electrophysiology session, a real mouse session
(NWB) loads into the same layout, and :func:`hippo_probe.ratemaps` runs unchanged on both.
"""

# %%
# Record the generalized network on 40 test trials (novel arenas of radius 0.33 m).
import hippo_probe as hp

net = hp.load_pretrained("generalized")
batch = hp.tasks.make_trials("generalized", n_trials=40, split="test", seed=0)
network = hp.record(net, batch)
network

# %%
# Load the mouse session: anterodorsal thalamus and CA1 units, position, head direction.
from _paths import MOUSE_NWB

mouse = hp.from_nwb(MOUSE_NWB)
print(mouse.sizes["unit"], "units,", float(mouse.time[-1] - mouse.time[0]) / 60, "min")

# %%
# The same call on both: occupancy-normalized maps, smoothed by normalized convolution.
# The maps are labelled xarray objects; ``.hp.plot()`` draws a grid of them.
net_maps = hp.ratemaps(network, bin_size=0.04)
mouse_maps = hp.ratemaps(mouse, bin_size=0.04)
net_maps.isel(unit=slice(0, 8)).hp.plot()
mouse_maps.isel(unit=slice(0, 8)).hp.plot()

# %%
# Skaggs information of each unit (the network's units shifted to a non-negative rate,
# as the result's attrs say).
info = hp.spatial_information(net_maps)
print(info.attrs["nonnegative_rate"] if "nonnegative_rate" in info.attrs else "")
print(hp.spatial_information(mouse_maps).information.round(3).values)
