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

Cluster faults end the run with a :class:`~pound_mc.errors.ClusterError` (one line, exit status
2 on the command line), never a traceback, and the chunks written so far are kept, so the same
command (on the cluster or locally) resumes unchanged:

* an address whose scheme is not ``tcp://`` (``tls://`` needs certificates, ``ucx://`` a
  transport pound-mc does not set up) is refused before connecting;
* an unreachable scheduler, or one that accepts the connection but does not answer (a frozen
  process), is given up after ``timeout_s`` (default :data:`TIMEOUT_S`);
* all workers lost (the engine scattered to them is lost with them), the scheduler lost, or a
  chunk that failed ``retries`` times: the error names what happened;
* no chunk finished for ``timeout_s`` seconds (a frozen scheduler, no workers left): given up.

There is no automatic retry of the whole run: after the cause is fixed, run the same command
again.

Start workers with one thread each and one worker process per core
(``dask worker ADDRESS --nworkers N --nthreads 1``): the kernels release the GIL but each
task uses one numba thread, so a worker thread is a core.

Before the progress bar starts, every worker connected at that time runs one simulation of the
study (:func:`warm_up_worker`), which compiles its kernels or loads them from its cache; the
client, which runs no simulation, compiles nothing.  So the bar's rate and ETA measure the
chunks alone, as for a local run; a worker that joins later loads its kernels in its first
chunk.
"""

from __future__ import annotations

import asyncio
import logging
import time
import uuid
from collections.abc import Iterable
from contextlib import ExitStack, contextmanager
from pathlib import Path

import numba

from pound_mc.errors import ClusterError, InputError
from pound_mc.study.runner import Chunk, run_study
from pound_mc.study.status import STATUS
from pound_mc.study.warmup import noticed

__all__ = ["run_study_distributed", "dask_executor", "run_chunk", "warm_up_worker", "TIMEOUT_S"]

_INSTALL = 'pip install "pound-mc[dask]"'
#: Seconds to wait for the scheduler to answer, and for the next chunk to finish.
TIMEOUT_S = 600.0
#: Address schemes pound-mc connects to.
SCHEMES = ("tcp",)


def _import_distributed(key: str = "--scheduler"):
    """The ``distributed`` module, or an :class:`InputError` saying how to install it.

    ``key``: the option that asked for a cluster (``--scheduler`` or ``--workers``).
    """
    try:
        import distributed
    except ImportError:
        raise InputError(
            f"running on a Dask cluster needs dask.distributed: {_INSTALL}", key=key
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
    except InputError as exc:
        # refused input (a scene the kernels do not run) fails the same on every try: it
        # comes back as the result, raised by the client as a local run raises it, without
        # retries or the worker's log of a failed task
        return exc
    finally:
        numba.set_num_threads(old)


def warm_up_worker(engine, index: int) -> float:
    """Run simulation ``index`` once on this worker, its result discarded: wall time [s].

    The worker compiles the study's kernels, or loads them from its cache, before any chunk
    (:func:`pound_mc.study.warmup.warm_up` on a worker).
    """
    t0 = time.perf_counter()
    refused = run_chunk(engine, index, index + 1)
    return refused if isinstance(refused, InputError) else time.perf_counter() - t0


#: Longest part of a cluster's own message a fault quotes (the rest is its task keys).
_FAULT_TEXT = 120
#: Exceptions of ``distributed`` that say the futures were cancelled: one future's, and the
#: many futures' one (whose message lists every key).
_CANCELLED = ("FutureCancelledError", "FuturesCancelledError", "CancelledError")


def _fault(exc: BaseException) -> str:
    """What a cluster failure means, in words: one line, without the cluster's task keys."""
    name = type(exc).__name__
    full = str(exc)
    text = full.strip().splitlines()[0] if full.strip() else ""
    if len(text) > _FAULT_TEXT:
        text = text[: _FAULT_TEXT - 3] + "..."
    if name in _CANCELLED:
        return "all workers were lost (and the study sent to them): the chunks were cancelled"
    if "lost" in full.lower() and "scatter" in full.lower():
        return f"all workers were lost (and the study sent to them): {name}: {text}"
    if name in ("CommClosedError", "StreamClosedError"):
        return f"the connection to the scheduler was lost: {name}: {text}"
    if name == "KilledWorker":
        return f"a chunk killed every worker that ran it: {text}"
    return f"{name}: {text}"


