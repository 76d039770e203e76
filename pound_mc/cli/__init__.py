"""The ``pound-mc`` command line.

Each group of subcommands lives next to the code it drives (``pound_mc.cli_*`` modules with a
``register(subparsers)`` function); this module only assembles them and turns input errors into
exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from pound_mc._version import __version__
from pound_mc.errors import InputError

# Modules that contribute subcommands, in the order they appear in ``--help``.
_SUBCOMMAND_MODULES = [
    "pound_mc.cli.physics",
    "pound_mc.cli.records",
    "pound_mc.cli.scene",
    "pound_mc.cli.study",
    "pound_mc.cli.analysis",
]


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every registered subcommand."""
    parser = argparse.ArgumentParser(
        prog="pound-mc",
        description=(
            "Monte Carlo studies of earthquake-induced pounding between adjacent buildings."
        ),
    )
    parser.add_argument("--version", action="version", version=f"pound-mc {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in _SUBCOMMAND_MODULES:
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (2 for bad input)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        status = args.func(args)
    except InputError as exc:
        print(f"pound-mc {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"pound-mc {args.command}: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader of our output went away (``pound-mc ... | head``): nothing more to say
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    return 0 if status is None else int(status)


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
