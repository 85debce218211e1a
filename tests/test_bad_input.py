"""Bad input gets a clear error (argument, value, what was expected), never a silently
wrong result or a third party's traceback. One test per kind of bad input not covered by
the storage, checkpoint and CLI tests."""

import glob
import os
import re
import shutil
import warnings

import numpy as np
import pytest

import hippo_probe as hp
from hippo_probe.analysis import AnalysisWarning
from hippo_probe.cli import main
from hippo_probe.errors import CheckpointError, RecordingError
from hippo_probe.recording import from_arrays, from_nwb, open_recording, save_recording, to_nwb

NWB = __import__("pathlib").Path(__file__).parent / "data" / "A2929-200711.nwb"
RNG = np.random.default_rng(0)
T = np.arange(400) * 0.1
XY = RNG.uniform(-0.5, 0.5, (400, 2))


def rec(**kw):
    return from_arrays(T, XY, **{"activity": RNG.random((400, 3)), **kw})


# ------------------------------------------------------------------ building recordings
@pytest.mark.parametrize("make, error, words", [
    (lambda: rec(activity=RNG.random((400, 3)) + 1j), TypeError,
     "`activity` must hold real numbers; got complex"),
    (lambda: from_arrays(T, XY + 0j, activity=np.ones((400, 1))), TypeError,
     "`position` must hold real numbers"),
    (lambda: rec(environment=1.5), ValueError, "`environment` must hold integer ids"),
    (lambda: rec(activity=np.zeros((400, 0))), RecordingError, "at least one unit"),
    (lambda: hp.validate(rec().isel(unit=slice(0, 0))), RecordingError,
     "`activity` must have at least one unit; got 0 units"),
    (lambda: rec(activity=-np.ones((400, 3)), activity_kind="spike_count"), RecordingError,
     "whole numbers >= 0; got -1.0"),
    (lambda: rec(unit=[1, "a", 2.0]), TypeError, "`unit` ids must be all integers or all "
                                                 "strings"),
    (lambda: hp.validate(rec().isel(time=slice(0, 0))), RecordingError,
     "`time` must hold at least one sample"),
])
def test_a_recording_that_cannot_be_right_is_refused(make, error, words):
    with pytest.raises(error, match=words.replace("(", r"\(").replace("[", r"\[")):
        make()


def test_attrs_that_cannot_be_stored_are_named(tmp_path):
    with pytest.raises(RecordingError, match="`note` \\(dataset attr\\) must be a string"):
        save_recording(rec().assign_attrs(note=object()), tmp_path / "r.zarr")
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------ analyses
def test_an_argument_that_would_have_no_effect_is_refused():
    maps = hp.ratemaps(rec())
    with pytest.raises(ValueError, match="`sigma` only applies when a recording is given"):
        hp.spatial_information(maps, sigma=0)


@pytest.mark.parametrize("call, words", [
    (lambda r: hp.ratemaps(r, bin_size=1e-4), r"`bin_size` asks for .* GiB"),
    (lambda r: hp.head_direction_tuning(r, n_bins=10**8), r"`n_bins` asks for .* GiB"),
    (lambda r: hp.conjunctive_tuning(r, n_bins=10**5), r"`n_bins` asks for .* GiB"),
    (lambda r: hp.conjunctive_tuning(r, n_directions=10**9),
     r"`n_directions` asks for .* GiB"),
])
def test_huge_bin_counts_are_refused_before_allocating(call, words):
    r = rec(head_direction=RNG.uniform(-3, 3, 400))
    with pytest.raises(ValueError, match=words):
        call(r)


@pytest.mark.parametrize("call", [
    lambda r, s: hp.spatial_information(r, n_shuffles=3, seed=s),
    lambda r, s: hp.head_direction_tuning(r, n_shuffles=3, seed=s),
    lambda r, s: hp.conjunctive_tuning(r, n_shuffles=3, seed=s),
    lambda r, s: hp.correlation_dimension(r, seed=s),
    lambda r, s: hp.tasks.make_trials("localization", 1, "test", s),
    lambda r, s: hp.load_pretrained("localization_compass", seed=s),
], ids=["spatial_information", "head_direction_tuning", "conjunctive_tuning",
        "correlation_dimension", "make_trials", "load_pretrained"])
@pytest.mark.parametrize("seed", ["a", 1.5])
def test_a_seed_that_is_not_an_integer_is_named(call, seed):
    with pytest.raises(TypeError, match=f"`seed` must be an integer; got {seed!r}"):
        call(rec(head_direction=RNG.uniform(-3, 3, 400)), seed)


@pytest.mark.parametrize("analysis", [
    "ratemaps", "spatial_information", "spatial_selectivity", "place_fields",
    "place_field_stability", "head_direction_tuning", "conjunctive_tuning", "border_score",
    "grid_score", "speed_score", "classify_cells", "context_cells", "remapping_similarity",
    "decode_environment", "correlation_dimension", "intrinsic_dimension"])
def test_a_recording_of_zero_samples_says_so(analysis):
    """Not "all NaN", not numpy's "cannot reshape array of size 0"."""
    empty = rec(head_direction=RNG.uniform(-3, 3, 400)).isel(time=slice(0, 0))
    with pytest.raises(ValueError, match="`rec` has 0 samples"):
        getattr(hp, analysis)(empty)


