"""Impact damping from the coefficient of restitution (and back).

Relations by name (:data:`RELATIONS`), for the Jankowski non-linear viscoelastic law unless
noted:

``jankowski2008``
    Jankowski (2008) eq. (2.9), ``xi = sqrt(5) (1 - e^2) / (2 pi e)``; the paper's relation and
    the default, so results compare with published ones.  Approximate: aimed at e = 0.65 the model
    really rebounds with about 0.685.
``jankowski2006``
    Jankowski (2006) EESD 35, ``xi = 9 sqrt(5) (1 - e^2) / (2 e (e (9 pi - 16) + 16))``.
``exact``
    The ``xi`` for which one free impact of the model really rebounds with ``e``.  In the
    dimensionless single impact ``u'' = -u^1.5 - 2 xi u^0.25 u'`` the restitution depends on
    ``xi`` alone, so one table (``data/restitution_exact.csv``, made by
    ``data/generate_exact_table.py``) inverted by monotone (PCHIP) interpolation is exact for
    every mass, stiffness and velocity.
``kelvin``
    The linear viscoelastic law (Anagnostopoulos 1992), ``xi = -ln e / sqrt(pi^2 + ln^2 e)``.

The Hertz-damp law takes a damping constant ``zeta`` [s/m] instead (:func:`hertzdamp_zeta`,
relations :data:`HERTZDAMP_RELATIONS`: ``ye2009``, the default, and ``muthukumar2006``), with
which one free impact rebounds with another restitution than the ``e`` it was given
(:func:`hertzdamp_restitution`: 0.630 and 0.775 for 0.65).
Which relations a law accepts is declared with the law
(:func:`pound_mc.physics.contact.allowed_relations`).
"""

from __future__ import annotations

import functools
import math
from importlib import resources

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator
from scipy.optimize import brentq

from pound_mc.errors import InputError

__all__ = [
    "RELATIONS",
    "HERTZDAMP_RELATIONS",
    "xi_from_e",
    "xi_jankowski2008",
    "xi_jankowski2006",
    "xi_exact",
    "xi_kelvin",
    "hertzdamp_zeta",
    "hertzdamp_restitution",
    "single_impact_restitution_hertzdamp",
    "effective_restitution",
    "restitution_of_xi",
    "single_impact_restitution",
    "exact_table",
    "largest_xi",
    "lowest_e",
]


def _check_e(e, name="e"):
    e = np.asarray(e, dtype=float)
    if not np.all(np.isfinite(e)) or np.any(e <= 0.0) or np.any(e > 1.0):
        raise InputError(
            f"coefficient of restitution must lie in (0, 1], got {e.tolist()}", key=name
        )
    return e


def _scalar_or_array(x):
    return float(x) if np.ndim(x) == 0 else x


def xi_jankowski2008(e):
    """Impact damping ratio from restitution, Jankowski (2008) eq. (2.9).

    ``xi = sqrt(5) (1 - e^2) / (2 pi e)``.

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-], in (0, 1].

    Returns
    -------
    float or ndarray
        Impact damping ratio ``xi`` [-].
    """
    e = _check_e(e)
    return _scalar_or_array(math.sqrt(5.0) * (1.0 - e**2) / (2.0 * math.pi * e))


def xi_jankowski2006(e):
    """Impact damping ratio from restitution, Jankowski (2006) EESD 35 p. 517.

    ``xi = 9 sqrt(5) (1 - e^2) / (2 e (e (9 pi - 16) + 16))``.

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-], in (0, 1].
    """
    e = _check_e(e)
    xi = 9.0 * math.sqrt(5.0) * (1.0 - e**2) / (2.0 * e * (e * (9.0 * math.pi - 16.0) + 16.0))
    return _scalar_or_array(xi)


