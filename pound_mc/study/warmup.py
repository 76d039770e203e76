"""Compile the kernels before the work starts: first-run notice and ``pound-mc compile``.

numba compiles a kernel the first time it is called with new argument types and caches the
machine code on disk (:mod:`pound_mc._jit`: where the cache lives and what survives).  A study's
first run would otherwise spend that time inside its first chunk, with the progress bar at 0 %
and its rate and ETA wrong.  :func:`warm_up` runs one simulation of the study through the same
batch function as the run, before the bar starts, and says so when it takes long (compiling
rather than loading the cache); :func:`compile_kernels` does the same for tiny in-memory
studies of every requested method and contact law, so that cluster images and Dask workers
start with the cache filled.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterable
from contextlib import contextmanager
from typing import TextIO

import numpy as np
from numba.core import event as numba_event

# imported as a module: a "from ... import" of it would add this file to the sources that key
# the kernel cache (see pound_mc._jit.source_key), and every edit here would recompile
import pound_mc._jit as jit_cache
from pound_mc.integrators import METHODS
from pound_mc.physics.contact import CONTACT_MODELS
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.status import STATUS

__all__ = [
    "COMPILING_MESSAGE",
    "NOTICE_AFTER_S",
    "compiling_notice",
    "noticed",
    "warm_up",
    "compile_kernels",
    "cache_directory",
]

#: Printed when the first call of the kernels takes longer than :data:`NOTICE_AFTER_S`.
COMPILING_MESSAGE = "compiling kernels (first run only)..."
#: Seconds after which the first call is taken to be compiling (loading the cache takes less).
NOTICE_AFTER_S = 3.0


def cache_directory() -> str:
    """Folder of this source's compiled kernels (see :mod:`pound_mc._jit`)."""
    return str(jit_cache.cache_root() / "numba" / jit_cache.source_key())


class _Compilations(numba_event.Listener):
    """Counts the numba compilations that start (a kernel loaded from the cache is none)."""

    def __init__(self):
        self.started = 0

    def on_start(self, event):
        self.started += 1

    def on_end(self, event):
        pass


@contextmanager
def compiling_notice(stream: TextIO | None = None, after_s: float | None = None, *,
                     where: str | None = None, quiet: bool = False):  # fmt: skip
    """Print :data:`COMPILING_MESSAGE` to ``stream`` once the block has compiled for ``after_s``.

    Here (``where`` None) the message is due when numba compiles a kernel in the block and
    the block has run ``after_s``: a slow first simulation whose kernels come from the cache
    is no compilation.  Elsewhere (``where``: the Dask workers, whose compilations this process
    does not see) it is due when the block runs longer than ``after_s``.  Yields a dict whose
    ``"shown"`` entry tells, after the block, whether it was due; ``quiet``: print nothing.
    """
    stream = sys.stderr if stream is None else stream
    after_s = NOTICE_AFTER_S if after_s is None else after_s
    state = {"shown": False}
    done = threading.Event()
    compilations = _Compilations()

    def show():
        state["shown"] = True
        if not quiet:
            text = where if where is not None else f"(cache: {cache_directory()})"
            STATUS.announce(f"{COMPILING_MESSAGE} {text}", stream)  # above the status line
            if stream is sys.stderr:  # the status line's stream: it counts the seconds
                STATUS.say("compiling kernels" + (f" {where}" if where is not None else ""))

    def notice():
        if done.wait(after_s):
            return
        while where is None and not compilations.started:
            if done.wait(0.1):
                return
        show()

    t0 = time.perf_counter()
    timer = threading.Thread(target=notice, daemon=True)
    with numba_event.install_listener("numba:compile", compilations):
        timer.start()
        try:
            yield state
        finally:
            done.set()
            timer.join()
            # a compilation in the last moments before the block ended, which the timer missed
            if not state["shown"] and compilations.started and time.perf_counter() - t0 >= after_s:
                show()


def warm_up(engine, index: int = 0, *, stream: TextIO | None = None, quiet: bool = False):
    """Run simulation ``index`` of the study once, so the run's kernels are compiled or loaded.

    Parameters
    ----------
    engine : pound_mc.study.engine.StudyEngine
        The prepared study; the simulation runs through its own batch function, method and
        contact law, so exactly the kernels of the run are compiled.
    index : int
        Flat index of the simulation (its result is discarded).
    stream : file, optional
        Where the first-run notice goes (default standard error).
    quiet : bool
        Print nothing.

    Returns
    -------
    seconds : float
        Wall time of the call [s].
    compiled : bool
        Whether it took long enough to be compiling (the notice was due).
    """
    return noticed(lambda: engine.run_indices(np.array([index], dtype=np.int64)), stream=stream,
                   quiet=quiet)  # fmt: skip


