"""Execute a study: chunks of simulations through the compiled kernels, resumable.

The simulations of a study are numbered in C order of ``study.shape`` = ``(record, *grid
axes, sample)`` and cut into chunks of ``chunk_size``.  Each finished chunk is written
atomically to ``<out>/<name>/chunk_<size>_NNNNNN.npz`` (temporary file renamed into place), so an
interrupted run (Ctrl-C, a killed process) loses at most the chunks in flight; re-running the
same study skips the finished ones.  When every chunk is done the dataset is assembled and
written to ``<out>/<name>.nc``.

Run identity: ``<out>/<name>/manifest.json`` holds the SHA-256 of the study text and of every
record file the study reads (:func:`pound_mc.study.records.input_hashes`) and the package
version; a resume whose inputs differ is refused, naming the changed input, unless
``fresh=True`` (then the earlier results are discarded).  An unreadable manifest is reported as
such, not as a changed study.

One writer per output: a run holds an exclusive advisory lock (:func:`fcntl.flock`) on
``<out>/.<name>.lock`` (which records its process id) from the manifest check to the dataset;
a second run on the same study and folder is refused at once.  The kernel releases the lock
when the process ends, however it ends, so a lock left by a killed run is never in the way.
Temporary files carry the process id (``.<file>.<pid>.part``); the ones a killed run left
behind are removed by the next run that takes the lock, and a failed write (disk full, a
read-only folder) removes its own and ends in an :class:`~pound_mc.errors.OutputError` naming
the path.

Every simulation writes only its own output slot and all random numbers are drawn before any
chunk runs, so results do not depend on thread count, chunk size or backend.

Chunks run through an *executor*: a callable ``executor(engine, chunks)`` that yields
``(chunk, result)`` pairs as chunks finish, in any order.  The default runs them in this process
on numba's threads (:func:`local_executor`); :mod:`pound_mc.study.distributed` runs them on a Dask
cluster.  Either way this process alone writes the chunk files and the dataset.  An executor
whose chunks run elsewhere has a ``warm_up(engine, index, quiet=...)`` attribute, called instead
of :func:`~pound_mc.study.warmup.warm_up` before the progress bar starts, so that the kernels
compile where the chunks run (the Dask workers), not here.

Test hook: when the environment variable ``POUND_MC_TEST_PAUSE_AT`` names a stage (see
:data:`PAUSE_STAGES`), the runner prints ``POUND_MC_TEST_PAUSE_AT: paused at <stage>`` to
standard error and sleeps there (``POUND_MC_TEST_PAUSE_S`` seconds, default 600), so the
interrupt drill (``tests/test_drills.py``) can kill the process at a known point.  It costs one
environment lookup per stage and is not meant for users.

Longer than 600 lines because the guarantees of a run (one writer per output, resumable
chunks checked against a manifest of the inputs, nothing half-written, a results folder told
from a folder of the user's) sit with the loop they guard.
"""

from __future__ import annotations

import collections
import fcntl
import io
import itertools
import json
import os
import shutil
import signal
import sys
import threading
import time
import tomllib
import zipfile
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from contextlib import closing, contextmanager
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from tqdm.auto import tqdm

from pound_mc._version import __version__
from pound_mc.errors import InputError, OutputError
from pound_mc.integrators.threads import numba_threads
from pound_mc.study.dataset import build_dataset, write_netcdf
from pound_mc.study.engine import StudyEngine
from pound_mc.study.records import input_hashes
from pound_mc.study.warmup import warm_up

__all__ = [
    "Chunk",
    "RunReport",
    "run_study",
    "local_executor",
    "plan_text",
    "chunk_ranges",
    "count_text",
    "default_chunk_size",
    "output_lock",
    "memory_estimate",
]

_MANIFEST = "manifest.json"

#: Environment variable of the test hook that pauses the runner at a named stage.
PAUSE_ENV = "POUND_MC_TEST_PAUSE_AT"
#: Stages of the test hook, in the order a run passes them (``K``: a chunk's index,
#: ``N``: the number of chunk files this call has written).
PAUSE_STAGES = (
    "manifest:part",  # manifest's temporary file written, not yet renamed
    "chunk:K:half",  # chunk K's temporary file half written
    "chunk:K:part",  # chunk K's temporary file complete, not yet renamed
    "chunks:N",  # N chunk files written by this call
    "dataset",  # every chunk done, dataset not yet assembled
    "netcdf",  # dataset assembled, not yet written
    "done",  # dataset written (the command line then draws the chart)
)


