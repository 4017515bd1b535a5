"""One BLAS thread: the product's matrices are small (the UKF's state is under 100 numbers, the analysis works frame by
frame), where BLAS threads only wait on each other. With the default (one thread per core) and the cores busy with
other work, filtering a 30-s recording took 35 s instead of 3 s. The agent and the server set this themselves, so
nobody has to set OPENBLAS_NUM_THREADS before starting them."""

from __future__ import annotations

from threadpoolctl import threadpool_limits


def one_blas_thread() -> threadpool_limits:
    """Limits every BLAS library loaded so far (numpy's and scipy's OpenBLAS) to one thread and returns the limiter
    (usable as a context manager that restores the earlier limits on exit; without it, for the rest of the process).
    """
    import scipy.linalg  # noqa: F401 - loads scipy's own OpenBLAS first, so that the limit reaches it too

    return threadpool_limits(limits=1, user_api="blas")