def noticed(work, *, stream: TextIO | None = None, quiet: bool = False, where: str | None = None):
    """Call ``work()``, the kernels' first call, under :func:`compiling_notice`.

    ``where``: where the kernels compile (default: here).  Returns the wall time of the call
    [s] and whether it took long enough to be compiling; when it did, says how long (unless
    ``quiet``).
    """
    stream = sys.stderr if stream is None else stream
    t0 = time.perf_counter()
    if not quiet and stream is sys.stderr:  # on a terminal: until the notice, and after it
        STATUS.say("loading the kernels" + (f" {where}" if where is not None else ""))
    try:
        with compiling_notice(stream, where=where, quiet=quiet) as state:
            work()
    finally:
        STATUS.clear()
    seconds = time.perf_counter() - t0
    if state["shown"] and not quiet:
        place = "" if where is None else f"{where} "
        STATUS.announce(f"kernels compiled {place}in {seconds:.1f} s (cached for later runs)",
                        stream)  # fmt: skip
    return seconds, state["shown"]


#: The ``[contact]`` table of a tiny study for each law (its own stiffness and damping keys).
_CONTACT = {
    "jankowski": "beta = 2.75e9\nxi = 0.35",
    "linear": "k_N_per_m = 9.3e8",
    "kelvin": "k_N_per_m = 9.3e8\nxi = 0.1",
    "hertz": "beta = 2.75e9",
    "hertzdamp": "beta = 2.75e9\ne = 0.65",
}

_SDOF = """
[left]
model = "sdof"
period_s = 0.5
damping_ratio = 0.05
mass_kg = 1.0e6

[right]
model = "sdof"
period_s = 1.0
damping_ratio = 0.05
mass_kg = 1.0e6
"""

_SHEAR = """
[left]
model = "shear"
storey_mass_kg = [1.0e6, 1.0e6]
storey_stiffness_N_per_m = [1.0e9, 1.0e9]
storey_height_m = [3.0, 3.0]
damping_ratio = 0.05

[right]
model = "shear"
storey_mass_kg = [1.0e6, 1.0e6, 1.0e6]
storey_stiffness_N_per_m = [0.8e9, 0.8e9, 0.8e9]
storey_height_m = [3.0, 3.0, 3.0]
damping_ratio = 0.05
"""

_YIELDING = _SHEAR.replace(
    "damping_ratio = 0.05",
    'damping_ratio = 0.05\nhysteresis = "bilinear"\nstorey_yield_disp_m = 0.002\n'
    "post_yield_ratio = 0.05",
)

#: Building pairs of :func:`compile_kernels`: each runs through its own batch function
#: (``yielding``: bilinear shear buildings, the inelastic kernels).
STRUCTURES = {"sdof": _SDOF, "shear": _SHEAR, "yielding": _YIELDING}


def tiny_study(method: str, law: str = "jankowski", structure: str = "sdof"):
    """A one-simulation study (2 s of the built-in K-NET record) of ``method`` and ``law``."""
    text = f"""
[study]
name = "compile"
seed = 1

[record]
source = "builtin:knet-akt013"
duration_s = 2.0
pga_g = 0.5
{STRUCTURES[structure]}
[contact]
model = "{law}"
gap_m = 0.0
{_CONTACT[law]}

[integrator]
method = "{method}"
"""
    return study_from_text(text)


def compile_kernels(
    methods: Iterable[str] | None = None,
    laws: Iterable[str] | None = None,
    structures: Iterable[str] = ("sdof", "shear", "yielding"),
    *,
    stream: TextIO | None = None,
) -> list[dict]:
    """Compile (or load from the cache) the kernels of every method, law and building pair.

    Each combination runs one simulation of :func:`tiny_study` through the batch function a
    study of that kind uses, so the cache then holds exactly what a run needs.

    Parameters
    ----------
    methods, laws : iterable of str, optional
        Integration methods (default all of :data:`pound_mc.integrators.METHODS`) and contact
        laws (default all of :data:`pound_mc.physics.contact.CONTACT_MODELS`).
    structures : iterable of str
        ``"sdof"`` (SDOF pairs), ``"shear"`` (shear buildings) and/or ``"yielding"``
        (yielding shear buildings; ``central-difference`` does not run them).
    stream : file, optional
        Where a line per combination is printed (None: nothing).

    Returns
    -------
    list of dict
        ``method``, ``law``, ``structure`` and ``seconds`` of each first call.
    """
    rows = []
    for structure in structures:
        for method in METHODS if methods is None else methods:
            for law in CONTACT_MODELS if laws is None else laws:
                engine = StudyEngine(tiny_study(method, law, structure))
                t0 = time.perf_counter()
                engine.run_indices(np.array([0], dtype=np.int64))
                seconds = time.perf_counter() - t0
                rows.append(
                    {"method": method, "law": law, "structure": structure, "seconds": seconds}
                )
                if stream is not None:
                    print(f"  {structure:5s} {method:18s} {law:9s} {seconds:7.2f} s",
                          file=stream, flush=True)  # fmt: skip
    return rows
