"""The reference's contact physics, written out here from the literature (nothing imported).

Everything the compiled kernels take from :mod:`pound_mc.physics` is restated for the
reference from its source, so that a defect there cannot pass the kernels' tests by being
shared with the reference:

* the force laws (:func:`contact_force`) and the elastic energy they store (:func:`stored`);
* the damping ratio ``xi`` from a restitution ``e`` (:func:`xi_of_e`): Jankowski (2008)
  eq. (2.9), Jankowski (2006) and Anagnostopoulos (1992) as formulas, and ``exact`` solved
  here by root finding on this module's own single-impact integration (the package reads a
  precomputed table instead);
* the Hertz-damp law's damping constant ``zeta`` (:func:`zeta_of_e`);
* the restitution one free impact really rebounds with (:func:`jankowski_rebound`,
  :func:`hertzdamp_rebound`), integrated through the approach *and* the restitution phase to
  separation (the package integrates to maximum compression and takes the rebound from the
  energy, seed eq. 2.3-2.5);
* the seed's Table 2 (:data:`TABLE_2`, transcribed from the paper, not read from the package's
  CSV) and the restitution at a quantile of its range at an impact velocity
  (:func:`restitution_at_velocity`).
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

__all__ = [
    "OPEN",
    "APPROACH",
    "RESTITUTION",
    "IMPACT_MIN_PENETRATION_M",
    "contact_force",
    "stored",
    "xi_of_e",
    "zeta_of_e",
    "jankowski_rebound",
    "hertzdamp_rebound",
    "TABLE_2",
    "restitution_at_velocity",
]

#: Phases of a contact: open, approach (``delta_dot > 0``), restitution.
OPEN, APPROACH, RESTITUTION = 0, 1, 2

#: The counting convention the kernels share (``../shared/DESIGN.md`` section 2, "an impact is
#: one contact episode"; ``integrators.outputs``): an episode is an impact once its penetration
#: exceeds 1 nm, far above the round-off of floor displacements (1e-16 m) and far below any
#: physical contact (B1's reach 1e-4 m).  A convention, not physics: restated, not imported.
IMPACT_MIN_PENETRATION_M = 1.0e-9

#: Laws whose stiffness is ``beta`` [N/m^1.5] (force ~ delta^1.5); the others take ``k`` [N/m].
_POWER_15 = ("jankowski", "hertz", "hertzdamp")


def contact_force(model, d, dd, stiffness, xi, m_eff, zeta, phase):
    """Contact force [N] in a phase (open, approach, restitution); arrays allowed.

    ``d`` the penetration [m], ``dd`` its rate [m/s], ``stiffness`` ``beta`` [N/m^1.5] or ``k``
    [N/m], ``xi`` the damping ratio, ``m_eff`` the effective mass [kg], ``zeta`` [s/m] the
    Hertz-damp constant of the episode.

    ``jankowski``: Jankowski (2008) eq. (1.1), ``beta d^1.5 + c dd`` while approaching with
    ``c = 2 xi sqrt(beta sqrt(d) m_eff)``, ``beta d^1.5`` in restitution; ``hertz``:
    ``beta d^1.5``; ``linear``: ``k d`` (Maison & Kasai 1992); ``kelvin``:
    ``k d + 2 xi sqrt(k m_eff) dd`` (Anagnostopoulos 1992); ``hertzdamp``:
    ``max(0, beta d^1.5 (1 + zeta dd))`` (Muthukumar & DesRoches 2006).
    """
    if phase == OPEN:
        return np.zeros_like(np.asarray(d, dtype=float))
    d = np.maximum(d, 0.0)
    if model == "jankowski":
        f = stiffness * d**1.5
        if phase == APPROACH:
            f = f + 2.0 * xi * np.sqrt(stiffness * np.sqrt(d) * m_eff) * dd
        return f
    if model == "hertz":
        return stiffness * d**1.5
    if model == "linear":
        return stiffness * d
    if model == "kelvin":
        return stiffness * d + 2.0 * xi * np.sqrt(stiffness * m_eff) * dd
    if model == "hertzdamp":
        return np.maximum(stiffness * d**1.5 * (1.0 + zeta * dd), 0.0)
    raise ValueError(f"unsupported contact model {model!r}")


def stored(model, d, stiffness) -> float:
    """Elastic energy [J] a contact holds at penetration ``d`` [m]: the spring's integral.

    ``int_0^d beta s^1.5 ds = 0.4 beta d^2.5`` (seed eq. 2.3's first term), or ``k d^2 / 2``.
    """
    d = max(float(d), 0.0)
    if model in _POWER_15:
        return 0.4 * stiffness * d**2.5
    return 0.5 * stiffness * d * d


# --------------------------------------------------------------------------- single impacts


def jankowski_rebound(xi: float, rtol: float = 1e-12) -> float:
    """Restitution of one free impact of the Jankowski law with damping ratio ``xi``.

    In lengths of ``(m_eff v0^2 / beta)^0.4`` and times of that over ``v0`` the impact is
    ``u'' = -u^1.5 - 2 xi u^0.25 u'`` while ``u' > 0`` and ``u'' = -u^1.5`` after, from
    ``u = 0``, ``u' = 1``, whatever the mass, stiffness and velocity; both phases are
    integrated (DOP853), the turn and the separation located as events, and the restitution is
    ``-u'`` at separation.
    """

    def approach(_t, y):
        u = max(y[0], 0.0)
        return [y[1], -(u**1.5) - 2.0 * xi * u**0.25 * y[1]]

    def restitution(_t, y):
        return [y[1], -(max(y[0], 0.0) ** 1.5)]

    def turn(_t, y):
        return y[1]

    def separation(_t, y):
        return y[0]

    turn.terminal = separation.terminal = True
    turn.direction = separation.direction = -1
    opts = {"method": "DOP853", "rtol": rtol, "atol": 1e-3 * rtol}
    sol = solve_ivp(approach, (0.0, 1e4), [0.0, 1.0], events=turn, **opts)
    t_turn, y_turn = sol.t_events[0][0], sol.y_events[0][0]
    # the turn is a maximum of u: start the elastic phase just after it, where u > 0 is falling
    sol = solve_ivp(restitution, (t_turn, t_turn + 1e4), [y_turn[0], 0.0], events=separation,
                    first_step=1e-6, **opts)  # fmt: skip
    return float(-sol.y_events[0][0][1])


def hertzdamp_rebound(e: float, relation: str, rtol: float = 1e-12) -> float:
    """Restitution of one free impact of the Hertz-damp law whose ``zeta`` aims at ``e``.

    ``zeta v0`` depends on ``e`` alone (:func:`zeta_of_e` at ``v0 = 1``), so in the units of
    :func:`jankowski_rebound` the impact is ``u'' = -max(u^1.5 (1 + zeta u'), 0)`` from
    ``u = 0``, ``u' = 1``: integrated (DOP853) until the bodies part, where ``u`` returns to 0
    or, first, where the force would pull (located as an event); the restitution is ``-u'``
    there.
    """
    f = zeta_of_e(e, 1.0, relation)

    def rhs(_t, y):
        u = max(y[0], 0.0)
        return [y[1], -max(u**1.5 * (1.0 + f * y[1]), 0.0)]

    def separation(_t, y):
        return y[0]

    def pull(_t, y):
        return 1.0 + f * y[1]  # the force's sign while u > 0

    separation.terminal = pull.terminal = True
    separation.direction = pull.direction = -1
    sol = solve_ivp(rhs, (0.0, 1e4), [0.0, 1.0], method="DOP853", rtol=rtol, atol=1e-3 * rtol,
                    events=[separation, pull])  # fmt: skip
    fired = [(te[0], k) for k, te in enumerate(sol.t_events) if te.size]
    if not fired:
        raise RuntimeError(f"the Hertz-damp impact did not end: {sol.message}")
    k = min(fired)[1]
    return float(-sol.y_events[k][0][1])


# --------------------------------------------------------------------------- relations


def _xi_jankowski2008(e):
    """Jankowski (2008) eq. (2.9): ``xi = sqrt(5) (1 - e^2) / (2 pi e)``."""
    return math.sqrt(5.0) * (1.0 - e * e) / (2.0 * math.pi * e)


def _xi_jankowski2006(e):
    """Jankowski (2006) EESD 35: ``xi = 9 sqrt(5) (1 - e^2) / (2 e (e (9 pi - 16) + 16))``."""
    return 9.0 * math.sqrt(5.0) * (1.0 - e * e) / (2.0 * e * (e * (9.0 * math.pi - 16.0) + 16.0))


def _xi_kelvin(e):
    """Anagnostopoulos (1992), exact for a Kelvin-Voigt impact: ``-ln e / sqrt(pi^2 + ln^2 e)``."""
    ln = math.log(e)
    return -ln / math.sqrt(math.pi**2 + ln * ln)


@functools.lru_cache(maxsize=4096)
def _xi_exact(e):
    """The ``xi`` whose free impact rebounds with ``e`` (:func:`jankowski_rebound`, Brent)."""
    if e >= 1.0:
        return 0.0
    hi = 1.0
    while jankowski_rebound(hi) > e:  # the rebound falls as xi grows
        hi *= 2.0
    return float(brentq(lambda x: jankowski_rebound(x) - e, 0.0, hi, xtol=1e-14, rtol=1e-14))


_XI = {
    "jankowski2008": _xi_jankowski2008,
    "jankowski2006": _xi_jankowski2006,
    "exact": _xi_exact,
    "kelvin": _xi_kelvin,
}


def xi_of_e(e: float, relation: str) -> float:
    """Damping ratio ``xi`` [-] for restitution ``e`` by ``relation`` (module docstring)."""
    return float(_XI[relation](float(e)))


_ZETA = {
    # Ye, Li & Zhu (2009): zeta = 8 (1 - e) / (5 e v0) [s/m]
    "ye2009": lambda e, v0: 8.0 * (1.0 - e) / (5.0 * e * v0),
    # Muthukumar & DesRoches (2006): zeta = 3 (1 - e^2) / (4 v0) [s/m]
    "muthukumar2006": lambda e, v0: 3.0 * (1.0 - e * e) / (4.0 * v0),
}


def zeta_of_e(e: float, v0: float, relation: str) -> float:
    """Hertz-damp constant ``zeta`` [s/m] for restitution ``e`` at impact velocity ``v0`` [m/s]."""
    return float(_ZETA[relation](float(e), float(v0)))


# --------------------------------------------------------------------------- Table 2

#: Jankowski (2008) Table 2, transcribed from the paper: per material, rows of prior-impact
#: velocity [m/s] and the measured range of ``e`` (min, max) [-].  Steel was not tested above
#: 2 m/s.
TABLE_2 = {
    "steel": ((0.2, 0.6415, 0.7438), (0.5, 0.5264, 0.7142), (1.0, 0.5140, 0.6239),
              (1.5, 0.4967, 0.5652), (2.0, 0.4863, 0.5057)),
    "concrete": ((0.2, 0.7230, 0.7840), (0.5, 0.6580, 0.6859), (1.0, 0.5858, 0.5981),
                 (1.5, 0.5378, 0.5658), (2.0, 0.4419, 0.5659), (3.0, 0.4311, 0.5001),
                 (4.0, 0.4278, 0.4826)),
    "timber": ((0.2, 0.6567, 0.6934), (0.5, 0.5852, 0.6356), (1.0, 0.5334, 0.5797),
               (1.5, 0.4851, 0.5354), (2.0, 0.4281, 0.5347), (3.0, 0.4076, 0.4708),
               (4.0, 0.4002, 0.4428)),
    "ceramics": ((0.2, 0.7575, 0.7996), (0.5, 0.6870, 0.7681), (1.0, 0.6270, 0.6697),
                 (1.5, 0.5770, 0.6456), (2.0, 0.5115, 0.5642), (3.0, 0.4737, 0.5208),
                 (4.0, 0.4330, 0.4921)),
}  # fmt: skip

#: The scene's policy ``extrapolate`` keeps ``e`` at or above this [-] (the project's choice,
#: ``../shared/DESIGN.md``; restated with the policy).
_E_FLOOR = 0.05


def _bound_at(v, rows, col, outside):
    """Column ``col`` (1: e_min, 2: e_max) of ``rows`` at velocity ``v`` [m/s]."""
    vs = [r[0] for r in rows]
    if v <= vs[0] or v >= vs[-1]:
        a, b = (rows[0], rows[1]) if v <= vs[0] else (rows[-2], rows[-1])
        end = rows[0] if v <= vs[0] else rows[-1]
        if outside != "extrapolate":  # "clamp": the nearest measured range held
            return end[col]
        slope = (b[col] - a[col]) / (b[0] - a[0])
        return min(max(end[col] + slope * (v - end[0]), _E_FLOOR), 1.0)
    k = next(i for i in range(1, len(vs)) if v <= vs[i])  # v in (vs[k-1], vs[k]]
    lo, hi = rows[k - 1], rows[k]
    w = (v - lo[0]) / (hi[0] - lo[0])
    return lo[col] + w * (hi[col] - lo[col])


def restitution_at_velocity(material: str, v: float, quantile: float, outside: str) -> float:
    """Restitution at ``quantile`` of Table 2's range for ``material`` at velocity ``v`` [m/s].

    ``e = e_min(v) + Q (e_max(v) - e_min(v))``, each bound linear in velocity between the
    table's rows; outside them held at the end row (``clamp``) or continued along the end
    segment (``extrapolate``, kept within ``[0.05, 1]``).
    """
    rows = TABLE_2[material]
    e_lo = _bound_at(float(v), rows, 1, outside)
    e_hi = _bound_at(float(v), rows, 2, outside)
    return e_lo + float(quantile) * (e_hi - e_lo)
