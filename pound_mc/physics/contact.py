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
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from pound_mc._docstring import fill
from pound_mc._jit import jit
from pound_mc.errors import InputError
from pound_mc.physics.relations import HERTZDAMP_RELATIONS, RELATIONS, largest_xi, lowest_e

__all__ = [
    "CONTACT_MODELS",
    "ContactLaw",
    "KernelLaw",
    "Parameter",
    "allowed_relations",
    "default_relation",
    "contact_law",
    "check_relation",
    "reported_xi",
    "kernel_damping",
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


#: Parameter descriptions the public force functions share (:func:`pound_mc._docstring.fill`).
_force_doc = fill(
    motion="delta : float\n    Penetration [m].\ndelta_dot : float\n    Penetration rate [m/s].",
    motion_unused="delta : float\n    Penetration [m].\n"
    "delta_dot : float\n    Penetration rate [m/s] (unused).",
    unused="xi : float\n    Unused.\nm_eff : float\n    Unused.",
)


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
@_force_doc
def jankowski_force(delta: float, delta_dot: float, beta: float, xi: float, m_eff: float) -> float:
    """Non-linear viscoelastic impact force [N], Jankowski (2008) eq. (1.1).

    ``F = beta delta^1.5 + c delta_dot`` while approaching (``delta_dot > 0``),
    ``F = beta delta^1.5`` during restitution (``delta_dot <= 0``), 0 without contact.

    Parameters
    ----------
    %(motion)s
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
@_force_doc
def linear_force(delta: float, delta_dot: float, k: float, xi: float, m_eff: float) -> float:
    """Linear elastic spring ``F = k delta`` [N] (Maison & Kasai 1992).

    ``delta_dot``, ``xi`` and ``m_eff`` are accepted for a uniform signature and ignored.

    Parameters
    ----------
    %(motion_unused)s
    k : float
        Impact spring stiffness [N/m].
    %(unused)s
    """
    if delta <= 0.0:
        return 0.0
    return k * delta


@jit
@_force_doc
def kelvin_force(delta: float, delta_dot: float, k: float, xi: float, m_eff: float) -> float:
    """Linear viscoelastic (Kelvin-Voigt) force ``F = k delta + c delta_dot`` [N].

    ``c = 2 xi sqrt(k m_eff)`` (Anagnostopoulos & Spiliopoulos 1992).  As published, the force
    may turn tensile near the end of restitution; it is not clipped.

    Parameters
    ----------
    %(motion)s
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
@_force_doc
def hertz_force(delta: float, delta_dot: float, beta: float, xi: float, m_eff: float) -> float:
    """Hertz elastic contact ``F = beta delta^1.5`` [N] (no dissipation).

    Parameters
    ----------
    %(motion_unused)s
    beta : float
        Hertz stiffness [N/m^1.5].
    %(unused)s
    """
    if delta <= 0.0:
        return 0.0
    return beta * delta * math.sqrt(delta)


@jit
@_force_doc
def hertzdamp_force(
    delta: float, delta_dot: float, beta: float, zeta: float, m_eff: float
) -> float:
    """Hertz contact with non-linear damping ``F = beta delta^1.5 (1 + zeta delta_dot)`` [N].

    Muthukumar & DesRoches (2006) with ``zeta = 3 (1 - e^2) / (4 v0)`` or Ye et al. (2009) with
    ``zeta = 8 (1 - e) / (5 e v0)`` (``relations.hertzdamp_zeta``); ``v0`` is the impact velocity
    of the episode.  The force is clipped at zero (no adhesion).

    Parameters
    ----------
    %(motion)s
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


def max_penetration_elastic(v0: ArrayLike, beta: ArrayLike, m_eff: ArrayLike) -> float | np.ndarray:
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


def contact_duration_hertz(v0: ArrayLike, beta: ArrayLike, m_eff: ArrayLike) -> float | np.ndarray:
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


# --------------------------------------------------------------------------- kernel side
# The compiled integrators evaluate a law through the functions below, one set per law, all
# with the same signature.  ``c0 = 2 xi sqrt(beta m_eff)`` is the damping constant of the
# Jankowski and Kelvin laws (precomputed per contact: seed eq. (1.1) reads ``c = c0 delta^0.25``
# for Jankowski's), ``zeta`` the damping constant of the current Hertz-damp episode [s/m].
# ``phase`` is 1 while approaching, 2 in restitution; the callers return 0 for ``phase == 0``
# and pass ``d >= 0`` (force) or ``d > 0`` (rate, gradient).  Their arithmetic is fixed: results
# are reproduced bit for bit across releases.


@jit(inline=True)
def _jankowski_k(d, dd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    f = beta * d * sd
    if phase == 1:
        f += c0 * math.sqrt(sd) * dd
    return f


@jit
def _jankowski_rate(d, dd, ddd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    r = 1.5 * beta * sd * dd
    if phase == 1:
        q = math.sqrt(sd)  # d^0.25
        r += c0 * (0.25 * dd * dd / (q * q * q) + q * ddd)
    return r


@jit(inline=True)
def _jankowski_grad(d, dd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    f = beta * d * sd
    fd = 1.5 * beta * sd
    fdd = 0.0
    if phase == 1:
        q = math.sqrt(sd)  # d^0.25
        f += c0 * q * dd
        fd += 0.25 * c0 * dd / (q * q * q)
        fdd = c0 * q
    return f, fd, fdd


@jit(inline=True)
def _linear_k(d, dd, beta, c0, zeta, phase):
    return beta * d


@jit
def _linear_rate(d, dd, ddd, beta, c0, zeta, phase):
    return beta * dd


@jit(inline=True)
def _linear_grad(d, dd, beta, c0, zeta, phase):
    return beta * d, beta, 0.0


@jit(inline=True)
def _kelvin_k(d, dd, beta, c0, zeta, phase):
    return beta * d + c0 * dd


@jit
def _kelvin_rate(d, dd, ddd, beta, c0, zeta, phase):
    return beta * dd + c0 * ddd


@jit(inline=True)
def _kelvin_grad(d, dd, beta, c0, zeta, phase):
    return beta * d + c0 * dd, beta, c0


@jit(inline=True)
def _hertz_k(d, dd, beta, c0, zeta, phase):
    return beta * d * math.sqrt(d)


@jit
def _hertz_rate(d, dd, ddd, beta, c0, zeta, phase):
    return 1.5 * beta * math.sqrt(d) * dd


@jit(inline=True)
def _hertz_grad(d, dd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    return beta * d * sd, 1.5 * beta * sd, 0.0


@jit(inline=True)
def _hertzdamp_k(d, dd, beta, c0, zeta, phase):
    f = beta * d * math.sqrt(d) * (1.0 + zeta * dd)
    return f if f > 0.0 else 0.0


@jit
def _hertzdamp_rate(d, dd, ddd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    f = beta * d * sd * (1.0 + zeta * dd)
    if f <= 0.0:
        return 0.0
    return 1.5 * beta * sd * dd * (1.0 + zeta * dd) + beta * d * sd * zeta * ddd


@jit(inline=True)
def _hertzdamp_grad(d, dd, beta, c0, zeta, phase):
    sd = math.sqrt(d)
    f = beta * d * sd * (1.0 + zeta * dd)
    if f <= 0.0:
        return 0.0, 0.0, 0.0
    return f, 1.5 * beta * sd * (1.0 + zeta * dd), beta * d * sd * zeta


@jit(inline=True)
def _stored_power15(d, beta):
    return 0.4 * beta * d * d * math.sqrt(d)  # int_0^d beta s^1.5 ds


@jit(inline=True)
def _stored_linear(d, beta):
    return 0.5 * beta * d * d


@jit
def _duration_hertz(v0, beta, meff):
    if v0 < 1e-12:
        v0 = 1e-12
    return 3.218 * (meff / beta) ** 0.4 * v0**-0.2  # DESIGN.md section 4


@jit
def _duration_linear(v0, beta, meff):
    return math.pi * math.sqrt(meff / beta)  # half a period of the contact spring


# --------------------------------------------------------------------------- registry


class Parameter(NamedTuple):
    """One parameter of a contact law: its scene key, units and meaning."""

    key: str
    units: str
    description: str


class KernelLaw(NamedTuple):
    """What the compiled integrators call for one law (see the notes above the functions).

    ``force(d, dd, beta, c0, zeta, phase)`` [N]; ``rate(d, dd, ddd, ...)`` its time derivative
    along the motion [N/s]; ``grad(...)`` the force and its partial derivatives by ``d`` and by
    ``dd``; ``stored(d, beta)`` the elastic energy held at penetration ``d`` [J];
    ``duration(v0, beta, m_eff)`` the estimated contact duration [s] that sizes sub-steps.
    """

    force: Callable
    rate: Callable
    grad: Callable
    stored: Callable
    duration: Callable


@dataclass(frozen=True)
class ContactLaw:
    """Declaration of one contact law: parameters, damping relations and force functions.

    Attributes
    ----------
    name : str
        The law's name (``[contact] model``).
    force : callable
        Public force function ``force(delta, delta_dot, stiffness, damping, m_eff)`` [N].
    stiffness_key, stiffness_units : str
        Scene key of the stiffness (``beta`` or ``k_N_per_m``) and its units.
    damping : str or None
        What the damping relation gives: ``"xi"`` (a ratio fixed per contact), ``"zeta"`` (the
        Hertz-damp constant [s/m], set per impact from ``e`` and the impact velocity), or None
        for laws without dissipation.
    relations : tuple of str
        Relations accepted for ``relation`` (``e`` to the damping); the first is the default.
    parameters : tuple of Parameter
        The law's parameters with their units.
    kernel : KernelLaw
        The compiled functions the integrators call.
    reference : str
        Where the law is published.
    """

    name: str
    force: Callable
    stiffness_key: str
    stiffness_units: str
    damping: str | None
    relations: tuple[str, ...]
    parameters: tuple[Parameter, ...]
    kernel: KernelLaw
    reference: str

    @property
    def default_relation(self) -> str | None:
        """Relation used when a scene gives ``e`` without ``relation`` (None: no damping)."""
        return self.relations[0] if self.relations else None

    def __getitem__(self, key: str):
        """Mapping access of the earlier registry (``law["force"]``, ``law["stiffness_units"]``)."""
        return getattr(self, key)


_GAP = Parameter("gap_m", "m", "initial separation of the floors that meet")
_BETA = Parameter("beta", "N m-1.5", "impact stiffness parameter")
_K = Parameter("k_N_per_m", "N m-1", "impact spring stiffness")
_XI = Parameter("xi", "1", "impact damping ratio (or e with a relation)")
_E = Parameter("e", "1", "coefficient of restitution")

#: What a law's stiffness parameter brings with it: the parameter, the elastic energy stored at
#: a penetration and the contact duration that sizes sub-steps (``beta``: F ~ delta^1.5, Hertz;
#: ``k_N_per_m``: F ~ delta, a spring).
_STIFFNESS = {
    "beta": (_BETA, _stored_power15, _duration_hertz),
    "k_N_per_m": (_K, _stored_linear, _duration_linear),
}
#: The parameter a scene sets a law's damping with, by what the damping relation gives.
_DAMPING = {"xi": (_XI,), "zeta": (_E,), None: ()}


def _declare(name, stiffness_key, damping, relations, reference) -> ContactLaw:
    """The :class:`ContactLaw` of law ``name``, its functions found by their names.

    The public force is ``{name}_force``, the compiled ones ``_{name}_k``, ``_{name}_rate`` and
    ``_{name}_grad``; the stiffness key fixes the units, stored energy and duration
    (:data:`_STIFFNESS`), the damping its parameter (:data:`_DAMPING`).
    """
    parameter, stored, duration = _STIFFNESS[stiffness_key]
    here = globals()
    compiled = (here[f"_{name}_{part}"] for part in ("k", "rate", "grad"))
    return ContactLaw(
        name,
        here[f"{name}_force"],
        stiffness_key,
        parameter.units,
        damping,
        tuple(relations),
        (_GAP, parameter, *_DAMPING[damping]),
        KernelLaw(*compiled, stored, duration),
        reference,
    )


#: Contact laws by name, in the order the compiled kernels number them.
CONTACT_MODELS: dict[str, ContactLaw] = {
    law.name: law
    for law in (
        _declare("jankowski", "beta", "xi", ("jankowski2008", "jankowski2006", "exact"),
                 "Jankowski (2008) eq. (1.1)"),
        _declare("linear", "k_N_per_m", None, (), "Maison & Kasai (1992)"),
        _declare("kelvin", "k_N_per_m", "xi", ("kelvin",), "Anagnostopoulos & Spiliopoulos (1992)"),
        _declare("hertz", "beta", None, (), "Hertz elastic contact"),
        _declare("hertzdamp", "beta", "zeta", HERTZDAMP_RELATIONS,
                 "Muthukumar & DesRoches (2006); Ye, Li & Zhu (2009)"),
    )
}  # fmt: skip


def contact_law(name: str) -> ContactLaw:
    """The declaration of contact law ``name``; an :class:`InputError` naming ``contact.model``."""
    try:
        return CONTACT_MODELS[name]
    except (KeyError, TypeError):
        raise InputError(
            f"unknown contact model {name!r}; allowed: {', '.join(CONTACT_MODELS)}",
            key="contact.model",
        ) from None


def allowed_relations(law: str) -> tuple[str, ...]:
    """Names accepted for ``[contact] relation`` with contact law ``law`` (empty: no damping)."""
    return contact_law(law).relations


def default_relation(law: str) -> str | None:
    """Relation used for ``law`` when a scene gives ``e`` without ``relation``."""
    return contact_law(law).default_relation


def check_relation(law: str, relation: str | None, *, file: str | None = None) -> str | None:
    """The relation ``law`` runs with: ``relation`` when the law accepts it, else its default.

    Raises
    ------
    InputError
        Naming ``contact.relation`` when ``relation`` belongs to another law (or none).
    """
    spec = contact_law(law)
    if relation is None:
        return spec.default_relation
    if relation not in spec.relations:
        allowed = ", ".join(spec.relations) if spec.relations else "none (the law has no damping)"
        raise InputError(
            f"relation {relation!r} does not belong to the {law!r} law; allowed: {allowed}",
            file=file,
            key="contact.relation",
        )
    return relation


def kernel_damping(law: str, e, xi):
    """The damping parameter the kernels take per contact for restitution ``e`` or ratio ``xi``.

    ``e`` itself for a law whose damping is set at every impact from ``e`` and the impact
    velocity (hertzdamp: its ``xi`` is NaN, :func:`reported_xi`), else the ratio ``xi``.
    Scenes (pairs and rows) and the study engine's batches take it from here.
    """
    return e if contact_law(law).damping == "zeta" else xi


def reported_xi(law: str, e, relation: str | None):
    """Impact damping ratio the kernels run with for restitution ``e`` under ``relation``.

    For the Jankowski and Kelvin laws the ratio ``xi`` from the relation; 0 for laws without
    damping (linear, hertz); NaN for ``hertzdamp``, whose damping is no constant ratio: the
    kernels set ``zeta`` (:func:`~pound_mc.physics.relations.hertzdamp_zeta`) from ``e`` and
    the impact velocity at every impact.
    """
    spec = contact_law(law)
    e = np.asarray(e, dtype=float)
    if spec.damping == "xi":
        relation = check_relation(law, relation)
        xi = np.asarray(RELATIONS[relation](e), dtype=float)
        if np.any(xi > largest_xi()):  # beyond the law's table, as xi is (kelvin's xi < 1)
            raise InputError(
                f"e = {float(np.min(e)):.4g} gives xi = {float(np.max(xi)):.4g} under "
                f"{relation}, beyond {largest_xi():.4g}, the end of the Jankowski law's "
                f"restitution table: e must be >= {lowest_e(relation):.4g} with this relation",
                key="contact.e",
            )
    else:
        check_relation(law, relation)
        xi = np.full(e.shape, 0.0 if spec.damping is None else np.nan)
    return float(xi) if xi.ndim == 0 else xi
