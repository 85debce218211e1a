"""Bad input gets a clear error (argument, value, what was expected), never a silently
wrong result or a third party's traceback. One test per probe of issue 15 not covered by
the storage, checkpoint and CLI tests."""

import glob
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
])
def test_huge_bin_counts_are_refused_before_allocating(call, words):
    r = rec(head_direction=RNG.uniform(-3, 3, 400))
    with pytest.raises(ValueError, match=words):
        call(r)


def test_a_string_seed_is_named():
    with pytest.raises(TypeError, match="`seed` must be an integer; got 'a'"):
        hp.spatial_information(rec(), n_shuffles=3, seed="a")


def test_a_recording_of_zero_samples_says_so():
    empty = rec().isel(time=slice(0, 0))
    with pytest.raises(ValueError, match="`rec` has 0 samples"):
        hp.ratemaps(empty)


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


def test_chunks_that_mean_nothing_are_not_called_corruption(tmp_path):
    save_recording(rec(), tmp_path / "r.zarr")
    with pytest.raises(ValueError, match="`chunks` must be 'trials', a dict"):
        open_recording(tmp_path / "r.zarr", chunks="bogus")


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


def test_nwb_paths_that_are_directories_say_so(tmp_path):
    with pytest.raises(IsADirectoryError, match="`path` must be an NWB file; got the "
                                                "directory"):
        from_nwb(tmp_path)
    with pytest.raises(IsADirectoryError, match="`path` must name an .nwb file"):
        to_nwb(rec(), tmp_path, overwrite=True)


def test_to_nwb_creates_a_missing_folder_and_refuses_an_empty_recording(tmp_path):
    pytest.importorskip("pynwb")
    dest = tmp_path / "new" / "r.nwb"
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)      # e.g. pynwb's "not .nwb" warning
        to_nwb(rec(), dest)
    assert from_nwb(dest, epoch=None).sizes["unit"] == 3
    with pytest.raises(RecordingError, match="at least one sample"):
        to_nwb(rec().isel(time=slice(0, 0)), tmp_path / "empty.nwb")


def test_an_nwb_file_with_a_garbled_block_is_refused_naming_the_variable(tmp_path):
    pytest.importorskip("pynwb")
    h5py = pytest.importorskip("h5py")
    garbled = tmp_path / "garbled.nwb"
    shutil.copy(NWB, garbled)
    with h5py.File(garbled, "r+") as f:
        x = f["acquisition/Position/x/data"]
        values = x[:]
        values[100:110] = 6e206
        x[:] = values
    with pytest.raises(RecordingError, match=r"`position` in .* holds 10 values beyond "
                                             r"1000 m \(first 6e\+206"):
        from_nwb(garbled)


def test_load_pretrained_names_what_it_expected():
    with pytest.raises(TypeError, match="`name` must be a shipped network's name"):
        hp.load_pretrained(None)
    with pytest.raises(ValueError, match="`seed` 7 of the network 'generalized_compass' is "
                                         "not shipped; shipped seeds: \\[0"):
        hp.load_pretrained("generalized_compass", seed=7)


# ------------------------------------------------------------------ the command line
@pytest.fixture(scope="module")
def shipped():
    from hippo_probe.pretrained import resolve_network_file
    from hippo_probe.training.checkpoint import load

    return load(resolve_network_file("localization_compass"))


def test_a_checkpoint_of_other_shapes_is_one_clear_line(shipped, tmp_path, capsys):
    import torch

    from hippo_probe.training.checkpoint import save_atomic

    bad = dict(shipped, model={k: (torch.zeros(3, 3) if i == 0 else v)
                               for i, (k, v) in enumerate(shipped["model"].items())})
    save_atomic(bad, tmp_path / "bad.pt")
    assert main(["evaluate", str(tmp_path / "bad.pt"), "--trials", "1"]) == 2
    err = capsys.readouterr().err
    assert "does not fit this Navigator" in err and "size mismatch" in err
    assert err.count("\n") == 1
    # a parameter missing altogether
    first = next(iter(shipped["model"]))
    save_atomic(dict(shipped, model={k: v for k, v in shipped["model"].items() if k != first}),
                tmp_path / "missing.pt")
    assert main(["evaluate", str(tmp_path / "missing.pt"), "--trials", "1"]) == 2
    err = capsys.readouterr().err
    assert "does not fit this Navigator" in err and "Missing key" in err and first in err


def test_resuming_a_checkpoint_without_optimizer_state_names_what_is_missing(
        shipped, tmp_path, capsys):
    from hippo_probe.training.checkpoint import save_atomic

    run = tmp_path / "run"
    save_atomic(shipped, run / "checkpoint.pt")          # a shipped network, not a run
    code = main(["train", "--task", "localization", "--world", "compass", "--steps", "1",
                 "--validation-trials", "2", "--out", str(run), "--no-progress"])
    assert code == 2
    assert "lacks ['optimizer'" in capsys.readouterr().err


def test_export_of_a_checkpoint_without_a_log_is_a_clear_error(shipped, tmp_path, capsys):
    from hippo_probe.training.checkpoint import save_atomic

    save_atomic({k: v for k, v in shipped.items() if k != "test"}, tmp_path / "checkpoint.pt")
    assert main(["export-network", str(tmp_path), "x", "--dest", str(tmp_path / "d")]) == 2
    assert "lacks ['log'" in capsys.readouterr().err


@pytest.mark.parametrize("argv, words", [
    (["--trials", "0"], "`--trials` must be > 0; got 0"),
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
