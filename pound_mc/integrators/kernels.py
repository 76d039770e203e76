"""Former single module of the kernels, kept so that existing imports keep working.

The kernels now live in one module per concern (:mod:`~pound_mc.integrators.toolkit`,
:mod:`~pound_mc.integrators.laws`, :mod:`~pound_mc.integrators.adaptive`,
:mod:`~pound_mc.integrators.fixed`, :mod:`~pound_mc.integrators.pair`) behind the boundary
:mod:`pound_mc.integrators.batch`; import from :mod:`pound_mc.integrators`.
"""

from pound_mc.integrators.batch import (
    CONTACT_OUTPUTS,
    METHODS,
    OUTPUTS,
    UNSTABLE_ENERGY_FRACTION,
    run_kernel,
    simulate_scene_batch,
    simulate_sdof_pairs,
)
from pound_mc.integrators.toolkit import exact_step_coefficients

__all__ = [
    "METHODS",
    "OUTPUTS",
    "CONTACT_OUTPUTS",
    "UNSTABLE_ENERGY_FRACTION",
    "run_kernel",
    "simulate_sdof_pairs",
    "simulate_scene_batch",
    "exact_step_coefficients",
]
