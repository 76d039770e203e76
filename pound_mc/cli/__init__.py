"""The ``pound-mc`` command line.

The arguments of every sub-command and the function that runs it are declared in
:mod:`pound_mc.cli.commands`; the functions live in ``pound_mc.cli.physics``, ``.records``,
``.scene``, ``.study`` and ``.analysis``, and only the module of the command given is imported.
This module builds the parser, dispatches, and turns input errors into exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from pathlib import Path

from pound_mc._version import __version__
from pound_mc.cli.commands import COMMANDS, HelpFormatter, add_commands
from pound_mc.errors import InputError, OutputError, named_by
from pound_mc.study.status import STATUS

#: Commands that say on a terminal what they are doing from the start (``run`` loads the
#: libraries and compiles for many seconds: :mod:`pound_mc.study.status`).
_STATUS_COMMANDS = ("run",)


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every registered subcommand."""
    parser = argparse.ArgumentParser(
        prog="pound-mc",
        description=(
            "Monte Carlo studies of earthquake-induced pounding between adjacent buildings. "
            "Start with: pound-mc init quickstart && pound-mc run quickstart.toml"
        ),
        formatter_class=HelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"pound-mc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    add_commands(sub)
    return parser


def command_function(name: str):
    """The function that runs sub-command ``name`` (a key of :data:`COMMANDS`), imported now."""
    module, function = COMMANDS[name]
    return getattr(importlib.import_module(module), function)


def _quiet_library_warnings() -> None:
    """Silence the libraries' warnings a command's own messages already cover.

    numpy's about NaN reductions (a summary over runs that all failed is NaN, which the run's
    status lines say) and obspy's about the files it reads (the record checks name the file
    and what is wrong); a warning of the tool itself still shows.
    """
    warnings.filterwarnings("ignore", category=RuntimeWarning, module=r"numpy(\..*)?$")
    warnings.filterwarnings("ignore", module=r"obspy(\..*)?$")
    warnings.filterwarnings(
        "ignore",
        message=r".*(All-NaN|Mean of empty|invalid value|"
        r"divide by zero|Degrees of freedom).*",
        category=RuntimeWarning,
    )


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for bad input)."""
    parser = build_parser()
    args, extra = parser.parse_known_args(argv)
    if extra:  # with the command's own usage, not the program's
        command_parser = getattr(args, "command_parser", None) or parser
        command_parser.error(f"unrecognized arguments: {' '.join(extra)}")
    if args.command in _STATUS_COMMANDS and not getattr(args, "no_progress", False):
        STATUS.say(f"pound-mc {args.command}: loading the libraries")  # the first seconds
    try:
        with warnings.catch_warnings():
            _quiet_library_warnings()
            status = command_function(args.handler)(args)
    except InputError as exc:
        STATUS.clear()
        scene = getattr(args, "scene", None)  # simulate: its record's errors, and the kernels'
        if scene is not None and (exc.file or exc.key) and not isinstance(exc, OutputError):
            exc = named_by(exc, Path(scene))  # (a law a method cannot step), in the scene file
        print(f"pound-mc {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        STATUS.clear()
        print(f"pound-mc {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output went away (``pound-mc ... | head``): nothing more to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except MemoryError:
        STATUS.clear()
        print(f"pound-mc {args.command}: error: out of memory; make the study or the record "
              "smaller", file=sys.stderr)  # fmt: skip
        return 2
    except OSError as exc:
        # a file or folder the command cannot read or write (permissions, a full disk)
        STATUS.clear()
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"pound-mc {args.command}: error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    finally:
        STATUS.clear()
    return 0 if status is None else int(status)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
