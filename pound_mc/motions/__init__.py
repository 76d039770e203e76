"""Ground motions: acceleration traces, readers, preprocessing, the catalogue, synthetic motions.

Modules, lowest first (each imports only those above it):

:mod:`~pound_mc.motions.traces`
    The trace every record becomes (acceleration in m/s^2, metadata in ``stats.pound``), units,
    :func:`record_arrays` and :func:`record_info`.
:mod:`~pound_mc.motions.readers`
    PEER NGA ``AT2`` and the formats obspy reads: :func:`read_record`, :func:`read_at2`.
:mod:`~pound_mc.motions.preprocessing`
    :func:`preprocess`: demean, filter, resample, truncate, scale.
:mod:`~pound_mc.motions.synthetic`
    Clough-Penzien stochastic motions.
:mod:`~pound_mc.motions.catalogue`
    The built-in records and :func:`load_record` (a path, ``builtin:NAME`` or
    ``synthetic:MODEL``).
"""

from __future__ import annotations

from pound_mc.motions.catalogue import BUILTIN_RECORDS, builtin_catalogue, load_record
from pound_mc.motions.preprocessing import preprocess
from pound_mc.motions.readers import FORMAT_UNITS, read_at2, read_record
from pound_mc.motions.synthetic import SYNTHETIC_MODELS
from pound_mc.motions.traces import (
    MAX_DT_S,
    UNIT_SPELLINGS,
    UNITS,
    UNITS_FROM,
    UNITS_TEXT,
    G,
    make_trace,
    record_arrays,
    record_info,
)

__all__ = [
    "G",
    "UNITS",
    "UNIT_SPELLINGS",
    "UNITS_FROM",
    "UNITS_TEXT",
    "MAX_DT_S",
    "FORMAT_UNITS",
    "BUILTIN_RECORDS",
    "SYNTHETIC_MODELS",
    "read_record",
    "read_at2",
    "preprocess",
    "load_record",
    "record_arrays",
    "record_info",
    "builtin_catalogue",
    "make_trace",
]
