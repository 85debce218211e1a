"""Network recordings and animal sessions share one layout, dtypes included."""

import pytest

from hippo_probe.recording import from_nwb, open_recording, save_recording

from .conftest import NWB_PATH, make_network_recording


def test_string_coords_have_one_dtype_in_memory_and_after_a_round_trip(tmp_path):
    pytest.importorskip("pynwb")
    network = make_network_recording()
    mouse = from_nwb(NWB_PATH, epoch="wake")
    save_recording(network, tmp_path / "net.zarr")
    reopened = open_recording(tmp_path / "net.zarr")
    for rec in (network, mouse, reopened):
        assert rec["space"].dtype == object
        assert list(rec["space"].values) == ["x", "y"]
    assert mouse["region"].dtype == object
