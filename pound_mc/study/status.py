"""A status line on the terminal: what a long command is doing now, and for how long.

``pound-mc run`` is never silent for long on a terminal: before the heavy imports it says it
is loading, then it reads the study and its records, starts the Dask workers, loads or compiles
the kernels, runs the chunks (the progress bar), writes the dataset and draws the charts, and
each step shows on one line that counts its seconds (``compiling kernels... 12 s``).  The line
is transient: it is erased when the step ends, so what stays on the screen (and in a log) is
what the command printed before.  Off a terminal (a pipe, a file, a test's capture) nothing is
drawn, and ``--no-progress`` turns it off too.

Only the standard library: the command line imports this before anything heavy.
"""

from __future__ import annotations

import sys
import threading
import time
from typing import TextIO

__all__ = ["StatusLine", "STATUS"]


class StatusLine:
    """One transient line on standard error, redrawn every ``every_s`` seconds.

    Parameters
    ----------
    every_s : float
        Seconds between redraws (the elapsed time shown counts in whole seconds).
    """

    def __init__(self, every_s: float = 1.0):
        self.every_s = every_s
        self.off = False
        self._text: str | None = None
        self._t0 = 0.0
        self._shown = False
        self._lock = threading.RLock()
        self._thread: threading.Thread | None = None

    @staticmethod
    def _stream() -> TextIO:
        return sys.stderr  # looked up at each use: a test may replace it

    def active(self) -> bool:
        """Whether a line is drawn: on, and standard error is a terminal."""
        if self.off:
            return False
        try:
            return self._stream().isatty()
        except (AttributeError, ValueError):  # a closed or odd stream
            return False

    def say(self, text: str) -> None:
        """Show ``text`` (what the command does now) with its elapsed seconds from now on."""
        if not self.active():
            return
        with self._lock:
            self._text, self._t0 = text, time.monotonic()
            self._draw()
            if self._thread is None:
                self._thread = threading.Thread(target=self._tick, daemon=True, name="status")
                self._thread.start()

    def clear(self) -> None:
        """Erase the line and stop counting (before other output takes the line)."""
        with self._lock:
            self._text = None
            self._erase()

    def announce(self, line: str, stream: TextIO | None = None) -> None:
        """Print ``line`` to stay (on ``stream``, default standard error), above the status."""
        stream = self._stream() if stream is None else stream
        with self._lock:
            self._erase()
            print(line, file=stream, flush=True)
            if self._text is not None:
                self._draw()

    def _draw(self) -> None:
        seconds = time.monotonic() - self._t0
        counted = f" {seconds:.0f} s" if seconds >= 0.5 else ""
        try:
            self._stream().write(f"\r{self._text}...{counted}\x1b[K")
            self._stream().flush()
            self._shown = True
        except (OSError, ValueError):  # the terminal went away: nothing more to draw
            self._text = None

    def _erase(self) -> None:
        if self._shown:
            try:
                self._stream().write("\r\x1b[K")
                self._stream().flush()
            except (OSError, ValueError):
                pass
            self._shown = False

    def _tick(self) -> None:
        while True:
            time.sleep(self.every_s)
            with self._lock:
                if self._text is not None:
                    self._draw()


#: The status line of this process (``pound-mc run`` and the steps it calls say what they do).
STATUS = StatusLine()
