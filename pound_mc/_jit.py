"""One place that fixes the numba options of every compiled kernel.

``cache=True`` keeps compiled machine code between processes, ``nogil=True`` lets the
threaded runner call kernels concurrently, ``error_model="numpy"`` drops the per-division
Python exception checks (a division by zero gives inf/nan, which the kernels flag).  No blanket
``fastmath``: it would delete the NaN and infinity checks that flag unstable simulations.
"""

from __future__ import annotations

import numba

_OPTIONS = {"cache": True, "nogil": True, "error_model": "numpy"}


def jit(func=None, *, parallel: bool = False, inline: bool = False):
    """Compile ``func`` with the project's numba options (usable with or without arguments).

    ``inline=True`` inlines a small helper into its callers at numba's IR level (hot helpers
    of the integrators); it still works when called from Python.
    """
    options = dict(_OPTIONS)
    if parallel:
        options["parallel"] = True
    if inline:
        options["inline"] = "always"

    def decorate(f):
        return numba.njit(**options)(f)

    if func is None:
        return decorate
    return decorate(func)