def dask_executor(client, *, retries: int = 3, timeout_s: float = TIMEOUT_S,
                  key: str = "--scheduler"):  # fmt: skip
    """Executor (see :func:`pound_mc.study.runner.run_study`) that runs chunks on a Dask cluster.

    Parameters
    ----------
    client : distributed.Client
        Connected client.
    retries : int
        Times a chunk whose task raised is tried again (a lost worker's chunks are
        rescheduled by the scheduler regardless).
    timeout_s : float
        Seconds without a finished chunk after which the cluster is given up [s].
    key : str
        The option that asked for the cluster (``--scheduler`` or ``--workers``), which its
        errors name.

    Raises
    ------
    pound_mc.errors.ClusterError
        The cluster failed (workers or scheduler lost, no chunk finished in ``timeout_s``).
    """
    distributed = _import_distributed()
    sent = {}  # the engine scattered to the workers (by the warm-up), reused by the run

    def scatter(engine):
        if sent.get("engine") is not engine:
            [sent["future"]] = client.scatter([engine], broadcast=True, hash=False,
                                              timeout=timeout_s)  # fmt: skip
            sent["engine"] = engine
        return sent["future"]

    def warm_up(engine, index: int = 0, *, stream=None, quiet: bool = False):
        """Run simulation ``index`` once on every worker (:func:`warm_up_worker`).

        Returns the wall time [s] (sending the study, which a new worker process imports
        pound-mc to receive, then the simulations) and whether the simulations took long
        enough to be compiling, as :func:`pound_mc.study.warmup.warm_up`.
        """
        t0 = time.perf_counter()
        try:
            if not quiet:  # a new worker imports pound-mc to receive it: seconds
                STATUS.say("sending the study to the Dask workers")
            shared = scatter(engine)  # not in the notice's time: imports, not compiling
            workers = list(client.scheduler_info()["workers"])
            tag = f"pound-mc-warm-up-{uuid.uuid4().hex[:8]}"
            futures = [
                client.submit(
                    warm_up_worker,
                    shared,
                    index,
                    key=f"{tag}-{k}",
                    workers=[w],
                    allow_other_workers=True,
                    pure=False,
                )
                for k, w in enumerate(workers)
            ]
            where = f"on {len(workers)} Dask worker{'s' * (len(workers) != 1)}"
            _, compiled = noticed(lambda: distributed.wait(futures, timeout=timeout_s),
                                  stream=stream, quiet=quiet, where=where)  # fmt: skip
            results = [future.result(timeout=timeout_s) for future in futures]
        except Exception as exc:  # every failure of the cluster, whatever its class
            raise ClusterError(
                f"the Dask cluster failed while its workers loaded the kernels: {_fault(exc)}",
                key=key,
            ) from None
        for result in results:
            if isinstance(result, InputError):
                raise result
        return time.perf_counter() - t0, compiled

    def run(engine, chunks: Iterable[Chunk]):
        chunks = list(chunks)
        if not chunks:
            return
        tag = f"pound-mc-{engine.study.name}-{uuid.uuid4().hex[:8]}"
        futures = {}
        failed = False
        try:
            shared = scatter(engine)
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
            while futures:
                try:
                    done, _ = distributed.wait(
                        list(futures), timeout=timeout_s, return_when="FIRST_COMPLETED"
                    )
                except TimeoutError:
                    failed = True
                    raise ClusterError(
                        f"no chunk finished in {timeout_s:g} s (a scheduler that does not "
                        "answer, or no workers left); finished chunks are kept: run again to "
                        "resume",
                        key=key,
                    ) from None
                for future in done:
                    chunk = futures.pop(future)
                    result = future.result(timeout=timeout_s)
                    future.release()
                    if isinstance(result, InputError):  # the cluster is sound: cancel the rest
                        raise result
                    yield chunk, result
        except InputError:  # a refused input (ClusterError too): as it is
            raise
        except GeneratorExit:
            raise
        except Exception as exc:  # every failure of the cluster, whatever its class
            failed = True
            raise ClusterError(
                f"the Dask cluster failed: {_fault(exc)}; finished chunks are kept: run again "
                "to resume",
                key=key,
            ) from None
        finally:
            if not failed:
                if futures:
                    client.cancel(list(futures))
                if "shared" in locals():
                    client.cancel([shared])
            sent.clear()

    run.warm_up = warm_up
    return run


