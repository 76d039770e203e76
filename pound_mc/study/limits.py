"""How large a study may be, and a screen of its size that needs none of the engine.

The limits are the schema's (:mod:`pound_mc.study.schema` takes them from here).
:func:`screen` reads a study file as :func:`~pound_mc.study.definition.load_study` does and
refuses the sizes that the full validation refuses, before anything heavy is imported:
``pound-mc check`` and ``pound-mc run`` call it first, so that a study that could never run
(``num = 1e8`` on a grid axis, a sample count or a grid product too large for memory) is
refused in about the time Python takes to start, in little memory.  What it lets through is
validated in full afterwards; it refuses nothing the full validation would accept.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from pound_mc.errors import InputError, parse_toml, read_text_file

__all__ = [
    "MAX_AXIS_VALUES",
    "MAX_SAMPLES",
    "MIN_BYTES_PER_SIMULATION",
    "physical_memory",
    "screen",
]

#: The least memory one simulation's results hold [bytes]: the per-simulation outputs and run
#: settings of :mod:`pound_mc.study.dataset` (98 bytes), twice (the arrays and the dataset);
#: the tests hold it to them.
MIN_BYTES_PER_SIMULATION = 196
#: Most values of one grid axis: a spectrum of a million points is a typing error.
MAX_AXIS_VALUES = 10**6
#: Largest number of samples per grid point (2^24: Sobol designs and memory stay sane).
MAX_SAMPLES = 2**24


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine, if the system says."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def _count(value, key: str, file: str, maximum: int) -> int | None:
    """``value`` as a count in [1, maximum] (the schema's message where it is not), or None.

    None where the value is not a number at all: the full validation says what is wrong.
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    if isinstance(value, float):
        if math.isfinite(value) and value == int(value) and 1 <= value <= maximum:
            return None  # a whole float in range: the schema's own message (not an integer)
        raise InputError(f"must be an integer, got {value!r}", file=file, key=key)
    if not 1 <= value <= maximum:
        raise InputError(f"must be an integer in [1, {maximum}], got {value}", file=file,
                         key=key)  # fmt: skip
    return value


def _axis_size(name: str, axis, file: str) -> int:
    """Values of grid axis ``name`` (1 where the full validation must say what it is)."""
    if isinstance(axis, list):
        return max(len(axis), 1)
    if isinstance(axis, dict) and "num" in axis:
        n = _count(axis["num"], f"grid.{name}.num", file, MAX_AXIS_VALUES)
        return 1 if n is None else n
    return 1


def screen(path: str | Path) -> None:
    """Refuse study file ``path`` where its size alone rules it out (see the module docstring).

    Reads and parses the file (a folder, a FIFO, a device, a file too large or nested too
    deeply is refused as by the full load), checks ``sampling.n`` and each grid axis's
    ``num``, and the least number of simulations (the grid's product times ``sampling.n``
    times one simulation per record entry) against the physical memory.  Raises
    :class:`~pound_mc.errors.InputError` naming the file and the key.
    """
    file = str(path)
    tables = parse_toml(read_text_file(path, "study file"), file=file)
    sampling = tables.get("sampling")
    n = 1
    if isinstance(sampling, dict) and "n" in sampling:
        n = _count(sampling["n"], "sampling.n", file, MAX_SAMPLES) or 1
    grid = tables.get("grid")
    sizes = {"sampling.n": n}
    if isinstance(grid, dict):
        sizes |= {f"grid.{k}": _axis_size(k, v, file) for k, v in grid.items()}
    records = tables.get("records")
    least = math.prod(sizes.values()) * max(len(records) if isinstance(records, list) else 1, 1)
    need = least * MIN_BYTES_PER_SIMULATION
    have = physical_memory()
    if have is not None and need > have:
        largest = max(sizes, key=sizes.get)
        raise InputError(
            f"at least {least:,} simulations need at least {need / 2**30:,.1f} GiB of memory "
            f"for their results, more than this machine's {have / 2**30:,.1f} GiB; make the "
            "grid or the number of samples smaller", file=file, key=largest)  # fmt: skip
