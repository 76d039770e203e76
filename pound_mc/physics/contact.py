"""Impact force laws and damping-restitution relations.

Every force law is a plain function of scalars compiled with numba, so the same function is
called from Python (``jankowski_force(1e-3, 0.2, 2.75e9, 0.35, 5e5)``) and from the compiled
integrators.  Sign convention (``../shared/DESIGN.md`` section 2): penetration
``delta = x_left - x_right - gap``, contact while ``delta > 0``, ``delta_dot > 0`` while the
bodies approach.  Forces are compressive-positive [N].

Glossary: ``delta`` penetration [m], ``delta_dot`` penetration rate [m/s], ``beta`` impact
stiffness parameter [N/m^1.5], ``k`` linear stiffness [N/m], ``xi`` impact damping ratio [-],
``e`` coefficient of restitution [-], ``m_eff = m1*m2/(m1+m2)`` effective mass [kg], ``t_c``
contact duration [s].

References
----------
Jankowski R. (2008) Theoretical and experimental assessment of parameters for the non-linear
viscoelastic model of structural pounding.  J. Theor. Appl. Mech. 46(3).
Jankowski R. (2006) Analytical expression between the impact damping ratio and the coefficient
of restitution in the non-linear viscoelastic model of structural pounding.  EESD 35, 517-524.
Anagnostopoulos S.A., Spiliopoulos K.V. (1992) An investigation of earthquake induced pounding
between adjacent buildings.  EESD 21, 289-302.
Maison B.F., Kasai K. (1992) Dynamics of pounding when two buildings collide.  EESD 21, 771-786.
Muthukumar S., DesRoches R. (2006) A Hertz contact model with non-linear damping for pounding
simulation.  EESD 35, 811-828.
Ye K., Li L., Zhu H. (2009) A note on the Hertz contact model with nonlinear damping for
pounding simulation.  EESD 38, 1135-1142.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit

__all__ = [
    "CONTACT_MODELS",
    "effective_mass",
    "jankowski_force",
    "jankowski_damping",
    "linear_force",
    "kelvin_force",
    "hertz_force",
    "hertzdamp_force",
    "contact_duration_hertz",
    "max_penetration_elastic",
]


@jit
def effective_mass(m1: float, m2: float) -> float:
    """Effective mass of two colliding bodies [kg]; ``m2 = inf`` gives ``m1`` (rigid wall).

    Parameters
    ----------
    m1, m2 : float
        Masses that meet [kg].
    """
    if math.isinf(m2):
        return m1
    if math.isinf(m1):
        return m2
    return m1 * m2 / (m1 + m2)


@jit
def jankowski_damping(delta: float, beta: float, xi: float, m_eff: float) -> float:
    """Impact element damping ``c = 2 xi sqrt(beta sqrt(delta) m_eff)`` [N s/m].

    Jankowski (2008), eq. (1.1).

    Parameters
    ----------
    delta : float
        Penetration [m] (``c = 0`` for ``delta <= 0``).
    beta : float
        Impact stiffness parameter [N/m^1.5].
    xi : float
        Impact damping ratio [-].
    m_eff : float
        Effective mass ``m1 m2 / (m1 + m2)`` [kg].
    """
    if delta <= 0.0:
        return 0.0
    return 2.0 * xi * math.sqrt(beta * math.sqrt(delta) * m_eff)


@jit
def jankowski_force(delta: float, delta_dot: float, beta: float, xi: float, m_eff: float) -> float:
    """Non-linear viscoelastic impact force [N], Jankowski (2008) eq. (1.1).

    ``F = beta delta^1.5 + c delta_dot`` while approaching (``delta_dot > 0``),
    ``F = beta delta^1.5`` during restitution (``delta_dot <= 0``), 0 without contact.

    Parameters
    ----------
    delta : float
        Penetration [m].
    delta_dot : float
        Penetration rate [m/s].
    beta : float
        Impact stiffness parameter [N/m^1.5].
    xi : float
        Impact damping ratio [-] (see :mod:`pound_mc.physics.relations` for ``xi`` from ``e``).
    m_eff : float
        Effective mass of the colliding bodies [kg].
    """
    if delta <= 0.0:
        return 0.0
    elastic = beta * delta * math.sqrt(delta)
    if delta_dot > 0.0:
        return elastic + jankowski_damping(delta, beta, xi, m_eff) * delta_dot
    return elastic


@jit
def linear_force(delta: float, delta_dot: float, k: float, xi: float, m_eff: float) -> float:
    """Linear elastic spring ``F = k delta`` [N] (Maison & Kasai 1992).

    ``delta_dot``, ``xi`` and ``m_eff`` are accepted for a uniform signature and ignored.

    Parameters
    ----------
    delta : float
        Penetration [m].
    delta_dot : float
        Penetration rate [m/s] (unused).
    k : float
        Impact spring stiffness [N/m].
    xi : float
        Unused.
    m_eff : float
        Unused.
    """
    if delta <= 0.0:
        return 0.0
    return k * delta


@jit
def kelvin_force(delta: float, delta_dot: float, k: float, xi: float, m_eff: float) -> float:
    """Linear viscoelastic (Kelvin-Voigt) force ``F = k delta + c delta_dot`` [N].

    ``c = 2 xi sqrt(k m_eff)`` (Anagnostopoulos & Spiliopoulos 1992).  As published, the force
    may turn tensile near the end of restitution; it is not clipped.

    Parameters
    ----------
    delta : float
        Penetration [m].
    delta_dot : float
        Penetration rate [m/s].
    k : float
        Impact spring stiffness [N/m].
    xi : float
        Impact damping ratio [-] (``relations.kelvin_xi``).
    m_eff : float
        Effective mass [kg].
    """
    if delta <= 0.0:
        return 0.0
    return k * delta + 2.0 * xi * math.sqrt(k * m_eff) * delta_dot


@jit
def hertz_force(delta: float, delta_dot: float, beta: float, xi: float, m_eff: float) -> float:
    """Hertz elastic contact ``F = beta delta^1.5`` [N] (no dissipation).

    Parameters
    ----------
    delta : float
        Penetration [m].
    delta_dot : float
        Penetration rate [m/s] (unused).
    beta : float
        Hertz stiffness [N/m^1.5].
    xi : float
        Unused.
    m_eff : float
        Unused.
    """
    if delta <= 0.0:
        return 0.0
    return beta * delta * math.sqrt(delta)


@jit
def hertzdamp_force(
    delta: float, delta_dot: float, beta: float, zeta: float, m_eff: float
) -> float:
    """Hertz contact with non-linear damping ``F = beta delta^1.5 (1 + zeta delta_dot)`` [N].

    Muthukumar & DesRoches (2006) with ``zeta = 3 (1 - e^2) / (4 v0)`` or Ye et al. (2009) with
    ``zeta = 8 (1 - e) / (5 e v0)`` (``relations.hertzdamp_zeta``); ``v0`` is the impact velocity
    of the episode.  The force is clipped at zero (no adhesion).

    Parameters
    ----------
    delta : float
        Penetration [m].
    delta_dot : float
        Penetration rate [m/s].
    beta : float
        Hertz stiffness [N/m^1.5].
    zeta : float
        Damping constant [s/m].
    m_eff : float
        Unused.
    """
    if delta <= 0.0:
        return 0.0
    f = beta * delta * math.sqrt(delta) * (1.0 + zeta * delta_dot)
    return f if f > 0.0 else 0.0


#: Contact models by name: force function and the integer code compiled kernels switch on.
CONTACT_MODELS = {
    "jankowski": {"code": 0, "force": jankowski_force, "stiffness_units": "N m-1.5"},
    "linear": {"code": 1, "force": linear_force, "stiffness_units": "N m-1"},
    "kelvin": {"code": 2, "force": kelvin_force, "stiffness_units": "N m-1"},
    "hertz": {"code": 3, "force": hertz_force, "stiffness_units": "N m-1.5"},
    "hertzdamp": {"code": 4, "force": hertzdamp_force, "stiffness_units": "N m-1.5"},
}


def max_penetration_elastic(v0, beta, m_eff):
    """Peak penetration of an elastic Hertz impact [m], Jankowski (2008) eq. (2.5).

    ``delta_max = (5 m_eff v0^2 / (4 beta))^(2/5)``.

    Parameters
    ----------
    v0 : float or array_like
        Impact (approach) velocity [m/s].
    beta : float or array_like
        Impact stiffness parameter [N/m^1.5].
    m_eff : float or array_like
        Effective mass [kg].
    """
    v0, beta, m_eff = (np.asarray(a, dtype=float) for a in (v0, beta, m_eff))
    return (5.0 * m_eff * v0**2 / (4.0 * beta)) ** 0.4


#: ``int_0^1 ds / sqrt(1 - s^2.5) = 0.4 B(0.4, 0.5)``; the elastic Hertz contact lasts
#: ``2 * HERTZ_DURATION_INTEGRAL * delta_max / v0`` (= 2.943 delta_max / v0).
HERTZ_DURATION_INTEGRAL = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)


def contact_duration_hertz(v0, beta, m_eff):
    """Duration of an elastic Hertz impact [s]: ``t_c = 2.943 delta_max / v0``.

    Equivalent to ``t_c = 3.218 (m_eff / beta)^0.4 v0^-0.2`` (DESIGN.md section 4).

    Parameters
    ----------
    v0 : float or array_like
        Impact velocity [m/s].
    beta : float or array_like
        Impact stiffness parameter [N/m^1.5].
    m_eff : float or array_like
        Effective mass [kg].
    """
    v0 = np.asarray(v0, dtype=float)
    return 2.0 * HERTZ_DURATION_INTEGRAL * max_penetration_elastic(v0, beta, m_eff) / v0
