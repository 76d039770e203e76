"""Stability of the integrators at an impact: predicted from theory and observed.

During contact the stiffest thing in the model is the contact spring.  Linearised at the peak
penetration of an elastic Hertz impact with approach velocity ``v0`` (seed eq. 2.5),
``k_c = 1.5 beta delta_max^0.5`` and the contact frequency is ``omega_c = sqrt(k_c / m_eff)``.

*Predicted*: from the spectral radius ``rho(Omega)`` of the method's amplification matrix on
``x'' = -omega_c^2 x`` (``Omega = dt omega_c``), the largest ``Omega`` at which one contact
(half a period of the contact spring, ``pi / Omega`` steps) gains less energy than the kernel's
instability flag allows: ``rho^(2 pi / Omega) <= 1 + UNSTABLE_ENERGY_FRACTION``.  For central
differences ``rho = 1`` up to ``Omega = 2`` (the classical limit) and grows fast beyond it.
Newmark average acceleration with the contact force lagged one step (``newmark-explicit``)
has the characteristic polynomial ``z (z - 1)^2 + (Omega^2 / 4)(z + 1)^2`` whose root near 1 is
``|z| ~ sqrt(1 + Omega^2)``: it gains energy at every step size, slowly for small ``Omega``.
The implicit ``newmark`` and ``adaptive`` (contact sub-steps sized from the contact duration,
not from ``dt``) have no limit.

*Observed*: an SDOF pair starting in contact with approach velocity ``v0`` and no ground
motion, integrated for a few impacts; bisection on ``dt`` for the largest step whose run the
kernel does not flag unstable.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from pound_mc.integrators import METHODS, UNSTABLE_ENERGY_FRACTION, run_kernel
from pound_mc.physics.structures import contacts_between, sdof
from pound_mc.scene import Scene

__all__ = [
    "contact_frequency",
    "predicted_limit",
    "impact_scene",
    "observed_limit",
    "stability_map",
]

#: Methods whose stable step is bounded at an impact.
BOUNDED = ("central-difference", "newmark-explicit")


def contact_frequency(beta: float, m_eff: float, v0: float) -> float:
    """Contact frequency ``omega_c`` [rad/s] of a Hertz impact linearised at its peak.

    Parameters
    ----------
    beta : float
        Impact stiffness parameter [N/m^1.5].
    m_eff : float
        Effective mass [kg].
    v0 : float
        Approach velocity [m/s].
    """
    d_max = (5.0 * m_eff * v0**2 / (4.0 * beta)) ** 0.4  # seed eq. (2.5)
    return math.sqrt(1.5 * beta * math.sqrt(d_max) / m_eff)


def _spectral_radius(method: str, omega_dt: float) -> float:
    o2 = omega_dt**2
    if method == "central-difference":
        roots = np.roots([1.0, -(2.0 - o2), 1.0])
    elif method == "newmark-explicit":
        # x_{n+1} - 2 x_n + x_{n-1} = -(O^2/4)(x_n + 2 x_{n-1} + x_{n-2})
        roots = np.roots([1.0, -2.0 + o2 / 4.0, 1.0 + o2 / 2.0, o2 / 4.0])
    else:
        return 1.0
    return float(np.max(np.abs(roots)))


def _energy_gain(method: str, omega_dt: float) -> float:
    """Energy factor over one contact (``pi / Omega`` steps) of the linearised scheme."""
    rho = _spectral_radius(method, omega_dt)
    return rho ** (2.0 * math.pi / omega_dt)


def predicted_limit(method: str) -> float:
    """Largest stable ``Omega = dt omega_c`` predicted by the linearised scheme.

    Stable means one contact gains less energy than the instability flag allows; inf for
    methods without a limit.
    """
    if method not in BOUNDED:
        return math.inf
    allowed = 1.0 + UNSTABLE_ENERGY_FRACTION
    lo, hi = 1e-3, 10.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if _energy_gain(method, mid) <= allowed:
            lo = mid
        else:
            hi = mid
    return lo


def impact_scene(beta: float, *, m_kg: float = 1.0e6, xi: float = 0.0):
    """SDOF pair (T = 2 s and 4 s, undamped, equal masses) for the stability drill."""
    left = sdof(2.0, m_kg, 0.0)
    right = sdof(4.0, m_kg, 0.0)
    return Scene(
        record={},
        left=left,
        right=right,
        contacts=contacts_between(left, right),
        gap_m=np.array([0.0]),
        contact_model="jankowski",
        stiffness=float(beta),
        xi=float(xi),
    )


def run_impact(scene, method: str, dt_s: float, *, v0: float = 0.5, duration_s: float = 3.0):
    """Run the drill: left mass moving at ``v0`` into the right one, no ground motion.

    Returns the kernel's outputs by name (see :data:`pound_mc.integrators.OUTPUTS`).
    """
    arrays = scene.modal_arrays()
    # no ground motion: one record interval, split by the kernel into steps of dt_s
    rec_dt = duration_s
    ag = np.zeros(2)
    v_modal = np.array([v0 * arrays["gamma"][0], 0.0])
    out, *_ = run_kernel(
        ag,
        rec_dt,
        **arrays,
        model=scene.contact_model,
        method=method,
        dt_s=dt_s,
        substeps=scene.substeps,
        v0=v_modal,
    )
    return out


def _stable(out) -> bool:
    return int(out["status"]) in (0, 3)  # ok, or inaccurate (stable, contacts under-resolved)


def observed_limit(beta: float, method: str, *, v0: float = 0.5, iterations: int = 14) -> float:
    """Largest stable step [s] found by bisection (the kernel's status flag decides)."""
    scene = impact_scene(beta)
    wc = contact_frequency(beta, scene.contacts[0].m_eff, v0)
    lo = 0.01 / wc
    hi = 20.0 / wc
    if not _stable(run_impact(scene, method, lo, v0=v0)):
        return float("nan")
    if _stable(run_impact(scene, method, hi, v0=v0)):
        return math.inf
    for _ in range(iterations):
        mid = math.sqrt(lo * hi)
        if _stable(run_impact(scene, method, mid, v0=v0)):
            lo = mid
        else:
            hi = mid
    return lo


def stability_map(betas=None, methods=None, *, v0: float = 0.5):
    """Predicted and observed largest stable ``dt omega_c`` for each method and stiffness.

    Returns
    -------
    pandas.DataFrame
        Columns ``method``, ``beta`` [N/m^1.5], ``omega_c`` [rad/s], ``predicted``,
        ``observed`` (both ``dt omega_c``; inf where no limit was found up to 20).
    """
    betas = np.geomspace(1e9, 1e12, 7) if betas is None else np.asarray(betas, float)
    methods = list(METHODS) if methods is None else methods
    rows = []
    for method in methods:
        for beta in betas:
            m_eff = impact_scene(beta).contacts[0].m_eff
            wc = contact_frequency(beta, m_eff, v0)
            dt = observed_limit(beta, method, v0=v0)
            rows.append(
                {
                    "method": method,
                    "beta": beta,
                    "omega_c": wc,
                    "predicted": predicted_limit(method),
                    "observed": dt * wc,
                }
            )
    return pd.DataFrame(rows)