def test_a_few_far_samples_setting_the_extent_are_warned_about():
    """100 glitches at 50 m among 20,000 samples in a 1 m box: every bin would be 1.5 m
    wide and the place field's information would vanish."""
    n = 20_000
    t = np.arange(n) * 0.05
    xy = np.random.default_rng(1).uniform(-0.5, 0.5, (n, 2))
    rate = np.exp(-((xy - 0.2) ** 2).sum(1) / (2 * 0.05 ** 2))
    xy[::200] = 50.0
    glitchy = from_arrays(t, xy, activity=rate)
    with pytest.warns(AnalysisWarning, match=r"100 of 20000 samples stretch the x extent"):
        coarse = hp.spatial_information(glitchy)
    with warnings.catch_warnings():
        warnings.simplefilter("error", AnalysisWarning)
        fine = hp.spatial_information(glitchy, extent=(-0.5, 0.5, -0.5, 0.5))
    assert float(fine.information[0]) > 10 * float(coarse.information[0])


# ------------------------------------------------------------------ files
def test_bytes_paths_work_like_str_paths(tmp_path):
    dest = str(tmp_path / "r.zarr").encode()
    save_recording(rec(), dest)
    assert open_recording(dest).sizes["unit"] == 3


@pytest.mark.parametrize("chunks", ["bogus", 1.5, ["time"]])
def test_chunks_that_mean_nothing_are_not_called_corruption(chunks, tmp_path):
    save_recording(rec(), tmp_path / "r.zarr")
    with pytest.raises(ValueError, match=r"`chunks` must be 'trials', a dict of chunk sizes "
                                         r"per dimension, an int or None; got "
                                         + re.escape(repr(chunks))):
        open_recording(tmp_path / "r.zarr", chunks=chunks)


@pytest.mark.parametrize("then", ["overwritten", "removed"])
def test_a_lazy_recording_whose_store_is_replaced_refuses_to_read(then, tmp_path):
    """Without the check the old handle read the new store's values (or zarr's fill
    value, 0, for a removed one), silently."""
    path = tmp_path / "r.zarr"
    save_recording(rec(), path)
    lazy = open_recording(path)
    if then == "overwritten":
        save_recording(rec(activity=np.full((400, 3), 2.0)), path, overwrite=True)
    else:
        shutil.rmtree(path)
    with pytest.raises(RecordingError, match=re.escape(f"`path` {path} was replaced or "
                                                       f"removed after this recording was "
                                                       f"opened")):
        lazy.activity.sum().compute()
    if then == "overwritten":               # opened again, it reads the new store
        assert float(open_recording(path).activity.mean()) == 2.0


def _set_attr_in_place(path):
    import zarr
    zarr.open_group(path, mode="r+").attrs["note"] = "added later"   # rewrites zarr.json


def _consolidate(path):
    import zarr
    zarr.consolidate_metadata(path)


def _touch(path):
    os.utime(path / "zarr.json", ns=(1, 1))


def _second_reader(path):
    open_recording(path).activity.sum().compute()


@pytest.mark.parametrize("meanwhile", [_set_attr_in_place, _consolidate, _touch,
                                       _second_reader, "chdir"])
def test_a_lazy_recording_reads_on_when_its_own_store_is_only_touched(meanwhile, tmp_path,
                                                                      monkeypatch):
    """The replaced-store check must not fire for the same store: metadata rewritten in
    place, a touched file, another reader, a relative path and a changed directory."""
    save_recording(rec(), tmp_path / "r.zarr")
    monkeypatch.chdir(tmp_path)
    lazy = open_recording("r.zarr")
    if meanwhile == "chdir":
        monkeypatch.chdir(tmp_path.parent)
    else:
        meanwhile(tmp_path / "r.zarr")
    assert float(lazy.activity.sum().compute()) > 0     # read (uniform activity), not refused


def test_a_flipped_byte_in_a_chunk_names_the_variable_and_the_store(tmp_path):
    path = tmp_path / "r.zarr"
    save_recording(rec(), path)
    chunk = sorted(glob.glob(str(path / "activity" / "c" / "*" / "*")))[0]
    raw = bytearray(open(chunk, "rb").read())
    raw[20] ^= 0xFF
    open(chunk, "wb").write(bytes(raw))
    with pytest.raises(RecordingError, match=f"`activity` of the store {path} could not be "
                                             f"read .*checksum"):
        open_recording(path).activity.sum().compute()


@pytest.mark.parametrize("call, words", [
    (lambda d: from_nwb(d), "`path` must be an NWB file; got the directory"),
    (lambda d: to_nwb(rec(), d, overwrite=True), "`path` must name an .nwb file"),
], ids=["from_nwb", "to_nwb"])
def test_nwb_paths_that_are_directories_say_so(call, words, tmp_path):
    """Not "does not exist" (from_nwb), not h5py's error (to_nwb)."""
    (tmp_path / "keep").write_text("")
    with pytest.raises(IsADirectoryError, match=words):
        call(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep"]


def test_to_nwb_creates_a_missing_folder(tmp_path):
    pytest.importorskip("pynwb")
    dest = tmp_path / "new" / "r.nwb"
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)      # e.g. pynwb's "not .nwb" warning
        to_nwb(rec(), dest)
    assert from_nwb(dest, epoch=None).sizes["unit"] == 3


def test_to_nwb_refuses_an_empty_recording(tmp_path):
    pytest.importorskip("pynwb")
    with pytest.raises(RecordingError, match="`time` must hold at least one sample; got a "
                                             "recording of 0 samples"):
        to_nwb(rec().isel(time=slice(0, 0)), tmp_path / "empty.nwb")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("dataset, words", [
    ("data", r"`position` in .* holds 10 values beyond 1000 m \(first 6e\+206"),
    ("timestamps", r"`position timestamps` in .* holds 10 values beyond 1e\+07 s "
                   r"\(first 6e\+206"),
    ("spike_times", r"`spike_times` in .* holds 10 values beyond 1e\+07 s "
                    r"\(first 6e\+206 at index 100\)"),
], ids=["position", "timestamps", "spike times"])
def test_an_nwb_file_with_a_garbled_block_is_refused_naming_the_variable(dataset, words,
                                                                         tmp_path):
    pytest.importorskip("pynwb")
    h5py = pytest.importorskip("h5py")
    garbled = tmp_path / "garbled.nwb"
    shutil.copy(NWB, garbled)
    blocks = {"data": ["acquisition/Position/x/data"], "spike_times": ["units/spike_times"],
              "timestamps": [f"acquisition/Position/{axis}/timestamps"    # one per axis
                             for axis in "xyz"]}[dataset]
    with h5py.File(garbled, "r+") as f:
        for name in blocks:
            block = f[name]
            values = block[:]
            values[100:110] = 6e206
            block[:] = values
    with pytest.raises(RecordingError, match=words):
        from_nwb(garbled)


