"""Measured impact parameters of building materials: the seed paper's Tables 1-3.

The tables live in one package CSV (``data/jankowski2008_tables.csv``, a ``table`` column
names the table) and are read with pandas:

* Table 1 - balls used in the drop experiment (grade, diameter [mm], mass [kg], count);
* Table 2 - coefficient of restitution ``e`` [-] against prior-impact velocity [m/s];
* Table 3 - impact stiffness parameter ``beta`` [N/m^1.5] against ball mass [kg].

Between tabulated velocities (Table 2) or ball masses (Table 3, at the middle of each mass
range) the bounds are linearly interpolated.  Outside the measured range the policy is
``outside="clamp"`` (default: the nearest measured range is held constant, e.g. building
masses of 1e6 kg get the heaviest ball's range) or ``outside="raise"`` (an
:class:`~pound_mc.errors.InputError`).  Steel was not tested above 2 m/s (Jankowski 2008, sec. 3).
"""

from __future__ import annotations

import functools
from importlib import resources

import numpy as np
import pandas as pd

from pound_mc.errors import InputError

__all__ = [
    "MATERIALS",
    "seed_tables",
    "table",
    "restitution_range",
    "stiffness_range",
    "material_ranges",
    "PER_IMPACT_OUTSIDE",
    "restitution_rows",
    "restitution_at",
]

#: Materials of the seed's experiment, in the paper's order.
MATERIALS = ("steel", "concrete", "timber", "ceramics")

_OUTSIDE_POLICIES = ("clamp", "raise")


@functools.cache
def _tables() -> pd.DataFrame:
    path = resources.files("pound_mc") / "data" / "jankowski2008_tables.csv"
    with resources.as_file(path) as p:
        return pd.read_csv(p, comment="#", dtype={"grade": str, "material": str})


def seed_tables() -> pd.DataFrame:
    """All three tables in one long frame (a copy; column ``table`` is 1, 2 or 3)."""
    return _tables().copy()


_TABLE_COLUMNS = {
    1: ["material", "grade", "ball_diameter_mm", "mass_min_kg", "mass_max_kg", "balls_tested"],
    2: ["material", "velocity_m_s", "e_min", "e_max"],
    3: ["material", "mass_min_kg", "mass_max_kg", "beta_min", "beta_max", "beta_mean"],
}


def table(number: int) -> pd.DataFrame:
    """One of the seed's tables (1, 2 or 3) with only the columns that apply to it.

    Parameters
    ----------
    number : {1, 2, 3}
        Table number in Jankowski (2008).
    """
    if number not in _TABLE_COLUMNS:
        raise InputError(f"the seed paper has tables 1, 2 and 3, not {number!r}", key="table")
    frame = _tables()
    out = frame.loc[frame["table"] == number, _TABLE_COLUMNS[number]].reset_index(drop=True)
    if number == 1:
        out["balls_tested"] = out["balls_tested"].astype(int)
        out["ball_diameter_mm"] = out["ball_diameter_mm"].astype(int)
    return out


def _check_material(material: str) -> str:
    if material not in MATERIALS:
        raise InputError(
            f"unknown material {material!r}; choose one of {list(MATERIALS)}", key="material"
        )
    return material


def _interp_rows(x, xs, columns, outside, what, unit, key):
    if outside not in _OUTSIDE_POLICIES:
        raise InputError(
            f"unknown policy {outside!r}; choose one of {list(_OUTSIDE_POLICIES)}", key="outside"
        )
    x = float(x)
    if not np.isfinite(x) or x <= 0.0:
        raise InputError(f"{what} must be finite and > 0 {unit}, got {x}", key=key)
    if outside == "raise" and not (xs[0] <= x <= xs[-1]):
        raise InputError(
            f"{what} {x} {unit} is outside the measured range {xs[0]}-{xs[-1]} {unit}", key=key
        )
    # np.interp holds the end values constant outside the table: the 'clamp' policy.
    return tuple(float(np.interp(x, xs, col)) for col in columns)


def restitution_range(
    material: str, velocity_m_s: float, *, outside: str = "clamp"
) -> tuple[float, float]:
    """Measured range of the coefficient of restitution at a prior-impact velocity.

    Jankowski (2008), Table 2; linear interpolation between the tabulated velocities.

    Parameters
    ----------
    material : {"steel", "concrete", "timber", "ceramics"}
        Material of both colliding bodies.
    velocity_m_s : float
        Prior-impact relative velocity [m/s].
    outside : {"clamp", "raise"}
        Policy outside the tabulated velocities (see the module docstring).

    Returns
    -------
    tuple of float
        ``(e_min, e_max)`` [-].
    """
    t2 = table(2)
    rows = t2[t2["material"] == _check_material(material)].sort_values("velocity_m_s")
    return _interp_rows(
        velocity_m_s,
        rows["velocity_m_s"].to_numpy(),
        (rows["e_min"].to_numpy(), rows["e_max"].to_numpy()),
        outside,
        "impact velocity",
        "m/s",
        "velocity_m_s",
    )


