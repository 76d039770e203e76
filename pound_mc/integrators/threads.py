"""How many threads the batches run on, set for a block and restored after it.

The batches of :mod:`pound_mc.integrators.batch` start as many Python threads as numba's
thread count, each running a serial ``nogil`` kernel over a slice of the simulations.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba

from pound_mc.errors import InputError

__all__ = ["numba_threads"]


@contextmanager
def numba_threads(n: int | None) -> Iterator[None]:
    """Run the kernels on ``n`` numba threads inside the block (``None``: numba's default).

    The previous setting is restored on exit (STYLE.md: restore ``set_num_threads`` in
    ``finally``); ``n`` above numba's thread pool is capped at the pool's size.
    """
    if n is None:
        yield
        return
    if n < 1:
        raise InputError(f"must be >= 1, got {n}", key="--threads")
    old = numba.get_num_threads()
    numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
    try:
        yield
    finally:
        numba.set_num_threads(old)
