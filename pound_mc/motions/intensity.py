"""Intensity measures of a ground motion and the factor that scales a record to a target.

``pga_g``
    Peak ground acceleration ``max |a_g|`` [g].
``sa_g``
    Pseudo-spectral acceleration ``omega^2 max |u|`` of a linear oscillator of period ``T``
    and damping ratio ``zeta`` (5 % by default) [g], stepped exactly for ground acceleration
    linear between samples (:func:`pound_mc.physics.spectra.response_spectrum`).

Both are linear in the record, so the factor that brings a record to a target intensity is the
ratio of the target to the record's own value (:func:`scale_factor`); the study grid axes
``record.pga_g`` and ``record.sa_g`` (DESIGN.md section 9) scale every record this way.

Acceleration is in m/s^2 and intensities in g, with the standard gravity
:data:`pound_mc.motions.G`.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc.errors import InputError
from pound_mc.motions import G, record_arrays
from pound_mc.physics.spectra import response_spectrum

__all__ = ["checked_sa_period", "pga_g", "sa_g", "scale_factor"]


def _arrays(record) -> tuple[float, np.ndarray]:
    """``(dt, acc)`` of an :class:`obspy.Trace` or a ``(dt, acc)`` pair."""
    if hasattr(record, "stats") and hasattr(record, "data"):
        return record_arrays(record)
    try:
        dt, acc = record
    except (TypeError, ValueError):
        raise InputError(
            f"a record must be an obspy Trace or a (dt, acc) pair, got {type(record).__name__}",
            key="record",
        ) from None
    return float(dt), np.asarray(acc, dtype=np.float64)


def pga_g(record) -> float:
    """Peak ground acceleration [g].

    Parameters
    ----------
    record : obspy.Trace or tuple of (float, array_like)
        A trace in m/s^2 or a ``(dt, acc)`` pair: sampling interval [s] and acceleration
        [m/s^2].

    Returns
    -------
    float
        ``max |acc| / G`` [g].

    Raises
    ------
    InputError
        Empty or non-finite acceleration.
    """
    _dt, acc = _arrays(record)
    return _pga(acc)


def _pga(acc) -> float:
    acc = np.asarray(acc, dtype=np.float64)
    if acc.ndim != 1 or acc.size == 0 or not np.all(np.isfinite(acc)):
        raise InputError("acceleration must be a non-empty 1-D array of finite values", key="acc")
    return float(np.max(np.abs(acc))) / G


def sa_g(dt: float, acc, period_s, damping: float = 0.05):
    """Pseudo-spectral acceleration ``omega^2 max|u|`` [g].

    Parameters
    ----------
    dt : float
        Sampling interval [s].
    acc : array_like
        Ground acceleration [m/s^2], linear between samples; the oscillator starts at rest.
    period_s : float or array_like
        Oscillator period(s) [s], > 0.
    damping : float, default 0.05
        Viscous damping ratio [-].

    Returns
    -------
    float or numpy.ndarray
        Sa [g]: a float for a scalar period, else one value per period.

    Raises
    ------
    InputError
        As :func:`pound_mc.physics.spectra.response_spectrum`.
    """
    values = response_spectrum(dt, acc, period_s, damping) / G
    return float(values[0]) if np.ndim(period_s) == 0 else values


def _target(value, name: str, unit: str = "g") -> float:
    try:
        target = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a number > 0 [{unit}], got {value!r}", key=name) from None
    if not (math.isfinite(target) and target > 0):
        raise InputError(f"{name} must be > 0 [{unit}], got {value!r}", key=name)
    return target


def checked_sa_period(value, dt: float, acc, key: str = "record.sa_period_s") -> float:
    """The period [s] of an Sa target, checked: a number > 0, no longer than the record.

    At a period longer than the record the oscillator does not complete a cycle within it:
    its peak response there is no spectral ordinate, and a record scaled to it is multiplied
    by about ``T^2`` (``1e6`` s: a factor of ``1e12``, every simulation unstable).

    Raises
    ------
    InputError
        Naming ``key``.
    """
    period = _target(value, key, "s")
    duration = (np.size(acc) - 1) * dt
    if period > duration:
        raise InputError(
            f"sa_period_s = {period:g} s is longer than the record ({duration:g} s): the record "
            "does not define its Sa there",
            key=key,
        )
    return period


def scale_factor(
    dt: float,
    acc,
    *,
    pga_g: float | None = None,
    sa_g: float | None = None,
    sa_period_s: float | None = None,
    damping: float = 0.05,
) -> float:
    """Factor that scales a record to a target PGA or a target Sa.

    Give exactly one of ``pga_g`` and ``sa_g`` (the latter with ``sa_period_s``).

    Parameters
    ----------
    dt : float
        Sampling interval [s].
    acc : array_like
        Ground acceleration [m/s^2].
    pga_g : float, optional
        Target peak ground acceleration [g].
    sa_g : float, optional
        Target pseudo-spectral acceleration at ``sa_period_s`` [g].
    sa_period_s : float, optional
        Period of the Sa target [s]; required with ``sa_g``.
    damping : float, default 0.05
        Damping ratio of the Sa oscillator [-].

    Returns
    -------
    float
        ``target / own value``: ``factor * acc`` has the target intensity (both measures are
        linear in the record).

    Raises
    ------
    InputError
        Neither or both targets, a missing or needless ``sa_period_s``, an ``sa_period_s``
        longer than the record, a target <= 0, or a record whose own intensity is zero.
    """
    if (pga_g is None) == (sa_g is None):
        raise InputError("give exactly one of pga_g and sa_g (the target intensity)", key="record")
    if pga_g is not None:
        if sa_period_s is not None:
            raise InputError("sa_period_s applies to an sa_g target only", key="record.sa_period_s")
        target = _target(pga_g, "record.pga_g")
        own = _pga(acc)
        what = "PGA"
    else:
        target = _target(sa_g, "record.sa_g")
        if sa_period_s is None:
            raise InputError(
                "an sa_g target needs the oscillator period sa_period_s [s]",
                key="record.sa_period_s",
            )
        period = _target(sa_period_s, "record.sa_period_s", "s")
        own = float(response_spectrum(dt, acc, period, damping)[0]) / G
        what = f"Sa({period:g} s)"
    if not own > 0:
        raise InputError(f"the record's {what} is zero: it cannot be scaled to a target", key="acc")
    if sa_g is not None:
        checked_sa_period(sa_period_s, dt, acc)
    return target / own
