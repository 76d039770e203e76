"""Validation: the tool against closed forms, textbook values, the seed's tables and references.

``pound-mc validate`` runs every case of :data:`CASES` (``--quick``: those marked quick) and
prints one row per compared quantity; :func:`run_cases` is the same from Python, and the
documentation's validation page draws its table and charts from it.  How a row is judged is
:mod:`pound_mc.validation.runner`'s; the cases live in :mod:`~pound_mc.validation.impact`
(closed forms), :mod:`~pound_mc.validation.chopra` (Chopra's El Centro examples),
:mod:`~pound_mc.validation.seed` (the seed's Tables 2 and 3) and
:mod:`~pound_mc.validation.scenes` (the SciPy reference).  Where the module
``pound_mc.validation.opensees`` is installed, its ``cases(quick)`` rows are added.
"""

from __future__ import annotations

import importlib
import sys

from tqdm import tqdm

from pound_mc.validation import chopra, impact, scenes, seed
from pound_mc.validation.runner import (
    GROUPS,
    KEYS,
    Case,
    evaluate,
    exit_status,
    judge,
    public,
    table,
)

__all__ = ["CASES", "GROUPS", "KEYS", "Case", "case_list", "exit_status", "judge", "public",
           "run_cases", "table"]  # fmt: skip

#: Every validation case, grouped by the kind of reference.
CASES: tuple[Case, ...] = (*impact.CASES, *chopra.CASES, *seed.CASES, *scenes.CASES)

#: The optional module of the OpenSees comparisons and the package it needs.
EXTERNAL = "pound_mc.validation.opensees"


def case_list(quick: bool = False) -> list[dict]:
    """The cases :func:`run_cases` runs, listed without running them.

    Each is ``case``, ``group``, ``source`` and ``quick``; the OpenSees cases, whose rows their
    own module makes, are not listed.
    """
    return [{"case": c.name, "group": c.group, "source": c.source, "quick": c.quick}
            for c in CASES if c.quick or not quick]  # fmt: skip


def _external(quick: bool) -> list[dict]:
    """The rows of ``pound_mc.validation.opensees.cases(quick)``, judged; none without it."""
    try:
        module = importlib.import_module(EXTERNAL)
    except ModuleNotFoundError as exc:
        if exc.name == EXTERNAL:
            return []  # not part of this installation
        return [{"case": "opensees", "quantity": "-", "value": None, "reference": None,
                 "source": "OpenSees", "group": "opensees", "tolerance": None, "passed": None,
                 "rel_error": None, "reason": f"cannot import {EXTERNAL}: {exc}"}]  # fmt: skip
    rows = []
    for row in module.cases(quick):
        rows.append(judge({"group": "opensees", **row}))
    return rows


def run_cases(
    quick: bool = False, *, progress: bool | None = False, external: bool = True
) -> list[dict]:
    """Run the validation cases and return their judged rows.

    Parameters
    ----------
    quick : bool
        Only the cases marked quick (a minute on a laptop, the kernels compiled).
    progress : bool or None
        Show a progress bar on stderr, one step a case (None: where stderr is a terminal).
    external : bool
        Also run the OpenSees cases where their module is installed.

    Returns
    -------
    list of dict
        One row per compared quantity, keys :data:`KEYS` and more (see
        :mod:`pound_mc.validation.runner`); ``_plot`` holds the histories a chart overlays.
    """
    chosen = [c for c in CASES if c.quick or not quick]
    rows: list[dict] = []
    disable = None if progress is None else not progress
    for case in tqdm(chosen, desc="validate", unit="case", file=sys.stderr, disable=disable):
        rows.extend(evaluate(case, quick))
    if external:
        rows.extend(_external(quick))
    return rows
