"""Sub-commands about ground motions: ``records list`` and ``records info``.

Their arguments are declared in :mod:`pound_mc.cli.commands`.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pound_mc.analysis.plot import save
from pound_mc.analysis.style import output_path
from pound_mc.errors import InputError
from pound_mc.motions import (
    BUILTIN_RECORDS,
    UNITS_FROM,
    G,
    builtin_catalogue,
    load_record,
    record_arrays,
    record_info,
    suites,
)
from pound_mc.physics.spectra import response_spectrum


def list_command(args) -> int:
    """``pound-mc records list``: the built-in records and the record suites."""
    catalogue = builtin_catalogue()
    suite_table = suites.suite_catalogue()
    if args.json:
        print(json.dumps({**catalogue, **suite_table}, indent=1))
        return 0
    columns = ("name", "event", "station", "component", "format", "source_package")
    rows = [
        {"name": f"builtin:{name}", **{k: str(entry[k]) for k in columns[1:]}}
        for name, entry in catalogue.items()
    ]
    widths = {c: max(len(c), *(len(r[c]) for r in rows)) for c in columns}
    print("  ".join(c.ljust(widths[c]) for c in columns).rstrip())
    print("  ".join("-" * widths[c] for c in columns))
    for row in rows:
        print("  ".join(row[c].ljust(widths[c]) for c in columns).rstrip())
    print()
    print("record suites ([[records]] source = NAME: one record per component):")
    for name, entry in suite_table.items():
        print(f"  {name}  ({entry['package']} package): {entry['description']}")
    return 0


def _resolve(source: str) -> str:
    """A bare catalogue name means ``builtin:NAME`` unless a file of that name exists."""
    if ":" not in source and source.lower() in BUILTIN_RECORDS and not Path(source).exists():
        return f"builtin:{source.lower()}"
    return source


def info_command(args) -> int:
    """``pound-mc records info``: PGA, duration and step of a record."""
    source = _resolve(args.source)
    seed = args.seed if source.lower().startswith("synthetic:") else None
    if ":" not in source and not Path(source).exists():  # neither a file nor a built-in name
        raise InputError("file not found, nor a built-in record (pound-mc records list)",
                         file=source)  # fmt: skip
    trace = load_record(
        source, demean=not args.raw, units=args.units, component=args.component, seed=seed
    )
    if args.plot:
        output_path(args.plot, key="--plot", suffix=".png")
    info = record_info(trace)
    if args.plot:
        _plot(trace, info, args.plot)
    if args.json:
        print(json.dumps(info))
        return 0
    print(f"{'record':<12} {info.get('source', source)}")
    for key in ("event", "date", "station", "component", "format"):
        if key in info:
            print(f"{key:<12} {info[key]}")
    if "source_units" in info:
        print(f"{'source units':<12} {info['source_units']}{_units_origin(trace, info)}")
    dt, _ = record_arrays(trace)
    print(f"{'samples':<12} {info['npts']} at dt = {dt:g} s ({1.0 / dt:g} Hz)")
    print(f"{'duration':<12} {info['duration_s']:.4g} s")
    print(f"{'PGA':<12} {info['pga_g']:.5g} g = {info['pga_m_s2']:.5g} m/s^2")
    if args.plot:
        print(f"wrote {args.plot}")
    return 0


def _units_origin(trace, info: dict) -> str:
    """Where the record's units came from, as a parenthesis (empty where unknown)."""
    origin = info.get("source_units_from")
    if origin not in UNITS_FROM:
        return ""
    words = UNITS_FROM[origin]
    if origin == "header":
        header = trace.stats.pound.get("header") or []
        if len(header) >= 3:
            words += f", line 3: {header[2].strip()!r}"
    elif origin == "units":
        words = "given with --units"
    return f" ({words})"


def _plot(trace, info: dict, path: str) -> None:
    dt, acc = record_arrays(trace)
    t = np.arange(acc.size) * dt
    periods = np.geomspace(max(0.02, 2.0 * dt), 5.0, 120)
    psa = response_spectrum(dt, acc, periods, damping=0.05)
    fig = Figure(figsize=(8.0, 6.5), layout="constrained")
    ax1, ax2 = fig.subplots(2, 1)
    ax1.plot(t, acc / G, lw=0.6, color="tab:blue")
    ax1.set_xlabel("time [s]")
    ax1.set_ylabel("ground acceleration [g]")
    title = info.get("source", "")
    details = ", ".join(str(info[k]) for k in ("event", "station", "component") if k in info)
    ax1.set_title(f"{title}\n{details}" if details else title, fontsize=9)
    ax1.grid(alpha=0.3)
    ax2.plot(periods, psa / G, color="tab:red")
    ax2.set_xscale("log")
    ax2.set_xlabel("period [s]")
    ax2.set_ylabel("pseudo-acceleration [g]")
    ax2.set_title("5 %-damped pseudo-acceleration response spectrum", fontsize=9)
    ax2.grid(alpha=0.3, which="both")
    save(fig, path)
