"""Execute a study: chunks of simulations through the compiled kernels, resumable.

The simulations of a study are numbered in C order of ``study.shape`` = ``(record, *grid
axes, sample)`` and cut into chunks of ``chunk_size``.  Each finished chunk is written
atomically to ``<out>/<name>/chunk_<size>_NNNNNN.npz`` (temporary file renamed into place), so an
interrupted run (Ctrl-C, a killed process) loses at most the chunks in flight; re-running the
same study skips the finished ones.  When every chunk is done the dataset is assembled and
written to ``<out>/<name>.nc``.

Resuming is safe (:mod:`pound_mc.study.resume`): the manifest and every chunk file hold the
run's identity (the hashes of the study text, of each record's samples as the engine holds
them and of the sampled values, and the versions of the packages that supply the data); a
chunk of other inputs is never mixed in: the run is refused, naming what changed, unless
``fresh=True`` (then the earlier results are discarded).

One writer per output, and no write through a link (:mod:`pound_mc.study.files`): a run holds
an exclusive lock on ``<out>/.<name>.lock`` from the manifest check to the dataset, a second
run on the same study and folder is refused at once, and every file it writes is one it has
just created, renamed into place.

Every simulation writes only its own output slot and all random numbers are drawn before any
chunk runs, so results do not depend on thread count, chunk size or backend.

Chunks run through an *executor*: a callable ``executor(engine, chunks)`` that yields
``(chunk, result)`` pairs as chunks finish, in any order.  The default runs them in this process
on numba's threads (:func:`local_executor`); :mod:`pound_mc.study.distributed` runs them on a Dask
cluster.  Either way this process alone writes the chunk files and the dataset.  An executor
whose chunks run elsewhere has a ``warm_up(engine, index, quiet=...)`` attribute, called instead
of :func:`~pound_mc.study.warmup.warm_up` before the progress bar starts, so that the kernels
compile where the chunks run (the Dask workers), not here.
"""

from __future__ import annotations

import io
import itertools
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait
from contextlib import closing, contextmanager
from dataclasses import dataclass
from pathlib import Path

import numba
import numpy as np
from tqdm.auto import tqdm

from pound_mc.errors import InputError
from pound_mc.integrators.threads import numba_threads
from pound_mc.study.dataset import build_dataset, write_netcdf
from pound_mc.study.engine import StudyEngine
from pound_mc.study.files import output_lock, pause_at, remove_parts, write_bytes_atomically
from pound_mc.study.limits import physical_memory
from pound_mc.study.resume import (
    MANIFEST,
    ChunkOfOtherInputs,
    RunIdentity,
    check_chunks,
    check_results_folder,
    chunk_path,
    discard_unstarted,
    load_chunk,
    resumed_chunk_size,
    write_manifest,
)
from pound_mc.study.status import STATUS
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
    "memory_estimate",
]


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
    n = f"n = {study.n}"
    if study.base_n is not None:  # Saltelli's design: N (D + 2) samples
        n = f"n = {study.n} (base N = {study.base_n} x {len(study.variables) + 2})"
    lines.append(f"  sampling  : {n}, method {study.method}, seed {study.sampling_seed}")
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


def _check_memory(study, layout: dict) -> None:
    """Refuse a study whose results do not fit in memory before anything is written."""
    need, have = memory_estimate(study, layout), physical_memory()
    if have is not None and need > have:
        raise InputError(
            f"{study.n_simulations:,} simulations need about {need / 2**30:,.1f} GiB of memory "
            f"for their results, more than this machine's {have / 2**30:,.1f} GiB; make the "
            "grid or the number of samples smaller",
            file=str(study.path) if study.path else None,
            key="sampling.n",
        )


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
        remove_parts(out_dir, study.name)
        work = out_dir / study.name
        started = not fresh and ((work / MANIFEST).exists() or (work / MANIFEST).is_symlink())
        existed = work.exists() and not fresh
        try:
            return _run_locked(
                study, out_dir, engine, layout, fresh, chunk_size, progress, max_chunks,
                executor, on_chunk,
            )  # fmt: skip
        except InputError:
            if not started:  # refused before its first chunk: leave nothing behind
                discard_unstarted(work, existed)
            raise
        finally:
            STATUS.clear()


def _results_arrays(study, layout: dict) -> dict[str, np.ndarray]:
    """Empty flat arrays of every result (an InputError where memory runs out)."""
    n = study.n_simulations
    try:
        return {name: np.empty((n, *tail), dtype=dtype) for name, (tail, dtype) in layout.items()}
    except MemoryError:
        raise InputError(
            f"not enough memory for the results of {n:,} simulations; make the grid or the "
            "number of samples smaller",
            file=str(study.path) if study.path else None,
            key="sampling.n",
        ) from None


