"""A checkpoint never runs code: a crafted pickle is refused before its payload runs."""

import os

import pytest
import torch

import hippo_probe as hp
from hippo_probe.errors import CheckpointError
from hippo_probe.model.checkpoint import load


class _Payload:
    """Pickles as a call of ``os.system``: what a malicious ``.pt`` would hold."""

    def __init__(self, marker):
        self.marker = marker

    def __reduce__(self):
        return (os.system, (f"touch {self.marker}",))


@pytest.fixture
def crafted(tmp_path):
    marker = tmp_path / "pwned"
    path = tmp_path / "network.pt"
    torch.save({"model": {"w": torch.zeros(2)}, "model_config": _Payload(marker)}, path)
    return path, marker


def test_a_crafted_checkpoint_is_refused_and_its_payload_never_runs(crafted):
    path, marker = crafted
    with pytest.raises(CheckpointError, match="refused without running anything"):
        load(path)
    with pytest.raises(CheckpointError, match="os.system|posix.system"):
        hp.load_pretrained(path)
    assert not marker.exists()


@pytest.mark.parametrize("protocol", [2, 4, 5])
def test_a_plain_pickle_is_refused_without_the_advice_to_load_it_unsafely(tmp_path,
                                                                          protocol):
    """A pickle of another protocol than torch's (not a torch file at all) is refused as
    one with code is, naming what was refused, and never repeats torch's advice to set
    weights_only=False; torch's warning about the protocol does not leak."""
    import pickle
    import warnings

    marker, path = tmp_path / "pwned", tmp_path / "plain.pt"
    with open(path, "wb") as f:
        pickle.dump({"model": _Payload(marker), "model_config": 1}, f, protocol=protocol)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(CheckpointError, match="refused without running anything") as err:
            load(path)
    assert "weights_only" not in str(err.value)
    assert not marker.exists()


TRAIN = ["train", "--task", "localization", "--world", "compass", "--steps", "1",
         "--validation-trials", "2", "--no-progress"]


@pytest.mark.parametrize("argv", [
    ["evaluate", "PT", "--trials", "1"],
    ["record", "--network", "PT", "--trials", "1", "--out", "TMP/rec.zarr"],
    [*TRAIN, "--init-from", "PT", "--out", "TMP/run"],
    [*TRAIN, "--out", "RUN"],                       # resuming the run it was put in
    ["export-network", "RUN", "x", "--dest", "TMP/dest"],
], ids=["evaluate", "record", "train --init-from", "train (resume)", "export-network"])
def test_every_loading_path_of_the_cli_refuses_it(argv, crafted, tmp_path, capsys):
    import shutil

    from hippo_probe.cli import main

    path, marker = crafted
    run = tmp_path / "crafted_run"
    run.mkdir()
    shutil.copy(path, run / "checkpoint.pt")
    argv = [a.replace("PT", str(path)).replace("RUN", str(run)).replace("TMP", str(tmp_path))
            for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "refused without running anything" in err and err.count("\n") == 1
    assert not marker.exists()


def test_shipped_networks_load_without_unpickling_code():
    for name in ("localization_compass", "generalized_compass", "specialized_compass",
                 "generalized_compass_readout"):
        assert hp.load_pretrained(name).world == "compass"


def test_record_stays_a_function_after_its_module_is_imported():
    import importlib

    importlib.import_module("hippo_probe.model.record")
    assert callable(hp.record)


def test_a_checkpoint_with_flipped_bytes_is_refused_not_resumed(tmp_path):
    """64 flipped bytes inside a tensor: torch would load them; the digest refuses."""
    import zipfile

    from hippo_probe.model.checkpoint import save_atomic

    path = tmp_path / "checkpoint.pt"
    save_atomic({"model": {"w": torch.randn(64, 64)}, "model_config": {"hidden": 8},
                 "step": 10, "optimizer": {"state": {0: {"step": torch.tensor(3.0),
                                                         "mask": torch.ones(2).bool()}}}},
                path)
    assert load(path)["step"] == 10          # 0-d and bool tensors digest too
    with zipfile.ZipFile(path) as z:
        entry = next(i for i in z.infolist() if i.filename.endswith("/data/0"))
    raw = bytearray(path.read_bytes())
    # the local header is 30 bytes + name + extra; flip bytes well inside the data
    name_len, extra_len = (int.from_bytes(raw[entry.header_offset + k:entry.header_offset
                                              + k + 2], "little") for k in (26, 28))
    start = entry.header_offset + 30 + name_len + extra_len + 1024
    raw[start:start + 64] = bytes(b ^ 0xFF for b in raw[start:start + 64])
    path.write_bytes(bytes(raw))
    assert torch.load(path, weights_only=True)["step"] == 10     # torch does not notice
    with pytest.raises(CheckpointError, match="is corrupt: its content does not match"):
        load(path)
