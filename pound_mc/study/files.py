"""The files of a run: one writer per output, writes that never go through a link.

Every file a run writes - its lock, the temporary files, the chunk files, the manifest, the
dataset, the charts - is a file this process has just created: a new name opened with
``O_CREAT | O_EXCL | O_NOFOLLOW``, or a file in a new private folder
(:func:`tempfile.mkdtemp`, mode 0700), moved to its place by :func:`os.replace`.  A rename
replaces whatever name is in the way, a symbolic link included, and never writes through it;
no file this process did not create is ever opened for writing or truncated.

One writer per output: :func:`output_lock` holds an exclusive advisory lock
(:func:`fcntl.flock`) on ``<out>/.<name>.lock``, a file it created itself and that records its
process id.  The kernel releases the lock when the process ends, however it ends; the next run
finds the file unlocked (a stale lock), removes that name and creates its own.  A symbolic link
or anything but a plain file at the lock's name is refused, naming it.

Temporary names carry the process id (``.<file>.<pid>.part``); the ones a killed run left
behind are removed by the next run that takes the lock (:func:`remove_parts`).  A failed write
(disk full, a read-only folder) removes its temporary file and ends in an
:class:`~pound_mc.errors.OutputError` naming the path.

Test hook: when the environment variable ``POUND_MC_TEST_PAUSE_AT`` names a stage (see
:data:`PAUSE_STAGES`), the runner prints ``POUND_MC_TEST_PAUSE_AT: paused at <stage>`` to
standard error and sleeps there (``POUND_MC_TEST_PAUSE_S`` seconds, default 600), so the
interrupt drill (``tests/test_drills.py``) can kill the process at a known point.  It costs one
environment lookup per stage and is not meant for users.
"""

from __future__ import annotations

import errno
import fcntl
import os
import shutil
import stat
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from pound_mc.errors import OutputError

__all__ = [
    "PAUSE_ENV",
    "PAUSE_STAGES",
    "output_lock",
    "part_path",
    "pause_at",
    "read_own",
    "remove_parts",
    "remove_tree",
    "temporary_beside",
    "write_bytes_atomically",
]

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

#: Flags that keep :func:`os.open` off symbolic links (0 where the system has none of them).
_NOFOLLOW = getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_CLOEXEC", 0)


def pause_at(stage: str) -> None:
    """Test hook: sleep at ``stage`` if ``POUND_MC_TEST_PAUSE_AT`` names it."""
    if os.environ.get(PAUSE_ENV) != stage:
        return
    print(f"{PAUSE_ENV}: paused at {stage}", file=sys.stderr, flush=True)
    time.sleep(float(os.environ.get("POUND_MC_TEST_PAUSE_S", "600")))


def part_path(path: Path) -> Path:
    """The temporary name of ``path`` in this process: ``.<name>.<pid>.part`` beside it."""
    return path.with_name(f".{path.name}.{os.getpid()}.part")


