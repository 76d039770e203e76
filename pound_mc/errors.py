"""Exceptions that carry the file and key a user has to fix.

Every problem with user input (a study or scene file, a record, a parameter) raises
:class:`InputError`.  The command line turns it into one clear message on standard error and
exit status 2; a traceback is reserved for bugs.
"""

from __future__ import annotations

import difflib
import os
import stat
import tomllib
from collections.abc import Iterable
from pathlib import Path


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
        prefix = ": ".join(printable(w) for w in where)
        message = printable(self.message)
        return f"{prefix}: {message}" if prefix else message


def printable(text) -> str:
    r"""``text`` with its control characters escaped (``\x1b``, ``\n``).

    One line, nothing a terminal would act on (a record source or key that holds escape
    sequences).
    """
    text = str(text)
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii")
                   for c in text)  # fmt: skip


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


#: Largest study or scene file read [bytes]: a TOML file of this size is a mistake (a record, a
#: dataset given in its place), not a study.
MAX_TEXT_FILE_BYTES = 16 * 2**20
#: Deepest nesting of tables and arrays a study or scene file may have: the schema has four
#: (``[sampling.vary]`` entries); Python's TOML parser recurses once per level.
MAX_NESTING = 32


def read_text_file(path, what: str) -> str:
    """The text of the study or scene file ``path`` (UTF-8, a leading BOM dropped).

    Refuses, naming the file, what is not a regular file (a folder, a FIFO that would block, a
    device such as ``/dev/zero`` that never ends), a file over :data:`MAX_TEXT_FILE_BYTES`,
    a link that leads nowhere, and text that is not UTF-8.
    """
    path = Path(path)
    name = str(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        if path.is_symlink():
            raise InputError("symbolic link that leads nowhere (a loop, or its target is "
                             "missing)", file=name) from None  # fmt: skip
        raise InputError(f"{what} not found", file=name) from None
    except OSError as exc:
        raise InputError(f"cannot read the {what}: {exc.strerror or exc}", file=name) from None
    if not stat.S_ISREG(info.st_mode):
        kind = ("a folder" if stat.S_ISDIR(info.st_mode) else
                "a FIFO" if stat.S_ISFIFO(info.st_mode) else "a device or socket")  # fmt: skip
        raise InputError(f"not a regular file ({kind}): give the {what} itself", file=name)
    if info.st_size > MAX_TEXT_FILE_BYTES:
        raise InputError(f"{info.st_size / 2**20:,.0f} MiB is too large for a {what} (at most "
                         f"{MAX_TEXT_FILE_BYTES / 2**20:g} MiB)", file=name)  # fmt: skip
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_TEXT_FILE_BYTES + 1)
        return data.decode("utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read the {what}: {exc}", file=name) from None


def nesting_problem(text: str) -> str | None:
    """Why TOML ``text`` nests too deeply to parse, or None (a cheap bound before parsing).

    Counts open brackets and braces outside strings, line by line, from their closing ones;
    a file deeper than :data:`MAX_NESTING` would exhaust the parser's recursion.
    """
    depth = top = 0
    quote = None
    for c in text:
        if quote:
            if c == quote:
                quote = None
        elif c in "\"'":
            quote = c
        elif c in "[{":
            depth += 1
            top = max(top, depth)
        elif c in "]}":
            depth = max(depth - 1, 0)
        elif c == "#":
            quote = "\n"  # a comment, to the line's end
    if top > MAX_NESTING:
        return f"nested {top} levels deep: at most {MAX_NESTING} (tables and arrays)"
    return None


def parse_toml(text: str, file=None) -> dict:
    """The tables of TOML ``text``.

    An :class:`InputError` naming ``file`` where it is not TOML or nests too deeply
    (:func:`nesting_problem`).
    """
    problem = nesting_problem(text)
    if problem is not None:
        raise InputError(problem, file=file)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML: {exc}", file=file) from None
    except RecursionError:
        raise InputError(f"nested too deeply (at most {MAX_NESTING} levels)", file=file) from None
