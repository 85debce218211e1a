"""The baselines dataset, its store and the ``hippo-probe baselines`` command."""

import numpy as np
import pytest

from hippo_probe.baselines import (BaselineConfig, NaiveBayesConfig, error_table,
                                   localization_errors, open_baselines, particle_filter,
                                   path_integration, run_baselines, save_baselines)
from hippo_probe.cli import main
from hippo_probe.tasks import make_trials

SMALL = BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=50))


@pytest.fixture(scope="module")
def generalized():
    batch = make_trials("generalized", 5, "test", 0, first=3)
    return batch, run_baselines(batch, n_particles=100, chunk=2, baseline=SMALL)


def test_layout_and_frames(generalized):
    batch, ds = generalized
    assert list(ds["trial_id"].values) == [3, 4, 5, 6, 7]
    assert ds["estimate_pf"].dims == ("trial_id", "trial_time", "space")
    assert ds["pf_cov"].dims == ("trial_id", "trial_time", "cov")
    assert list(ds["cov"].values) == ["xx", "yy", "xy"]
    assert "class_probability_pfslam" not in ds                 # no classes here
    # arena frame: the start-relative estimates with the start added back
    pi = path_integration(batch).estimate.swapaxes(0, 1) + batch.start[:, None]
    assert np.allclose(ds["estimate_pi"].values, pi)
    # chunking does not change the particle filter (per-trial random streams)
    pf = particle_filter(batch, 100).estimate.swapaxes(0, 1) + batch.start[:, None]
    assert np.array_equal(ds["estimate_pf"].values, pf)
    for name, var in ds.data_vars.items():
        assert "long_name" in var.attrs, name
    assert ds.attrs["frame"] == "arena" and ds.attrs["task"] == "generalized"


def test_errors_are_frame_free(generalized):
    batch, ds = generalized
    errors = localization_errors(ds)
    pi = path_integration(batch).error(batch).mean(axis=1)
    assert np.allclose(errors.sel(baseline="pi").values, pi)
    assert list(errors["baseline"].values) == ["pi", "sh", "nb", "pf"]
    assert "path integration" in error_table(ds)


def test_store_round_trip_and_no_overwrite(generalized, tmp_path):
    _, ds = generalized
    path = save_baselines(ds, tmp_path / "b.zarr")
    back = open_baselines(path)
    assert np.array_equal(back["estimate_sh"].values, ds["estimate_sh"].values)
    assert list(back["space"].values) == ["x", "y"]
    assert back.attrs["attrs_pf"] == ds.attrs["attrs_pf"]
    with pytest.raises(FileExistsError, match="exists"):
        save_baselines(ds, path)
    save_baselines(ds.isel(trial_id=[0]), path, overwrite=True)
    assert open_baselines(path).sizes["trial_id"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.zarr"]   # nothing left over


def test_specialized_has_class_posteriors():
    batch = make_trials("specialized", 2, "test", 0)
    ds = run_baselines(batch, n_particles=100, slam_particles=200, baseline=SMALL)
    prob = ds["class_probability_pfslam"]
    assert prob.dims == ("trial_id", "trial_time", "environment_id")
    assert prob.sizes["environment_id"] == 100
    assert np.allclose(prob.sum("environment_id"), 1.0, atol=1e-5)
    # PF-SLAM tracks the heading drift too, and its estimate is kept (darkness world)
    drift = ds["estimate_drift_pfslam"]
    assert drift.dims == ("trial_id", "trial_time") and drift.attrs["units"] == "rad"
    truth = ds["heading_drift"]
    assert float(abs(drift - truth).mean()) < float(abs(truth).mean()) + 0.05


def test_cli(tmp_path, capsys):
    out, png = tmp_path / "loc.zarr", tmp_path / "fig" / "loc.png"
    args = ["baselines", "--task", "localization", "--split", "test", "--trials", "2",
            "--particles", "50", "--prior-trials", "50", "--out", str(out),
            "--plot", str(png)]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "particle filter" in text and "200 s" in text
    assert open_baselines(out).sizes["trial_id"] == 2 and png.stat().st_size > 0
    assert main(args) == 2                                      # refuses to overwrite
    assert "--overwrite" in capsys.readouterr().err
    assert main(["baselines", "--task", "maze", "--out", str(out)]) == 2
    assert "`task` must be one of" in capsys.readouterr().err


def test_a_subset_of_methods_gives_the_same_numbers(generalized):
    batch, ds = generalized
    part = run_baselines(batch, n_particles=100, chunk=2, baseline=SMALL,
                         methods=["pf", "pi"])
    assert part.attrs["methods"] == ["pi", "pf"]
    assert "estimate_sh" not in part and "estimate_nb" not in part
    for name in ("estimate_pi", "estimate_pf", "pf_cov", "estimate_drift_pf"):
        assert np.array_equal(part[name].values, ds[name].values), name
    only_pi = run_baselines(batch, methods=["pi"])
    assert "pf_cov" not in only_pi and only_pi.attrs["n_particles"] == 0
    with pytest.raises(ValueError, match="`methods`.*pfslam"):
        run_baselines(batch, methods=["pfslam"])         # no classes in this task


def test_methods_as_one_name_or_none_at_all(generalized):
    batch, _ = generalized
    assert run_baselines(batch, methods="pi").attrs["methods"] == ["pi"]
    with pytest.raises(ValueError, match="at least one"):
        run_baselines(batch, methods=[])
