"""The seed's measured tables: the virtual drop test against Jankowski (2008) Tables 2 and 3.

The seed paper dropped balls of steel, concrete, timber and ceramics on a rigid surface of the
same material, measured the coefficient of restitution (Table 2, a range at each impact
velocity) and fitted the impact stiffness ``beta`` to the force histories (Table 3, a range for
each ball).  :func:`pound_mc.physics.droptest.drop_test` (``pound-mc droptest``) simulates that
experiment; here it runs as ``pound-mc droptest`` does by default (the middle ball of Table 1,
``beta`` from Table 3 at its mass), with the ``exact`` relation:

* Table 2: aimed at each end of the measured range at 1 m/s, the ball must rebound inside the
  range (tolerance 1e-6 outside it: the exact relation's table is interpolated to about 1e-9,
  the drop test integrated to 1e-9).  The seed's own eq. (2.9) overshoots by up to 5 %, more
  than most ranges are wide, which is why the exact relation is used to reproduce them.
* Table 3: the ``beta`` a least-squares fit of the virtual force history recovers (the
  restitution phase, ``F = beta delta^1.5``, as the experiment's fit did) for each ball of
  Table 1 must lie in that ball's range; ranges as printed, no tolerance.
"""

from __future__ import annotations

import numpy as np

from pound_mc.physics import materials
from pound_mc.physics.droptest import drop_test
from pound_mc.validation.runner import Case

__all__ = ["CASES", "fitted_beta"]

VELOCITY = 1.0  # m/s, the drop test's default impact velocity
_T2 = "Jankowski (2008) Table 2"
_T3 = "Jankowski (2008) Table 3"


def _balls(material: str):
    t1 = materials.table(1)
    return t1[t1["material"] == material].reset_index(drop=True)


def _middle_ball_mass(material: str) -> float:
    """The mass ``pound-mc droptest`` uses by default: the middle ball of Table 1 [kg]."""
    balls = _balls(material)
    middle = balls.iloc[len(balls) // 2]
    return 0.5 * float(middle["mass_min_kg"] + middle["mass_max_kg"])


def _table2_range(material: str, velocity: float) -> tuple[float, float]:
    t2 = materials.table(2)
    row = t2[(t2["material"] == material) & np.isclose(t2["velocity_m_s"], velocity)]
    return float(row["e_min"].iloc[0]), float(row["e_max"].iloc[0])


def table2(quick: bool = False) -> list[dict]:
    """The drop test aimed at each end of Table 2's range at 1 m/s rebounds inside it."""
    rows, plot = [], []
    for material in materials.MATERIALS:
        mass = _middle_ball_mass(material)
        beta = materials.stiffness_range(material, mass)[2]
        low, high = _table2_range(material, VELOCITY)
        for end, e in (("low", low), ("high", high)):
            res = drop_test(mass, VELOCITY, beta, e=e, relation="exact")
            rows.append({"quantity": f"e {material}, {VELOCITY:g} m/s, {end} end",
                         "value": res.restitution, "reference_low": low,
                         "reference_high": high, "tolerance": 1e-6})  # fmt: skip
            if end == "low":
                plot.append((f"{material}, {mass:.3g} kg", res.time_s * 1e3, res.force_N / 1e3))
    rows[0]["_plot"] = {
        "title": "Virtual drop tests at 1 m/s (the low end of Table 2's e)",
        "xlabel": "time [ms]",
        "ylabel": "impact force [kN]",
        "series": plot,
    }
    return rows


def fitted_beta(result) -> float:
    """The ``beta`` [N/m^1.5] a fit to a drop test's force history recovers.

    Least squares of ``F = beta delta^1.5`` over the restitution phase (``delta_dot <= 0``).
    """
    phase = (result.velocity_history_m_s <= 0.0) & (result.penetration_m > 0.0)
    d15 = result.penetration_m[phase] ** 1.5
    return float(np.sum(result.force_N[phase] * d15) / np.sum(d15 * d15))


def table3(quick: bool = False) -> list[dict]:
    """For each ball of Table 1 (``quick``: the middle one of each material), the fitted beta.

    It must lie in the ball's Table 3 range.
    """
    t3 = materials.table(3)
    rows = []
    for material in materials.MATERIALS:
        balls = t3[t3["material"] == material].reset_index(drop=True)
        for k, ball in balls.iterrows():
            if quick and k != len(balls) // 2:
                continue
            mass = 0.5 * float(ball["mass_min_kg"] + ball["mass_max_kg"])
            beta = materials.stiffness_range(material, mass)[2]
            e = float(np.mean(materials.restitution_range(material, VELOCITY)))
            res = drop_test(mass, VELOCITY, beta, e=e, relation="exact")
            rows.append({"quantity": f"beta {material}, {mass:.3g} kg",
                         "value": fitted_beta(res), "reference_low": float(ball["beta_min"]),
                         "reference_high": float(ball["beta_max"]), "tolerance": 0.0,
                         "units": "N/m^1.5"})  # fmt: skip
    return rows


_ABOUT2 = (
    "The virtual drop test (pound-mc droptest: a ball of the middle mass of Table 1 on a rigid "
    "surface at 1 m/s, beta from Table 3, integrated by SciPy's DOP853 to 1e-12) aimed with the "
    "exact relation at each end of Table 2's measured range must rebound inside the range; "
    "tolerance 1e-6 outside it, the accuracy of the exact relation's table. The seed's own "
    "eq. (2.9) would rebound up to 5 % higher, outside most of these ranges."
)
_ABOUT3 = (
    "For each ball of Table 1, the drop test at the beta pound-mc takes from Table 3 for its "
    "mass (the mean, interpolated between the balls) and Table 2's mid-range e; a least-squares "
    "fit of F = beta delta^1.5 to its restitution phase, as the experiment fitted its force "
    "histories, must recover a beta inside the ball's Table 3 range, as printed (tolerance 0)."
)

#: The seed's cases.
CASES = (
    Case("droptest-table2", "seed", _T2, table2, quick=True, about=_ABOUT2),
    Case(
        "droptest-table3",
        "seed",
        _T3,
        table3,
        quick=True,
        about=_ABOUT3 + " The quick set takes the middle ball of each material.",
    ),
)
