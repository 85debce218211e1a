"""
Which network has place cells? The map scorecard
================================================

The study's generalized network localizes well, but its units are smooth gradients over
the arena. ``generalized_nonneg`` departs from the study in one ingredient: its units
are non-negative (``h = o * relu(tanh c)``) and training adds an L1 cost on their
activity. :func:`hippo_probe.map_scorecard` measures both alike, with verdicts by rules
fixed before any variant was trained: are there place fields, and do the maps remap
globally between two arenas?
"""

# %%
# The same trials for both networks: 40 test trials in two arenas neither network
# trained in (the first two of the specialized task's arenas).
import dataclasses

import pandas as pd

import hippo_probe as hp

two_arenas = dataclasses.replace(hp.tasks.task_config("specialized"), n_arenas=2,
                                 classify=False)
batch = hp.tasks.make_trials("specialized", n_trials=40, split="test", seed=0,
                             config=two_arenas)
recordings = {name: hp.record(hp.load_pretrained(name), batch)
              for name in ("generalized", "generalized_nonneg")}

# %%
# The scorecard of each, side by side. Most of the non-negative units are silent; the
# active ones have compact fields, so the place-field verdict flips, but their maps
# correlate about as much across the two arenas as within one: no global remapping.
cards = {name: hp.map_scorecard(rec, bin_size=0.03) for name, rec in recordings.items()}
table = pd.DataFrame({name: {**{k: float(card[k]) for k in card.data_vars
                                if card[k].ndim == 0},
                             "place fields": card.attrs["place_fields"],
                             "global remapping": card.attrs["global_remapping"]}
                      for name, card in cards.items()})
print(cards["generalized"].attrs["place_rule"])
print(cards["generalized"].attrs["remapping_rule"])
table

# %%
# What the numbers summarize: the variant's eight most spatially informative units, in
# arena 0 (top) and arena 1 (bottom), each in its own colour scale (the peaks are
# small: the L1 cost keeps the activity low). Several fire in one arena and are silent in
# the other, as cells do in global remapping; across all the active units, though, the
# median map correlation between the arenas is no lower than within one, so the verdict
# stays "no". (Units silent in an arena have no defined map correlation or information;
# the warnings say which.)
import matplotlib.pyplot as plt

nonneg = recordings["generalized_nonneg"]
information = hp.spatial_information(nonneg, bin_size=0.03).information
best = sorted(information.fillna(-1).argsort().values[::-1][:8])
maps = hp.ratemaps(nonneg, bin_size=0.03, by="environment")
fig = plt.figure(figsize=(13, 4.4), layout="constrained")
for panel, arena in zip(fig.subfigures(2, 1), maps.environment.values):
    hp.plot.ratemap_grid(maps, units=best, group=arena, fig=panel)

# %%
# The study's network in the same two arenas: every unit active everywhere, a gradient
# whose direction barely changes between the arenas.
study_maps = hp.ratemaps(recordings["generalized"], bin_size=0.03, by="environment")
fig = plt.figure(figsize=(13, 4.4), layout="constrained")
for panel, arena in zip(fig.subfigures(2, 1), study_maps.environment.values):
    hp.plot.ratemap_grid(study_maps, units=range(8), group=arena, fig=panel)
