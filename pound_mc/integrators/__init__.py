"""Compiled time integrators for two buildings that pound, and an independent reference.

Modules: :mod:`~pound_mc.integrators.batch` (the boundary: names in, named outputs out),
:mod:`~pound_mc.integrators.adaptive`, :mod:`~pound_mc.integrators.fixed` and
:mod:`~pound_mc.integrators.pair` (the methods), :mod:`~pound_mc.integrators.laws` (kernel side
of the contact laws), :mod:`~pound_mc.integrators.toolkit` (exact linear steps, Hermite
screens), :mod:`~pound_mc.integrators.outputs` (output layout),
:mod:`~pound_mc.integrators.reference` (SciPy solution sharing no code with the kernels) and
:mod:`~pound_mc.integrators.threads`.
"""

from pound_mc.integrators.batch import (
    CONTACT_OUTPUTS,
    METHODS,
    OUTPUTS,
    UNSTABLE_ENERGY_FRACTION,
    KernelResult,
    KernelSettings,
    kernel_settings,
    run_kernel,
    simulate_scene_batch,
    simulate_sdof_pairs,
)
from pound_mc.integrators.threads import numba_threads
from pound_mc.integrators.toolkit import exact_step_coefficients

__all__ = [
    "METHODS",
    "OUTPUTS",
    "CONTACT_OUTPUTS",
    "UNSTABLE_ENERGY_FRACTION",
    "KernelResult",
    "KernelSettings",
    "kernel_settings",
    "run_kernel",
    "simulate_sdof_pairs",
    "simulate_scene_batch",
    "exact_step_coefficients",
    "numba_threads",
]