def _pause_at(stage: str) -> None:
    """Test hook: sleep at ``stage`` if ``POUND_MC_TEST_PAUSE_AT`` names it."""
    if os.environ.get(PAUSE_ENV) != stage:
        return
    print(f"{PAUSE_ENV}: paused at {stage}", file=sys.stderr, flush=True)
    time.sleep(float(os.environ.get("POUND_MC_TEST_PAUSE_S", "600")))


@dataclass(frozen=True)
class Chunk:
    """One chunk of a study: simulations ``start .. stop-1``, stored in ``path``."""

    index: int
    start: int
    stop: int
    path: Path


@dataclass
class RunReport:
    """What a run did."""

    path: Path | None
    n_simulations: int
    chunks_total: int
    chunks_run: int
    seconds: float
    complete: bool
    interrupted: bool = False
    simulations_run: int = 0
    #: Seconds of the warm-up simulation before the chunks (compilation or cache load),
    #: not counted in ``seconds``.
    warmup_seconds: float = 0.0
    #: Whether the warm-up took long enough to be compiling rather than loading the cache.
    warmup_compiled: bool = False

    @property
    def rate(self) -> float:
        """Simulations per second over the chunks run in this call."""
        return self.simulations_run / self.seconds if self.seconds > 0 else float("nan")


