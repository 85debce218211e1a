"""
Head-direction tuning: ADn cells and network units
==================================================

The anterodorsal thalamus holds the classic head-direction cells. The study's networks
receive a drifting head-direction input; how tuned are their units?
:func:`hippo_probe.head_direction_tuning` gives each unit's tuning curve and mean vector
length, with significance from circular time shifts.
"""

# %%
import hippo_probe as hp
from _paths import MOUSE_NWB

mouse = hp.from_nwb(MOUSE_NWB, position_units="m")
adn = mouse.isel(unit=mouse.region.values == "adn") if "region" in mouse.coords else mouse
hd_mouse = hp.head_direction_tuning(adn, n_shuffles=20)
hd_mouse.hp.plot()
print("ADn mean vector lengths", hd_mouse.mean_vector_length.round(2).values)

# %%
net = hp.load_pretrained("localization")
rec = hp.record(net, hp.tasks.make_trials("localization", n_trials=20, split="test", seed=0))
hd_net = hp.head_direction_tuning(rec.isel(unit=slice(0, 12)), n_shuffles=20)
hd_net.hp.plot()
print("network mean vector lengths", hd_net.mean_vector_length.round(2).values)
