import numba
import pytest
import torch
from threadpoolctl import threadpool_info, threadpool_limits

from hippo_probe._threads import limit_threads


@pytest.fixture
def restore_threads():
    torch_before, numba_before = torch.get_num_threads(), numba.get_num_threads()
    pools_before = {p["filepath"]: p["num_threads"] for p in threadpool_info()}
    yield
    torch.set_num_threads(torch_before)
    numba.set_num_threads(numba_before)
    for pool in threadpool_info():
        threadpool_limits(pools_before.get(pool["filepath"], pool["num_threads"]),
                          user_api=pool["user_api"])


def test_limit_threads_bounds_every_pool(restore_threads):
    limit_threads(1)
    assert torch.get_num_threads() == 1
    assert numba.get_num_threads() == 1
    assert threadpool_info(), "NumPy's BLAS should be loaded"
    assert all(p["num_threads"] == 1 for p in threadpool_info())


@pytest.mark.parametrize("bad", [0, -1, 1.5, True])
def test_limit_threads_refuses_a_bad_count(bad):
    with pytest.raises((ValueError, TypeError), match="`n`"):
        limit_threads(bad)