@pytest.mark.parametrize("kwargs, error, words", [
    (dict(name=None), TypeError, "`name` must be a shipped network's name"),
    (dict(name=""), TypeError, "`name` must be a shipped network's name"),
    (dict(name="generalized_compass", seed=7), ValueError,
     "`seed` 7 of the network 'generalized_compass' is not shipped; shipped seeds: \\[0"),
], ids=["None", "empty", "unshipped seed"])
def test_load_pretrained_names_what_it_expected(kwargs, error, words):
    with pytest.raises(error, match=words):
        hp.load_pretrained(**kwargs)


# ------------------------------------------------------------------ the command line
@pytest.fixture(scope="module")
def shipped():
    from hippo_probe.pretrained import resolve_network_file
    from hippo_probe.model.checkpoint import load

    return load(resolve_network_file("localization_compass"))


@pytest.mark.parametrize("damage, words", [("shapes", "size mismatch"),
                                           ("missing", "Missing key")])
def test_a_checkpoint_of_other_shapes_is_one_clear_line(damage, words, shipped, tmp_path,
                                                        capsys):
    """Not torch's RuntimeError from load_state_dict."""
    import torch

    from hippo_probe.model.checkpoint import save_atomic

    first = next(iter(shipped["model"]))
    model = dict(shipped["model"])
    if damage == "shapes":
        model[first] = torch.zeros(3, 3)
    else:
        del model[first]
    save_atomic(dict(shipped, model=model), tmp_path / "bad.pt")
    assert main(["evaluate", str(tmp_path / "bad.pt"), "--trials", "1"]) == 2
    err = capsys.readouterr().err
    assert "does not fit this Navigator" in err and words in err and first in err
    assert err.count("\n") == 1


def test_resuming_a_checkpoint_without_optimizer_state_names_what_is_missing(
        shipped, tmp_path, capsys):
    from hippo_probe.model.checkpoint import save_atomic

    run = tmp_path / "run"
    save_atomic(shipped, run / "checkpoint.pt")          # a shipped network, not a run
    code = main(["train", "--task", "localization", "--world", "compass", "--steps", "1",
                 "--validation-trials", "2", "--out", str(run), "--no-progress"])
    assert code == 2
    assert "lacks ['optimizer'" in capsys.readouterr().err


def test_export_of_a_checkpoint_without_a_log_is_a_clear_error(shipped, tmp_path, capsys):
    from hippo_probe.model.checkpoint import save_atomic

    save_atomic({k: v for k, v in shipped.items() if k != "test"}, tmp_path / "checkpoint.pt")
    assert main(["export-network", str(tmp_path), "x", "--dest", str(tmp_path / "d")]) == 2
    assert "lacks ['log'" in capsys.readouterr().err
    assert not (tmp_path / "d").exists()                 # no empty folder left behind


def _exportable(shipped, run):
    """A run's checkpoint made of a shipped network: what export-network needs."""
    from hippo_probe.model.checkpoint import save_atomic

    save_atomic(dict(shipped, log={"class_weight": 0.0}, step=1, best_model=None,
                     best_loss=1.0), run / "checkpoint.pt")
    return run


@pytest.mark.parametrize("command", ["export-network", "world-stats --json",
                                     "world-stats --plot"])
def test_outputs_into_a_folder_that_does_not_exist_are_written(command, shipped, tmp_path):
    """The folders are made, not a torch RuntimeError ("Parent directory does not exist")
    or a FileNotFoundError."""
    new = tmp_path / "new" / "deeper"
    if command == "export-network":
        argv = ["export-network", str(_exportable(shipped, tmp_path)), "x", "--dest",
                str(new)]
        made = [new / "x.pt", new / "x.log.json"]
    else:
        made = [new / ("stats.json" if command.endswith("json") else "trials.png")]
        argv = ["world-stats", "--trials", "2", command.split()[1], str(made[0])]
    assert main(argv) == 0
    assert all(p.is_file() for p in made)
    assert sorted(p.name for p in new.iterdir()) == sorted(p.name for p in made)


def test_export_onto_a_file_is_one_clear_line(shipped, tmp_path, capsys):
    (tmp_path / "a_file").write_text("")
    run = _exportable(shipped, tmp_path / "run")
    assert main(["export-network", str(run), "x", "--dest", str(tmp_path / "a_file")]) == 2
    assert "--dest {} is a file; give a folder".format(tmp_path / "a_file") in \
        capsys.readouterr().err


@pytest.mark.parametrize("option", ["--particles", "--slam-particles"])
def test_zero_particles_are_refused_not_replaced_by_the_default(option, tmp_path, capsys):
    """`--particles 0` once ran the default 1,000 particles, silently."""
    out = tmp_path / "b.zarr"
    assert main(["baselines", "--task", "specialized", "--trials", "1", option, "0",
                 "--out", str(out), "--no-progress"]) == 2
    assert f"argument {option}: must be a whole number >= 1; got 0" in \
        capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv, words", [
    (["--trials", "0"], "argument --trials: must be a whole number >= 1; got 0"),
    (["--out", "EXISTING"], "--out {existing} already exists; pass --overwrite"),
])
def test_record_checks_its_arguments_before_working(argv, words, tmp_path, capsys):
    existing = tmp_path / "r.zarr"
    existing.mkdir()
    argv = [str(existing) if a == "EXISTING" else a for a in argv]
    base = ["record", "--network", "localization_compass", "--trials", "1",
            "--out", str(tmp_path / "new.zarr")]
    assert main(base + argv) == 2
    assert words.format(existing=existing) in capsys.readouterr().err
    assert not (tmp_path / "new.zarr").exists()


