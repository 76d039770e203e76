"""Sub-commands for single scenes and the numerics: ``simulate``, ``bench``, ``stability``.

Their arguments are declared in :mod:`pound_mc.cli.commands`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from pound_mc.analysis.plot_numerics import (
    stability_map_chart,
    time_history_chart,
    work_precision_chart,
)
from pound_mc.analysis.style import output_path, write_atomically
from pound_mc.errors import InputError, OutputError
from pound_mc.integrators import METHODS
from pound_mc.motions import record_arrays
from pound_mc.motions.preprocessing import WINDOW_PEAK_WARN
from pound_mc.numerics.bench import SCENES, benchmark, head_to_head, peers, shear_scaling
from pound_mc.numerics.stability import stability_map
from pound_mc.scene import load_scene, schema, simulate


def simulate_command(args) -> int:
    """``pound-mc simulate``: one scene; exit status 1 unless it ends ok."""
    scene = load_scene(args.scene)
    if args.method is not None and args.method not in METHODS:
        raise InputError(f"unknown method {args.method!r}; allowed: {', '.join(METHODS)}",
                         key="--method")  # fmt: skip
    if args.dt is not None and (problem := schema.INTEGRATOR["dt_s"].problem(args.dt)):
        raise InputError(problem, key="--dt")  # the bounds of the file's integrator.dt_s
    if args.plot:
        output_path(args.plot, key="--plot", suffix=".png")
    trace = scene.load_record()
    scene.hold_record(record_arrays(trace))  # read once: the run takes it from here
    kept = trace.stats.pound.get("window_peak_fraction", 1.0)
    if kept < WINDOW_PEAK_WARN:  # as check and run say of a study's records
        print(f"warning: {args.scene}: the record.duration_s window keeps {100 * kept:.2g} % of "
              "the record's peak acceleration, which comes later; scaled, that window is not "
              "the earthquake (give a longer duration_s, or none)", file=sys.stderr)  # fmt: skip
    try:
        res = simulate(scene, history=args.plot is not None, method=args.method, dt_s=args.dt)
    except InputError as exc:  # a method given here, not in the file, is named as given
        if args.method is None or exc.key != "integrator.method":
            raise
        raise InputError(exc.message, key="--method") from None
    if args.plot:
        time_history_chart(res, args.plot)
    info = res.to_json()
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        print(f"scene            {args.scene}")
        print(f"method           {info['method']} (contact law {info['contact_model']})")
        print(f"status           {info['status']}")
        print(f"impacts          {_text(info['impacts'], 'd')}")
        print(f"peak force       {_text(info['peak_force_N'], '.6g')} N at t = "
              f"{_text(info['peak_force_time_s'], '.6g')} s")  # fmt: skip
        print(f"max penetration  {_text(info['max_penetration_m'], '.6g')} m")
        if scene.row is None:
            print(f"peak disp left   {_text(info['peak_disp_left_m'], '.6g')} m")
            print(f"peak disp right  {_text(info['peak_disp_right_m'], '.6g')} m")
        else:  # every building of the row, left to right
            for b in info["buildings"]:
                print(f"{'building ' + str(b['building']):<17}peak disp "
                      f"{_text(b['peak_disp'], '.6g')} m" + (
                          f", ductility {_text(b['peak_ductility'], '.4g')}"
                          if scene.inelastic else "") + f" ({b['model']})")  # fmt: skip
        if scene.inelastic:  # the yielding buildings' demands (NaN: an elastic building)
            if scene.row is None:
                for side in ("left", "right"):
                    print(f"{'ductility ' + side:<17}"
                          f"{_text(info[f'peak_ductility_{side}'], '.4g')}")  # fmt: skip
            print(f"hysteresis       {_text(info['hysteretic_energy'], '.6g')} J (dissipated "
                  "by yielding)")  # fmt: skip
        print(f"energy residual  {_text(info['energy_residual'], '.3g')} (of the energy put in)")
        for line in scene.contact_lines():
            print(line)
        if args.plot:
            print(f"chart            {args.plot}")
    return 0 if info["status"] == "ok" else 1


def _text(value, spec: str) -> str:
    """``value`` formatted by ``spec``; ``nan`` where a run that is not ok has none (None)."""
    return "nan" if value is None else format(value, spec)


def bench_command(args) -> int:
    """``pound-mc bench``: B1 head to head with ratios, then the work-precision sweep.

    ``--json`` prints one object: ``head_to_head`` (rows), ``ratios``, ``overheads``,
    ``load_before`` / ``load_after`` (``os.getloadavg()``), ``repeats``, and ``sweep`` (the
    work-precision rows, also written to ``bench.csv``) and ``shear_scaling`` (``adaptive`` on
    shear pairs of 3+5, 10+10 and 20+20 storeys, with a shear scene in ``--scenes``); both
    absent with ``--head-to-head-only``.  ``--peers`` runs only
    :func:`~pound_mc.numerics.bench.peers` (B1 in OpenSees and in ``adaptive``); its JSON:
    ``peers`` (rows), the load averages, ``repeats``, the reference's peak force and
    impacts, ``opensees_reason`` (why OpenSees was not timed, or null).
    """
    for m in args.methods or []:
        if m not in METHODS:
            raise InputError(
                f"unknown method {m!r}; allowed: {', '.join(METHODS)}", key="--methods"
            )
    for s in args.scenes:
        if s not in SCENES:
            raise InputError(f"unknown scene {s!r}; allowed: {', '.join(SCENES)}", key="--scenes")
    if args.repeats < 1:
        raise InputError(f"must be >= 1, got {args.repeats}", key="--repeats")
    if args.peers:
        return _peers(args)
    out = None if args.head_to_head_only else _out_dir(args.out)  # before minutes of timing
    duel, info = head_to_head(repeats=args.repeats)
    if not args.json:
        _print_head_to_head(duel, info)
    if args.head_to_head_only:
        if args.json:
            print(json.dumps({"head_to_head": duel.to_dict(orient="records"), **info}, indent=1))
        return 0
    table = benchmark(args.scenes, args.methods, repeats=args.repeats, progress=not args.json)
    # the shear pairs of growing size, with a shear scene asked for
    shear = any(name.startswith("shear") for name in args.scenes)
    scaling = shear_scaling(repeats=args.repeats) if shear else None
    write_atomically(out / "bench.csv", lambda tmp: table.to_csv(tmp, index=False))
    work_precision_chart(table, out / "work_precision.png")
    if args.json:
        sweep = json.loads(table.to_json(orient="records"))
        extra = {} if scaling is None else {"shear_scaling": scaling.to_dict(orient="records")}
        print(json.dumps({"head_to_head": duel.to_dict(orient="records"), **info,
                          "sweep": sweep, **extra}, indent=1))  # fmt: skip
        return 0
    cols = ["scene", "method", "dt_s", "substeps", "seconds", "impacts", "err_peak_force",
            "err_peak_disp_left", "err_peak_disp_right", "status"]  # fmt: skip
    print("\nwork-precision sweep (median of each point after compilation, one thread):")
    print(table[cols].to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    if scaling is not None:
        print("\nadaptive on shear pairs of growing size (median, one thread, interleaved):")
        print(scaling.to_string(index=False, float_format=lambda x: f"{x:.3g}"))
    print(f"wrote {out / 'bench.csv'} and {out / 'work_precision.png'}")
    return 0


def _peers(args) -> int:
    """``pound-mc bench --peers``: B1 in OpenSees and in ``adaptive``; exit 0 either way."""
    table, info = peers(repeats=args.repeats)
    if args.json:
        rows = json.loads(table.to_json(orient="records"))  # NaN as null
        print(json.dumps({"peers": rows, **info}, indent=1))
        return 0
    load = " / ".join(f"{x:.2f}" for x in info["load_before"])
    print(f"B1 against other tools: one thread, interleaved, median of {info['repeats']} runs "
          f"each; load average {load} (1/5/15 min) before")  # fmt: skip
    if info["opensees_reason"]:
        print(f"OpenSees is not timed: {info['opensees_reason']}")
    print(f"{'contender':22s} {'time [ms]':>10s} {'x adaptive':>10s} {'peak-force error':>17s} "
          f"{'disp error':>10s} {'impacts':>7s}")  # fmt: skip
    for r in table.itertuples():
        disp = max(r.err_peak_disp_left, r.err_peak_disp_right)
        print(f"{r.label:22s} {r.seconds * 1e3:10.3f} {r.x_adaptive:10.1f} "
              f"{r.err_peak_force:17.2e} {disp:10.2e} {r.impacts:7d}")  # fmt: skip
    print(f"reference (SciPy, tight tolerance): peak force {info['reference_peak_force']:.6g} N, "
          f"{info['reference_impacts']} impacts; errors relative to it, disp the larger of "
          "the two buildings'")  # fmt: skip
    print("an OpenSees time is the whole run: model, analysis and reading its recorders")
    load = " / ".join(f"{x:.2f}" for x in info["load_after"])
    print(f"load average after: {load}")
    return 0


def _print_head_to_head(duel, info) -> None:
    """The head-to-head table, its ratios and the machine load, as text."""
    load = " / ".join(f"{x:.2f}" for x in info["load_before"])
    print(f"B1 head to head: one thread, interleaved, median of {info['repeats']} runs each; "
          f"load average {load} (1/5/15 min) before")  # fmt: skip
    print(f"{'contender':28s} {'time [ms]':>10s} {'x adaptive':>10s} {'peak-force error':>17s} "
          f"{'impacts':>7s}")  # fmt: skip
    for r in duel.itertuples():
        print(f"{r.label:28s} {r.seconds * 1e3:10.3f} {r.x_adaptive:10.2f} "
              f"{r.err_peak_force:17.2e} {r.impacts:7d}")  # fmt: skip
    print("ratios (median over the rounds of the ratio within a round):")
    for name, value in info["ratios"].items():
        print(f"  {name:42s} {value:8.2f}")
    print("set-up of the public call (median over the rounds of simulate() minus the kernel):")
    for name, value in info["overheads"].items():
        print(f"  {name:42s} {value:8.3f}" + ("  (below the timing noise)" if value < 0 else ""))
    load = " / ".join(f"{x:.2f}" for x in info["load_after"])
    print(f"load average after: {load}")


def stability_command(args) -> int:
    """``pound-mc stability``: the largest stable step against contact stiffness."""
    out = _out_dir(args.out)  # before the map is computed
    table = stability_map()
    _write_table(args, out, table, "stability.csv", stability_map_chart, "stability_map.png",
                 ".4g")  # fmt: skip
    return 0


def _out_dir(path) -> Path:
    """The ``--out`` folder, made and checked writable before any work is done."""
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
        probe = out / ".pound-mc-write-check"
        probe.touch()
        probe.unlink()
    except OSError as exc:
        raise OutputError(f"cannot write results here: {exc.strerror or exc}", file=str(out),
                          key="--out") from None  # fmt: skip
    return out


def _write_table(args, out, table, csv_name, chart, png_name, number_format,
                 columns=None) -> None:  # fmt: skip
    """Write ``table`` as CSV and its chart into ``out`` (:func:`_out_dir`); print it.

    As JSON (``args.json``) or as text showing ``columns`` (default all), numbers in
    ``number_format``.
    """
    write_atomically(out / csv_name, lambda tmp: table.to_csv(tmp, index=False))
    chart(table, out / png_name)
    if args.json:
        print(table.to_json(orient="records", indent=1))
    else:
        shown = table if columns is None else table[columns]
        print(shown.to_string(index=False, float_format=lambda x: f"{x:{number_format}}"))
        print(f"wrote {out / csv_name} and {out / png_name}")