async def _identity(distributed, address: str) -> dict:
    """Ask the scheduler at ``address`` who it is (a scheduler that does not answer hangs)."""
    comm = await distributed.comm.connect(address)
    try:
        await comm.write({"op": "identity", "reply": True})
        return await comm.read()
    finally:
        comm.abort()


def _connect(distributed, stack: ExitStack, scheduler: str | None, workers: int | None,
             timeout_s: float = TIMEOUT_S):  # fmt: skip
    if scheduler is not None:
        scheme, sep, _ = scheduler.partition("://")
        if sep and scheme.lower() not in SCHEMES:
            raise ClusterError(
                f"unsupported address scheme {scheme + '://'!r} in {scheduler!r}; pound-mc "
                f"connects to {', '.join(s + '://' for s in SCHEMES)} schedulers",
                key="--scheduler",
            )
        try:
            asyncio.run(asyncio.wait_for(_identity(distributed, scheduler), timeout_s))
            return stack.enter_context(distributed.Client(scheduler, timeout=timeout_s))
        except Exception as exc:  # unreachable, refused, no answer: every way connecting fails
            raise ClusterError(
                f"cannot connect to the Dask scheduler {scheduler!r} within {timeout_s:g} s: "
                f"{type(exc).__name__}: {exc or 'no answer'}",
                key="--scheduler",
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
            silence_logs=logging.CRITICAL,  # a worker's heartbeat tracebacks are not ours
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
    timeout_s: float = TIMEOUT_S,
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
    timeout_s : float
        Seconds to wait for the scheduler to answer and for each next chunk [s].
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
    distributed = _import_distributed(given[0] if given[0] != "client" else "--scheduler")
    key = "--workers" if workers is not None else "--scheduler"
    with ExitStack() as stack:
        stack.enter_context(_quiet_cluster_logs())
        stack.callback(STATUS.clear)  # last: after the cluster has stopped
        if client is None:
            if kwargs.get("progress", True):  # on a terminal: the cluster takes seconds
                STATUS.say(f"starting {workers} Dask worker{'s' * (workers != 1)}"
                           if workers is not None else f"connecting to {scheduler}")  # fmt: skip
            client = _connect(distributed, stack, scheduler, workers, timeout_s)
        executor = dask_executor(client, retries=retries, timeout_s=timeout_s, key=key)
        report = run_study(study, out_dir, executor=executor, **kwargs)
        if workers is not None and kwargs.get("progress", True):  # stopping takes seconds
            STATUS.say(f"stopping the Dask worker{'s' * (workers != 1)}")
        return report


@contextmanager
def _quiet_cluster_logs():
    """Keep ``distributed``'s own log records (tracebacks of a lost scheduler) off the screen.

    The run says what failed in one line (:class:`~pound_mc.errors.ClusterError`); the
    client's loggers would print the same failure again as tracebacks.
    """
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        logger.setLevel(level)
