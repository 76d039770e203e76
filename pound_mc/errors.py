"""Exceptions that carry the file and key a user has to fix.

Every problem with user input (a study or scene file, a record, a parameter) raises
:class:`InputError`.  The command line turns it into one clear message on standard error and
exit status 2; a traceback is reserved for bugs.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable


class InputError(ValueError):
    """Bad user input: names the file (if any), the key or line, and what is allowed.

    Parameters
    ----------
    message : str
        What is wrong and, where possible, the allowed values.
    file : str, optional
        The file the problem is in.
    key : str, optional
        Dotted key path (``"contact.gap_m"``) or a line reference (``"line 3"``).
    """

    def __init__(self, message: str, *, file: str | None = None, key: str | None = None):
        self.message = message
        self.file = None if file is None else str(file)
        self.key = key
        super().__init__(self.__str__())

    def __str__(self) -> str:
        where = []
        if self.file:
            where.append(self.file)
        if self.key:
            where.append(self.key)
        prefix = ": ".join(where)
        return f"{prefix}: {self.message}" if prefix else self.message


class InputErrors(InputError):
    """Several input problems found at once (a study file reports all of them together)."""

    def __init__(self, errors: Iterable[InputError]):
        self.errors = list(errors)
        text = "\n".join(str(e) for e in self.errors)
        ValueError.__init__(self, text)
        self.message = text
        self.file = None
        self.key = None

    def __str__(self) -> str:
        return "\n".join(str(e) for e in self.errors)


class OutputError(InputError):
    """A file or folder a run cannot write (disk full, read-only, not a folder, locked).

    Reported like :class:`InputError` (one line naming the path, exit status 2): the fix is
    the user's (free space, another ``--out``), not the program's.
    """


class ClusterError(InputError):
    """A Dask cluster that cannot be reached or failed during a run (exit status 2).

    The message says what happened; the chunks written so far are kept, so running the same
    command again resumes.
    """


def named_by(exc: InputError, file, *, table: str = "record") -> InputError:
    """``exc``, met reading what ``file`` names (a record), as an error of ``file``.

    The message says each thing once: ``file`` and its key (``exc``'s own ``record.*`` key
    moved to ``table``, ``"records[2].component"``; ``table.source`` for a problem inside the
    record), then the record's own file and line where ``exc`` names them, then what is wrong.
    An error of ``file`` itself, or one that names no file and a key that is not dotted (a
    command-line option), is returned as it is; one that names neither is ``table.source``'s;
    :class:`InputErrors` item by item.

    Parameters
    ----------
    exc : InputError
        The error as raised (``file``: the record, ``key``: a ``record.*`` key or a line).
    file : str or Path
        The study or scene file that names the record.
    table : str
        The record's table in ``file`` (``"record"``, ``"records[2]"``).

    Returns
    -------
    InputError
    """
    if isinstance(exc, InputErrors):
        return InputErrors(named_by(e, file, table=table) for e in exc.errors)
    file = None if file is None else str(file)
    key = exc.key or ""
    if exc.file == file or (exc.file is None and key and "." not in key):
        return exc  # the naming file's own error, or an option's
    inner = [exc.file] if exc.file else []
    if key == "record" or key.startswith("record."):
        key = table + key.removeprefix("record")
    elif "." not in key or key.startswith("line "):  # a place in the record's file
        inner += [key] if key else []
        key = f"{table}.source"
    return InputError(": ".join([*inner, exc.message]), file=file, key=key)


def did_you_mean(key: str, allowed: Iterable[str]) -> str:
    """`` (did you mean 'damping_ratio'?)`` for a misspelt ``key``, else an empty string."""
    close = difflib.get_close_matches(str(key), [str(a) for a in allowed], n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""
