"""A study whose size alone rules it out is refused before the engine is imported (#38).

``pound-mc check`` and ``run`` screen the file (:func:`pound_mc.study.limits.screen`) first:
the refusal of ``num = 1e8`` must not wait for numba, scipy or matplotlib to load (the
issue measured 84 s and 5.7 GB before any refusal; it asks for under 2 s and 200 MB).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pound_mc.study import limits

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = (ROOT / "studies" / "quickstart.toml").read_text()
GAPS = '"contact.gap_m" = [0.02, 0.05, 0.1, 0.2, 0.3]'

# the child runs the command in process, then says which heavy modules it loaded and its peak
# resident memory: VmHWM of its own address space (ru_maxrss would carry the forking parent's
# over the exec)
CHILD = """
import json, re, sys
from pound_mc.cli import main
status = main(sys.argv[1:])
heavy = [m for m in ("numba", "scipy", "matplotlib", "obspy") if m in sys.modules]
with open("/proc/self/status") as fh:
    rss = int(re.search(r"VmHWM:\\s*(\\d+) kB", fh.read()).group(1)) / 1024
print(json.dumps({"status": status, "heavy": heavy, "rss_mb": rss}))
"""


def _study(tmp_path: Path, old: str, new: str) -> Path:
    assert old in QUICKSTART
    path = tmp_path / "big.toml"
    path.write_text(QUICKSTART.replace(old, new))
    return path


CASES = {
    # the case: a float count, far past the schema's largest axis (10**6)
    "num float": (GAPS, '"contact.gap_m" = { start = 0.01, stop = 0.3, num = 1e8 }',
                  "grid.contact.gap_m.num: must be an integer, got 100000000.0"),
    "num int": (GAPS, '"contact.gap_m" = { start = 0.01, stop = 0.3, num = 100000000 }',
                "grid.contact.gap_m.num: must be an integer in [1, 1000000], got 100000000"),
    "samples": ("n = 2\n", "n = 100000000\n",
                "sampling.n: must be an integer in [1, 16777216], got 100000000"),
    # each axis within its limit, their product (8.1e11 x 5 x 2 simulations) past any memory
    "product": (GAPS, '"contact.gap_m" = { start = 0.01, stop = 0.3, num = 900000 }\n'
                '"left.period_s" = { start = 0.1, stop = 2.0, num = 900000 }',
                "grid.contact.gap_m: at least 8,100,000,000,000 simulations need at least"),
}  # fmt: skip


@pytest.mark.parametrize(
    ("command", "case"), [("check", case) for case in sorted(CASES)] + [("run", "num float")]
)
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads Linux's /proc")
def test_refused_before_the_engine(tmp_path, command, case):
    old, new, message = CASES[case]
    path = _study(tmp_path, old, new)
    out = tmp_path / "out"
    argv = [command, str(path)] + (["--out", str(out)] if command == "run" else [])
    proc = subprocess.run([sys.executable, "-c", CHILD, *argv], capture_output=True, text=True,
                          timeout=120, cwd=tmp_path)  # fmt: skip
    report = json.loads(proc.stdout.strip().splitlines()[-1])
    assert report["status"] == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, lines
    assert lines[0].startswith(f"pound-mc {command}: error: {path}: {message}")
    assert report["heavy"] == []  # refused before numba, scipy, matplotlib, obspy loaded
    assert report["rss_mb"] < 200
    assert not out.exists()  # nothing written


def test_screen_lets_a_valid_study_through(tmp_path):
    # the quickstart itself: 44 components x 5 x 5 x 2 simulations, far inside any memory
    path = tmp_path / "q.toml"
    path.write_text(QUICKSTART)
    limits.screen(path)


def test_whole_float_in_range_is_left_to_the_schema(tmp_path):
    # num = 5.0 is not a size problem: the full validation names it (not an integer)
    path = _study(tmp_path, GAPS, '"contact.gap_m" = { start = 0.01, stop = 0.3, num = 5.0 }')
    limits.screen(path)