def default_chunk_size(n: int) -> int:
    """Simulations per chunk when the study does not say: about 50 chunks, 256 to 8192 each.

    Small enough for a live progress bar and little work lost to an interruption, large
    enough to keep every thread busy and the chunk files few.
    """
    return int(min(8192, max(256, -(-n // 50))))


def chunk_ranges(n: int, chunk_size: int) -> list[tuple[int, int]]:
    """Half-open index ranges ``[start, stop)`` covering ``range(n)``."""
    return [(s, min(s + chunk_size, n)) for s in range(0, n, chunk_size)]


@contextmanager
def _stop_between_chunks():
    """Turn the first Ctrl-C into a request to stop after the chunks in flight.

    Yields a :class:`threading.Event` that is set on SIGINT; a second Ctrl-C raises
    :class:`KeyboardInterrupt` at once.  Outside the main thread nothing is installed.
    """
    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum, frame):
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()
        print(
            "\nCtrl-C: stopping after the chunks in flight (press again to abort at once)",
            file=sys.stderr,
        )

    old = signal.signal(signal.SIGINT, handler)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, old)


def part_path(path: Path) -> Path:
    """The temporary name of ``path`` in this process: ``.<name>.<pid>.part`` beside it."""
    return path.with_name(f".{path.name}.{os.getpid()}.part")


def _atomic_write_bytes(path: Path, data: bytes, stage: str) -> None:
    """Write ``data`` to a temporary file, flush it to disk and rename it to ``path``.

    A reader sees either no ``path`` or the complete file, never a part of it; the temporary
    file (:func:`part_path`) an interrupted write leaves behind is never read and is removed
    by the next run.  A write that fails (disk full, read-only folder) removes it and raises
    :class:`~pound_mc.errors.OutputError` naming ``path``.
    """
    tmp = part_path(path)
    try:
        with open(tmp, "wb") as fh:
            half = len(data) // 2
            fh.write(data[:half])
            fh.flush()
            _pause_at(f"{stage}:half")
            fh.write(data[half:])
            fh.flush()
            os.fsync(fh.fileno())
        _pause_at(f"{stage}:part")
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write: {exc.strerror or exc}", file=str(path)) from None


def _atomic_savez(path: Path, stage: str = "chunk", **arrays) -> None:
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    _atomic_write_bytes(path, buffer.getvalue(), stage)


def _atomic_write_text(path: Path, text: str, stage: str = "text") -> None:
    _atomic_write_bytes(path, text.encode(), stage)


def count_text(n: int, noun: str) -> str:
    """``1 chunk``, ``3 chunks``."""
    return f"{n:,} {noun}{'s' * (n != 1)}"


def plan_text(study, chunk_size: int | None = None, seconds_per_simulation: float | None = None):
    """A human-readable plan: axes, counts, chunks and (optionally) the estimated time."""
    chunk_size = chunk_size or study.chunk_size or default_chunk_size(study.n_simulations)
    lines = [f"study {study.name!r} (seed {study.seed}, hash {study.hash[:12]})"]
    lines.append(f"  records   : {len(study.records)} ({', '.join(study.record_names)})")
    for key, values in study.grid.items():
        names = study.grid_labels.get(key)
        span = ", ".join(names) if names else f"{values.min():g} .. {values.max():g}"
        lines.append(f"  grid      : {key} = {count_text(values.size, 'value')} {span}")
    lines.append(f"  sampling  : n = {study.n}, method {study.method}, seed {study.sampling_seed}")
    for v in study.variables:
        lines.append(f"    {v.key}: {v.source}")
    n = study.n_simulations
    lines.append(
        f"  simulations: {n:,} in {count_text(len(chunk_ranges(n, chunk_size)), 'chunk')} of "
        f"{min(chunk_size, n):,}"
    )
    if seconds_per_simulation is not None:
        total = n * seconds_per_simulation
        lines.append(
            f"  estimated : {seconds_per_simulation * 1e3:.3f} ms per simulation -> "
            f"{total:.1f} s ({total / 3600:.2f} h) with the current threads"
        )
    return "\n".join(lines)


@contextmanager
def output_lock(out_dir: Path, name: str):
    """Hold the exclusive advisory lock of study ``name``'s results in ``out_dir``.

    The lock file ``<out_dir>/.<name>.lock`` holds the process id of the run that has it.

    Raises
    ------
    pound_mc.errors.OutputError
        Another live process holds the lock (its id named), or the folder cannot be written.
    """
    path = Path(out_dir) / f".{name}.lock"
    while True:
        try:
            Path(out_dir).mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            where = exc.filename or path
            if Path(out_dir).exists() and not Path(out_dir).is_dir():
                raise OutputError("is a file, not a folder: give --out a folder",
                                  file=str(out_dir)) from None  # fmt: skip
            raise OutputError(f"cannot write: {exc.strerror or exc}", file=str(where)) from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            holder = os.pread(fd, 64, 0).decode(errors="replace").strip() or "unknown"
            os.close(fd)
            raise OutputError(
                f"another run (process {holder}) is writing these results; wait for it to "
                "end, or give another --out",
                file=str(path),
            ) from None
        try:
            same = os.fstat(fd).st_ino == os.stat(path).st_ino
        except FileNotFoundError:
            same = False
        if same:
            break
        os.close(fd)  # the holder removed the file as we opened it: take the new one
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield path
    finally:
        path.unlink(missing_ok=True)
        os.close(fd)


def _remove_parts(out_dir: Path, name: str) -> None:
    """Remove the temporary files killed runs left behind (the caller holds the lock)."""
    work = out_dir / name
    stale = list(work.glob(".*.part")) if work.is_dir() else []
    stale += out_dir.glob(f".{name}.nc.*part")
    for path in stale:
        path.unlink(missing_ok=True)


def _flat(table: dict, prefix: str = "") -> dict:
    """``{"contact.gap_m": 0.01, ...}`` of a TOML document (arrays of tables by index)."""
    out = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            value = {f"[{k}]": v for k, v in enumerate(value)}
            out.update(_flat(value, name))
        elif isinstance(value, dict):
            out.update(_flat(value, f"{name}."))
        else:
            out[name] = value
    return out


def _changed_keys(before: str, now: str, most: int = 3) -> str:
    """`` (sampling.n: 4 -> 8)``: the keys whose values differ between two study texts."""
    try:
        old, new = _flat(tomllib.loads(before)), _flat(tomllib.loads(now))
    except tomllib.TOMLDecodeError:
        return ""
    keys = [k for k in dict.fromkeys([*old, *new])
            if k not in old or k not in new or old[k] != new[k]]  # fmt: skip
    if not keys:
        return " (comments or layout only)"

    def value(table, key):
        return repr(table[key]) if key in table else "(none)"

    shown = [f"{k}: {value(old, k)} -> {value(new, k)}" for k in keys[:most]]
    more = f" and {len(keys) - most} more" if len(keys) > most else ""
    return f" ({', '.join(shown)}{more})"


def _changed_inputs(old: dict, inputs: dict, text: str | None = None) -> list[str]:
    """The inputs whose hash differs from the earlier run's (``manifest.json``).

    ``text``: the study's text now, told against the manifest's (if it holds one) key by key.
    """
    before = old.get("inputs")
    if not isinstance(before, dict):  # a manifest of an older version: the study hash only
        before = {"study": old.get("study_hash")}
    changed = []
    for key, value in inputs.items():
        if before.get(key) != value:
            what = "the study file" if key == "study" else key
            if key == "study" and text is not None and isinstance(old.get("study_text"), str):
                what += _changed_keys(old["study_text"], text)
            changed.append(what + (" (not in the earlier run)" if key not in before else ""))
    changed += [f"{key} (no longer read)" for key in before if key not in inputs]
    if old.get("pound_mc_version") != __version__:
        changed.append(f"the package version ({old.get('pound_mc_version')} -> {__version__})")
    return changed


def _not_ours(work: Path) -> list[str]:
    """What ``work`` holds that no run writes (a folder without a manifest; a plain file)."""
    if work.is_symlink() or not work.exists():
        return []
    if not work.is_dir():
        return [work.name]
    if (work / _MANIFEST).exists():
        return []
    ours = ("chunk_", ".chunk_")
    return sorted(p.name for p in work.iterdir()
                  if not (p.name.startswith(ours) or p.name.endswith(".part")))  # fmt: skip


def _check_manifest(work: Path, study, fresh: bool) -> None:
    manifest = work / _MANIFEST
    inputs = input_hashes(study)
    if foreign := _not_ours(work):  # --fresh removed a folder of the user's files
        more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
        shown = ", ".join(foreign[:3]) + more
        raise OutputError(
            f"exists and is no pound-mc results folder (it holds {shown}): give another --out "
            "or study name; nothing was removed or written",
            file=str(work),
        )
    if fresh and (work.exists() or work.is_symlink()):
        _remove_tree(work)
    elif manifest.exists():
        try:
            old = json.loads(manifest.read_text(encoding="utf-8"))
            if not isinstance(old, dict):
                raise ValueError("not a JSON object")
        except (OSError, ValueError) as exc:
            raise InputError(
                f"the manifest of earlier results is unreadable or corrupt ({exc}); run with "
                "--fresh to discard them and start again",
                file=str(manifest),
            ) from None
        changed = _changed_inputs(old, inputs, study.text)
        if changed:
            raise InputError(
                f"changed since the results in {work} were started: {'; '.join(changed)}; "
                "run with --fresh to discard them and start again",
                file=str(study.path) if study.path else None,
            )
    try:
        work.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create: {exc.strerror or exc}", file=str(work)) from None
    if not manifest.exists():
        _atomic_write_text(
            manifest,
            json.dumps(
                {
                    "study_name": study.name,
                    "study_hash": study.hash,
                    "n_simulations": study.n_simulations,
                    "shape": list(study.shape),
                    "pound_mc_version": __version__,
                    "inputs": inputs,
                    "study_text": study.text,  # to say which keys a changed study changed
                },
                indent=1,
            ),
            stage="manifest",
        )


def _discard_unstarted(work: Path, existed: bool) -> None:
    """Remove the manifest (and the folder) of a run refused before its first chunk file.

    Bad input found only once the kernels start (a hysteresis ``adaptive`` cannot step, say)
    would otherwise leave ``<out>/<name>/manifest.json`` of a run that never ran.  The folder
    goes too where the run made it (``existed`` false) and it is left empty; a link to a
    folder stays.
    """
    if not work.is_dir() or any(work.glob("chunk_*.npz")):
        return
    (work / _MANIFEST).unlink(missing_ok=True)
    if not existed and not work.is_symlink():
        try:
            work.rmdir()
        except OSError:  # not empty: not ours to remove
            pass


def _remove_tree(work: Path) -> None:
    """Remove earlier results (``--fresh``); a file or link in their place goes too."""
    try:
        if work.is_dir() and not work.is_symlink():
            shutil.rmtree(work)
        else:
            work.unlink()
    except OSError as exc:
        raise OutputError(f"cannot remove: {exc.strerror or exc}", file=str(work)) from None


def memory_estimate(study, layout: dict) -> int:
    """Bytes of memory a run holds for its results: the flat arrays, twice (the dataset).

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        The study.
    layout : dict
        :meth:`pound_mc.study.engine.StudyEngine.result_layout`.
    """
    per_sim = sum(
        np.dtype(dtype).itemsize * int(np.prod(tail, dtype=np.int64))
        for tail, dtype in layout.values()
    )
    return 2 * study.n_simulations * per_sim


def _physical_memory() -> int | None:
    """Bytes of physical memory of this machine, if the system says."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def _check_memory(study, layout: dict) -> None:
    """Refuse a study whose results do not fit in memory before anything is written."""
    need, have = memory_estimate(study, layout), _physical_memory()
    if have is not None and need > have:
        raise InputError(
            f"{study.n_simulations:,} simulations need about {need / 2**30:,.1f} GiB of memory "
            f"for their results, more than this machine's {have / 2**30:,.1f} GiB; make the "
            "grid or the number of samples smaller",
            file=str(study.path) if study.path else None,
            key="sampling.n",
        )


def _load_chunk(path: Path, study, start: int, stop: int, layout: dict) -> dict | None:
    """A finished chunk's arrays, or None if it is missing or not from this study."""
    if not path.exists():
        return None
    try:
        with open(path, "rb") as fh, np.load(fh, allow_pickle=False) as data:
            if str(data["study_hash"]) != study.hash:
                return None
            if int(data["start"]) != start or int(data["stop"]) != stop:
                return None
            out = {name: data[name] for name in layout}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None  # unreadable or partial: run it again
    if any(out[name].shape != (stop - start, *tail) for name, (tail, _) in layout.items()):
        return None
    return out


#: Runs chunks and yields ``(chunk, result)`` pairs as they finish (in any order).
Executor = Callable[[object, list[Chunk]], Iterator[tuple[Chunk, dict[str, np.ndarray]]]]


#: Chunks per thread from which the local executor runs whole chunks on each thread: every
#: chunk split over all threads waits at three barriers (a thread idles while the other ends
#: its slices), one chunk per thread waits only at the end of the run, for at most a chunk.
CHUNKS_PER_THREAD = 8


def local_executor(threads: int | None = None) -> Executor:
    """Executor that runs chunks in this process on numba's threads.

    With :data:`CHUNKS_PER_THREAD` chunks per thread or more, each thread runs whole chunks,
    its kernels on one numba thread (:func:`_chunks_on_threads`); with fewer, the chunks run
    one after the other, each split over every thread.  The results are the same either way:
    each simulation writes only its own slot.  The executor *drains*: when the iterable of
    chunks ends early (the runner's Ctrl-C), the chunks in flight finish and are yielded.

    Parameters
    ----------
    threads : int, optional
        Number of numba threads of the compiled kernels (default: numba's default); restored
        when the run ends.
    """
    if threads is not None and threads < 1:
        raise InputError(f"must be >= 1, got {threads}", key="--threads")

    def run(engine, chunks: Iterable[Chunk]):
        with numba_threads(threads):
            workers = numba.get_num_threads()
            many = hasattr(chunks, "__len__") and len(chunks) >= CHUNKS_PER_THREAD * workers
            if workers > 1 and many:
                yield from _chunks_on_threads(engine, chunks, workers)
                return
            for chunk in chunks:
                yield chunk, engine.run_range(chunk.start, chunk.stop)

    run.drains = True
    return run


def _chunks_on_threads(engine, chunks: Iterable[Chunk], workers: int):
    """Run whole chunks on ``workers`` threads, one numba thread each; yield them as they end.

    At most ``workers`` chunks are in flight, and the next one is taken from ``chunks`` when
    one ends (before it is yielded, so that no thread waits while its file is written).
    """

    def one(chunk):
        numba.set_num_threads(1)  # thread-local: this chunk's kernels run on this thread
        return engine.run_range(chunk.start, chunk.stop)

    feed = iter(chunks)
    running = {}
    pool = ThreadPoolExecutor(workers)
    try:
        for chunk in itertools.islice(feed, workers):
            running[pool.submit(one, chunk)] = chunk
        while running:
            done, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in sorted(done, key=lambda f: running[f].index):
                chunk = running.pop(future)
                result = future.result()
                following = next(feed, None)
                if following is not None:
                    running[pool.submit(one, following)] = following
                yield chunk, result
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


class _Feed:
    """The chunks to run, cut short by a Ctrl-C: iterating ends once ``stop`` is set."""

    def __init__(self, chunks: list[Chunk], stop: threading.Event):
        self.chunks = chunks
        self.stop = stop

    def __len__(self) -> int:
        return len(self.chunks)

    def __iter__(self) -> Iterator[Chunk]:
        for chunk in self.chunks:
            if self.stop.is_set():
                return
            yield chunk


def run_study(
    study,
    out_dir: str | Path = "outputs",
    *,
    threads: int | None = None,
    fresh: bool = False,
    chunk_size: int | None = None,
    progress: bool = True,
    engine=None,
    max_chunks: int | None = None,
    executor: Executor | None = None,
    on_chunk: Callable[[Chunk], None] | None = None,
):
    """Run every simulation of ``study`` and write ``<out_dir>/<name>.nc``.

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        A validated study.
    out_dir : str or Path
        Output folder; chunk files go to ``<out_dir>/<name>/``.
    threads : int, optional
        Number of threads of the compiled kernels (default: numba's default); only for the
        default executor.
    fresh : bool
        Discard earlier results of this study (needed after the study file changed).
    chunk_size : int, optional
        Simulations per chunk (default: the study's ``chunk_size``, else
        :func:`default_chunk_size`).
    progress : bool
        Show a progress bar with rate and ETA.
    engine : pound_mc.study.engine.StudyEngine, optional
        Prepared engine (records loaded, samples drawn); made from ``study`` if not given.
    max_chunks : int, optional
        Stop after running this many chunks (the run stays resumable); for tests and drills.
    executor : callable, optional
        Runs the chunks still to do (:data:`Executor`); default :func:`local_executor`.
    on_chunk : callable, optional
        Called with each :class:`Chunk` once its file is written (for progress hooks and tests).

    Returns
    -------
    RunReport
        Counts, time and the dataset path (``None`` while incomplete).
    """
    if executor is None:
        executor = local_executor(threads)
    elif threads is not None:
        raise InputError("sets the threads of the local backend only", key="--threads")
    out_dir = Path(out_dir)
    chunk_size = chunk_size or study.chunk_size or default_chunk_size(study.n_simulations)
    engine = engine or StudyEngine(study)
    layout = engine.result_layout()  # {name: (shape after the simulation axis, dtype)}
    _check_memory(study, layout)
    with output_lock(out_dir, study.name):
        _remove_parts(out_dir, study.name)
        work = out_dir / study.name
        started = not fresh and (work / _MANIFEST).exists()
        existed = work.exists() and not fresh
        try:
            return _run_locked(
                study, out_dir, engine, layout, fresh, chunk_size, progress, max_chunks,
                executor, on_chunk,
            )  # fmt: skip
        except InputError:
            if not started:  # refused before its first chunk: leave nothing behind
                _discard_unstarted(work, existed)
            raise


def _chunk_path(work: Path, chunk_size: int, index: int) -> Path:
    """The file of chunk ``index`` of a run cut into chunks of ``chunk_size`` simulations."""
    return work / f"chunk_{chunk_size}_{index:06d}.npz"


def _chunk_size_of(path: Path) -> int | None:
    """The chunk size in the name of a :func:`_chunk_path` file (None: not such a name)."""
    parts = path.stem.split("_")
    if len(parts) != 3 or parts[0] != "chunk" or not (parts[1] + parts[2]).isdigit():
        return None
    return int(parts[1]) or None


def _resumed_chunk_size(work: Path, chunk_size: int) -> int:
    """The chunk size to go on with: that of the finished chunks in ``work``, if any.

    A run resumed with another ``chunk_size`` (``--chunk-size``) keeps the chunks it has: the
    size they were cut to wins, and a note says so (without them, every simulation would run
    again).  Among chunk files of several sizes, the requested size wins if it has any, else
    the size with the most files.
    """
    sizes = collections.Counter()
    for path in work.glob("chunk_*_*.npz"):
        size = _chunk_size_of(path)
        if size is not None:
            sizes[size] += 1
    if not sizes or chunk_size in sizes:
        return chunk_size
    size, count = sizes.most_common(1)[0]
    print(
        f"{work} holds {count_text(count, 'finished chunk')} of {size:,} simulations: going on "
        f"with that chunk size ({chunk_size:,} applies to a fresh run, --fresh)",
        file=sys.stderr,
        flush=True,
    )
    return size


def _run_locked(study, out_dir, engine, layout, fresh, chunk_size, progress, max_chunks, executor,
                on_chunk) -> RunReport:  # fmt: skip
    """:func:`run_study` once the output lock is held."""
    work = out_dir / study.name
    _check_manifest(work, study, fresh)

    n = study.n_simulations
    chunk_size = _resumed_chunk_size(work, chunk_size)  # --fresh removed them
    ranges = chunk_ranges(n, chunk_size)
    try:
        flat = {name: np.empty((n, *tail), dtype=dtype) for name, (tail, dtype) in layout.items()}
    except MemoryError:
        raise InputError(
            f"not enough memory for the results of {n:,} simulations; make the grid or the "
            "number of samples smaller",
            file=str(study.path) if study.path else None,
            key="sampling.n",
        ) from None
    todo = []
    for k, (start, stop) in enumerate(ranges):
        path = _chunk_path(work, chunk_size, k)
        done = _load_chunk(path, study, start, stop, layout)
        if done is None:
            todo.append(Chunk(k, start, stop, path))
        else:
            for name in layout:
                flat[name][start:stop] = done[name]
    if max_chunks is not None:
        todo_now = todo[: max(0, max_chunks)]
    else:
        todo_now = todo

    # compile (or load from the cache) the run's kernels before the bar starts, so that its
    # rate and ETA measure simulations only
    warmup_s = 0.0
    compiled = False
    if todo_now:
        warm = getattr(executor, "warm_up", warm_up)  # where the chunks run
        warmup_s, compiled = warm(engine, todo_now[0].start)  # with or without the bar
    t0 = time.perf_counter()
    ran = 0
    simulations_run = 0
    interrupted = False
    bar = tqdm(
        total=n,
        initial=n - sum(c.stop - c.start for c in todo),
        unit="sim",
        unit_scale=True,
        disable=not progress,
        desc=study.name,
        smoothing=0.1,
    )
    try:
        with (
            _stop_between_chunks() as stop_requested,
            closing(iter(executor(engine, _Feed(todo_now, stop_requested)))) as results,
        ):
            for chunk, result in results:
                _atomic_savez(
                    chunk.path,
                    stage=f"chunk:{chunk.index}",
                    study_hash=np.array(study.hash),
                    start=np.array(chunk.start),
                    stop=np.array(chunk.stop),
                    **{name: result[name] for name in layout},
                )
                for name in layout:
                    flat[name][chunk.start : chunk.stop] = result[name]
                ran += 1
                simulations_run += chunk.stop - chunk.start
                bar.update(chunk.stop - chunk.start)
                _pause_at(f"chunks:{ran}")
                if on_chunk is not None:
                    on_chunk(chunk)
                # a draining executor yields the chunks in flight once the feed has stopped
                if stop_requested.is_set() and not getattr(executor, "drains", False):
                    break
        interrupted = stop_requested.is_set() and ran < len(todo)
    finally:
        bar.close()
    seconds = time.perf_counter() - t0
    complete = ran == len(todo)
    if not complete:
        return RunReport(None, n, len(ranges), ran, seconds, False, interrupted, simulations_run,
                         warmup_s, compiled)  # fmt: skip

    _pause_at("dataset")
    results = {name: a.reshape(study.shape + a.shape[1:]) for name, a in flat.items()}
    ds = build_dataset(study, results, engine.dataset_parameters(), provenance=engine.provenance())
    _pause_at("netcdf")
    path = write_netcdf(ds, out_dir / f"{study.name}.nc")
    _pause_at("done")
    seconds = time.perf_counter() - t0
    return RunReport(path, n, len(ranges), ran, seconds, True, False, simulations_run, warmup_s,
                     compiled)  # fmt: skip
