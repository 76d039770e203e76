"""Independent single-impact solution used by the tests.

Deliberately different from the package's own integration: physical units (not the
dimensionless form), SciPy's implicit Radau method (not DOP853), the force law written out
here from seed eq. (1.1) (not imported), and separation located by an event on delta.
"""

import math

from scipy.integrate import solve_ivp


def jankowski_impact(m_eff, v0, beta, xi, rtol=1e-11):
    """Return (restitution, max penetration, contact duration) of one free impact."""

    def rhs(_t, y):
        d, v = y
        if d <= 0.0:
            return [v, 0.0]
        force = beta * d**1.5
        if v > 0.0:
            force += 2.0 * xi * math.sqrt(beta * math.sqrt(d) * m_eff) * v
        return [v, -force / m_eff]

    def end(_t, y):
        return y[0]

    end.terminal = True
    end.direction = -1

    def turn(_t, y):
        return y[1]

    turn.direction = -1
    d_scale = (m_eff * v0**2 / beta) ** 0.4
    t_end = 50.0 * d_scale / v0
    # Start slightly inside the contact so the end event is not triggered at t = 0.
    t0 = 1e-9 * d_scale / v0
    sol = solve_ivp(
        rhs,
        (t0, t_end),
        [v0 * t0, v0],
        method="Radau",
        rtol=rtol,
        atol=[rtol * d_scale * 1e-3, rtol * v0 * 1e-3],
        events=[end, turn],
    )
    v_f = sol.y_events[0][0][1]
    d_max = sol.y_events[1][0][0]
    return abs(v_f) / v0, d_max, sol.t_events[0][0]


def hertzdamp_impact(m_eff, v0, beta, zeta, rtol=1e-11):
    """Return the restitution of one free impact of ``F = max(beta d^1.5 (1 + zeta d'), 0)``.

    The Hertz-damp law written out here (Muthukumar & DesRoches 2006, Ye et al. 2009); the
    bodies part where the force would pull or where ``d`` returns to 0, whichever first.
    """

    def rhs(_t, y):
        d, v = y
        if d <= 0.0:
            return [v, 0.0]
        return [v, -max(beta * d**1.5 * (1.0 + zeta * v), 0.0) / m_eff]

    def end(_t, y):
        return y[0]

    end.terminal = True
    end.direction = -1
    d_scale = (m_eff * v0**2 / beta) ** 0.4
    t0 = 1e-9 * d_scale / v0
    sol = solve_ivp(
        rhs,
        (t0, 50.0 * d_scale / v0),
        [v0 * t0, v0],
        method="Radau",
        rtol=rtol,
        atol=[rtol * d_scale * 1e-3, rtol * v0 * 1e-3],
        events=end,
    )
    return abs(sol.y_events[0][0][1]) / v0
