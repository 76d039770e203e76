"""Linear elastic response spectra of a ground motion.

The single-degree-of-freedom oscillator ``u'' + 2 zeta omega u' + omega^2 u = -a_g(t)`` is
stepped exactly for ground acceleration that is linear between samples (the excitation the
engine uses, DESIGN.md section 2): the recurrence of Nigam & Jennings (1969), here obtained as
the matrix exponential of the oscillator augmented with the excitation and its slope, so one
formula serves every damping ratio (including 0 and >= 1).  All periods advance together, one
vectorised step per sample.

References
----------
Nigam, N. C., Jennings, P. C. (1969). Calculation of response spectra from strong-motion
earthquake records. Bull. Seismol. Soc. Am. 59(2), 909-922.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm

from pound_mc._jit import jit
from pound_mc.errors import InputError

__all__ = ["response_spectrum", "sdof_transition"]


def sdof_transition(dt: float, periods, damping: float = 0.05) -> np.ndarray:
    """Exact one-step maps of linear SDOF oscillators under piecewise-linear excitation.

    Parameters
    ----------
    dt : float
        Step [s].
    periods : array_like
        Natural periods [s], > 0.
    damping : float, default 0.05
        Viscous damping ratio [-], >= 0.

    Returns
    -------
    numpy.ndarray, shape (len(periods), 2, 4)
        ``[u, v]_{n+1} = M[:, :2] @ [u, v]_n + M[:, 2] a_n + M[:, 3] (a_{n+1} - a_n) / dt`` for
        ground acceleration ``a`` [m/s^2], relative displacement ``u`` [m] and velocity
        ``v`` [m/s].
    """
    omega = 2.0 * np.pi / np.asarray(periods, dtype=np.float64)
    system = np.zeros((omega.size, 4, 4))
    system[:, 0, 1] = 1.0
    system[:, 1, 0] = -(omega**2)
    system[:, 1, 1] = -2.0 * damping * omega
    system[:, 1, 2] = -1.0  # forcing -a_g
    system[:, 2, 3] = 1.0  # a_g grows with constant slope over the step
    return expm(system * dt)[:, :2, :]


@jit
def _peak_displacements(m, acc, slopes):  # pragma: no cover - compiled
    """``max |u|`` per period: the exact piecewise-linear recurrence, sample by sample.

    ``m[k]`` holds rows ``u`` and ``v`` of period ``k``'s transition matrix
    (:func:`sdof_transition`); the sums are taken in the order of the matrix product, so the
    result is the same as the NumPy form of the recurrence.
    """
    n_periods = m.shape[0]
    peak = np.zeros(n_periods)
    for k in range(n_periods):
        a_uu, a_uv, a_ua, a_us = m[k, 0, 0], m[k, 0, 1], m[k, 0, 2], m[k, 0, 3]
        a_vu, a_vv, a_va, a_vs = m[k, 1, 0], m[k, 1, 1], m[k, 1, 2], m[k, 1, 3]
        u = 0.0
        v = 0.0
        top = 0.0
        for i in range(slopes.size):
            a_n = acc[i]
            s_n = slopes[i]
            u, v = (
                a_uu * u + a_uv * v + a_ua * a_n + a_us * s_n,
                a_vu * u + a_vv * v + a_va * a_n + a_vs * s_n,
            )
            top = max(top, abs(u))
        peak[k] = top
    return peak


def response_spectrum(dt: float, acc, periods, damping: float = 0.05) -> np.ndarray:
    """Pseudo-acceleration response spectrum ``omega^2 max|u|``.

    Parameters
    ----------
    dt : float
        Sampling interval of ``acc`` [s].
    acc : array_like
        Ground acceleration [m/s^2], linear between samples; the oscillators start at rest.
    periods : array_like
        Natural periods [s], > 0.
    damping : float, default 0.05
        Viscous damping ratio [-].

    Returns
    -------
    numpy.ndarray
        Pseudo-acceleration [m/s^2] for each period (same units as ``acc``).

    Raises
    ------
    InputError
        Non-positive ``dt`` or periods, negative damping, empty or non-finite ``acc``.
    """
    acc = np.asarray(acc, dtype=np.float64)
    periods = np.atleast_1d(np.asarray(periods, dtype=np.float64))
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"dt must be > 0 s, got {dt!r}", key="dt")
    if periods.size == 0 or not np.all(np.isfinite(periods) & (periods > 0)):
        raise InputError("periods must be finite and > 0 s", key="periods")
    if not (math.isfinite(damping) and damping >= 0):
        raise InputError(f"damping must be >= 0, got {damping!r}", key="damping")
    if acc.ndim != 1 or acc.size == 0 or not np.all(np.isfinite(acc)):
        raise InputError("acceleration must be a non-empty 1-D array of finite values", key="acc")
    m = sdof_transition(dt, periods, damping)
    slopes = np.diff(acc) / dt
    peak = _peak_displacements(np.ascontiguousarray(m[:, :2, :]), acc, slopes)
    omega = 2.0 * np.pi / periods
    return omega**2 * peak