def xi_kelvin(e):
    """Damping ratio of the linear viscoelastic law, Anagnostopoulos (1992).

    ``xi = -ln e / sqrt(pi^2 + ln^2 e)``; exact for the Kelvin-Voigt impact element.

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-], in (0, 1].
    """
    e = _check_e(e)
    ln = np.log(e)
    return _scalar_or_array(-ln / np.sqrt(math.pi**2 + ln**2))


def single_impact_restitution(xi: float, rtol: float = 1e-13) -> float:
    """Restitution one free impact of the Jankowski law really produces, for a given ``xi``.

    Integrates the dimensionless approach phase ``u'' = -u^1.5 - 2 xi u^0.25 u'`` from
    ``u = 0, u' = 1`` to maximum compression (``u' = 0``, located as an event) with DOP853.
    Restitution is elastic, so the rebound speed follows from energy:
    ``e = sqrt(4/5 u_max^2.5)`` (Jankowski 2008, eqs. 2.3-2.5 in dimensionless form).

    Parameters
    ----------
    xi : float
        Impact damping ratio [-], >= 0.
    rtol : float
        Relative tolerance of the integration.

    Returns
    -------
    float
        Coefficient of restitution [-].
    """
    if not (np.isfinite(xi) and xi >= 0.0):
        raise InputError(f"impact damping ratio must be finite and >= 0, got {xi}", key="xi")

    def rhs(_t, y):
        u = y[0] if y[0] > 0.0 else 0.0
        return [y[1], -(u**1.5) - 2.0 * xi * u**0.25 * y[1]]

    def max_compression(_t, y):
        return y[1]

    max_compression.terminal = True
    max_compression.direction = -1
    sol = solve_ivp(
        rhs,
        (0.0, 1e3),
        [0.0, 1.0],
        method="DOP853",
        rtol=rtol,
        atol=rtol * 1e-2,
        events=max_compression,
    )
    u_max = sol.y_events[0][0][0]
    return math.sqrt(0.8 * u_max**2.5)


@functools.cache
def exact_table() -> pd.DataFrame:
    """Return the shipped ``xi``-``e`` table of the ``exact`` relation (columns ``xi``, ``e``)."""
    path = resources.files("pound_mc") / "data" / "restitution_exact.csv"
    with resources.as_file(path) as p:
        table = pd.read_csv(p, comment="#")
    return table.sort_values("xi").reset_index(drop=True)


@functools.cache
def _exact_interpolants():
    table = exact_table()
    xi = table["xi"].to_numpy()
    e = table["e"].to_numpy()
    forward = PchipInterpolator(xi, e, extrapolate=False)  # e(xi), decreasing
    order = np.argsort(e)
    inverse = PchipInterpolator(e[order], xi[order], extrapolate=False)  # xi(e)
    return forward, inverse, float(e.min()), float(xi.max())


def xi_exact(e):
    """Impact damping ratio that makes one free impact rebound with exactly ``e``.

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-], within the table's range (about 0.008 to 1].
    """
    e = _check_e(e)
    _, inverse, e_min, _ = _exact_interpolants()
    if np.any(e < e_min):
        raise InputError(
            f"relation 'exact' is tabulated for e >= {e_min:.4g}, got {np.min(e):.4g}", key="e"
        )
    xi = np.where(e >= 1.0, 0.0, inverse(np.minimum(e, 1.0)))
    return _scalar_or_array(np.maximum(xi, 0.0))


def restitution_of_xi(xi: ArrayLike) -> float | np.ndarray:
    """Restitution the Jankowski law really produces for impact damping ratio ``xi``.

    Interpolated in the ``exact`` table (accurate to better than 1e-6); independent of mass,
    stiffness and impact velocity.

    Parameters
    ----------
    xi : float or array_like
        Impact damping ratio [-], >= 0.
    """
    xi = np.asarray(xi, dtype=float)
    forward, _, _, xi_max = _exact_interpolants()
    if not np.all(np.isfinite(xi)) or np.any(xi < 0.0) or np.any(xi > xi_max):
        raise InputError(f"impact damping ratio must lie in [0, {xi_max:.4g}]", key="xi")
    return _scalar_or_array(forward(xi))


