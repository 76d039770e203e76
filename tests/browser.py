"""Debian's chromium, headless, for the tests that look at pages as a reader would.

``tests/test_analysis.py`` (the HTML report) and ``tests/test_docs_pages.py`` (the built
documentation, offline) run it with :data:`COMMON_FLAGS` and their own window and mode.
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
#: No sandbox (CI runs as root), no GPU, no first-run pages or background traffic, no
#: scrollbars, one device pixel per CSS pixel.
COMMON_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-dev-shm-usage",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--force-device-scale-factor=1",
]


def run_chromium(tmp_path: Path, flags: list[str], *args: str, timeout: float):
    """Run chromium with ``flags`` and ``args`` in a fresh profile under ``tmp_path``."""
    profile = tmp_path / f"profile-{len(list(tmp_path.glob('profile-*')))}"
    return subprocess.run(
        [CHROMIUM, *flags, f"--user-data-dir={profile}", *args],
        capture_output=True,
        text=True,
        timeout=timeout,
    )
