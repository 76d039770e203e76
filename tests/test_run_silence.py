"""``pound-mc run`` on a cold kernel cache is never silent for long on a terminal (issue 41).

The command runs as a person runs it: a new process, its standard error a terminal (a pseudo
terminal here, read with the time of every write), a kernel cache of its own that starts
empty (``NUMBA_CACHE_DIR`` in a new folder: every kernel compiles).  The first words come
after Python's start and ``import pound_mc`` (xarray), before the heavy imports; from then to
the last line no two writes are more than :data:`MOST_SILENCE_S` apart: loading the libraries,
reading the records, starting the Dask workers, compiling, the progress bar, the dataset and
every chart each keep a line that counts its seconds.  (A progress bar redraws with ``\\r``:
the writes are split at ``\\r`` and ``\\n``.)
"""

from __future__ import annotations

import os
import re
import select
import shutil
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from studies import SMALL_SDOF, write_study

pty = pytest.importorskip("pty", reason="a pseudo terminal (POSIX) stands for the person's")
fcntl = pytest.importorskip("fcntl", reason="POSIX only")
termios = pytest.importorskip("termios", reason="POSIX only")

ROOT = Path(__file__).resolve().parent.parent
#: The longest silence allowed between two writes [s] (issue 41's acceptance: 2 s).
MOST_SILENCE_S = 2.0
#: The first words come after Python's start and ``import pound_mc`` (xarray): well under a
#: second on an idle machine, seconds on a loaded one [s].
FIRST_WORDS_S = 10.0
#: From the last line (the work is done) to the exit: Python's teardown of numba, scipy and
#: the rest, about a second on a loaded machine [s].
LAST_WORDS_S = 5.0


def _timed_run(argv: list[str], cwd: Path, cache: Path, limit_s: float = 900.0):
    """Run ``pound-mc argv`` with its output on a pseudo terminal.

    Returns the exit status, the writes to the terminal as ``[(seconds after the start,
    text)]`` (the text split at carriage returns and newlines, escape sequences removed) and
    the seconds to the exit.
    """
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "MPLBACKEND": "Agg"}
    env.pop("POUND_MC_CACHE_DIR", None)  # the cache is the new folder's
    master, slave = pty.openpty()
    # a terminal of 100 columns and 30 rows (a new pseudo terminal has none: no bar fits)
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    t0 = time.monotonic()
    proc = subprocess.Popen(
        [sys.executable, "-m", "pound_mc", *argv],
        cwd=cwd,
        env=env,
        stdin=subprocess.DEVNULL,
        stdout=slave,  # both streams on the terminal, as a person sees them
        stderr=slave,
    )
    os.close(slave)
    writes = []
    try:
        while time.monotonic() - t0 < limit_s:
            ready, _, _ = select.select([master], [], [], 0.05)
            if not ready:
                if proc.poll() is not None:
                    break
                continue
            try:
                data = os.read(master, 65536)
            except OSError:  # EIO: the process closed the terminal
                break
            if not data:
                break
            now = time.monotonic() - t0
            for piece in re.split(rb"[\r\n]", data):
                text = re.sub(r"\x1b\[[0-9;]*[A-Za-z]", "", piece.decode(errors="replace"))
                if text.strip():
                    writes.append((now, text.strip()))
    finally:
        os.close(master)
        if proc.poll() is None:
            proc.kill()
        proc.wait()
    return proc.returncode, writes, time.monotonic() - t0


def _silences(writes) -> list[tuple[float, str]]:
    """Each silence [s] from a write to the next, with the text before it."""
    return [(b[0] - a[0], a[1]) for a, b in zip(writes, writes[1:], strict=False)]


def _check_never_silent(writes, end, status):
    assert status == 0, writes[-5:]
    assert len(writes) > 1, writes
    first = writes[0][0]
    longest = max(_silences(writes))
    tail = end - writes[-1][0]  # after the last line: the interpreter's own teardown
    print(f"first words after {first:.2f} s; longest silence {longest[0]:.2f} s after "
          f"{longest[1]!r}; exit {tail:.2f} s after the last line; {end:.1f} s in all")  # fmt: skip
    assert first < FIRST_WORDS_S, writes[:3]
    assert longest[0] <= MOST_SILENCE_S, longest
    assert tail < LAST_WORDS_S, writes[-3:]
    return longest


@pytest.mark.slow
def test_a_cold_run_of_the_quickstart_is_never_silent(tmp_path):
    shutil.copytree(ROOT / "studies", tmp_path / "studies")
    status, writes, end = _timed_run(
        ["run", "studies/quickstart.toml", "--out", "outputs"], tmp_path, tmp_path / "cache"
    )
    _check_never_silent(writes, end, status)
    texts = [text for _, text in writes]
    # it says what it does: loading, reading the records, compiling, the bar, the charts
    for words in ("loading the libraries", "reading quickstart.toml and its records",
                  "compiling kernels (first run only)", "sim/s",
                  "drawing quickstart_required_gap.png"):  # fmt: skip
        assert any(words in text for text in texts), (words, texts[:20])
    assert (tmp_path / "outputs" / "quickstart_required_gap.png").is_file()


@pytest.mark.slow
def test_a_dask_run_says_it_starts_its_workers(tmp_path):
    pytest.importorskip("distributed")
    study = write_study(tmp_path, SMALL_SDOF)
    status, writes, end = _timed_run(
        ["run", str(study), "--out", "outputs", "--workers", "2", "--no-plot"],
        tmp_path,
        tmp_path / "cache",
    )
    _check_never_silent(writes, end, status)
    texts = [text for _, text in writes]
    # it says so while the cluster starts (22-31 s of silence in issue 41), while the workers
    # receive the study, and while they load or compile the kernels
    for words in ("starting 2 Dask workers", "sending the study to the Dask workers",
                  "kernels on 2 Dask workers", "stopping the Dask workers"):  # fmt: skip
        assert any(words in text for text in texts), (words, texts)
