"""Run a study's chunks on a Dask cluster (optional: ``pip install "pound-mc[dask]"``).

The client (the process that runs ``pound-mc run``) prepares the study as for a local run -
records read, every random number drawn - and sends the prepared
:class:`~pound_mc.study.engine.StudyEngine` once to every worker.  Each task runs one chunk's range
of simulations through the same :meth:`~pound_mc.study.engine.StudyEngine.run_range` as the local
backend, on one numba thread, and returns the arrays; the client writes each chunk file
atomically as results arrive and assembles the dataset at the end
(:func:`pound_mc.study.runner.run_study`).  The chunk files, the resume logic and the numbers are
the local run's: a run started on a cluster can be finished locally and the other way round.

A worker lost mid-study (a killed process, a lost node) loses only its chunks in flight: the
scheduler gives them to other workers; a task that raises is tried again ``retries`` times.

Start workers with one thread each and one worker process per core
(``dask worker ADDRESS --nworkers N --nthreads 1``): the kernels release the GIL but each
task uses one numba thread, so a worker thread is a core.
"""

from __future__ import annotations

import logging
import uuid
from collections.abc import Iterable
from contextlib import ExitStack
from pathlib import Path

import numba

from pound_mc.errors import InputError
from pound_mc.study.runner import Chunk, run_study

__all__ = ["run_study_distributed", "dask_executor", "run_chunk"]

_INSTALL = 'pip install "pound-mc[dask]"'


def _import_distributed():
    """The ``distributed`` module, or an :class:`InputError` saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise InputError(
            f"running on a Dask cluster needs dask.distributed: {_INSTALL}", key="--scheduler"
        ) from None
    return distributed


def run_chunk(engine, start: int, stop: int) -> dict:
    """Run simulations ``start .. stop-1`` on one numba thread (the task of a Dask worker).

    Parameters
    ----------
    engine : pound_mc.study.engine.StudyEngine
        The prepared study.
    start, stop : int
        Half-open range of flat simulation indices.

    Returns
    -------
    dict
        ``{output name: array}`` as :meth:`pound_mc.study.engine.StudyEngine.run_range`.
    """
    old = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        return engine.run_range(start, stop)
    finally:
        numba.set_num_threads(old)


def dask_executor(client, *, retries: int = 3):
    """Executor (see :func:`pound_mc.study.runner.run_study`) that runs chunks on a Dask cluster.

    Parameters
    ----------
    client : distributed.Client
        Connected client.
    retries : int
        Times a chunk whose task raised is tried again (a lost worker's chunks are
        rescheduled by the scheduler regardless).
    """
    distributed = _import_distributed()

    def run(engine, chunks: Iterable[Chunk]):
        chunks = list(chunks)
        if not chunks:
            return
        tag = f"pound-mc-{engine.study.name}-{uuid.uuid4().hex[:8]}"
        [shared] = client.scatter([engine], broadcast=True, hash=False)
        futures = {}
        try:
            for chunk in chunks:
                future = client.submit(
                    run_chunk,
                    shared,
                    chunk.start,
                    chunk.stop,
                    key=f"{tag}-{chunk.index}",
                    retries=retries,
                    pure=False,
                )
                futures[future] = chunk
            for future in distributed.as_completed(list(futures)):
                chunk = futures.pop(future)
                result = future.result()
                future.release()
                yield chunk, result
        finally:
            if futures:
                client.cancel(list(futures))
            client.cancel([shared])

    return run


def _connect(distributed, stack: ExitStack, scheduler: str | None, workers: int | None):
    if scheduler is not None:
        try:
            return stack.enter_context(distributed.Client(scheduler, timeout="20s"))
        except (OSError, TimeoutError, ValueError) as exc:
            raise InputError(
                f"cannot connect to the Dask scheduler {scheduler!r}: {exc}", key="--scheduler"
            ) from None
    if workers is None or workers < 1:
        raise InputError(f"must be >= 1, got {workers}", key="--workers")
    cluster = stack.enter_context(
        distributed.LocalCluster(
            n_workers=workers,
            processes=True,
            threads_per_worker=1,
            host="127.0.0.1",
            dashboard_address=":0",  # the scheduler's HTTP server on a free port
            silence_logs=logging.ERROR,
            env={"NUMBA_NUM_THREADS": "1"},
        )
    )
    return stack.enter_context(distributed.Client(cluster))


def run_study_distributed(
    study,
    out_dir: str | Path = "outputs",
    *,
    scheduler: str | None = None,
    workers: int | None = None,
    client=None,
    retries: int = 3,
    **kwargs,
):
    """Run ``study`` on a Dask cluster and write ``<out_dir>/<name>.nc``.

    Give exactly one of ``scheduler`` (the address of a running scheduler), ``workers`` (start
    a local cluster of that many one-threaded worker processes on 127.0.0.1) or ``client``.

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        A validated study.
    out_dir : str or Path
        Output folder, as for :func:`pound_mc.study.runner.run_study`.
    scheduler : str, optional
        Scheduler address (``tcp://host:8786``).
    workers : int, optional
        Worker processes of a local cluster.
    client : distributed.Client, optional
        An existing client (left open).
    retries : int
        Retries of a chunk whose task raised.
    **kwargs
        ``fresh``, ``chunk_size``, ``progress``, ``engine``, ``max_chunks``, ``on_chunk`` of
        :func:`pound_mc.study.runner.run_study`.

    Returns
    -------
    pound_mc.study.runner.RunReport
        As for a local run.
    """
    given = [
        name for name, v in (("--scheduler", scheduler), ("--workers", workers)) if v is not None
    ]
    if client is not None:
        given.append("client")
    if len(given) != 1:
        raise InputError(
            "give either --scheduler ADDRESS or --workers N" + (f", not {given}" if given else ""),
            key="--scheduler",
        )
    distributed = _import_distributed()
    with ExitStack() as stack:
        if client is None:
            client = _connect(distributed, stack, scheduler, workers)
        return run_study(study, out_dir, executor=dask_executor(client, retries=retries), **kwargs)
