"""Sub-commands that run studies: ``run`` and ``check``.

Their arguments are declared in :mod:`pound_mc.cli.commands`.
"""

from __future__ import annotations

import shutil
import sys
import time
import tomllib
from collections.abc import Iterator
from functools import partial
from importlib import resources
from pathlib import Path

import numpy as np
import xarray as xr

from pound_mc.analysis.distribution_chart import distribution_chart
from pound_mc.analysis.inelastic_chart import inelastic_chart, yielding_sides
from pound_mc.analysis.plot import CONTACT_DIM, GAP_DIM, spectrum_panels
from pound_mc.analysis.profiles import contacts_chart
from pound_mc.analysis.risk_chart import fragility_panels, required_gap_chart
from pound_mc.analysis.sensitivity_chart import sensitivity_chart
from pound_mc.errors import InputError
from pound_mc.integrators import METHODS
from pound_mc.integrators.accuracy import STATUS_INACCURATE
from pound_mc.integrators.outputs import STATUS_OK
from pound_mc.physics.contact import CONTACT_MODELS
from pound_mc.study.dataset import STATUS_FLAGS
from pound_mc.study.definition import load_study
from pound_mc.study.distributed import _import_distributed, run_study_distributed
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import (
    chunk_ranges,
    count_text,
    default_chunk_size,
    memory_estimate,
    plan_text,
    run_study,
)
from pound_mc.study.schema import STUDY
from pound_mc.study.status import STATUS
from pound_mc.study.warmup import cache_directory, compile_kernels, warm_up

