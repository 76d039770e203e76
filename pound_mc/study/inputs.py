"""A study's records, read and preprocessed for its engine, every problem named in the file.

:func:`load_traces` reads every record table of a study (files, built-in records, suites,
synthetic motions) through :func:`pound_mc.motions.load_record`, naming the study file and the
record's key for each one that cannot be read; :func:`load_records` gives their arrays.
"""

from __future__ import annotations

import numpy as np

from pound_mc.errors import InputError, InputErrors, named_by
from pound_mc.motions import load_record, record_arrays

__all__ = ["load_records", "load_traces"]


def load_records(study) -> list[tuple[float, np.ndarray]]:
    """Read and preprocess every record of ``study``: ``[(dt_s, acceleration), ...]``.

    Raises
    ------
    InputError
        Every record that cannot be read, keyed in the study file (``record.duration_s``,
        ``records[2].source``); a problem inside a record file names that file too.
    """
    return [record_arrays(trace) for trace in load_traces(study)]


def load_traces(study) -> list:
    """Read and preprocess every record of ``study``: the obspy Traces (with their metadata).

    Raises
    ------
    InputError
        As :func:`load_records`.
    """
    fname = None if study.path is None else str(study.path)
    base_dir = None if study.path is None else study.path.parent
    out, errors = [], []
    for i, record in enumerate(study.records):
        spec = dict(record)
        spec.pop("name", None)
        spec.pop("sa_period_s", None)  # the period of the record.sa_g axis, not a step
        source = spec.pop("source")
        where = study.record_table(i) + "."
        try:
            out.append(load_record(source, base_dir=base_dir, **spec))
        except InputError as exc:
            exc = named_by(exc, fname, table=where[:-1])
            errors.extend(getattr(exc, "errors", [exc]))
        except (OSError, ValueError, TypeError) as exc:
            errors.append(
                InputError(f"cannot read {source!r}: {exc}", file=fname, key=where + "source")
            )
    if errors:
        raise InputErrors(errors)
    return out
