"""Virtual drop test: the seed paper's experiment, simulated.

A ball of mass ``m1`` hits a rigid surface (``m2 -> inf``) at velocity ``v0``; the contact
follows Jankowski's law (seed eq. 1.1) or, for comparison, any other law of
:data:`pound_mc.physics.contact.CONTACT_MODELS`.  The single impact is integrated in physical units
with SciPy's DOP853 at tight tolerance, in two phases split at maximum compression (where the
damping term switches off), so that the restitution achieved, peak penetration, peak force
and contact duration are accurate to about 1e-9.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from pound_mc.errors import InputError
from pound_mc.physics.contact import CONTACT_MODELS, effective_mass, max_penetration_elastic
from pound_mc.physics.relations import HERTZDAMP_RELATIONS, hertzdamp_zeta, xi_from_e

__all__ = ["DropTestResult", "drop_test"]


@dataclass(frozen=True)
class DropTestResult:
    """Outcome of one virtual drop test (SI units)."""

    model: str
    mass_kg: float
    velocity_m_s: float
    beta: float
    xi: float
    m_eff_kg: float
    restitution: float
    max_penetration_m: float
    peak_force_N: float
    contact_duration_s: float
    time_s: np.ndarray = field(repr=False)
    penetration_m: np.ndarray = field(repr=False)
    velocity_history_m_s: np.ndarray = field(repr=False)
    force_N: np.ndarray = field(repr=False)

    def as_dict(self) -> dict:
        """Scalar results as a JSON-ready dict (every field but the time histories)."""
        return {f.name: getattr(self, f.name) for f in fields(self) if f.repr}


def _positive(name, value):
    value = float(value)
    if not (np.isfinite(value) and value > 0.0):
        raise InputError(f"must be finite and > 0, got {value}", key=name)
    return value


def drop_test(
    mass_kg: float,
    velocity_m_s: float,
    beta: float,
    *,
    xi: float | None = None,
    e: float | None = None,
    relation: str | None = None,
    model: str = "jankowski",
    mass2_kg: float = math.inf,
    rtol: float = 1e-12,
    n_history: int = 400,
) -> DropTestResult:
    """Simulate one impact of a ball on a rigid (or finite-mass) body.

    Parameters
    ----------
    mass_kg : float
        Ball mass ``m1`` [kg].
    velocity_m_s : float
        Prior-impact velocity ``v0`` [m/s].
    beta : float
        Impact stiffness [N/m^1.5] (``k`` [N/m] for the ``linear`` and ``kelvin`` laws).
    xi : float, optional
        Impact damping ratio [-] (the damping constant ``zeta`` [s/m] for ``hertzdamp``);
        give either ``xi`` or ``e`` (neither for the elastic ``linear`` and ``hertz`` laws).
    e : float, optional
        Target coefficient of restitution [-], turned into ``xi`` with ``relation``.
    relation : str, optional
        xi-e relation name (:data:`pound_mc.physics.relations.RELATIONS`, or
        :data:`~pound_mc.physics.relations.HERTZDAMP_RELATIONS` for ``hertzdamp``).  Default
        ``jankowski2008`` (``kelvin`` for the Kelvin law, ``ye2009`` for Hertz-damp).
    model : str
        Contact law, a key of :data:`pound_mc.physics.contact.CONTACT_MODELS`.
    mass2_kg : float
        Mass of the other body [kg]; ``inf`` for the paper's rigid surface.
    rtol : float
        Relative tolerance of the integration.
    n_history : int
        Points of the returned time history.

    Returns
    -------
    DropTestResult
        Restitution achieved ``|v_f| / v0``, peak penetration, peak force, contact duration and
        the time history of penetration, penetration rate and force.
    """
    m1 = _positive("mass_kg", mass_kg)
    v0 = _positive("velocity_m_s", velocity_m_s)
    beta = _positive("beta", beta)
    if not (mass2_kg > 0.0):
        raise InputError(f"must be > 0 (inf for a rigid surface), got {mass2_kg}", key="mass2_kg")
    if model not in CONTACT_MODELS:
        raise InputError(
            f"unknown contact model {model!r}; choose one of {sorted(CONTACT_MODELS)}", key="model"
        )
    force_law = CONTACT_MODELS[model]["force"]
    if CONTACT_MODELS[model].damping is None:  # elastic: no damping to set
        if e is not None or xi not in (None, 0.0):
            raise InputError(
                f"the {model!r} law has no damping (elastic: it rebounds with e = 1); give "
                "neither xi nor e",
                key="e" if xi is None else "xi",
            )
        xi = 0.0
    if (xi is None) == (e is None):
        raise InputError("give exactly one of xi and e", key="xi")
    if xi is None:
        if model == "hertzdamp":
            relation = relation or "ye2009"
            if relation not in HERTZDAMP_RELATIONS:
                raise InputError(
                    f"unknown relation {relation!r} for hertzdamp; choose one of "
                    f"{sorted(HERTZDAMP_RELATIONS)}",
                    key="relation",
                )
            xi = float(hertzdamp_zeta(e, v0, relation))
        else:
            xi = float(
                xi_from_e(e, relation or ("kelvin" if model == "kelvin" else "jankowski2008"))
            )
    xi = float(xi)
    if not (np.isfinite(xi) and xi >= 0.0):
        raise InputError(f"must be finite and >= 0, got {xi}", key="xi")
    m_eff = float(effective_mass(m1, float(mass2_kg)))

    if CONTACT_MODELS[model]["stiffness_units"] == "N m-1":
        d_ref = v0 * math.sqrt(m_eff / beta)  # linear spring: v0 / omega
    else:
        d_ref = float(max_penetration_elastic(v0, beta, m_eff))  # seed eq. (2.5), e = 1
    t_ref = d_ref / v0
    atol = [rtol * d_ref * 1e-3, rtol * v0 * 1e-3]

    def rhs(_t, y):
        return [y[1], -force_law(y[0], y[1], beta, xi, m_eff) / m_eff]

    def max_compression(_t, y):
        return y[1]

    max_compression.terminal = True
    max_compression.direction = -1

    def separation(_t, y):
        return y[0]

    separation.terminal = True
    separation.direction = -1

    opts = {"method": "DOP853", "rtol": rtol, "atol": atol, "dense_output": True}
    approach = solve_ivp(rhs, (0.0, 100.0 * t_ref), [0.0, v0], events=max_compression, **opts)
    if approach.status != 1:
        raise RuntimeError("drop test: maximum compression not reached")
    t1 = float(approach.t_events[0][0])
    d_max = float(approach.y_events[0][0][0])
    restitution_phase = solve_ivp(
        rhs, (t1, t1 + 100.0 * t_ref), [d_max, 0.0], events=separation, **opts
    )
    if restitution_phase.status != 1:
        raise RuntimeError("drop test: separation not reached")
    t2 = float(restitution_phase.t_events[0][0])
    v_f = float(restitution_phase.y_events[0][0][1])

    # Peak force: during restitution it is beta*delta^1.5, largest at d_max; during approach the
    # damping term may move the peak earlier, so maximise the dense output there.
    def neg_force(t):
        d, v = approach.sol(t)
        return -force_law(d, v, beta, xi, m_eff)

    grid = np.linspace(0.0, t1, 801)
    k = int(np.argmin([neg_force(t) for t in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, grid.size - 1)]
    best = minimize_scalar(neg_force, bounds=(lo, hi), method="bounded", options={"xatol": 1e-14})
    peak = max(-float(best.fun), -neg_force(grid[k]), beta * d_max**1.5)

    n1 = max(n_history // 2, 2)
    ta = np.linspace(0.0, t1, n1)
    tb = np.linspace(t1, t2, n_history - n1 + 1)[1:]
    ya, yb = approach.sol(ta), restitution_phase.sol(tb)
    time = np.concatenate([ta, tb])
    pen = np.concatenate([ya[0], yb[0]])
    vel = np.concatenate([ya[1], yb[1]])
    force = np.array([force_law(d, v, beta, xi, m_eff) for d, v in zip(pen, vel, strict=True)])
    # fields in their declared order: the scalars, then the histories
    return DropTestResult(model, m1, v0, beta, xi, m_eff, abs(v_f) / v0, d_max, peak, t2,
                          time, pen, vel, force)  # fmt: skip
