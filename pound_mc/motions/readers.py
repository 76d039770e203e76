"""Reading accelerograms: PEER NGA ``AT2`` and every format obspy reads.

Formats and units
-----------------
* PEER NGA ``AT2`` (our reader, :func:`read_at2`): units from the header's third line
  (``UNITS OF G`` is the PEER convention and the default).
* ``KNET`` (K-NET/KiK-net ASCII): obspy returns the raw integer counts and puts the header's
  scale factor, converted from gal to m/s^2, in ``stats.calib``; we multiply by it, so the values
  are in m/s^2.
* ``KINEMETRICS_EVT``: obspy returns raw counts with ``stats.calib = fullscale * 9.81 /
  (2**23 * sensitivity)`` [m/s^2 per count], i.e. with g = 9.81 m/s^2.  We multiply by ``calib``
  and by 9.80665/9.81, so the values are (volts / sensitivity) [g] times the standard gravity
  :data:`G` that the rest of the package uses.
* Any other format obspy reads (MiniSEED, SAC, GSE2, SEISAN, ...) carries no reliable
  acceleration units: the data are taken as stored and ``units`` must be given.

``units`` (``"g" | "gal" | "m/s^2"``) overrides the format's default; it names the units of the
values after the format's calibration step above.
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
    UNITS,
    G,
    _check_samples,
    _unit_name,
    make_trace,
    obspy,
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

# Third header line: what the series is and in which units.
_AT2_UNITS = (
    (re.compile(r"\bUNITS\s+OF\s+G\b|\bIN\s+G\b", re.I), "g"),
    (re.compile(r"CM\s*/\s*S(EC)?\s*(/\s*S(EC)?|\^?2|\*\*2)|\bGALS?\b", re.I), "gal"),
    (re.compile(r"\bM\s*/\s*S(EC)?\s*(/\s*S(EC)?|\^?2|\*\*2)", re.I), "m/s^2"),
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


def _read_at2_values(path: Path) -> tuple[np.ndarray, float, dict[str, Any]]:
    """Samples (in the file's units), dt and header metadata of a PEER AT2 file."""
    try:
        text = path.read_text(encoding="latin-1")
    except OSError as exc:
        raise InputError(f"cannot read the file: {exc.strerror or exc}", file=path) from None
    lines = text.splitlines()
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
    source_units = "g"
    for pattern, name in _AT2_UNITS:
        if pattern.search(description):
            source_units = name
            break
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
    return values, dt, meta


def read_at2(path: str | os.PathLike) -> obspy.Trace:
    """Read a PEER NGA ``AT2`` acceleration file.

    The first three lines are text (title; ``EVENT, DATE, STATION, COMPONENT``; the series
    description with its units), the fourth gives the sample count and step in either form
    ``NPTS=  5372, DT=   .0100 SEC`` or ``5372   0.0100   NPTS, DT``; the samples follow, any
    number per line.

    Parameters
    ----------
    path : str or os.PathLike
        The AT2 file.

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2], not preprocessed; header text in ``stats.pound``.

    Raises
    ------
    InputError
        Missing file, malformed header, sample count different from NPTS, non-numeric or
        non-finite samples, dt <= 0, empty record.
    """
    path = _existing_file(path)
    values, dt, meta = _read_at2_values(path)
    factor = UNITS[meta["source_units"]]
    return make_trace(values * factor, dt, source=str(path), file=str(path), format="AT2", **meta)


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


# (name, detector, reader) tried in order; readers return traces in the file's units.
_READERS: list[tuple[str, Callable[[Path], bool], Callable[[Path], list[obspy.Trace]]]] = [
    ("AT2", _looks_like_at2, _read_at2_traces),
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
    :func:`read_at2`'s parser, everything else through :func:`obspy.read` (MiniSEED, SAC, K-NET,
    Kinemetrics EVT, GSE2, ...).

    Parameters
    ----------
    path : str or os.PathLike
        The record file.
    units : {"g", "gal", "m/s^2"}, optional
        Units of the values in the file (after the format's calibration); default per format,
        see :data:`FORMAT_UNITS`.  Required for formats without units.
    component : str, optional
        Which trace of a multi-trace file (its channel, e.g. ``"EW"`` or ``"0"``, or its
        SEED id); for a single-trace file, checked against it when given.

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2] with metadata in ``stats.pound``.

    Raises
    ------
    InputError
        Missing or unreadable file, unknown format, bad samples, bad units, missing or
        ambiguous component.
    """
    path = _existing_file(path)
    for _name, detect, reader in _READERS:
        if detect(path):
            traces = reader(path)
            break
    else:  # pragma: no cover - the last reader accepts everything
        raise InputError("unknown format", file=path)
    trace = _select_component(traces, component, file=path)
    pound = trace.stats.pound
    _check_samples(trace.data, trace.stats.delta, file=path)
    if units is not None:
        source_units = _unit_name(units, file=path)
    elif pound.source_units is not None:
        source_units = pound.source_units
    else:
        raise InputError(
            f"format {pound.format} does not say what units its values are in; give "
            f"units = {' | '.join(repr(u) for u in UNITS)}",
            file=path,
            key="record.units",
        )
    # Readers return values in the file's (calibrated) units: AT2 keeps them as written.
    trace.data = trace.data * UNITS[source_units]
    pound.source_units = source_units
    pound.units = "m/s^2"
    return trace
