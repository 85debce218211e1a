"""
Which network has place cells? The map scorecard
================================================

The study's generalized network localizes well, but its units are smooth gradients over
the arena. ``generalized_nonneg`` departs from the study in two ingredients: its units
are non-negative (``h = o * relu(tanh c)``) and its training adds an L1 cost on their
activity; it trained 20,000 steps (the study's network 40,000) and localizes worse: 3.26×
the oracular particle filter's error after 100 s on 1,000 test trials of the generalized
task, against 2.02× (``analyses/map_ingredients.py``; 3.18–3.26× over its three seeds).
:func:`hippo_probe.map_scorecard` measures both alike, with verdicts by rules fixed
before any variant was trained: are there place fields, and do the maps remap globally
between two arenas?
"""

# %%
# The same trials for both networks: 40 test trials in two arenas neither network
# trained in (the first two of the specialized task's arenas).
import dataclasses

import matplotlib.pyplot as plt
import numpy as np
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
# (40 trials make noisy maps; the scorecard of record uses 140, see the results guide.)
# Units silent in an arena have no map correlation there, and units silent in both no
# spatial information: the warnings say which.
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
# What the numbers summarize: the variant's eight most spatially informative units (by
# the information of their activity in each arena, averaged over the two), in arena 0
# (top) and arena 1 (bottom), each unit divided by its peak over both arenas so that its
# two maps compare.
# Several fire in one arena only and others fire in different places in the two, as
# cells do in global remapping; but they are the most informative units, not the typical
# ones: across all active units, the scorecard's
# ``fraction_active_in_one_environment`` is small and the median map correlation between
# the arenas is no lower than within one.
nonneg = recordings["generalized_nonneg"]
information = hp.spatial_information(nonneg, bin_size=0.03, by="environment").information
information = information.mean("environment").fillna(-1)
best = np.sort(information.unit.values[np.argsort(information.values)[::-1][:8]])


def both_arenas(maps, units):
    """The maps of ``units`` in every arena, each unit divided by its peak over all."""
    sub = maps.sel(unit=units)
    sub = sub / sub.max(("environment", "y", "x"))
    sub.attrs = {**maps.attrs, "long_name": "activity / the unit's peak in both arenas"}
    fig = plt.figure(figsize=(13, 4.4), layout="constrained")
    for panel, arena in zip(fig.subfigures(2, 1), sub.environment.values):
        hp.plot.ratemap_grid(sub, group=arena, scale="shared", fig=panel)


both_arenas(hp.ratemaps(nonneg, bin_size=0.03, by="environment"), best)
# sphinx_gallery_thumbnail_number = 1

# %%
# The study's network in the same two arenas, its first eight units: no unit silent, each
# a gradient whose direction barely changes between the arenas. (Its activity is signed;
# the maps are drawn as recorded.)
study = hp.ratemaps(recordings["generalized"], bin_size=0.03, by="environment")
fig = plt.figure(figsize=(13, 4.4), layout="constrained")
for panel, arena in zip(fig.subfigures(2, 1), study.environment.values):
    hp.plot.ratemap_grid(study, units=study.unit.values[:8], group=arena, fig=panel)