def _finished_chunks(work: Path, study, identity: RunIdentity, ranges, chunk_size: int,
                     layout: dict, flat: dict) -> list[Chunk]:  # fmt: skip
    """Fill ``flat`` from the finished chunk files; the chunks still to run.

    Raises
    ------
    InputError
        A chunk file of other inputs (:func:`~pound_mc.study.resume.check_chunks`).
    """
    todo, others = [], []
    for k, (start, stop) in enumerate(ranges):
        path = chunk_path(work, chunk_size, k)
        try:
            done = load_chunk(path, identity, start, stop, layout)
        except ChunkOfOtherInputs as exc:
            others.append((path, exc.inputs))
            continue
        if done is None:
            todo.append(Chunk(k, start, stop, path))
        else:
            for name in layout:
                flat[name][start:stop] = done[name]
    check_chunks(work, study, identity, others)
    return todo


@contextmanager
def _redrawn(bar, every_s: float = 1.0):
    """Redraw the progress ``bar`` every ``every_s`` seconds while the block runs.

    The bar draws itself when a chunk finishes; between chunks (a long chunk, the first one)
    its elapsed time and rate are redrawn, so the run is never silent for long.
    """
    if bar.disable:
        yield
        return
    done = threading.Event()

    def redraw():
        while not done.wait(every_s):
            bar.refresh()

    thread = threading.Thread(target=redraw, daemon=True, name="bar")
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()


def _write_chunk(chunk: Chunk, result: dict, identity: RunIdentity, study, layout: dict) -> None:
    """Write a finished chunk's file: its range, the run's identity and its results."""
    buffer = io.BytesIO()
    np.savez(
        buffer,
        study_hash=np.array(study.hash),
        start=np.array(chunk.start),
        stop=np.array(chunk.stop),
        **identity.chunk_fields(),
        **{name: result[name] for name in layout},
    )
    write_bytes_atomically(chunk.path, buffer.getvalue(), stage=f"chunk:{chunk.index}")


def _run_locked(study, out_dir, engine, layout, fresh, chunk_size, progress, max_chunks, executor,
                on_chunk) -> RunReport:  # fmt: skip
    """:func:`run_study` once the output lock is held."""
    STATUS.say("checking the chunks of earlier runs")
    work = out_dir / study.name
    identity = RunIdentity.of(study, engine)  # of the data the engine holds
    has_manifest = check_results_folder(work, study, fresh, identity)

    n = study.n_simulations
    chunk_size = resumed_chunk_size(work, chunk_size)  # --fresh removed them
    ranges = chunk_ranges(n, chunk_size)
    flat = _results_arrays(study, layout)
    todo = _finished_chunks(work, study, identity, ranges, chunk_size, layout, flat)
    if not has_manifest:
        write_manifest(work, study, identity)
    todo_now = todo if max_chunks is None else todo[: max(0, max_chunks)]

    # compile (or load from the cache) the run's kernels before the bar starts, so that its
    # rate and ETA measure simulations only
    warmup_s = 0.0
    compiled = False
    if todo_now:
        warm = getattr(executor, "warm_up", warm_up)  # where the chunks run
        warmup_s, compiled = warm(engine, todo_now[0].start)  # with or without the bar
    STATUS.clear()  # the bar's line now
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
            _redrawn(bar),
            closing(iter(executor(engine, _Feed(todo_now, stop_requested)))) as results,
        ):
            for chunk, result in results:
                _write_chunk(chunk, result, identity, study, layout)
                for name in layout:
                    flat[name][chunk.start : chunk.stop] = result[name]
                ran += 1
                simulations_run += chunk.stop - chunk.start
                bar.update(chunk.stop - chunk.start)
                pause_at(f"chunks:{ran}")
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

    pause_at("dataset")
    STATUS.say(f"writing {study.name}.nc")
    results = {name: a.reshape(study.shape + a.shape[1:]) for name, a in flat.items()}
    ds = build_dataset(study, results, engine.dataset_parameters(), provenance=engine.provenance())
    pause_at("netcdf")
    path = write_netcdf(ds, out_dir / f"{study.name}.nc")
    pause_at("done")
    seconds = time.perf_counter() - t0
    return RunReport(path, n, len(ranges), ran, seconds, True, False, simulations_run, warmup_s,
                     compiled)  # fmt: skip