def largest_xi() -> float:
    """Largest impact damping ratio of the ``exact`` table (71.17), the end of its e = 0.00785.

    The restitution the Jankowski law rebounds with (:func:`restitution_of_xi`) is known up to
    it; a larger ``xi`` is refused.
    """
    return _exact_interpolants()[3]


@functools.cache
def lowest_e(relation: str) -> float:
    """Smallest restitution ``relation`` takes for the Jankowski law (0 for ``kelvin``).

    Below it the relation's ``xi`` exceeds :func:`largest_xi` (``exact``: its table ends).
    """
    if relation == "kelvin":
        return 0.0
    if relation == "exact":
        return _exact_interpolants()[2]
    func = RELATIONS[relation]  # decreasing in e, 0 at e = 1
    return float(brentq(lambda e: float(func(e)) - largest_xi(), 1e-9, 1.0, xtol=1e-15))


#: xi-e relations for the Jankowski and Kelvin laws, by name.
RELATIONS = {
    "jankowski2008": xi_jankowski2008,
    "jankowski2006": xi_jankowski2006,
    "exact": xi_exact,
    "kelvin": xi_kelvin,
}


def xi_from_e(e: ArrayLike, relation: str = "jankowski2008") -> float | np.ndarray:
    """Impact damping ratio for a coefficient of restitution, by relation name.

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-], in (0, 1].
    relation : {"jankowski2008", "jankowski2006", "exact", "kelvin"}
        Which relation (see the module docstring).  ``kelvin`` is for the linear viscoelastic law.
    """
    try:
        func = RELATIONS[relation]
    except KeyError:
        raise InputError(
            f"unknown relation {relation!r}; choose one of {sorted(RELATIONS)}", key="relation"
        ) from None
    return func(e)


def effective_restitution(e: ArrayLike, relation: str = "jankowski2008") -> float | np.ndarray:
    """Restitution the Jankowski law really produces when ``xi`` comes from ``relation``.

    Parameters
    ----------
    e : float or array_like
        Target coefficient of restitution [-].
    relation : str
        One of :data:`RELATIONS` except ``kelvin`` (which belongs to another force law).
    """
    if relation == "kelvin":
        raise InputError("relation 'kelvin' belongs to the linear viscoelastic law", key="relation")
    return restitution_of_xi(xi_from_e(e, relation))


def _zeta_muthukumar2006(e, v0):
    """Muthukumar & DesRoches (2006): ``zeta = 3 (1 - e^2) / (4 v0)`` [s/m]."""
    return 3.0 * (1.0 - e**2) / (4.0 * v0)


def _zeta_ye2009(e, v0):
    """Ye, Li & Zhu (2009): ``zeta = 8 (1 - e) / (5 e v0)`` [s/m]."""
    return 8.0 * (1.0 - e) / (5.0 * e * v0)


#: Damping-constant relations of the Hertz-damp law, by name (the first is the default).  Each
#: is written once, for scalars and arrays alike; the compiled integrators call the same
#: functions with the impact velocity of each episode.
HERTZDAMP_RELATIONS = {"ye2009": _zeta_ye2009, "muthukumar2006": _zeta_muthukumar2006}


def hertzdamp_zeta(e: ArrayLike, v0: ArrayLike, relation: str = "ye2009") -> float | np.ndarray:
    """Damping constant ``zeta`` [s/m] of the Hertz-damp law for restitution ``e``.

    ``muthukumar2006``: ``zeta = 3 (1 - e^2) / (4 v0)`` (Muthukumar & DesRoches 2006);
    ``ye2009``: ``zeta = 8 (1 - e) / (5 e v0)`` (Ye, Li & Zhu 2009).

    Parameters
    ----------
    e : float or array_like
        Coefficient of restitution [-].
    v0 : float or array_like
        Impact velocity of the episode [m/s], > 0.
    relation : {"muthukumar2006", "ye2009"}
        Which relation.
    """
    e = _check_e(e)
    v0 = np.asarray(v0, dtype=float)
    if np.any(~(v0 > 0.0)):
        raise InputError("impact velocity must be > 0", key="v0")
    try:
        func = HERTZDAMP_RELATIONS[relation]
    except KeyError:
        raise InputError(
            f"unknown relation {relation!r}; choose one of {sorted(HERTZDAMP_RELATIONS)}",
            key="relation",
        ) from None
    return _scalar_or_array(func(e, v0))


