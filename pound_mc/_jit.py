"""One place that fixes the numba options of every compiled kernel.

``cache=True`` keeps compiled machine code between processes, ``nogil=True`` lets the
threaded runner call kernels concurrently.  No blanket ``fastmath``: it would delete the
NaN and infinity checks that flag unstable simulations.
"""

from __future__ import annotations

import numba

_OPTIONS = {"cache": True, "nogil": True}


def jit(func=None, *, parallel: bool = False):
    """Compile ``func`` with the project's numba options (usable with or without arguments)."""
    options = dict(_OPTIONS, parallel=parallel) if parallel else dict(_OPTIONS)

    def decorate(f):
        return numba.njit(**options)(f)

    if func is None:
        return decorate
    return decorate(func)
