"""Bound the native thread pools of this process (one process per core)."""

from threadpoolctl import threadpool_limits

from ._validators import check_positive


def limit_threads(n: int) -> None:
    """Use at most ``n`` threads in BLAS/OpenMP, torch and numba (those installed).

    ``torch.set_num_threads`` alone leaves NumPy/SciPy's BLAS pool at one thread per core;
    two processes, one per core, each fitting with scikit-learn, then oversubscribe the
    cores and both run slower.

    Parameters
    ----------
    n : int
        Threads per pool, ≥ 1.
    """
    n = check_positive("n", n, integer=True)
    threadpool_limits(n)
    try:
        import torch
    except ImportError:                 # an analysis-only install
        pass
    else:
        torch.set_num_threads(n)
    import numba

    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
