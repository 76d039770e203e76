"""Classical separation-gap rules for two adjacent buildings.

Given the peak linear displacements ``u1`` and ``u2`` [m] of two adjacent buildings (relative to
the ground, each building analysed alone), the gap that design codes and the literature ask for
is one of

``ABS``
    absolute sum, ``|u1| + |u2|``: the buildings move out of phase at the same instant; an upper
    bound on the linear relative displacement, so no pounding can occur with a larger gap.
``SRSS``
    square root of the sum of squares, ``sqrt(u1^2 + u2^2)``: the two peaks statistically
    independent.
``DDC``
    double difference combination, ``sqrt(u1^2 + u2^2 - 2 rho u1 u2)`` (Jeng et al. 1992,
    Penzien 1997): the peak of the relative displacement of two linear oscillators under the
    same random excitation, with ``rho`` the cross-correlation of their responses, the CQC
    coefficient of Der Kiureghian (1981) for white-noise excitation,

    ``rho = 8 sqrt(z1 z2) (z1 + r z2) r^1.5 /
    ((1 - r^2)^2 + 4 z1 z2 r (1 + r^2) + 4 (z1^2 + z2^2) r^2)``,  ``r = T1 / T2 = omega2 /
    omega1``

    (Der Kiureghian 1981, eq. for ``rho_ij`` with ``r = omega_j / omega_i``; the same formula
    is Chopra 2012, eq. 13.7.10).  ``rho = 1`` for equal periods and equal damping (the
    buildings move in phase, DDC = ``|u1 - u2|``) and ``rho -> 0`` for well separated
    periods (DDC -> SRSS).  ``0 <= rho <= 1`` for positive damping, so DDC <= SRSS <= ABS.

:func:`required_gaps` computes the three from a record and two SDOF oscillators (the exact
linear response of :mod:`pound_mc.physics.spectra`);
:func:`pound_mc.analysis.gaps.study_gaps` does so for every simulation of a study (or of the
dataset it wrote), so that a chart of pounding probability against gap can mark the three rules.

References
----------
Der Kiureghian, A. (1981). A response spectrum method for random vibration analysis of MDF
systems. Earthq. Eng. Struct. Dyn. 9(5), 419-435.
Jeng, V., Kasai, K., Maison, B. F. (1992). A spectral difference method to estimate building
separations to avoid pounding. Earthq. Spectra 8(2), 201-223.
Penzien, J. (1997). Evaluation of building separation distance required to prevent pounding
during strong earthquakes. Earthq. Eng. Struct. Dyn. 26(8), 849-858.
Chopra, A. K. (2012). Dynamics of Structures, 4th ed. Prentice Hall, sec. 13.7.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pound_mc.errors import InputError
from pound_mc.physics.spectra import response_spectrum

__all__ = [
    "gap_abs",
    "gap_srss",
    "gap_ddc",
    "cqc_correlation",
    "SeparationGaps",
    "peak_displacements",
    "required_gaps",
    "gap_asce7",
    "gap_ec8",
]


def gap_abs(u1, u2):
    """Absolute-sum separation rule ``|u1| + |u2|``.

    Parameters
    ----------
    u1, u2 : float or array_like
        Peak displacements of the two buildings [m].

    Returns
    -------
    float or numpy.ndarray
        Required gap [m].
    """
    return np.abs(u1) + np.abs(u2)


def gap_srss(u1, u2):
    """Square-root-of-sum-of-squares separation rule ``sqrt(u1^2 + u2^2)``.

    Takes the peak displacements ``u1``, ``u2`` [m] and returns the required gap [m] as
    :func:`gap_abs` does.
    """
    return np.hypot(u1, u2)


def gap_asce7(u1, u2, *, r: float, cd: float, ie: float = 1.0):
    """Separation of ASCE/SEI 7-22 section 12.12.2 from two buildings' elastic displacements.

    Each building's maximum inelastic response displacement is ``delta_M = Cd delta_max / Ie``
    (section 12.12.2, the displacement of eq. 12.8-16 at the critical location), where
    ``delta_max``, the displacement of the elastic analysis under the design forces (reduced
    by the response modification coefficient ``R``), is here the building's elastic
    displacement ``u`` under the record over ``R``; adjacent structures on the same property
    are separated by at least ``delta_MT = sqrt(delta_M1^2 + delta_M2^2)`` (section
    12.12.2).

    Parameters
    ----------
    u1, u2 : array_like
        Peak elastic (linear, unreduced) displacements of the two buildings [m].
    r, cd, ie : float
        Response modification coefficient ``R``, deflection amplification factor ``Cd`` and
        importance factor ``Ie`` (ASCE 7-22 tables 12.2-1 and 1.5-2).
    """
    m1 = cd * np.asarray(u1, float) / (r * ie)
    m2 = cd * np.asarray(u2, float) / (r * ie)
    return np.hypot(m1, m2)


def gap_ec8(u1, u2, *, q: float, qd: float | None = None, same_levels: bool = False):
    """Separation of EN 1998-1:2004 section 4.4.2.7 from two buildings' elastic displacements.

    Each building's displacement is ``d_s = q_d d_e`` (expression 4.23), ``d_e`` that of the
    linear analysis under the design spectrum (reduced by the behaviour factor ``q``): here
    the elastic displacement ``u`` under the record over ``q``.  Buildings of the same
    property are separated by at least the SRSS of the two ``d_s`` (4.4.2.7(3)), reduced by
    the factor 0.7 where their floor elevations are the same (4.4.2.7(4)).

    Parameters
    ----------
    u1, u2 : array_like
        Peak elastic (linear, unreduced) displacements of the two buildings [m].
    q : float
        Behaviour factor of the design (EN 1998-1 sections 5 to 9).
    qd : float, optional
        Displacement behaviour factor (default ``q``, as 4.3.4(1) assumes).
    same_levels : bool
        Whether the two buildings' floors are at the same elevations (the 0.7 of 4.4.2.7(4)).
    """
    qd = q if qd is None else qd
    d1 = qd * np.asarray(u1, float) / q
    d2 = qd * np.asarray(u2, float) / q
    return (0.7 if same_levels else 1.0) * np.hypot(d1, d2)


def cqc_correlation(period1_s, period2_s, damping1=0.05, damping2=0.05):
    """Correlation of two linear oscillators' responses: the CQC coefficient.

    ``rho = 8 sqrt(z1 z2) (z1 + r z2) r^1.5 / ((1 - r^2)^2 + 4 z1 z2 r (1 + r^2)
    + 4 (z1^2 + z2^2) r^2)`` with ``r = T1 / T2`` (Der Kiureghian 1981; Chopra 2012,
    eq. 13.7.10, where ``r = omega_j / omega_i`` and ``i`` is building 1).

    Parameters
    ----------
    period1_s, period2_s : float or array_like
        Natural periods [s], > 0.
    damping1, damping2 : float or array_like
        Viscous damping ratios [-], > 0 (with zero damping ``rho`` is 0 unless ``r = 1``,
        where it is undefined).

    Returns
    -------
    float or numpy.ndarray
        ``rho`` [-], in ``[0, 1]``; 1 for equal periods and damping ratios.
    """
    t1 = np.asarray(period1_s, dtype=float)
    t2 = np.asarray(period2_s, dtype=float)
    z1 = np.asarray(damping1, dtype=float)
    z2 = np.asarray(damping2, dtype=float)
    if np.any(~(t1 > 0)) or np.any(~(t2 > 0)):
        raise InputError("periods must be > 0 s", key="period_s")
    if np.any(~(z1 > 0)) or np.any(~(z2 > 0)):
        raise InputError("damping ratios must be > 0", key="damping_ratio")
    r = t1 / t2
    num = 8.0 * np.sqrt(z1 * z2) * (z1 + r * z2) * r**1.5
    den = (1.0 - r**2) ** 2 + 4.0 * z1 * z2 * r * (1.0 + r**2) + 4.0 * (z1**2 + z2**2) * r**2
    rho = num / den
    return float(rho) if rho.ndim == 0 else rho


def gap_ddc(u1, u2, rho):
    """Double-difference-combination separation rule ``sqrt(u1^2 + u2^2 - 2 rho u1 u2)``.

    Parameters
    ----------
    u1, u2 : float or array_like
        Peak displacements of the two buildings [m] (magnitudes).
    rho : float or array_like
        Correlation of the two responses [-] (:func:`cqc_correlation`).

    Returns
    -------
    float or numpy.ndarray
        Required gap [m] (Jeng et al. 1992; Penzien 1997).
    """
    a, b = np.abs(u1), np.abs(u2)
    with np.errstate(invalid="ignore"):  # NaN or infinite peaks in, NaN out (inf - inf)
        return np.sqrt(np.maximum(a**2 + b**2 - 2.0 * np.asarray(rho) * a * b, 0.0))


@dataclass(frozen=True)
class SeparationGaps:
    """Peak linear displacements of two buildings and the gaps the three rules require.

    Attributes
    ----------
    u1, u2 : float
        Peak linear displacements of building 1 (left) and 2 (right) [m].
    rho : float
        CQC correlation of their responses [-].
    abs, srss, ddc : float
        Required gaps [m] by the ABS, SRSS and DDC rules.
    """

    u1: float
    u2: float
    rho: float
    abs: float
    srss: float
    ddc: float


def _fine(dt: float, acc: np.ndarray, substeps: int) -> tuple[float, np.ndarray]:
    """The record linearly interpolated at ``substeps`` points per interval (same excitation)."""
    if substeps == 1:
        return dt, acc
    t = np.arange(acc.size) * dt
    fine_t = np.linspace(0.0, t[-1], (acc.size - 1) * substeps + 1)
    return dt / substeps, np.interp(fine_t, t, acc)


def peak_displacements(dt, acc, periods, damping=0.05, *, substeps: int = 8) -> np.ndarray:
    """Peak linear displacements ``max |u(t)|`` of SDOF oscillators starting at rest.

    The excitation is ``acc`` linearly interpolated (as in the engine, DESIGN.md section 2); the
    oscillators are stepped exactly (:func:`pound_mc.physics.spectra.response_spectrum`) at
    ``substeps`` points per sample interval, so the maximum between samples is caught to a
    relative error of about ``(pi dt / (substeps T))^2 / 2``.

    Parameters
    ----------
    dt : float
        Sampling interval of ``acc`` [s].
    acc : array_like
        Ground acceleration [m/s^2].
    periods : array_like
        Natural periods [s], > 0.
    damping : float, default 0.05
        Viscous damping ratio [-], >= 0.
    substeps : int, default 8
        Evaluation points per sample interval (>= 1).

    Returns
    -------
    numpy.ndarray
        Peak displacement [m] relative to the ground, one per period.
    """
    if not (isinstance(substeps, int) and substeps >= 1):
        raise InputError(f"substeps must be an integer >= 1, got {substeps!r}", key="substeps")
    acc = np.asarray(acc, dtype=float)
    periods = np.atleast_1d(np.asarray(periods, dtype=float))
    fdt, facc = _fine(float(dt), acc, substeps)
    omega = 2.0 * math.pi / periods
    return response_spectrum(fdt, facc, periods, damping) / omega**2


def required_gaps(
    dt,
    acc,
    period1_s: float,
    period2_s: float,
    damping1: float = 0.05,
    damping2: float = 0.05,
    *,
    substeps: int = 8,
) -> SeparationGaps:
    """Peak linear displacements of two SDOF buildings under a record, and the required gaps.

    Parameters
    ----------
    dt : float
        Sampling interval of ``acc`` [s].
    acc : array_like
        Ground acceleration [m/s^2] (e.g. from :func:`pound_mc.motions.record_arrays`).
    period1_s, period2_s : float
        Natural periods of building 1 (left) and 2 (right) [s].
    damping1, damping2 : float, default 0.05
        Their viscous damping ratios [-].
    substeps : int, default 8
        Evaluation points per sample interval (:func:`peak_displacements`).

    Returns
    -------
    SeparationGaps
        ``u1``, ``u2`` [m] (elastic spectral displacements), ``rho`` [-] and the ABS, SRSS and
        DDC gaps [m].
    """
    u1 = float(peak_displacements(dt, acc, [period1_s], damping1, substeps=substeps)[0])
    u2 = float(peak_displacements(dt, acc, [period2_s], damping2, substeps=substeps)[0])
    rho = float(cqc_correlation(period1_s, period2_s, damping1, damping2))
    return SeparationGaps(
        u1=u1,
        u2=u2,
        rho=rho,
        abs=float(gap_abs(u1, u2)),
        srss=float(gap_srss(u1, u2)),
        ddc=float(gap_ddc(u1, u2, rho)),
    )
