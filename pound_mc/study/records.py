"""Record tables of a study: suites and globs expanded, and the intensity axis's needs.

:func:`expand_records` turns ``[[records]]`` tables whose ``source`` is a suite
(``"suite:fema-p695-farfield"``) or a glob (``"records/*.AT2"``) into one table per component
or file; :func:`check_intensity` checks that an intensity grid axis can scale every record.
Used by :mod:`pound_mc.study.definition`.
"""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

from pound_mc.errors import InputError
from pound_mc.motions import suites

__all__ = ["check_intensity", "expand_records", "record_files", "input_hashes"]


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
    installed packages (their version is in the run's identity) and are not listed.
    """
    base_dir = None if study.path is None else Path(study.path).parent
    out = []
    for i, record in enumerate(study.records):
        source = record.get("source")
        if not isinstance(source, str) or re.match(r"^[A-Za-z][\w-]+:", source):
            continue  # builtin:, suite:, synthetic:
        path = Path(source).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = base_dir / path
        out.append((f"{study.record_table(i)}.source", path))
    return out


def input_hashes(study) -> dict[str, str]:
    """The identity of a study's inputs: SHA-256 of the study text and of every record file.

    Returns
    -------
    dict
        ``{"study": hash of the text, "<key> (<path>)": hash of the file's bytes, ...}``, the
        path relative to the study's folder (absolute outside it), so that the same study
        given by another path (``studies/a.toml``, ``/abs/studies/a.toml``, ``a.toml`` from
        ``studies/``) resumes; a file that cannot be read hashes to ``"unreadable"`` (reading
        it then fails with its own message).
    """
    out = {"study": study.hash}
    base = Path(study.path).resolve().parent if study.path is not None else Path.cwd()
    for key, path in record_files(study):
        shown = Path(path).resolve()
        if shown.is_relative_to(base):
            shown = shown.relative_to(base)
        digest = hashlib.sha256()
        try:
            with open(path, "rb") as fh:
                for block in iter(lambda: fh.read(1 << 20), b""):
                    digest.update(block)
            value = digest.hexdigest()
        except OSError:
            value = "unreadable"
        out[f"{key} ({shown})"] = value
    return out
