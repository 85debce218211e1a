"""
Remapping between two arenas
============================

Do a network's spatial maps change when its arena changes? Population vectors of rate
maps from trials in the same arena are compared with those from different arenas
(:func:`hippo_probe.remapping_similarity`); the control permutes the arena labels.
"""

# %%
import numpy as np

import hippo_probe as hp

# 400 specialized-task trials spread over the 100 familiar arenas; keep the two arenas
# visited most, so each has several trials.
net = hp.load_pretrained("specialized")
batch = hp.tasks.make_trials("specialized", n_trials=400, split="test", seed=0)
rec = hp.record(net, batch)
ids, counts = np.unique(rec.trial_environment.values, return_counts=True)
two = ids[np.argsort(counts)[-2:]]
rec = hp.select_trials(rec, environments=two)
print("arenas", two, "trials", rec.sizes["trial_id"])

# %%
sim = hp.remapping_similarity(rec, bin_size=0.05)
sim.hp.plot()
print(sim["median"].to_series().round(3))