# ------------------------------------------------------------------ damaged sessions
def _session():
    """A valid 6-trial, 2-arena recording with everything the analyses read."""
    n_trials, n = 6, 120
    rng = np.random.default_rng(3)
    t = np.concatenate([k * 20.0 + 0.1 * np.arange(1, n + 1) for k in range(n_trials)])
    # a random walk at about 0.1 m/s, folded into the 1 m square
    walk = np.cumsum(rng.normal(0, 0.01, (n * n_trials, 2)), axis=0)
    xy = np.abs((walk + 0.5) % 2 - 1) - 0.5
    env = np.repeat([0, 1, 0, 1, 0, 1], n)
    r = from_arrays(t, xy, activity=rng.random((n * n_trials, 4)),
                    head_direction=rng.uniform(-3, 3, n * n_trials),
                    trial=np.repeat(np.arange(n_trials), n), environment=env)
    prob = np.full((n * n_trials, 2), 0.25)
    prob[np.arange(n * n_trials), env] = 0.75
    cov = np.c_[rng.uniform(0.01, 0.1, (n * n_trials, 2)), rng.normal(0, 0.01, n * n_trials)]
    return r.assign(
        estimate=(("time", "space"), xy + 0.01, {"units": "m", "long_name": "estimate"}),
        class_probability=(("time", "environment_id"), prob,
                           {"units": "1", "long_name": "class probability"}),
        pf_cov=(("time", "cov"), cov, {"units": "m^2", "long_name": "PF covariance"}),
        readout_weight=(("environment_id", "unit"), rng.normal(size=(2, 4)),
                        {"units": "1", "long_name": "readout weight"})
    ).assign_coords(cov=("cov", ["xx", "yy", "xy"], {"units": "1", "long_name": "cov"}))


def _damage(kind):
    r = _session()
    t = r.time.values.copy()
    if kind == "inf position":
        pos = r.position.values.copy()
        pos[7, 0] = np.inf
        return r.assign(position=(r.position.dims, pos, r.position.attrs)), "position"
    if kind in ("NaN activity", "text activity", "complex activity"):
        act = r.activity.values.copy()
        act[3, 1] = np.nan
        act = {"NaN activity": act, "text activity": r.activity.values.astype(str),
               "complex activity": r.activity.values + 1j}[kind]
        return r.assign(activity=(r.activity.dims, act, r.activity.attrs)), "activity"
    if kind == "reversed time":
        t[:120] = t[:120][::-1]
    elif kind == "duplicate time":
        t[5] = t[4]
    elif kind == "NaN time":
        t[9] = np.nan
    if kind.endswith("time"):
        return r.assign_coords(time=("time", t, r.time.attrs)), "time"
    if kind == "environment changes in a trial":
        env = r.environment.values.copy()
        env[60:120] = 1
        return r.assign_coords(environment=("time", env, r.environment.attrs)), "environment"
    if kind == "negative dt":
        return r.assign_attrs(dt=-0.4), "dt"
    if kind == "text dt":
        return r.assign_attrs(dt="0.1"), "dt"
    if kind == "dt in ms":                      # samples 0.1 s apart, labelled 100
        return r.assign_attrs(dt=100.0), "dt"
    if kind == "trial in two pieces":           # trial 0's label on trial 2's samples
        trial = r.trial.values.copy()
        trial[240:360] = 0
        return r.assign_coords(trial=("time", trial, r.trial.attrs)), "trial"
    raise AssertionError(kind)


DAMAGE = ["inf position", "NaN activity", "text activity", "complex activity",
          "reversed time", "duplicate time", "NaN time", "environment changes in a trial",
          "negative dt", "text dt", "dt in ms", "trial in two pieces"]
ANALYSES = {
    "ratemaps": lambda r: hp.ratemaps(r, bin_size=0.1),
    "spatial_information": lambda r: hp.spatial_information(r, n_shuffles=2, bin_size=0.1),
    "spatial_selectivity": lambda r: hp.spatial_selectivity(r, bin_size=0.1),
    "place_field_stability": lambda r: hp.place_field_stability(r, bin_size=0.1),
    "head_direction_tuning": lambda r: hp.head_direction_tuning(r, n_shuffles=2),
    "remapping_similarity": lambda r: hp.remapping_similarity(r, bin_size=0.1),
    "context_cells": lambda r: hp.context_cells(r, bin_size=0.1),
    "decode_covariance": lambda r: hp.decode_covariance(r, n_folds=3),
    "decode_environment": lambda r: hp.decode_environment(r, times=[5.0], n_folds=3),
    "correlation_dimension": lambda r: hp.correlation_dimension(r, max_points=200),
    "intrinsic_dimension": lambda r: hp.intrinsic_dimension(r, max_points=200),
    "localization_error": lambda r: hp.localization_error(r),
    "classification_accuracy": lambda r: hp.classification_accuracy(r),
    "border_score": lambda r: hp.border_score(r, n_shuffles=2, bin_size=0.1),
    "grid_score": lambda r: hp.grid_score(r, n_shuffles=2, bin_size=0.1),
    "speed_score": lambda r: hp.speed_score(r, n_shuffles=2),
    "conjunctive_tuning": lambda r: hp.conjunctive_tuning(r, n_shuffles=2),
    "classify_cells": lambda r: hp.classify_cells(r, n_shuffles=2, bin_size=0.1),
    "place_fields": lambda r: hp.place_fields(r, bin_size=0.1),
    "poisson_spikes": lambda r: hp.poisson_spikes(r.assign_attrs(activity_kind="rate"), 5.0),
}


