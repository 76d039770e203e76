"""What a validation case is, how its results are judged, and the table they print as.

A case is a function that runs the tool on one problem and returns one or more rows, each a
quantity the tool computed beside its reference::

    {"quantity": "max_penetration", "value": 0.02003, "reference": 0.02003,
     "tolerance": 1e-6, "units": "m"}

or, for a reference that is a range (the seed's measured restitution), ``reference_low`` and
``reference_high`` in place of ``reference``.  :func:`judge` adds the relative error and the
verdict, so that every case is judged by the same rule:

* a point reference: ``rel_error = |value - reference| / |reference|``;
* a range: ``rel_error`` is 0 inside it and the distance outside it relative to the nearer
  bound, ``(low - value) / |low|`` below, ``(value - high) / |high|`` above;
* ``passed`` is ``rel_error <= tolerance`` (a NaN value fails);
* a row that cannot run (an optional package missing) carries ``passed`` None and a
  ``reason``; it is listed, and it is no failure.

A case that raises gives one failed row whose ``reason`` is the error.  Keys that start with
``_`` (the time histories the documentation draws) stay out of the JSON (:func:`public`).
"""

from __future__ import annotations

import math
import traceback
from collections.abc import Callable, Iterable
from dataclasses import dataclass

__all__ = ["GROUPS", "KEYS", "Case", "evaluate", "exit_status", "judge", "public", "table"]

#: The kinds of reference, in the order the table lists them.
GROUPS = {
    "closed-form": "closed forms and independent single-impact solutions",
    "chopra": "Chopra's textbook values (El Centro 1940, no pounding)",
    "seed": "the seed paper's measured tables (Jankowski 2008)",
    "reference": "the project's SciPy reference on real-record scenes",
    "opensees": "OpenSees (openseespy), identical scenes",
}

#: Keys of every row of ``pound-mc validate --json`` (DESIGN.md section 10), in table order.
KEYS = ("case", "quantity", "value", "reference", "source", "rel_error", "tolerance", "passed")


@dataclass(frozen=True)
class Case:
    """One validation case.

    Attributes
    ----------
    name : str
        Its name, the ``case`` of every row it gives.
    group : str
        The kind of reference (a key of :data:`GROUPS`).
    source : str
        Where the reference comes from, as the table shows it (a row may name its own).
    run : callable
        ``run(quick)`` runs the tool and returns the rows (dicts with ``quantity``, ``value``,
        ``reference`` or ``reference_low`` and ``reference_high``, ``tolerance``; optional
        ``units``, ``source`` and ``_plot``); ``quick`` (``--quick``) may ask for fewer.
    quick : bool
        Part of ``pound-mc validate --quick``.
    about : str
        How the reference was built and what the tolerance means (the documentation's text).
    """

    name: str
    group: str
    source: str
    run: Callable[[bool], list[dict]]
    quick: bool = False
    about: str = ""


def _number(x) -> float | None:
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def judge(row: dict) -> dict:
    """``row`` with ``rel_error`` and ``passed`` set by the rule of the module docstring.

    A row that says it cannot run (``passed`` None with a ``reason``) is returned as it is,
    with ``rel_error`` None.
    """
    out = dict(row)
    if "passed" in out and out["passed"] is None and out.get("reason"):
        out.setdefault("rel_error", None)
        return out
    value, tol = _number(out.get("value")), _number(out.get("tolerance"))
    if "reference_low" in out or "reference_high" in out:
        low, high = _number(out.get("reference_low")), _number(out.get("reference_high"))
        out["reference"] = [low, high]
        if value is None or low is None or high is None or math.isnan(value):
            rel = math.nan
        elif value < low:
            rel = (low - value) / abs(low)
        elif value > high:
            rel = (value - high) / abs(high)
        else:
            rel = 0.0
    else:
        ref = _number(out.get("reference"))
        if value is None or ref is None or ref == 0.0:
            rel = math.nan
        else:
            rel = abs(value - ref) / abs(ref)
    out["rel_error"] = None if math.isnan(rel) else rel
    out["passed"] = bool(tol is not None and not math.isnan(rel) and rel <= tol)
    if not out["passed"] and value is None:
        out.setdefault("reason", "no value")
    return out


def _failure(case: Case, exc: BaseException) -> dict:
    where = traceback.extract_tb(exc.__traceback__)[-1] if exc.__traceback__ else None
    at = f" ({where.filename.rsplit('/', 1)[-1]}:{where.lineno})" if where else ""
    return {"case": case.name, "quantity": "run", "value": None, "reference": None,
            "source": case.source, "group": case.group, "rel_error": None, "tolerance": None,
            "passed": False, "reason": f"{type(exc).__name__}: {exc}{at}"}  # fmt: skip


def evaluate(case: Case, quick: bool = False) -> list[dict]:
    """Run ``case`` (``case.run(quick)``) and judge its rows; one failed row if it raises."""
    try:
        rows = case.run(quick)
    except Exception as exc:  # a case that breaks is a failure to report, not a crash
        return [_failure(case, exc)]
    out = []
    for row in rows:
        full = {"case": case.name, "source": case.source, "group": case.group, **row}
        out.append(judge(full))
    return out


def exit_status(rows: Iterable[dict]) -> int:
    """1 when any row failed (``passed`` False), else 0; a row that could not run is no failure."""
    return 1 if any(row.get("passed") is False for row in rows) else 0


def public(row: dict) -> dict:
    """The row as ``--json`` prints it.

    The pinned :data:`KEYS` first, no ``_`` keys, NaN or infinite numbers as None (JSON has
    none).
    """
    out = {key: row.get(key) for key in KEYS}
    out.update({k: v for k, v in row.items() if k not in out and not k.startswith("_")})
    for key, value in out.items():
        if isinstance(value, float) and not math.isfinite(value):
            out[key] = None
    return out


def _fmt(x) -> str:
    if x is None:
        return "-"
    if isinstance(x, list | tuple):
        return "-".join(_fmt(v) for v in x)
    if isinstance(x, float):
        return f"{x:.6g}"
    return str(x)


def table(rows: list[dict]) -> str:
    """The rows as a plain-text table, one line each, and a closing count."""
    head = ("case", "quantity", "value", "reference", "source", "rel_error", "tolerance",
            "passed")  # fmt: skip
    lines = []
    for row in rows:
        passed = {True: "yes", False: "FAIL", None: "n/a"}[row.get("passed")]
        units = f" {row['units']}" if row.get("units") else ""
        rel = row.get("rel_error")
        lines.append((
            row["case"], row["quantity"], _fmt(row.get("value")) + units,
            _fmt(row.get("reference")) + units, row.get("source", ""),
            "-" if rel is None else f"{rel:.2e}",
            "-" if row.get("tolerance") is None else f"{row['tolerance']:.1e}", passed,
        ))  # fmt: skip
    widths = [max(len(str(r[i])) for r in [head, *lines]) for i in range(len(head))]
    text = ["  ".join(str(c).ljust(w) for c, w in zip(r, widths, strict=True)).rstrip()
            for r in [head, *lines]]  # fmt: skip
    failed = sum(row.get("passed") is False for row in rows)
    skipped = [row for row in rows if row.get("passed") is None]
    text.append("")
    text.append(f"{len(rows)} checks: {len(rows) - failed - len(skipped)} passed, {failed} "
                f"failed, {len(skipped)} could not run")  # fmt: skip
    for row in skipped + [row for row in rows if row.get("passed") is False and "reason" in row]:
        text.append(f"  {row['case']}: {row['reason']}")
    return "\n".join(text)
