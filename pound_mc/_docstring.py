"""Parameter descriptions written once and substituted into the docstrings that share them.

As matplotlib's ``_docstring.interpd`` and pandas' ``@doc``: a docstring names a shared block
on a line of its own as ``%(name)s``, and :func:`fill` replaces that line by the block, each of
its lines indented as the placeholder is.  The rendered docstring (``help()``, Sphinx) reads
as if the block were written out in place; the block has one place to be edited.  Only whole
``%(name)s`` lines are replaced, so a ``%`` anywhere else in a docstring stays as written, and
a placeholder without a block fails at import time.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import TypeVar

__all__ = ["fill"]

F = TypeVar("F", bound=Callable)

_PLACEHOLDER = re.compile(r"^([ \t]*)%\((\w+)\)s[ \t]*$", re.MULTILINE)


def fill(**blocks: str) -> Callable[[F], F]:
    """Decorator: replace each ``%(name)s`` line of a docstring by ``blocks[name]``.

    Parameters
    ----------
    **blocks : str
        The shared blocks by name, as numpydoc text without indentation (a parameter's line,
        its description lines indented by four spaces).

    Returns
    -------
    callable
        The decorator; it returns the function itself, its ``__doc__`` filled in.

    Raises
    ------
    KeyError
        A placeholder names no block.
    """

    def substitute(match: re.Match) -> str:
        indent, name = match.groups()
        return indent + blocks[name].replace("\n", "\n" + indent)

    def decorate(func: F) -> F:
        func.__doc__ = _PLACEHOLDER.sub(substitute, func.__doc__ or "")
        return func

    return decorate