@pytest.mark.parametrize("analysis", sorted(ANALYSES))
def test_every_analysis_accepts_the_valid_session(analysis):
    hp.validate(_session())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ANALYSES[analysis](_session())


@pytest.mark.parametrize("kind", DAMAGE)
@pytest.mark.parametrize("analysis", sorted(ANALYSES))
def test_every_analysis_refuses_a_damaged_session(analysis, kind):
    bad, var = _damage(kind)
    with pytest.raises(RecordingError):
        hp.validate(bad)
    with pytest.raises(RecordingError, match=f"`{var}`"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ANALYSES[analysis](bad)


def _spike_counts(r, edit):
    """``r`` as a spike-count session (Poisson counts), its counts then edited."""
    counts = np.random.default_rng(4).poisson(0.5, r.activity.shape).astype(float)
    edit(counts)
    return r.assign(activity=(r.activity.dims, counts, r.activity.attrs)).assign_attrs(
        activity_kind="spike_count")


COUNT_DAMAGE = {
    "counts shifted by a half": lambda c: c.__iadd__(0.5),
    "one negative count": lambda c: c.__setitem__((500, 2), -3.0),
}


@pytest.mark.parametrize("kind", sorted(COUNT_DAMAGE))
@pytest.mark.parametrize("analysis", sorted(set(ANALYSES) - {"poisson_spikes"}))
def test_every_analysis_refuses_spike_counts_that_are_not_counts(analysis, kind):
    """Counts edited after the session was built (validate refuses them) are refused by
    every analysis's entry check too, instead of being mapped into plausible rates."""
    bad = _spike_counts(_session(), COUNT_DAMAGE[kind])
    index = "(0, 0)" if kind.startswith("counts") else "(500, 2)"
    with pytest.raises(RecordingError, match=r"whole numbers >= 0; got .* at index "
                                             + re.escape(index)), \
            warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ANALYSES[analysis](bad)


def test_valid_spike_counts_pass_the_entry_check():
    good = _spike_counts(_session(), lambda c: None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        hp.ratemaps(good, bin_size=0.1)
        hp.spatial_information(good, bin_size=0.1)


def test_the_count_rule_finds_the_first_bad_entry_past_the_first_slice():
    from hippo_probe.recording.validate import check_block
    counts = np.zeros((300_000, 8))              # 2.4 million entries: several slices
    counts[250_001, 5] = 1.25
    counts[270_000, 0] = -1
    with pytest.raises(RecordingError, match=r"got 1\.25 at index \(250001, 5\)"):
        check_block("activity", counts, kind="spike_count")
    with pytest.raises(RecordingError, match=r"got -1 at index \(270000, 0\)"):
        check_block("activity", counts.astype(np.int64), kind="spike_count")
    # the block's origin in the recording shifts the index named
    with pytest.raises(RecordingError, match=r"at index \(250101, 5\)"):
        check_block("activity", counts, origin=(100, 0), kind="spike_count")
    assert check_block("activity", counts, kind="rate") is counts


def test_a_lazy_session_of_fractional_counts_is_not_saved(tmp_path):
    good = _spike_counts(_session(), lambda c: None)
    lazy = good.activity.chunk({"time": 120})
    bad = good.assign(activity=lazy.copy(data=lazy.data.astype(np.float32) + 0.5))
    with pytest.raises(RecordingError, match="whole numbers >= 0"):
        save_recording(bad, tmp_path / "r.zarr")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize("kw, words", [
    ({"min_speed": 100}, ("`min_speed` = 100 m/s leaves no sample to map: 720 of 720 are "
                          "slower")),
    ({"extent": (2, 3, 2, 3)}, ("`extent` = (2, 3, 2, 3) leaves no sample to map: 720 of "
                                "720 positions lie outside it")),
])
def test_an_argument_that_leaves_nothing_to_map_is_named(kw, words):
    with pytest.raises(ValueError, match=re.escape(words)):
        hp.ratemaps(_session(), bin_size=0.1, **kw)


def test_a_speed_that_is_unknown_is_not_called_slow():
    """Trials of one sample have no speed: min_speed=0 said all were 'slower' than 0."""
    n = 200
    xy = np.c_[np.linspace(0, 1, n), np.linspace(0, 1, n) ** 2]
    one_sample_trials = hp.from_arrays(np.arange(n) * 0.04, xy, activity=np.ones(n),
                                       trial=np.arange(n), dt=0.02)
    with pytest.raises(ValueError, match=re.escape(
            "`min_speed` = 0.0 m/s leaves no sample to map: the speed of 200 of 200 is "
            "unknown (trials of one sample")):
        hp.ratemaps(one_sample_trials, bin_size=0.1, min_speed=0.0)


def test_a_min_speed_above_the_default_max_speed_names_the_default():
    with pytest.raises(ValueError, match=re.escape(
            "`min_speed` must be < the default max_speed 0.5 m/s; got 10.0 (pass a larger "
            "max_speed too)")):
        hp.speed_score(_session(), min_speed=10, n_shuffles=0)


def test_activity_beyond_float32_is_named_rather_than_called_inf():
    with pytest.raises(ValueError, match=re.escape(
            "`activity` must fit float32 (|value| <= 3.4e38), as the recording stores it; "
            "found 1e+39 at index (3, 0)")):
        hp.from_arrays(np.arange(10.0), np.zeros((10, 2)), activity=np.r_[np.ones(3), 1e39,
                                                                        np.ones(6)])


@pytest.mark.parametrize("kind, meant", [("spike_counts", "spike_count"), ("Rate", "rate"),
                                         ("lstm-hidden", "lstm_hidden")])
def test_a_near_miss_of_a_known_activity_kind_is_refused(kind, meant):
    """A typo would read spike counts as a generic signal (no division by dt)."""
    words = f"got {kind!r}: did you mean {meant!r}?"
    with pytest.raises(RecordingError, match=re.escape(words)):
        rec(activity_kind=kind)
    with pytest.raises(RecordingError, match=re.escape(words)):
        hp.ratemaps(_session().assign_attrs(activity_kind=kind), bin_size=0.1)


def test_an_unknown_activity_kind_is_warned_about():
    with pytest.warns(UserWarning, match="activity_kind 'spikes', which the analyses do not "
                                         "know"):
        hp.ratemaps(_session().assign_attrs(activity_kind="spikes"), bin_size=0.1)


# ------------------------------------------------------------------ too little data
@pytest.mark.parametrize("analysis", ["spatial_information", "head_direction_tuning",
                                      "grid_score", "border_score", "conjunctive_tuning",
                                      "classify_cells"])
def test_shuffles_on_a_one_sample_recording_name_the_minimum(analysis):
    one = _session().isel(time=slice(0, 1))
    with pytest.raises(ValueError, match="need a recording of at least 4 samples; got 1"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ANALYSES[analysis](one)


@pytest.mark.parametrize("analysis", ["speed_score", "conjunctive_tuning",
                                      "decode_covariance", "poisson_spikes",
                                      "decode_environment", "intrinsic_dimension",
                                      "ratemaps", "head_direction_tuning"])
def test_a_recording_without_units_is_refused(analysis):
    empty = _session().isel(unit=slice(0, 0))
    with pytest.raises(ValueError, match="at least one unit"):
        ANALYSES[analysis](empty)


def test_nested_cross_validation_needs_three_folds():
    with pytest.raises(ValueError, match="`n_folds` must be >= 3: one fold is held out"):
        hp.decode_covariance(_session(), n_folds=2)
    assert np.isfinite(hp.decode_covariance(_session(), n_folds=3).r2).all()


@pytest.mark.parametrize("times", [None, [1e6]])
def test_decoding_at_times_no_trial_reaches_warns_and_says_why(times):
    # trials of 12 s (their last sample 11.9 s after the first): the default times (50, 100, 200 s) and 1e6 s fall after every trial
    with pytest.warns(AnalysisWarning, match="decoding accuracy is NaN .* no sample at"):
        res = hp.decode_environment(_session(), times=times, n_folds=3)
    assert np.isnan(res.accuracy).all()
    assert "the longest trial lasts 11.9 s" in next(iter(res.attrs["nan_reasons"].values()))


# ------------------------------------------------------------------ options by type
@pytest.mark.parametrize("call, words", [
    (lambda: hp.remapping_similarity(_session(), center_units="no"),
     "`center_units` must be True or False; got 'no'"),
    (lambda: hp.validate(_session(), check_data="yes"),
     "`check_data` must be True, False or None; got 'yes'"),
])
def test_a_string_is_not_taken_for_a_bool(call, words):
    with pytest.raises(TypeError, match=re.escape(words)):
        call()


def test_save_and_export_refuse_a_string_for_overwrite(tmp_path):
    with pytest.raises(TypeError, match="`overwrite` must be True or False; got 'no'"):
        save_recording(_session(), tmp_path / "r.zarr", overwrite="no")
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------ accepted nonsense
def test_nonsense_options_and_inputs_are_refused(tmp_path):
    r = _session()
    with pytest.raises(ValueError, match="`min_bins` must be >= 2"):
        hp.place_field_stability(r, bin_size=0.1, min_bins=-1)
    with pytest.raises(ValueError, match="`weights` must not contain NaN or inf"):
        hp.context_cells(r, np.full((2, 4), np.nan), bin_size=0.1)
    with pytest.raises(ValueError, match="must hold probabilities .* sum to 0"):
        hp.classification_accuracy(r.assign(class_probability=r.class_probability * 0))
    save_recording(r, tmp_path / "r.zarr")
    for chunks in (-1, 0, True, {"time": 0}):
        with pytest.raises(ValueError, match="`chunks`"):
            open_recording(tmp_path / "r.zarr", chunks=chunks)
    with pytest.raises(ValueError, match="`dt` must be a number of seconds > 0; got '0.1'"):
        from_arrays(T, XY, activity=np.ones((400, 1)), dt="0.1")


def test_suspicious_units_are_warned_about():
    with pytest.warns(UserWarning, match="if it is in degrees, pass np.deg2rad"):
        from_arrays(T, XY, activity=np.ones((400, 1)),
                    head_direction=np.linspace(0, 359, 400))
    with pytest.warns(UserWarning, match="every spike of 1 of 2 units .* falls outside"):
        from_arrays(T, XY, spike_times=[[1.0, 2.0], [1e5, 2e5]])


# ------------------------------------------------------------------ messages, not internals
def test_wrong_kinds_of_input_get_messages_not_internal_errors(tmp_path):
    r = _session()
    cases = [
        (lambda: hp.ratemaps(r, extent="x"), TypeError, "`extent` must hold real numbers"),
        (lambda: hp.localization_error(r, centre="x"), TypeError,
         "`centre` must hold real numbers"),
        (lambda: hp.localization_error(r, estimate="activity"), ValueError,
         "`rec.activity` must be a position"),
        (lambda: hp.correlation_dimension(np.array([["a", "b"]] * 50)), TypeError,
         "`rec_or_array` must hold real numbers"),
        (lambda: from_arrays(np.array(["a"] * 10), np.zeros((10, 2)),
                             activity=np.ones((10, 1))), TypeError,
         "`time` must hold real numbers"),
        (lambda: hp.speed_score(r.assign(position=(("time", "xyz"), np.c_[
            r.position.values, r.position.values[:, :1]])), n_shuffles=2), RecordingError,
         "`position` (of `rec`) must have dims ('time', 'space')"),
        (lambda: hp.border_score(r, walls=np.full((4, 2), np.nan), n_shuffles=2,
                                 bin_size=0.1), ValueError, "`walls` must not contain NaN"),
        (lambda: hp.poisson_spikes(np.ones((10, 2)), 5.0), TypeError,
         "`rec` must be a recording"),
        (lambda: hp.poisson_spikes(r.isel(time=slice(0, 0)).assign_attrs(
            activity_kind="rate"), 5.0), RecordingError, "at least one unit and one sample"),
        (lambda: hp.classification_accuracy(r.assign_coords(
            environment=("time", r.environment.values.astype(str)))), RecordingError,
         "`environment` (of `rec`) must hold integer ids"),
        (lambda: hp.classify_cells(r.assign_coords(
            environment=("time", r.environment.values.astype(str))), n_shuffles=2),
         RecordingError, "`environment` (of `rec`) must hold integer ids"),
    ]
    for call, error, words in cases:
        with pytest.raises(error, match=re.escape(words)):
            call()
    (tmp_path / "afile").write_text("x")
    with pytest.raises(NotADirectoryError, match="is a file, not a folder"):
        save_recording(r, tmp_path / "afile" / "x.zarr")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]


# ------------------------------------------------------------------ denial of service
def test_a_checkpoint_declaring_a_huge_network_is_refused_before_allocating(tmp_path):
    import resource

    import torch

    from hippo_probe.model.checkpoint import save_atomic

    net = hp.load_pretrained("localization")
    obj = torch.load(net.info["file"], weights_only=True)
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    for declared, words in ((10**7, "`hidden_size` must be <= 16384"),
                            (512, "declares hidden_size=512")):
        crafted = dict(obj, model_config=dict(obj["model_config"], hidden_size=declared))
        save_atomic(crafted, tmp_path / "crafted.pt")
        with pytest.raises(CheckpointError, match=re.escape(words)):
            hp.load_pretrained(tmp_path / "crafted.pt")
    # nothing near a 10**7-unit network (400 TB) or even a 512-unit one was allocated
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 200_000


@pytest.mark.parametrize("dataset", ["acquisition/Position/x/data", "units/spike_times"])
def test_an_nwb_dataset_declaring_terabytes_is_refused_before_reading(tmp_path, dataset):
    import h5py

    path = tmp_path / "crafted.nwb"
    shutil.copy(NWB, path)
    with h5py.File(path, "r+") as f:
        attrs = dict(f[dataset].attrs)
        del f[dataset]
        # 10**12 float64 declared, nothing written: a file of a few kB
        d = f.create_dataset(dataset, shape=(10**12,), dtype="f8", chunks=(10**6,),
                             fillvalue=0.0)
        d.attrs.update(attrs)
    assert path.stat().st_size < 2 * NWB.stat().st_size
    with pytest.raises(RecordingError, match=r"declares shape \(1000000000000,\) .* refused"):
        from_nwb(path)


# ------------------------------------------------------------------ leftovers
def test_a_store_left_aside_by_an_interrupted_overwrite_is_restored(tmp_path):
    r = _session()
    save_recording(r, tmp_path / "r.zarr")
    # an overwrite killed between its renames: the old store aside, nothing at the name
    os.rename(tmp_path / "r.zarr", tmp_path / ".r.zarr.old-0badc0de")
    with pytest.warns(UserWarning, match="its previous version .* is restored"):
        back = open_recording(tmp_path / "r.zarr")
    np.testing.assert_array_equal(back.activity.values, r.activity.values.astype(np.float32))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.zarr"]
    # and once the new store is in place, a copy aside is cleaned by the next save
    os.rename(tmp_path / "r.zarr", tmp_path / ".r.zarr.old-0badc0de")
    with pytest.warns(UserWarning, match="is restored"):
        save_recording(r, tmp_path / "r.zarr", overwrite=True)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.zarr"]


def test_a_write_that_fails_midway_leaves_no_partial_store_and_keeps_the_old(tmp_path,
                                                                          monkeypatch):
    import errno
    import threading

    import zarr.storage

    n, n_trials = 40_000, 40
    t = (np.arange(n) + np.repeat(np.arange(n_trials), n // n_trials) + 1) * 0.02
    full = from_arrays(t, RNG.uniform(-0.5, 0.5, (n, 2)),
                       activity=RNG.random((n, 8)).astype(np.float32),
                       trial=np.repeat(np.arange(n_trials), n // n_trials),
                       activity_kind="rate")
    save_recording(full, tmp_path / "a.zarr")
    save_recording(hp.select_trials(full, trials=[0]), tmp_path / "b.zarr")
    lazy = open_recording(tmp_path / "a.zarr")      # written from dask's worker threads
    real, count, lock = zarr.storage.LocalStore.set, [0], threading.Lock()

    async def disk_full_at_the_fifth_chunk(self, key, value):
        with lock:
            count[0] += "/c" in key
            fifth = "/c" in key and count[0] == 5
        if fifth:
            raise OSError(errno.ENOSPC, "No space left on device")
        return await real(self, key, value)

    monkeypatch.setattr(zarr.storage.LocalStore, "set", disk_full_at_the_fifth_chunk)
    with pytest.raises(OSError, match="No space left"):
        save_recording(lazy, tmp_path / "b.zarr", overwrite=True)
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.zarr", "b.zarr"]
    assert open_recording(tmp_path / "b.zarr").sizes["time"] == n // n_trials


# ------------------------------------------------------------------ NWB files from elsewhere
def _edited_nwb(tmp_path, edit):
    import h5py

    path = tmp_path / "edited.nwb"
    shutil.copy(NWB, path)
    with h5py.File(path, "r+") as f:
        edit(f, h5py)
    return path


def _replace(f, name, values):
    attrs = dict(f[name].attrs)
    del f[name]
    f.create_dataset(name, data=values)
    f[name].attrs.update(attrs)


@pytest.mark.parametrize("edit, words", [
    (lambda f, h: [_replace(f, f"acquisition/Position/{a}/data",
                            np.full(f[f"acquisition/Position/{a}/data"].shape, np.nan))
                   for a in "xyz"], "position axis 'x' .* has no finite value"),
    (lambda f, h: f["acquisition/Position/x/data"].attrs.modify("conversion", 0.0),
     "`x.conversion` must be a finite non-zero factor"),
    (lambda f, h: [f[f"acquisition/Position/{a}/data"].attrs.modify("unit", "furlongs")
                   for a in "xyz"], "position unit 'furlongs'"),
    (lambda f, h: _replace(f, "units/spike_times_index",
                           f["units/spike_times_index"][:][::-1].copy()),
     "`spike_times_index` .* is not non-decreasing"),
    (lambda f, h: f.__setitem__("acquisition/elsewhere",
                                h.ExternalLink("/etc/other.h5", "/data")),
     "links to data in other files"),
])
def test_a_damaged_nwb_file_is_refused(tmp_path, edit, words):
    path = _edited_nwb(tmp_path, edit)
    with pytest.raises(RecordingError, match=words):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from_nwb(path)


def test_negative_spike_times_are_warned_about(tmp_path):
    def edit(f, h):
        st = f["units/spike_times"][:]
        st[:5] = -1.0
        _replace(f, "units/spike_times", st)
    with pytest.warns(UserWarning, match="5 spike times .* are negative"):
        from_nwb(_edited_nwb(tmp_path, edit))


@pytest.mark.parametrize("what", ["a chunk", "a variable"])
def test_a_store_linking_outside_itself_is_refused(tmp_path, what):
    a, b = tmp_path / "a.zarr", tmp_path / "b.zarr"
    save_recording(_session(), a)
    save_recording(_session().assign(activity=_session().activity * 2), b)
    if what == "a variable":
        shutil.rmtree(a / "activity")
        os.symlink(b / "activity", a / "activity")
    else:
        chunk = next(p for p in (a / "activity").rglob("*") if p.is_file()
                     and p.name != "zarr.json")
        twin = b / chunk.relative_to(a)
        chunk.unlink()
        os.symlink(twin, chunk)
    with pytest.raises(RecordingError, match="links to .* outside it; refused"):
        open_recording(a)


@pytest.mark.parametrize("damage, words", [
    # the marker's count no longer matches the array's metadata: refused before reading
    ("deleted with the marker edited", "array `activity` .* where 0 were written"),
    ("copied between arrays", "are not those written")])
def test_chunks_that_are_not_those_written_are_refused(tmp_path, damage, words):
    import json as js

    path = tmp_path / "r.zarr"
    r = _session()
    save_recording(r.assign(estimate=r.position * 1.5), path)
    if damage == "copied between arrays":
        # position and estimate have the same shape, chunks and dtype: each chunk's own
        # checksum holds, but it is the other array's chunk
        src = next(p for p in (path / "position" / "c").rglob("*") if p.is_file())
        shutil.copy(src, path / "estimate" / "c" / src.relative_to(path / "position" / "c"))
    else:
        chunk = next(p for p in (path / "activity" / "c").rglob("*") if p.is_file())
        chunk.unlink()
        meta = js.loads((path / "zarr.json").read_text())
        meta["attributes"]["_hippo_probe_store"]["nchunks"]["activity"] -= 1
        (path / "zarr.json").write_text(js.dumps(meta))
    with pytest.raises(RecordingError, match=words):
        open_recording(path)


def test_head_direction_in_degrees_that_wraps_is_refused():
    """Degrees wrap at 360, which radians never do between two samples."""
    turning = (np.arange(400) * 3.0) % 360                # degrees, wrapping every 120
    with pytest.raises(ValueError, match=r"`head_direction` must be in radians; it wraps "
                                         r"at 360 \(from 357 to 0 between samples 119 "
                                         r"and 120\)"):
        rec(head_direction=turning)
    # unwrapped radians (a cumulative angle past 2 pi) are wrapped, with the warning
    with pytest.warns(UserWarning, match="more than 2 pi"):
        r = rec(head_direction=np.arange(400) * 0.05)
    assert np.abs(r.head_direction.values).max() <= np.pi


@pytest.mark.parametrize("analysis", ["spatial_information", "head_direction_tuning",
                                      "grid_score", "border_score"])
def test_shuffles_per_group_are_refused_and_not_drawn_by_default(analysis):
    """A shift over the whole recording would mix the environments' activity into each
    one's null (a flat unit in one arena reads as significant there)."""
    call = getattr(hp, analysis)
    kw = {} if analysis == "head_direction_tuning" else {"bin_size": 0.1}
    with pytest.raises(ValueError, match=r"`n_shuffles` = 3 with `by` = 'environment': the "
                                         r"time shifts run over the whole recording"):
        call(_session(), by="environment", n_shuffles=3, **kw)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = call(_session(), by="environment", **kw)         # no shuffles by default
        alone = call(hp.select_trials(_session(), environments=1), n_shuffles=3, seed=0,
                     **kw)
    assert "p_value" not in res or np.isnan(res["p_value"]).all()
    assert res.attrs.get("n_shuffles", 0) == 0
    assert alone.attrs["n_shuffles"] == 3