def _create_new(path: Path) -> int:
    """Open ``path`` as a new file of this process for writing (never through a link).

    A name already there (a temporary file a killed process with this id left, or a link
    planted at it) is removed first: removing a name never touches what a link points to.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | _NOFOLLOW
    try:
        return os.open(path, flags, 0o644)
    except FileExistsError:
        path.unlink()
        return os.open(path, flags, 0o644)


def write_bytes_atomically(path: Path, data: bytes, stage: str) -> None:
    """Write ``data`` to a new temporary file, flush it to disk and rename it to ``path``.

    A reader sees either no ``path`` or the complete file, never a part of it; the temporary
    file (:func:`part_path`) an interrupted write leaves behind is never read and is removed
    by the next run.  A link at ``path`` is replaced, never written through.  ``stage`` names
    the test hook's stages (``<stage>:half``, ``<stage>:part``).

    Raises
    ------
    pound_mc.errors.OutputError
        The write failed (disk full, read-only folder, a folder at ``path``): the temporary
        file is removed and the message names ``path``.
    """
    tmp = part_path(path)
    try:
        with os.fdopen(_create_new(tmp), "wb") as fh:
            half = len(data) // 2
            fh.write(data[:half])
            fh.flush()
            pause_at(f"{stage}:half")
            fh.write(data[half:])
            fh.flush()
            os.fsync(fh.fileno())
        pause_at(f"{stage}:part")
        os.replace(tmp, path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise OutputError(f"cannot write: {exc.strerror or exc}", file=str(path)) from None


@contextmanager
def temporary_beside(path: Path) -> Iterator[Path]:
    """A path to write ``path``'s content to, moved to ``path`` when the block ends cleanly.

    For writers that take a file name (netCDF, matplotlib, pandas): the name is inside a new
    folder that only this user can enter (:func:`tempfile.mkdtemp` beside ``path``, named
    ``.<name>.<pid>.<random>.part``), so nothing can be planted at it; the file is renamed
    over ``path`` (a link there is replaced, not followed) and the folder removed, also when
    the block fails.  The caller makes ``path``'s folder and turns :class:`OSError` into its
    own message.
    """
    folder = Path(
        tempfile.mkdtemp(prefix=f".{path.name}.{os.getpid()}.", suffix=".part", dir=path.parent)
    )
    try:
        tmp = folder / path.name
        yield tmp
        os.replace(tmp, path)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def read_own(path: Path) -> bytes | None:
    """The bytes of the plain file ``path`` (None: no such file), never read through a link.

    Raises
    ------
    OSError
        A link at ``path`` (``ELOOP``), a folder, or the file cannot be read.
    """
    try:
        fd = os.open(path, os.O_RDONLY | _NOFOLLOW)
    except FileNotFoundError:
        return None
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            raise OSError(errno.EINVAL, "not a plain file", str(path))
        return fh.read()


def _lock_error(path: Path, exc: OSError) -> OutputError:
    """The message of a lock file that cannot be opened (a link, a folder, no access)."""
    if exc.errno == errno.ELOOP or path.is_symlink():
        return OutputError(
            "is a symbolic link, not a lock file of pound-mc (which never writes through a "
            "link): remove it, or give another --out",
            file=str(path),
        )
    return OutputError(f"cannot write: {exc.strerror or exc}", file=str(exc.filename or path))


def _open_lock(out_dir: Path, path: Path) -> tuple[int, bool] | None:
    """``(fd, created)`` of the lock file: a new one, or the one there (None: it just went)."""
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        try:
            return os.open(path, os.O_RDWR | os.O_CREAT | os.O_EXCL | _NOFOLLOW, 0o644), True
        except FileExistsError:
            fd = os.open(path, os.O_RDWR | os.O_NONBLOCK | _NOFOLLOW)
    except FileNotFoundError:
        if out_dir.is_dir():
            return None  # the holder removed its lock file as we opened it: try again
        raise OutputError("cannot write: No such file or directory", file=str(out_dir)) from None
    except OSError as exc:
        if out_dir.exists() and not out_dir.is_dir():
            raise OutputError("is a file, not a folder: give --out a folder",
                              file=str(out_dir)) from None  # fmt: skip
        raise _lock_error(path, exc) from None
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise OutputError("is not a lock file of pound-mc: remove it, or give another --out",
                          file=str(path))  # fmt: skip
    return fd, False


def _same_file(fd: int, path: Path) -> bool:
    """Whether ``path`` (not followed) is still the file open as ``fd``."""
    try:
        here, there = os.fstat(fd), os.lstat(path)
    except FileNotFoundError:
        return False
    return (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


@contextmanager
def output_lock(out_dir: Path, name: str) -> Iterator[Path]:
    """Hold the exclusive advisory lock of study ``name``'s results in ``out_dir``.

    The lock file ``<out_dir>/.<name>.lock`` is created by the run that holds it (``O_EXCL``,
    never through a link) and holds its process id.  A lock file nobody holds (left by a
    killed run) is removed and replaced by a new one; the file goes when the lock is released.

    Raises
    ------
    pound_mc.errors.OutputError
        Another live process holds the lock (its id named); the folder cannot be written; a
        symbolic link or anything but a plain file is at the lock's name.
    """
    out_dir = Path(out_dir)
    path = out_dir / f".{name}.lock"
    while True:
        opened = _open_lock(out_dir, path)
        if opened is None:
            continue
        fd, created = opened
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
        if created and _same_file(fd, path):
            break
        try:
            if _same_file(fd, path):  # a stale lock: its name goes, a file of our own takes it
                path.unlink(missing_ok=True)
        except OSError as exc:
            raise OutputError(f"cannot write: {exc.strerror or exc}", file=str(path)) from None
        finally:
            os.close(fd)  # (or the file went as we opened it): try again
    try:
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield path
    finally:
        if _same_file(fd, path):
            path.unlink(missing_ok=True)
        os.close(fd)


def _pid_alive(name: str) -> bool:
    """Whether the process id in a temporary name (``.<file>.<pid>.<random>.part``) runs."""
    fields = name.removesuffix(".part").rsplit(".", 2)
    if len(fields) != 3 or not fields[1].isdigit():
        return False
    try:
        os.kill(int(fields[1]), 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True  # someone else's process, or not a process id: leave it
    return True


def _remove_part(path: Path) -> None:
    """Remove a temporary file or folder (a link at its name goes, never what it points to)."""
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)


def remove_parts(out_dir: Path, name: str) -> None:
    """Remove the temporary files and folders killed runs left behind (the caller holds the lock).

    Those of the chunk files and the manifest (``<out_dir>/<name>/.*.part``) and of the
    dataset go; those of the charts (drawn after the lock is released) go where the process
    that made them has ended.
    """
    work = out_dir / name
    stale = list(work.glob(".*.part")) if work.is_dir() else []
    stale += out_dir.glob(f".{name}.nc.*part")
    stale += (p for p in out_dir.glob(f".{name}_*.png.*.part") if not _pid_alive(p.name))
    for path in stale:
        _remove_part(path)


def remove_tree(work: Path) -> None:
    """Remove earlier results (``--fresh``); a file or link in their place goes too."""
    try:
        if work.is_dir() and not work.is_symlink():
            shutil.rmtree(work)
        else:
            work.unlink()
    except OSError as exc:
        raise OutputError(f"cannot remove: {exc.strerror or exc}", file=str(work)) from None
