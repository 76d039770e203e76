"""Dask backend on a real LocalCluster: identical results, a worker killed mid-study."""

import logging
import os
import signal
import sys
import time

import pytest
from test_runner import STUDY, N, _assert_identical

from pound_mc.cli import main
from pound_mc.study.definition import load_study
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import chunk_ranges, run_study
from studies import study_text

distributed = pytest.importorskip("distributed")

pytestmark = [
    pytest.mark.slow,
    # closing a cluster whose worker was killed can leave a socket or a pipe to the dead
    # process unclosed until garbage collection; that is the cluster's shutdown, not ours
    pytest.mark.filterwarnings("ignore::ResourceWarning"),
    pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning"),
]


def _local_cluster(n_workers: int):
    """One-threaded worker processes on loopback (the layout ``--workers N`` starts)."""
    return distributed.LocalCluster(
        n_workers=n_workers,
        processes=True,
        threads_per_worker=1,
        host="127.0.0.1",
        dashboard_address=":0",  # the scheduler's HTTP server on a free port
        silence_logs=logging.CRITICAL,
        env={"NUMBA_NUM_THREADS": "1"},
    )


@pytest.fixture(scope="module")
def cluster():
    """Two one-threaded worker processes on loopback (the layout ``--workers 2`` starts)."""
    with _local_cluster(2) as cluster:
        yield cluster


@pytest.fixture(scope="module")
def study_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "small.toml"
    path.write_text(STUDY)
    return path


@pytest.fixture(scope="module")
def reference(study_file, tmp_path_factory):
    """The local backend's dataset: one chunk, one thread."""
    out = tmp_path_factory.mktemp("ref")
    report = run_study(load_study(study_file), out, threads=1, chunk_size=N, progress=False)
    return report.path


def test_scheduler_run_equals_local_run(cluster, study_file, reference, tmp_path, capsys):
    out = tmp_path / "dask"
    argv = ["run", str(study_file), "--out", str(out), "--no-plot", "--no-progress"]
    assert main([*argv, "--scheduler", cluster.scheduler_address, "--chunk-size", "5"]) == 0
    assert len(list((out / "small").glob("chunk_5_*.npz"))) == len(chunk_ranges(N, 5))
    _assert_identical(reference, out / "small.nc")
    # resumable exactly like a local run: nothing left to do, the same dataset again
    assert main([*argv, "--chunk-size", "5"]) == 0
    assert "0 of 10 chunks run" in capsys.readouterr().out
    _assert_identical(reference, out / "small.nc")


def _compiled_batch_kernels() -> int:
    """Signatures of the batch kernels compiled or loaded from the cache in this process."""
    from pound_mc.integrators import batch

    return sum(len(getattr(f, "overloads", ())) for f in vars(batch).values())


def test_every_worker_loads_the_kernels_before_the_first_chunk(study_file, tmp_path):
    # The progress bar's rate and ETA measure the chunks only: before it starts, each worker
    # runs one simulation (compiling its kernels or loading them from its cache), as a local
    # run does before its bar.  Before this, each worker paid it in its first chunk.
    from pound_mc.study.distributed import dask_executor, run_study_distributed

    study = load_study(study_file)
    with (
        _local_cluster(2) as cluster,
        distributed.Client(cluster) as client,
    ):
        assert set(client.run(_compiled_batch_kernels).values()) == {0}  # fresh processes
        seconds, _ = dask_executor(client).warm_up(StudyEngine(study), 0, quiet=True)
        assert seconds > 0.0
        loaded = client.run(_compiled_batch_kernels)
        assert len(loaded) == 2 and min(loaded.values()) > 0, loaded
        report = run_study_distributed(study, tmp_path, client=client, progress=False)
        assert report.complete and report.warmup_seconds > 0.0


class SlowEngine(StudyEngine):
    """An engine whose chunks take at least 0.2 s, so chunks are in flight when a worker dies.

    Pickled by reference: the spawned workers get this process's ``sys.path`` (tests/ included
    by conftest) and import it from this module.
    """

    def run_range(self, start, stop):
        """Run the range as usual, then wait."""
        out = super().run_range(start, stop)
        time.sleep(0.2)
        return out


def test_worker_killed_mid_study(cluster, study_file, reference, tmp_path):
    from pound_mc.study.distributed import run_study_distributed

    chunk_size = 4
    total = len(chunk_ranges(N, chunk_size))
    written = []
    killed = {}
    with distributed.Client(cluster) as client:
        pids = client.run(os.getpid)

        def kill_one_busy_worker(chunk):
            written.append(chunk.index)
            if killed or len(written) < 3:
                return
            busy = [addr for addr, keys in client.processing().items() if keys]
            if not busy:
                return  # try again after the next chunk
            addr = busy[0]
            killed["addr"] = addr
            killed["tasks"] = list(client.processing()[addr])
            os.kill(pids[addr], signal.SIGKILL)

        study = load_study(study_file)
        report = run_study_distributed(
            study,
            tmp_path,
            client=client,
            chunk_size=chunk_size,
            progress=False,
            on_chunk=kill_one_busy_worker,
            retries=2,
            engine=SlowEngine(study),
        )
    assert killed["tasks"], "the killed worker had chunks in flight"
    assert report.complete and report.chunks_run == total
    # every chunk written exactly once: nothing lost, nothing duplicated
    assert sorted(written) == list(range(total))
    files = sorted((tmp_path / "small").glob("chunk_*.npz"))
    assert len(files) == total
    assert not list((tmp_path / "small").glob(".*.part"))
    _assert_identical(reference, report.path)