#: Fixed cost per chunk of a local run (writing its file, Python around the batch call) [s],
#: measured on a 2-core machine (docs/performance.md); added to the estimate.
CHUNK_OVERHEAD_S = 0.003
#: ``check`` warns when one simulation takes longer than this [s]: such a study is
#: effectively endless (a step far too short, a record far too long).
SLOW_SIMULATION_S = 30.0


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
    if not args.dask_timeout > 0:
        raise InputError(f"must be > 0, got {args.dask_timeout}", key="--dask-timeout")
    if dask:
        # a missing optional dependency is reported before any work, naming the option
        _import_distributed("--workers" if args.workers is not None else "--scheduler")
    STATUS.off = args.no_progress
    STATUS.say(f"reading {Path(args.study).name} and its records")
    study = load_study(args.study)
    engine = StudyEngine(study)
    for line in engine.record_warnings:
        STATUS.announce(line)
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
                study,
                args.out,
                scheduler=args.scheduler,
                workers=args.workers,
                timeout_s=args.dask_timeout,
                **common,
            )
        else:
            report = run_study(study, args.out, threads=args.threads, **common)
    except KeyboardInterrupt:
        STATUS.clear()
        print(
            f"interrupted: finished chunks are kept under {Path(args.out) / study.name}; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    STATUS.clear()
    if not report.complete:
        print(
            f"interrupted after {count_text(report.chunks_run, 'chunk')}: finished chunks are "
            f"kept under {Path(args.out) / study.name}; run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    print(
        f"{count_text(report.n_simulations, 'simulation')}, {report.chunks_run} of "
        f"{count_text(report.chunks_total, 'chunk')} run in {report.seconds:.1f} s"
        + (f" after {report.warmup_seconds:.1f} s of compiling" if report.warmup_compiled else "")
        + (f" ({report.rate:,.0f} simulations/s)" if report.chunks_run else "")
        + f"; {time.perf_counter() - t0:.1f} s with the dataset"
    )
    print(f"wrote {report.path}")
    for line in status_warnings(report.path):
        print(line, file=sys.stderr)
    if all_failed(report.path):  # nothing to chart: every run unstable or not converged
        print(f"pound-mc run: error: {study.path}: every simulation failed (unstable or not "
              "converged): no result to analyse; refine integrator.dt_s (substeps with "
              "adaptive) or check the scene", file=sys.stderr)  # fmt: skip
        return ALL_FAILED_STATUS
    if not args.no_plot:
        for png in _charts(study, report.path, Path(args.out)):
            STATUS.clear()
            print(f"wrote {png}")
    return 0


#: Exit status of a run in which every simulation failed (DESIGN.md section 10).
ALL_FAILED_STATUS = 3


def all_failed(path: Path) -> bool:
    """Whether every simulation of the dataset at ``path`` is unstable or not converged."""
    with xr.open_dataset(path) as ds:
        status = ds["status"].values
    return bool(status.size) and not np.isin(status, (STATUS_OK, STATUS_INACCURATE)).any()


def status_warnings(path: Path) -> list[str]:
    """Lines for the simulations of a dataset that did not end ``ok``, with what that means.

    Also how many the accuracy check's refinements ran again (``refinements``) and how many
    of those it still flags.
    """
    with xr.open_dataset(path) as ds:
        status = ds["status"].values.ravel()
        refined = ds["refinements"].values.ravel() if "refinements" in ds else None
    n = status.size
    count = {name: int((status == code).sum()) for code, name in STATUS_FLAGS.items()}
    lines = []
    if refined is not None and np.any(refined > 0):
        n_refined = int((refined > 0).sum())
        still = int(((refined > 0) & (status == STATUS_INACCURATE)).sum())
        lines.append(
            f"note: {n_refined:,} of {n:,} simulations flagged by the accuracy check were run "
            f"again finer (dt_s halved, substeps doubled, up to {int(refined.max())} times); "
            f"{still:,} of them remain flagged"
        )
    if count["inaccurate"]:
        lines.append(
            f"warning: {count['inaccurate']:,} of {n:,} simulations flagged inaccurate (their "
            "peak force is in doubt: left out of the force spectrum, counted for the pounding "
            "probability); refine integrator.dt_s (substeps with adaptive)"
        )
    failed = count["unstable"] + count["not_converged"]
    if failed:
        lines.append(
            f"warning: {failed:,} of {n:,} simulations unstable or not converged (left out of "
            "every summary); refine integrator.dt_s"
        )
    return lines


def _charts(study, path: Path, out: Path) -> Iterator[Path]:
    """The charts ``run`` draws, chosen from what the dataset holds: each file once written.

    Without an intensity axis: the impact force spectrum, one panel per material where the
    material is a grid axis the spectrum would otherwise hold at its first value
    (:func:`~pound_mc.analysis.plot.spectrum_panels`), and with yielding buildings
    (:func:`~pound_mc.analysis.inelastic_chart.yielding_sides`) also the inelastic spectrum
    (ductility demand and peak force, :func:`~pound_mc.analysis.inelastic_chart.inelastic_chart`).
    With two or more gaps on the grid: the pounding probability against the gap with the
    separation rules and the required gap (``_required_gap.png``); with an intensity axis the
    fragility curves; with more than one contact (shear buildings) the peak force per contact
    (``_contacts.png``).  A study without ``[grid]`` has no axis to draw a spectrum against: its
    chart is the distribution of the peak force over the samples.  A study sampled with
    Saltelli's design also gets the Sobol' indices of its peak force (``_sensitivity.png``,
    :func:`~pound_mc.analysis.sensitivity_chart.sensitivity_chart`).
    """
    with xr.open_dataset(path) as ds:
        ds.load()
        charts = []  # (file name's kind, how to draw it)
        if study.method == "saltelli":
            charts.append(("sensitivity", sensitivity_chart))
        if not study.grid:
            charts.append(("distribution", distribution_chart))
        else:
            if study.intensity_key is None:
                charts.append(("spectrum", spectrum_panels))
                sides = yielding_sides(ds)
                if sides:
                    charts.append(("inelastic", partial(inelastic_chart, side=sides[0])))
            if GAP_DIM in ds.dims and ds.sizes[GAP_DIM] > 1:
                base_dir = study.path.parent
                charts.append(("required_gap", partial(required_gap_chart, base_dir=base_dir)))
            if study.intensity_key is not None:
                charts.append(("fragility", fragility_panels))
            if CONTACT_DIM in ds.dims and ds.sizes[CONTACT_DIM] > 1 and "contact_peak_force" in ds:
                charts.append(("contacts", contacts_chart))
        for kind, draw in charts:
            png = out / f"{study.name}_{kind}.png"
            STATUS.say(f"drawing {png.name}")
            draw(ds, png)
            yield png


def check_command(args) -> int:
    """``pound-mc check``: validate a study, print its plan and cost; write no results.

    The estimate times the study itself: the kernels are first compiled (or loaded from the
    cache, see :mod:`pound_mc._jit`) by one warm-up simulation, then ``--calibrate``
    simulations (default: at least 64, and enough to last a second,
    :meth:`~pound_mc.study.engine.StudyEngine.calibrate`) spread evenly over the study run
    with the given threads; their time per
    simulation times the study's size, plus a fixed cost per chunk, is the estimate of the
    run's chunk time (compile time excluded: the run warms up the same way, and after this
    check the kernels are cached).
    """
    study = load_study(args.study)
    for key in ("threads", "chunk_size", "calibrate"):
        value = getattr(args, key)
        if value is not None and value < 1:
            raise InputError(f"must be >= 1, got {value}", key="--" + key.replace("_", "-"))
    engine = StudyEngine(study)
    warm_s, did_compile = warm_up(engine)
    seconds, _, timed = engine.calibrate(workers=args.threads, n=args.calibrate)
    chunk_size = args.chunk_size or study.chunk_size or default_chunk_size(study.n_simulations)
    n_chunks = len(chunk_ranges(study.n_simulations, chunk_size))
    per_sim = seconds + n_chunks * CHUNK_OVERHEAD_S / study.n_simulations
    print(plan_text(study, chunk_size=chunk_size, seconds_per_simulation=per_sim))
    print(resources_text(study, engine, Path(args.out)))
    if seconds > SLOW_SIMULATION_S:
        print(
            f"  warning   : one simulation takes {seconds:.0f} s (more than "
            f"{SLOW_SIMULATION_S:.0f} s): lengthen integrator.dt_s or shorten the record",
        )
    for line in engine.record_warnings:
        print(f"  {line}")
    for line in engine.scene.contact_lines():
        print(f"  {line}")
    if did_compile:
        where = f"kernels compiled now in {warm_s:.1f} s and cached; a run with them cached"
    else:
        where = f"kernels loaded from the cache in {warm_s:.2f} s; a run"
    print(
        f"  calibration: {timed:,} simulations spread over the "
        f"study, plus {CHUNK_OVERHEAD_S * 1e3:.0f} ms per chunk; compile time not included "
        f"({where} does not compile)"
    )
    print("  (nothing written)")
    return 0


def resources_text(study, engine, out: Path) -> str:
    """The memory and disk a run of ``study`` needs, and the free space under ``out``."""
    results = memory_estimate(study, engine.result_layout())
    records = sum(acc.nbytes for _dt, acc in engine.records)
    disk = results  # the chunk files and the dataset, each about the results' size
    probe = out if out.exists() else next((p for p in out.parents if p.exists()), Path("."))
    free = shutil.disk_usage(probe).free
    text = (
        f"  memory    : about {(results + records) / 2**20:,.1f} MiB (results "
        f"{results / 2**20:,.1f}, records {records / 2**20:,.1f})\n"
        f"  disk      : about {disk / 2**20:,.1f} MiB under {out} "
        f"({free / 2**30:,.1f} GiB free)"
    )
    if disk > free:
        text += "\n  warning   : not enough free disk space for the results"
    return text


def compile_command(args) -> int:
    """``pound-mc compile``: compile the kernels of methods and laws into the disk cache."""
    for key, allowed, given in (
        ("--methods", METHODS, args.methods),
        ("--laws", tuple(CONTACT_MODELS), args.laws),
    ):
        bad = [v for v in given or () if v not in allowed]
        if bad:
            raise InputError(f"unknown {', '.join(bad)}; allowed: {', '.join(allowed)}", key=key)
    print(f"compiling kernels into {cache_directory()}", flush=True)
    rows = compile_kernels(args.methods, args.laws, args.structures, stream=sys.stdout)
    total = sum(r["seconds"] for r in rows)
    print(f"{len(rows)} combinations ready in {total:.1f} s")
    return 0


def shipped_studies() -> dict[str, Path]:
    """The study files shipped with the package (``studies/*.toml``), by name."""
    folder = Path(str(resources.files("pound_mc") / "studies"))
    return {p.stem: p for p in sorted(folder.glob("*.toml"))}


def study_template(name: str) -> str:
    """The text of a new study ``name``: the commented template of the package data.

    Raises
    ------
    InputError
        ``name`` is not a study name (letters, digits, ``-`` and ``_``).
    """
    if problem := STUDY["name"].problem(name):
        raise InputError(problem, key="--new")
    template = resources.files("pound_mc") / "templates" / "study.toml"
    return template.read_text(encoding="utf-8").replace("{name}", name)


def _init_new(args) -> int:
    """``pound-mc init --new NAME``: write the commented template as ``NAME.toml``."""
    if args.name:
        raise InputError(f"give a shipped study ({args.name}) or --new NAME, not both")
    name = args.new.removesuffix(".toml")
    text = study_template(name)
    path = Path(args.dir) / f"{name}.toml"
    if path.exists() and not args.force:
        raise InputError("exists; pass --force to overwrite it", file=str(path))
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    print(f"wrote {path}")
    print(f"next: edit it, then pound-mc check {path} && pound-mc run {path}")
    return 0


def init_command(args) -> int:
    """``pound-mc init [NAME]``: write a shipped study (and the scenes it reads) into a folder.

    ``--new NAME`` writes a new study from the commented template instead.
    """
    if args.new is not None:
        return _init_new(args)
    studies = shipped_studies()
    if not args.name:
        print("shipped studies (pound-mc init NAME writes NAME.toml here):")
        for name, path in studies.items():  # each by its [study] description (one line)
            about = tomllib.loads(path.read_text(encoding="utf-8"))["study"].get("description")
            print(f"  {name:20s} {about or ''}")
        return 0
    name = args.name.removesuffix(".toml")
    if name not in studies:
        raise InputError(f"no shipped study {name!r}; there are: {', '.join(studies)}")
    source = studies[name]
    text = source.read_text(encoding="utf-8")
    out = Path(args.dir)
    targets = {out / source.name: text}
    for scene in sorted(source.parent.glob("scenes/*.toml")):
        if f"scenes/{scene.name}" in text:
            targets[out / "scenes" / scene.name] = scene.read_text(encoding="utf-8")
    existing = [str(p) for p in targets if p.exists()]
    if existing and not args.force:
        raise InputError("exists; pass --force to overwrite it", file=existing[0])
    for path, content in targets.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(content, encoding="utf-8")
        print(f"wrote {path}")
    first = next(iter(targets))
    print(f"next: pound-mc check {first} && "
          f"pound-mc run {first}")  # fmt: skip
    return 0