def stiffness_range(
    material: str, mass_kg: float, *, outside: str = "clamp"
) -> tuple[float, float, float]:
    """Measured range of the impact stiffness parameter for a colliding mass.

    Jankowski (2008), Table 3; linear interpolation between the middles of the ball-mass ranges.

    Parameters
    ----------
    material : {"steel", "concrete", "timber", "ceramics"}
        Material of both colliding bodies.
    mass_kg : float
        Mass of the impacting body [kg].
    outside : {"clamp", "raise"}
        Policy outside the tested ball masses (see the module docstring).

    Returns
    -------
    tuple of float
        ``(beta_min, beta_max, beta_mean)`` [N/m^1.5].
    """
    t3 = table(3)
    rows = t3[t3["material"] == _check_material(material)]
    mid = 0.5 * (rows["mass_min_kg"].to_numpy() + rows["mass_max_kg"].to_numpy())
    order = np.argsort(mid)
    columns = tuple(rows[c].to_numpy()[order] for c in ("beta_min", "beta_max", "beta_mean"))
    return _interp_rows(mass_kg, mid[order], columns, outside, "mass", "kg", "mass_kg")


def material_ranges(material: str) -> dict[str, tuple[float, float]]:
    """Whole measured ranges of ``e`` (Table 2, all velocities) and ``beta`` (Table 3, all masses).

    These are the default sampling ranges of a study's ``{ material = NAME }`` variables.

    Parameters
    ----------
    material : {"steel", "concrete", "timber", "ceramics"}
        Material name.

    Returns
    -------
    dict
        ``{"e": (e_min, e_max), "beta": (beta_min, beta_max)}``.
    """
    _check_material(material)
    t2, t3 = table(2), table(3)
    r2 = t2[t2["material"] == material]
    r3 = t3[t3["material"] == material]
    return {
        "e": (float(r2["e_min"].min()), float(r2["e_max"].max())),
        "beta": (float(r3["beta_min"].min()), float(r3["beta_max"].max())),
    }


#: Policies outside Table 2's velocities for restitution set per impact: ``clamp`` (the nearest
#: measured range held constant, as :func:`restitution_range`) or ``extrapolate`` (the end
#: segments continued linearly, ``e`` kept within ``[E_FLOOR, 1]``).
PER_IMPACT_OUTSIDE = ("clamp", "extrapolate")
#: Lowest restitution an extrapolated range may reach [-].
E_FLOOR = 0.05


def restitution_rows(material: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Table 2 rows of one material: velocities [m/s], ``e_min`` and ``e_max`` [-], by velocity.

    Writable copies: pandas' copy-on-write hands out read-only views, a different numba type
    from the kernels' other arrays, which compiled every kernel a second time for per-impact
    restitution.
    """
    t2 = table(2)
    rows = t2[t2["material"] == _check_material(material)].sort_values("velocity_m_s")
    return tuple(
        rows[c].to_numpy(dtype=float, copy=True) for c in ("velocity_m_s", "e_min", "e_max")
    )


def restitution_at(material: str, velocity_m_s, quantile, *, outside: str = "clamp"):
    """Restitution at quantile ``quantile`` of the measured range at a prior-impact velocity.

    ``e = e_min(v) + Q (e_max(v) - e_min(v))``, Table 2 linear in velocity between its rows;
    outside them by ``outside`` (:data:`PER_IMPACT_OUTSIDE`).  Arrays broadcast.

    Parameters
    ----------
    material : {"steel", "concrete", "timber", "ceramics"}
        Material of both colliding bodies.
    velocity_m_s : float or array_like
        Prior-impact relative velocity [m/s].
    quantile : float or array_like
        Quantile ``Q`` of the measured range [-], in [0, 1].
    outside : {"clamp", "extrapolate"}
        Policy outside the tabulated velocities.

    Returns
    -------
    float or numpy.ndarray
        Coefficient of restitution [-].
    """
    if outside not in PER_IMPACT_OUTSIDE:
        raise InputError(
            f"unknown policy {outside!r}; choose one of {list(PER_IMPACT_OUTSIDE)}", key="outside"
        )
    v, lo, hi = restitution_rows(material)
    x, q = np.broadcast_arrays(
        np.asarray(velocity_m_s, dtype=float), np.asarray(quantile, dtype=float)
    )
    shape = x.shape
    x, q = x.ravel(), q.ravel()
    e_lo = np.interp(x, v, lo)
    e_hi = np.interp(x, v, hi)
    if outside == "extrapolate":
        for end, (a, b) in (("low", (0, 1)), ("high", (-2, -1))):
            sel = x < v[0] if end == "low" else x > v[-1]
            for arr, col in ((e_lo, lo), (e_hi, hi)):
                slope = (col[b] - col[a]) / (v[b] - v[a])
                ref = 0 if end == "low" else -1
                arr[...] = np.where(sel, col[ref] + slope * (x - v[ref]), arr)
        e_lo = np.clip(e_lo, E_FLOOR, 1.0)
        e_hi = np.clip(e_hi, E_FLOOR, 1.0)
    e = (e_lo + q * (e_hi - e_lo)).reshape(shape)
    return float(e) if e.ndim == 0 else e