def test_local_cluster_from_the_command_line(study_file, reference, tmp_path):
    out = tmp_path / "workers"
    argv = ["run", str(study_file), "--out", str(out), "--no-plot", "--no-progress"]
    assert main([*argv, "--workers", "2", "--chunk-size", "12"]) == 0
    _assert_identical(reference, out / "small.nc")


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "not both"),
        (["--workers", "2", "--threads", "2"], "--threads"),
        (["--workers", "0"], "--workers: must be >= 1"),
        (["--scheduler", "no-port"], "cannot connect"),
        # defect class 3: an unsupported scheme was a traceback, now refused before connecting
        (["--scheduler", "tls://127.0.0.1:8786"], "unsupported address scheme 'tls://'"),
        (["--scheduler", "tcp://127.0.0.1:8786", "--dask-timeout", "0"], "--dask-timeout"),
    ],
)
def test_bad_cluster_options(study_file, tmp_path, capsys, extra, message):
    out = tmp_path / "bad"
    assert main(["run", str(study_file), "--out", str(out), "--no-plot", *extra]) == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_refused_input_reads_as_in_a_local_run(tmp_path, capfd):
    """A study the kernels refused (once an elastic-perfectly plastic SDOF with ``adaptive``,
    now restitution set per impact on an undamped law) failed on the workers: the worker's
    traceback, then a ClusterError naming ``--scheduler``.  The refusal reads as a local
    run's: the same one line naming the file and the key, exit status 2, no retries."""
    path = tmp_path / "undamped.toml"
    path.write_text(study_text(
        contact={"e": None, "model": "hertz", "restitution": "velocity", "material": "concrete",
                 "e_quantile": 0.5},
        sampling={"n": 2, "vary": None},
    ))  # fmt: skip
    argv = ["run", str(path), "--no-plot", "--no-progress"]
    errors = []
    for extra in (["--out", str(tmp_path / "local")], ["--out", str(tmp_path / "dask"),
                                                       "--workers", "1"]):  # fmt: skip
        assert main([*argv, *extra]) == 2
        errors.append(capfd.readouterr().err)
    assert errors[0] == errors[1], errors
    assert "contact.restitution" in errors[1] and errors[1].count("\n") == 1
    assert not list(tmp_path.glob("*/*.nc")) and not list(tmp_path.glob("*/*/chunk_*"))


def test_missing_dask_names_the_extra(study_file, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    out = tmp_path / "nodask"
    assert main(["run", str(study_file), "--out", str(out), "--workers", "2"]) == 2
    err = capsys.readouterr().err
    assert 'pip install "pound-mc[dask]"' in err and "--workers: " in err  # the option given
    assert not out.exists()


def test_unreachable_and_frozen_scheduler(study_file, tmp_path, capsys):
    """Defect class 3: a frozen scheduler (accepts, never answers) hung the client silently.

    A socket that listens but never answers stands for a SIGSTOPped scheduler; a closed port
    for an unreachable one.  Both end in one line, exit 2, within ``--dask-timeout``.
    """
    import socket

    with socket.socket() as frozen, socket.socket() as closed:
        frozen.bind(("127.0.0.1", 0))
        frozen.listen()
        closed.bind(("127.0.0.1", 0))  # bound, not listening: connecting is refused
        for sock in (frozen, closed):
            out = tmp_path / f"out{sock.fileno()}"
            address = f"tcp://127.0.0.1:{sock.getsockname()[1]}"
            argv = ["run", str(study_file), "--out", str(out), "--no-plot", "--no-progress"]
            t0 = time.monotonic()
            assert main([*argv, "--scheduler", address, "--dask-timeout", "1"]) == 2
            assert time.monotonic() - t0 < 30
            err = capsys.readouterr().err
            assert f"cannot connect to the Dask scheduler {address!r}" in err, err
            assert "Traceback" not in err and err.count("\n") == 1, err
            assert not out.exists()


def test_all_workers_lost_then_resume(study_file, reference, tmp_path):
    """Defect class 3: losing every worker ended in a FutureCancelledError traceback.

    Every worker is killed after the second chunk: the run ends in a ClusterError (exit 2 on the
    command line) within the timeout, the finished chunks are kept, and a local run resumes to
    the reference dataset.
    """
    from pound_mc.errors import ClusterError
    from pound_mc.study.distributed import run_study_distributed

    study = load_study(study_file)
    with (
        _local_cluster(1) as cluster,
        distributed.Client(cluster) as client,
    ):
        pids = client.run(os.getpid)
        written = []

        def kill_all(chunk):
            written.append(chunk.index)
            if len(written) == 2:
                for pid in pids.values():
                    os.kill(pid, signal.SIGKILL)
                cluster.scale(0)  # no replacement worker: the cluster is gone

        with pytest.raises(ClusterError, match="finished chunks are kept"):
            run_study_distributed(
                study,
                tmp_path,
                client=client,
                chunk_size=4,
                progress=False,
                on_chunk=kill_all,
                timeout_s=10,
                engine=SlowEngine(study),
            )
    kept = sorted((tmp_path / "small").glob("chunk_4_*.npz"))
    assert len(kept) >= 2
    assert not (tmp_path / ".small.lock").exists()  # the lock was released
    report = run_study(study, tmp_path, chunk_size=4, progress=False)
    assert report.chunks_run == len(chunk_ranges(N, 4)) - len(kept)
    _assert_identical(reference, report.path)
