"""Subcommands that run studies: ``run`` and ``check``."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``run`` and ``check`` to the ``pound-mc`` parser."""
    p = sub.add_parser("run", help="run a study and write <out>/<name>.nc and a spectrum chart")
    p.add_argument("study", metavar="STUDY.toml")
    p.add_argument("--out", default="outputs", metavar="DIR", help="output folder (outputs)")
    p.add_argument("--threads", type=int, metavar="N", help="numba threads (in-process run)")
    p.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="run on a local Dask cluster of N worker processes (one thread each)",
    )
    p.add_argument(
        "--scheduler", metavar="ADDRESS", help="run on the Dask cluster of this scheduler"
    )
    p.add_argument("--fresh", action="store_true", help="discard earlier results of this study")
    p.add_argument("--chunk-size", type=int, metavar="N", help="simulations per chunk file")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--no-plot", action="store_true", help="do not draw the spectrum chart")
    p.set_defaults(func=_run)

    p = sub.add_parser("check", help="validate a study and print its plan; writes nothing")
    p.add_argument("study", metavar="STUDY.toml")
    p.add_argument("--threads", type=int, metavar="N", help="threads for the estimate")
    p.add_argument("--chunk-size", type=int, metavar="N", help="simulations per chunk file")
    p.add_argument(
        "--calibrate", type=int, default=64, metavar="N", help="simulations timed for the estimate"
    )
    p.set_defaults(func=_check)


def _run(args) -> int:
    from pound_mc.errors import InputError
    from pound_mc.study.definition import load_study
    from pound_mc.study.engine import StudyEngine
    from pound_mc.study.runner import run_study

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
        from pound_mc.study.distributed import _import_distributed

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
            from pound_mc.study.distributed import run_study_distributed

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
        import xarray as xr

        from pound_mc.analysis.plot import spectrum_chart

        png = Path(args.out) / f"{study.name}_spectrum.png"
        with xr.open_dataset(report.path) as ds:
            spectrum_chart(ds, png)
        print(f"wrote {png}")
    return 0


def _check(args) -> int:
    from pound_mc.errors import InputError
    from pound_mc.study.definition import load_study
    from pound_mc.study.engine import StudyEngine
    from pound_mc.study.runner import plan_text

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
