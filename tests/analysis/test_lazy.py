"""The analyses on lazy recordings: opened from zarr, and under a dask.distributed cluster."""

import numpy as np
import pytest

import hippo_probe as hp


def test_opened_from_zarr_equals_in_memory(place_rec, tmp_path):
    rec, _ = place_rec
    path = tmp_path / "place.zarr"
    hp.save_recording(rec, path)
    lazy = hp.open_recording(path)
    assert hasattr(lazy.activity.data, "dask")
    maps = hp.ratemaps(lazy, bin_size=0.05)
    np.testing.assert_allclose(maps.values, hp.ratemaps(rec, bin_size=0.05).values,
                               rtol=1e-12, equal_nan=True)
    info = hp.spatial_information(lazy, bin_size=0.05)
    np.testing.assert_allclose(info.information, hp.spatial_information(rec, bin_size=0.05)
                               .information, rtol=1e-12)
    hd = hp.head_direction_tuning(lazy, n_shuffles=3)
    np.testing.assert_allclose(hd.mean_vector_length,
                               hp.head_direction_tuning(rec, n_shuffles=3).mean_vector_length,
                               rtol=1e-12)
    assert hasattr(lazy.activity.data, "dask")  # still lazy: nothing was loaded into it


def _on_cluster(rec, processes):
    distributed = pytest.importorskip("distributed")
    lazy = rec.chunk({"time": 4000})
    local = hp.ratemaps(lazy, bin_size=0.05, by="trial")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=processes,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client, \
            distributed.get_task_stream(client) as stream:
        remote = hp.ratemaps(lazy, bin_size=0.05, by="trial")
    workers = {task["worker"] for task in stream.data}
    assert len(workers) == 2  # the work ran on both workers, not locally
    np.testing.assert_allclose(remote.values, local.values, rtol=1e-12, equal_nan=True)
    np.testing.assert_array_equal(remote.occupancy, local.occupancy)


def test_ratemaps_on_a_two_worker_local_cluster_equal_local(place_rec):
    _on_cluster(place_rec[0], processes=False)


@pytest.mark.slow
def test_ratemaps_on_a_two_process_local_cluster_equal_local(place_rec):
    # worker processes: the graph and the numba kernel travel by pickling (~20 s start-up)
    _on_cluster(place_rec[0], processes=True)
