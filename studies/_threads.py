"""The thread settings of a benchmark: stated with every result, and varied so that one run reports both.

MKL PARDISO (the factorization and the compliance columns), OpenBLAS (numpy's and scipy's dense algebra: the Newton
systems) and OpenMP each keep a pool of threads. A number measured with one pool size says little about another:
the HCM-1 contact path was 0.8x one linear solve with MKL_NUM_THREADS=1 and 3.1-4.1x with the default threads on two
loaded cores (the linear solve gains from threads, the small dense Newton systems lose). ``threadpoolctl`` limits
the loaded pools at run time, so a benchmark times the same work with one thread and with the default side by side.
"""

from __future__ import annotations

import contextlib
import os

__all__ = ["THREAD_VARIABLES", "THREAD_CHOICES", "thread_settings", "describe_threads", "thread_modes",
           "limited_threads"]

THREAD_VARIABLES = ("MKL_NUM_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")
THREAD_CHOICES = ("both", "1", "default")


def thread_settings() -> dict:
    """The environment variables that set pool sizes (unset: the library's default), the CPUs and each loaded
    pool's present size (``threadpoolctl.threadpool_info``)."""
    from threadpoolctl import threadpool_info

    _load_pools()
    pools: dict = {}
    for pool in threadpool_info():
        pools[pool["internal_api"]] = max(pools.get(pool["internal_api"], 0), int(pool["num_threads"]))
    return {"environment": {name: os.environ.get(name, "unset") for name in THREAD_VARIABLES},
            "cpus": os.cpu_count(), "pools": pools}


def describe_threads(settings: dict) -> str:
    """One line: the variables, the pools and the CPUs."""
    variables = ", ".join(f"{name}={value}" for name, value in settings["environment"].items())
    pools = ", ".join(f"{name} {count}" for name, count in sorted(settings["pools"].items())) or "none loaded"
    return f"{variables}; thread pools: {pools}; {settings['cpus']} CPUs"


def thread_modes(choice: str) -> list[tuple[str, int | None]]:
    """(label, thread limit or None for the default) of each setting to time: ``both`` gives one thread first, then
    the default."""
    if choice not in THREAD_CHOICES:
        raise ValueError(f"--threads={choice!r} is not one of {list(THREAD_CHOICES)}")
    modes = {"1": [("1 thread", 1)], "default": [("default threads", None)]}
    return modes["1"] + modes["default"] if choice == "both" else modes[choice]


@contextlib.contextmanager
def limited_threads(limit: int | None):
    """Every loaded thread pool (MKL, OpenBLAS, OpenMP) at ``limit`` threads inside the block; None: unchanged."""
    if limit is None:
        yield
        return
    from threadpoolctl import threadpool_limits

    _load_pools()
    with threadpool_limits(limits=limit):
        yield


def _load_pools() -> None:
    """Load MKL (through a tiny PARDISO solve, where pypardiso is installed) and the BLAS pools, so that the limit
    reaches them: threadpoolctl sees only libraries already loaded."""
    import numpy as np
    import scipy.linalg  # noqa: F401

    np.linalg.solve(np.eye(2), np.ones(2))
    try:
        import pypardiso
        import scipy.sparse as sp
    except ImportError:
        return
    pypardiso.spsolve(sp.identity(2, format="csr"), np.ones(2))
