"""
Decoding the particle filter's uncertainty from the units
=========================================================

The study asks whether the network represents not only where the rat is but how sure it
is. An oracular particle filter run on the same trials gives the posterior covariance;
:func:`hippo_probe.decode_covariance` regresses it on the units (ridge, cross-validated
by trial) and reports R² per component.
"""

# %%
import hippo_probe as hp

batch = hp.tasks.make_trials("localization", n_trials=12, split="test", seed=0)
pf = hp.baselines.particle_filter(batch, n_particles=500)
rec = hp.record(hp.load_pretrained("localization"), batch,
                baselines={"estimate_pf": pf.estimate, "pf_cov": pf.cov})

# %%
dec = hp.decode_covariance(rec, n_folds=3)
print(dec.r2.to_series().round(2))
dec.hp.plot()