def single_impact_restitution_hertzdamp(
    e: float, relation: str = "ye2009", rtol: float = 1e-13
) -> float:
    """Restitution one free impact of the Hertz-damp law really produces for target ``e``.

    With ``zeta = f(e) / v0`` (:data:`HERTZDAMP_RELATIONS`) and lengths in units of
    ``(m v0^2 / beta)^0.4``, times in that over ``v0``, the impact is
    ``u'' = -max(u^1.5 (1 + f(e) u'), 0)`` from ``u = 0, u' = 1``, whatever the mass,
    stiffness and velocity; integrated with DOP853 to separation (``u = 0`` again, located as an
    event), the restitution is ``-u'`` there.  The force is clipped at zero as the law's is, so
    the bodies may part before ``u`` returns to 0 (``muthukumar2006`` then rebounds with at
    least 0.66 whatever ``e``).

    Parameters
    ----------
    e : float
        Target coefficient of restitution [-], in (0, 1].
    relation : {"ye2009", "muthukumar2006"}
        Which relation gives ``zeta``.
    rtol : float
        Relative tolerance of the integration.
    """
    f = float(hertzdamp_zeta(e, 1.0, relation))

    def rhs(_t, y):
        u = y[0] if y[0] > 0.0 else 0.0
        return [y[1], -max(u**1.5 * (1.0 + f * y[1]), 0.0)]

    def separation(_t, y):
        return y[0]

    separation.terminal = True
    separation.direction = -1
    sol = solve_ivp(rhs, (0.0, 1e3), [0.0, 1.0], method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                    events=separation)  # fmt: skip
    return float(-sol.y_events[0][0][1])


@functools.cache
def _hertzdamp_interpolants() -> tuple:
    path = resources.files("pound_mc") / "data" / "restitution_hertzdamp.csv"
    with resources.as_file(path) as p:
        table = pd.read_csv(p, comment="#").sort_values("e")
    e = table["e"].to_numpy()
    return float(e[0]), {
        rel: PchipInterpolator(e, table[rel].to_numpy(), extrapolate=False)
        for rel in HERTZDAMP_RELATIONS
    }


def hertzdamp_restitution(e: ArrayLike, relation: str = "ye2009") -> float | np.ndarray:
    """Restitution the Hertz-damp law really rebounds with when ``zeta`` comes from target ``e``.

    Independent of mass, stiffness and impact velocity
    (:func:`single_impact_restitution_hertzdamp`); interpolated in the shipped table
    (``data/restitution_hertzdamp.csv``, made by ``data/generate_exact_table.py``), integrated
    directly below its smallest ``e`` (0.005).  NaN stays NaN.

    Parameters
    ----------
    e : float or array_like
        Target coefficient of restitution [-], in (0, 1].
    relation : {"ye2009", "muthukumar2006"}
        Which relation gives ``zeta``.
    """
    if relation not in HERTZDAMP_RELATIONS:
        raise InputError(
            f"unknown relation {relation!r}; choose one of {sorted(HERTZDAMP_RELATIONS)}",
            key="relation",
        )
    e = np.asarray(e, dtype=float)
    known = np.isfinite(e)
    _check_e(e[known])
    e_min, interpolants = _hertzdamp_interpolants()
    out = np.full(e.shape, np.nan)
    out[known] = interpolants[relation](e[known])
    low = known & (e < e_min)
    for value in np.unique(e[low]):
        out[e == value] = single_impact_restitution_hertzdamp(float(value), relation)
    return _scalar_or_array(out)
