"""``pound-mc run`` and ``check`` behind a screen of the study's size (no engine imported).

:func:`pound_mc.study.limits.screen` refuses a study whose size alone rules it out before
:mod:`pound_mc.cli.study` (numba, scipy, matplotlib, the records' readers) is imported, so
that such a study is refused in about the time Python takes to start.
"""

from __future__ import annotations

import importlib

from pound_mc.study.limits import screen


def _screened(name: str):
    def command(args) -> int:
        screen(args.study)
        return getattr(importlib.import_module("pound_mc.cli.study"), name)(args)

    command.__name__ = name
    command.__doc__ = f"``pound_mc.cli.study.{name}`` after :func:`~pound_mc.study.limits.screen`."
    return command


run_command = _screened("run_command")
check_command = _screened("check_command")
