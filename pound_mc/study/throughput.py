"""Throughput of a study with and without the accuracy check, paired in one process.

``python -m pound_mc.study.throughput STUDY.toml [--chunks N] [--repeats N]`` prints, as JSON,
the simulations per second of the study's chunks run without ``integrator.accuracy_check`` and
with it (:func:`check_throughput`), their ratio and the load averages around the timing.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pound_mc.integrators.threads import numba_threads
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import chunk_ranges, default_chunk_size

__all__ = ["check_throughput", "main"]


def _with_check(text: str, on: bool) -> str:
    """A study's text with ``integrator.accuracy_check`` set to ``on``."""
    line = f"accuracy_check = {'true' if on else 'false'}"
    if re.search(r"(?m)^\s*accuracy_check\s*=.*$", text):
        return re.sub(r"(?m)^\s*accuracy_check\s*=.*$", line, text)
    if re.search(r"(?m)^\[integrator\]\s*$", text):
        return re.sub(r"(?m)^\[integrator\]\s*$", f"[integrator]\n{line}", text, count=1)
    return f"{text}\n[integrator]\n{line}\n"


def check_throughput(path, chunks: int = 8, repeats: int = 3, progress: bool = True) -> dict:
    """Runs per second of a study with and without the accuracy check, paired, one thread.

    ``chunks`` of the study's chunk size, spread evenly over it; every repeat runs each chunk
    without the check and with it (in alternating order), in this process, on one thread, so
    that a change of load hits both alike.  The refinement of flagged runs counts (it is part
    of the check's cost).  Returns both rates, their ratio and the load averages.
    """
    text = Path(path).read_text()
    engines = {on: StudyEngine(study_from_text(_with_check(text, on), file=path))
               for on in (False, True)}  # fmt: skip
    study = engines[False].study
    size = study.chunk_size or default_chunk_size(study.n_simulations)
    ranges = chunk_ranges(study.n_simulations, size)
    picked = [ranges[int(k)] for k in np.linspace(0, len(ranges) - 1, chunks).round()]
    load0 = os.getloadavg()
    seconds = {False: 0.0, True: 0.0}
    runs = 0
    flagged = 0
    with numba_threads(1):
        for on in (False, True):  # compile (or load numba's cache)
            engines[on].run_range(0, 1)
        jobs = [(r, c) for r in range(repeats) for c in range(len(picked))]
        for rep, c in tqdm(jobs, desc="paired chunks", disable=not progress):
            start, stop = picked[c]
            for on in (False, True) if (rep + c) % 2 == 0 else (True, False):
                t0 = time.perf_counter()
                out = engines[on].run_range(start, stop)
                seconds[on] += time.perf_counter() - t0
                if on:
                    flagged += int(np.count_nonzero(out["refinements"]))
            runs += stop - start
    rate = {on: runs / seconds[on] for on in seconds}
    return {"study": str(path), "runs": runs, "runs_per_s_without": rate[False],
            "runs_per_s_with": rate[True], "ratio": rate[True] / rate[False],
            "refined": flagged, "load_before": load0, "load_after": os.getloadavg()}  # fmt: skip


def main(argv=None) -> int:
    """Command line: ``python -m pound_mc.study.throughput STUDY.toml``."""
    parser = argparse.ArgumentParser(prog="python -m pound_mc.study.throughput",
                                     description=__doc__.split("\n\n")[0])  # fmt: skip
    parser.add_argument("study", help="study file (TOML)")
    parser.add_argument("--chunks", type=int, default=8, help="chunks timed, spread evenly")
    parser.add_argument("--repeats", type=int, default=3, help="rounds over those chunks")
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    got = check_throughput(args.study, args.chunks, args.repeats, not args.no_progress)
    print(json.dumps(got, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
