"""Sub-commands that run studies: ``run`` and ``check``.

Their arguments are declared in :mod:`pound_mc.cli.commands`.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import xarray as xr

from pound_mc.analysis.plot import spectrum_chart
from pound_mc.analysis.risk_chart import fragility_panels, required_gap_chart
from pound_mc.errors import InputError
from pound_mc.study.definition import load_study
from pound_mc.study.distributed import _import_distributed, run_study_distributed
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import plan_text, run_study


def run_command(args) -> int:
    """``pound-mc run``: run a study (threads or Dask), write its dataset and chart."""
    for key in ("chunk_size", "threads", "workers"):
        value = getattr(args, key)
        if value is not None and value < 1:
            raise InputError(f"must be >= 1, got {value}", key="--" + key.replace("_", "-"))
    dask = args.scheduler is not None or args.workers is not None
    if args.scheduler is not None and args.workers is not None:
        raise InputError("give either --scheduler or --workers, not both", key="--workers")
    if dask and args.threads is not None:
        raise InputError(
            "sets the threads of an in-process run; each Dask worker runs on one thread",
            key="--threads",
        )
    if dask:
        _import_distributed()  # a missing optional dependency is reported before any work
    study = load_study(args.study)
    engine = StudyEngine(study)
    t0 = time.perf_counter()
    common = dict(
        fresh=args.fresh,
        chunk_size=args.chunk_size,
        progress=not args.no_progress,
        engine=engine,
    )
    try:
        if dask:
            report = run_study_distributed(
                study, args.out, scheduler=args.scheduler, workers=args.workers, **common
            )
        else:
            report = run_study(study, args.out, threads=args.threads, **common)
    except KeyboardInterrupt:
        print(
            f"interrupted: finished chunks are kept under {Path(args.out) / study.name}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    if not report.complete:
        print(
            f"interrupted after {report.chunks_run} chunks: finished chunks are kept under "
            f"{Path(args.out) / study.name}; run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    print(
        f"{report.n_simulations:,} simulations, {report.chunks_run} of {report.chunks_total} "
        f"chunks run in {report.seconds:.1f} s"
        + (f" ({report.rate:,.0f} simulations/s)" if report.chunks_run else "")
        + f"; {time.perf_counter() - t0:.1f} s with the dataset"
    )
    print(f"wrote {report.path}")
    if not args.no_plot:
        for png in _charts(study, report.path, Path(args.out)):
            print(f"wrote {png}")
    return 0


def _charts(study, path: Path, out: Path) -> list[Path]:
    """The charts ``run`` draws: the spectrum, or with an intensity axis two risk charts.

    With an intensity axis: the required gap against the rules (when the gap is on the grid)
    and the fragility curves.
    """
    written = []
    with xr.open_dataset(path) as ds:
        ds.load()
        if study.intensity_key is None:
            written.append(out / f"{study.name}_spectrum.png")
            spectrum_chart(ds, written[-1])
            return written
        if "contact.gap_m" in study.grid and len(study.grid["contact.gap_m"]) > 1:
            written.append(out / f"{study.name}_required_gap.png")
            required_gap_chart(ds, written[-1], base_dir=study.path.parent)
        written.append(out / f"{study.name}_fragility.png")
        fragility_panels(ds, written[-1])
    return written


def check_command(args) -> int:
    """``pound-mc check``: validate a study, print its plan and cost; write nothing."""
    study = load_study(args.study)
    if args.threads is not None and args.threads < 1:
        raise InputError(f"must be >= 1, got {args.threads}", key="--threads")
    engine = StudyEngine(study)
    seconds, compile_s = engine.calibrate(workers=args.threads, n=args.calibrate)
    print(plan_text(study, chunk_size=args.chunk_size, seconds_per_simulation=seconds))
    print(
        f"  calibration: {args.calibrate} simulations spread over the study; "
        f"first call {compile_s:.1f} s (compilation or numba's cache)"
    )
    print("  (nothing written)")
    return 0
