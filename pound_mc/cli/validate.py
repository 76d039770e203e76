"""``pound-mc validate``: the validation cases, their table, and an exit status.

Its arguments are declared in :mod:`pound_mc.cli.commands`; the cases and how they are judged
are :mod:`pound_mc.validation`'s.
"""

from __future__ import annotations

import json

from pound_mc.validation import exit_status, public, run_cases, table


def validate_command(args) -> int:
    """Run the validation cases (``--quick``: the quick ones) and print them.

    The table (or, with ``--json``, a list of case objects) goes to stdout, the progress bar
    to stderr; exit status 1 when any case failed, 0 otherwise (a case that could not run,
    ``passed`` null, is no failure).
    """
    # the bar only where stderr is a terminal (tqdm's own test), never with --no-progress
    rows = run_cases(args.quick, progress=None if not args.no_progress else False)
    if args.json:
        print(json.dumps([public(row) for row in rows], indent=1))
    else:
        print(table(rows))
    return exit_status(rows)
