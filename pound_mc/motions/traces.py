"""Acceleration traces: the trace every record becomes, its units and its summaries.

Every record becomes an :class:`obspy.Trace` holding ground acceleration in m/s^2 (float64),
with what is known about it in ``trace.stats.pound`` (an :class:`obspy.core.util.AttribDict`):

``source``
    What the user asked for (a path, ``builtin:NAME`` or ``synthetic:MODEL``).
``file``
    The file read (absent for synthetic motions).
``format``
    ``"AT2"`` or the obspy format name (``"KNET"``, ``"KINEMETRICS_EVT"``, ``"MSEED"``, ...).
``event``, ``station``, ``component``
    Text from the file header where the format has it, else ``""``.
``source_units``
    Units of the values in the file (after the format's own calibration, see
    :mod:`pound_mc.motions.readers`).
``units``
    Always ``"m/s^2"``: the units of ``trace.data``.
``processing``
    What :func:`pound_mc.motions.preprocessing.preprocess` did, in order.
"""

from __future__ import annotations

import importlib
import math
import warnings
from typing import Any

import numpy as np

from pound_mc.errors import InputError

# obspy <= 1.5 enumerates its plugins through a deprecated importlib.metadata interface on
# import; that warning is about obspy's own code, so it is silenced while obspy is first loaded.
# The plain import statements below then bind the already loaded modules.
with warnings.catch_warnings():
    warnings.filterwarnings(
        "ignore", message="SelectableGroups dict interface", category=DeprecationWarning
    )
    importlib.import_module("obspy")

import obspy  # noqa: E402
from obspy.core.util import AttribDict  # noqa: E402

__all__ = ["G", "UNITS", "MAX_DT_S", "make_trace", "record_arrays", "record_info"]

#: Standard gravity [m/s^2] (CGPM 1901), used for every conversion from and to g.
G = 9.80665
#: Longest sampling interval accepted for an accelerogram [s].
MAX_DT_S = 1.0

#: Acceleration units a record may be in, as factors to m/s^2.
UNITS: dict[str, float] = {"g": G, "gal": 0.01, "m/s^2": 1.0}
_UNIT_ALIASES = {"cm/s^2": "gal", "cm/s/s": "gal", "m/s/s": "m/s^2", "m/s2": "m/s^2"}


# --------------------------------------------------------------------------- units


def _unit_name(units: str, *, file=None, key="record.units") -> str:
    """Canonical unit name for ``units`` or an :class:`InputError` listing the choices."""
    if not isinstance(units, str):
        raise InputError(
            f"units must be one of {', '.join(repr(u) for u in UNITS)}, got {units!r}",
            file=file,
            key=key,
        )
    name = units.strip()
    name = _UNIT_ALIASES.get(name.lower(), name)
    for canonical in UNITS:
        if name.lower() == canonical.lower():
            return canonical
    raise InputError(
        f"unknown units {units!r}; choose one of {', '.join(repr(u) for u in UNITS)}",
        file=file,
        key=key,
    )


# --------------------------------------------------------------------------- traces


def make_trace(data, dt_s: float, **meta: Any) -> obspy.Trace:
    """Build a trace of acceleration in m/s^2 with the ``stats.pound`` metadata.

    Parameters
    ----------
    data : array_like
        Acceleration samples [m/s^2].
    dt_s : float
        Sampling interval [s].
    **meta
        Entries for ``stats.pound`` (``source``, ``format``, ``event``, ``station``,
        ``component``, ``source_units``, ...).

    Returns
    -------
    obspy.Trace
    """
    pound = {
        "source": "",
        "format": "",
        "event": "",
        "station": "",
        "component": "",
        "source_units": "m/s^2",
        "units": "m/s^2",
        "processing": [],
    }
    pound.update(meta)
    trace = obspy.Trace(data=np.ascontiguousarray(data, dtype=np.float64))
    trace.stats.delta = float(dt_s)
    trace.stats.station = str(pound["station"])[:64]
    trace.stats.channel = str(pound["component"])[:64]
    trace.stats.pound = AttribDict(pound)
    return trace


def _where(trace: obspy.Trace) -> str | None:
    pound = trace.stats.get("pound", {})
    return pound.get("source") or pound.get("file") or None


def _check_samples(data: np.ndarray, dt: float, *, file, what: str = "record") -> None:
    """Reject empty records, bad sampling intervals and non-finite samples."""
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(f"sampling interval must be > 0 s, got dt = {dt!r}", file=file)
    if dt > MAX_DT_S:
        raise InputError(
            f"sampling interval dt = {dt:g} s is too long for an accelerogram "
            f"(at most {MAX_DT_S:g} s)",
            file=file,
        )
    if data.size == 0:
        raise InputError(f"the {what} holds no samples (empty record)", file=file)
    bad = np.flatnonzero(~np.isfinite(data))
    if bad.size:
        i = int(bad[0])
        raise InputError(
            f"{bad.size} non-finite sample(s) (NaN or infinite); first is sample {i} "
            f"(0-based index; t = {i * dt:g} s): {float(data[i])}",
            file=file,
        )


# --------------------------------------------------------------------------- views


def record_arrays(trace: obspy.Trace) -> tuple[float, np.ndarray]:
    """``(dt_s, acceleration)`` for the kernels.

    Returns
    -------
    dt_s : float
        Sampling interval [s].
    acceleration : numpy.ndarray
        Contiguous float64 samples [m/s^2].
    """
    return float(trace.stats.delta), np.ascontiguousarray(trace.data, dtype=np.float64)


def record_info(trace: obspy.Trace) -> dict[str, Any]:
    """Summary of a record, JSON-serialisable.

    Returns
    -------
    dict
        ``npts``, ``dt_s`` [s], ``duration_s`` [s] (``(npts - 1) * dt``), ``pga_g`` [g],
        ``pga_m_s2`` [m/s^2], ``units`` (of the data, ``"m/s^2"``), and where known
        ``source``, ``format``, ``event``, ``station``, ``component``, ``source_units``,
        ``processing``.
    """
    dt, data = record_arrays(trace)
    peak = float(np.max(np.abs(data))) if data.size else 0.0
    info: dict[str, Any] = {
        "npts": int(data.size),
        "dt_s": dt,
        "duration_s": (data.size - 1) * dt if data.size else 0.0,
        "pga_g": peak / G,
        "pga_m_s2": peak,
        "units": "m/s^2",
    }
    pound = trace.stats.get("pound", {})
    for key in ("source", "format", "event", "date", "station", "component", "source_units"):
        value = pound.get(key)
        if value not in (None, ""):
            info[key] = str(value)
    if pound.get("processing"):
        info["processing"] = list(pound["processing"])
    if pound.get("seed") is not None:
        info["seed"] = int(pound["seed"])
    return info
