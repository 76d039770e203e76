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
    :mod:`pound_mc.motions.readers`): a key of :data:`UNITS`.
``source_units_from``
    Where ``source_units`` came from (see :data:`UNITS_FROM`): ``"header"`` (the file's
    header names them), ``"units"`` (the ``units`` key, ``--units``), ``"default"`` (an AT2
    header that names none: g, the PEER convention) or ``"format"`` (the format's own units).
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

__all__ = [
    "G",
    "UNITS",
    "UNIT_SPELLINGS",
    "UNITS_TEXT",
    "UNITS_FROM",
    "UNITS_CHOICES",
    "MAX_DT_S",
    "make_trace",
    "record_arrays",
    "record_info",
    "unit_spelling",
]

#: Standard gravity [m/s^2] (CGPM 1901), used for every conversion from and to g.
G = 9.80665
#: Longest sampling interval accepted for an accelerogram [s].
MAX_DT_S = 1.0

#: Acceleration units a record may be in (canonical names), as factors to m/s^2.
UNITS: dict[str, float] = {
    # factors as NIST SP 811 (2008), appendix B.9, "acceleration", gives them (all exact)
    "g": G,  # standard acceleration of gravity g_n, 9.80665 m/s^2
    "gal": 0.01,  # 1 Gal = 1 cm/s^2
    "m/s^2": 1.0,
    "mm/s^2": 1.0e-3,
    "in/s^2": 0.0254,  # 1 in = 0.0254 m (B.8, inch)
    "ft/s^2": 0.3048,  # 1 ft = 0.3048 m (B.8, foot)
    "kilogal": 10.0,  # 1 kGal = 1000 Gal
}

# The ways of writing "per second squared" after a length: "/s^2", "/sec/sec", ...
_PER_S2 = ("/s^2", "/s2", "/s**2", "/s\u00b2", "/s/s", "/sec^2", "/sec2", "/sec**2",
           "/sec\u00b2", "/sec/sec")  # fmt: skip
# Length before "per second squared" -> canonical unit.
_LENGTHS = {"m": "m/s^2", "cm": "gal", "mm": "mm/s^2", "in": "in/s^2", "ft": "ft/s^2"}
# Units written as one name.
_NAMES = {"g": "g", "gal": "gal", "gals": "gal", "kilogal": "kilogal", "kilogals": "kilogal",
          "kgal": "kilogal", "kgals": "kilogal"}  # fmt: skip

#: Every accepted spelling of an acceleration unit -> its canonical name in :data:`UNITS`.
#: Spellings are lower case without spaces (:func:`unit_spelling` reduces any text to that
#: form); the one table behind the ``units`` key and the units an AT2 header names.
UNIT_SPELLINGS: dict[str, str] = {
    **_NAMES,
    **{length + per: unit for length, unit in _LENGTHS.items() for per in _PER_S2},
}

#: Where a record's ``source_units`` came from -> the words that say so.
UNITS_FROM: dict[str, str] = {
    "header": "named by the file's header",
    "units": "given by the units key",
    "default": "the PEER default: the AT2 header names no units, so g",
    "format": "the format's own units",
}

#: The accepted units as one sentence (the ``units`` key's reference and its errors).
UNITS_TEXT = (
    ", ".join(f"`{u}`" for u in UNITS)
    + " (`gal` is `cm/s^2`; any case, spaces ignored; `/s^2` may also be written "
    + ", ".join(f"`{per}`" for per in _PER_S2[1:])
    + "; `kgal` for `kilogal`)"
)
#: The same for an error message.
UNITS_CHOICES = (
    f"choose one of {', '.join(repr(u) for u in UNITS)} (also spelt 'cm/s^2', 'mm/s/s', "
    "'in/sec^2', 'ft/sec/sec', 'kgal', ...)"
)


# --------------------------------------------------------------------------- units


def unit_spelling(text: str) -> str:
    """``text`` in the form of :data:`UNIT_SPELLINGS`' keys: lower case, no white space."""
    return "".join(text.split()).lower()


def _unit_name(units: str, *, file=None, key="record.units") -> str:
    """Canonical unit name for ``units`` or an :class:`InputError` listing the choices."""
    if isinstance(units, str) and unit_spelling(units) in UNIT_SPELLINGS:
        return UNIT_SPELLINGS[unit_spelling(units)]
    problem = (
        f"unknown units {units!r}"
        if isinstance(units, str)
        else f"units must be a string, got {units!r}"
    )
    raise InputError(f"{problem}; {UNITS_CHOICES}", file=file, key=key)


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
        ``source_units_from`` (a key of :data:`UNITS_FROM`), ``processing``.
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
    keys = ("source", "format", "event", "date", "station", "component", "source_units",
            "source_units_from")  # fmt: skip
    for key in keys:
        value = pound.get(key)
        if value not in (None, ""):
            info[key] = str(value)
    if pound.get("processing"):
        info["processing"] = list(pound["processing"])
    if pound.get("seed") is not None:
        info["seed"] = int(pound["seed"])
    return info
