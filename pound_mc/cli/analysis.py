"""Subcommands that look at results: ``plot`` and ``report``.

``pound-mc plot FILE --kind KIND`` draws one chart.  What ``FILE`` is depends on the kind:

==================  ======================================================================
kind                file
==================  ======================================================================
``spectrum``        a study dataset (``pound-mc run``'s ``.nc``)
``probability``     a study dataset with the gap on its grid
``distribution``    a study dataset
``restitution``     a study dataset (its sampled ``e`` marked) or nothing: ``-``
``work-precision``  ``pound-mc bench``'s CSV (``outputs/bench.csv``)
``stability``       ``pound-mc stability``'s CSV (``outputs/stability.csv``)
``history``         a scene file (``.toml``), or a study dataset with ``--sel``/``--sample``:
                    that simulation is rebuilt from the dataset's study text and run again
==================  ======================================================================
"""

from __future__ import annotations

import argparse
from pathlib import Path

#: Chart kinds of ``pound-mc plot``.
KINDS = (
    "spectrum",
    "probability",
    "distribution",
    "restitution",
    "work-precision",
    "stability",
    "history",
)


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``plot`` and ``report`` to the ``pound-mc`` parser."""
    p = sub.add_parser(
        "plot",
        help="draw a chart of a study dataset, a bench/stability CSV or a scene",
        description=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("file", metavar="FILE", help="RESULT.nc, bench.csv, stability.csv or SCENE.toml")
    p.add_argument("--kind", required=True, choices=KINDS, help="which chart")
    p.add_argument("--out", metavar="FILE.png", help="PNG to write (default next to FILE)")
    p.add_argument(
        "--sel",
        action="append",
        default=[],
        metavar="DIM=VALUE",
        help="hold a grid dimension at a value (nearest); repeatable",
    )
    p.add_argument("--record", metavar="N|NAME", help="record index or name")
    p.add_argument("--sample", type=int, default=0, metavar="N", help="sample (history; 0)")
    p.add_argument("--line", metavar="DIM", help="dimension drawn as one line per value")
    p.add_argument("--by", metavar="DIM", help="dimension of the distribution chart's groups")
    p.set_defaults(func=_plot)

    p = sub.add_parser("report", help="write a self-contained HTML results page of a study")
    p.add_argument("file", metavar="RESULT.nc")
    p.add_argument("--out", metavar="FILE.html", help="page to write (default next to RESULT.nc)")
    p.set_defaults(func=_report)


def _parse_sel(items) -> dict:
    from pound_mc.errors import InputError

    out = {}
    for item in items:
        dim, sep, value = item.partition("=")
        if not sep or not dim:
            raise InputError(f"expected DIM=VALUE, got {item!r}", key="--sel")
        try:
            out[dim] = float(value)
        except ValueError:
            out[dim] = value
    return out


def _record(value):
    if value is None:
        return None
    return int(value) if value.lstrip("-").isdigit() else value


def _open_dataset(path: Path):
    import xarray as xr

    from pound_mc.errors import InputError

    if not path.is_file():
        raise InputError("no such file", file=str(path))
    try:
        return xr.open_dataset(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"not a readable netCDF dataset: {exc}", file=str(path)) from None


def _read_csv(path: Path, columns):
    import pandas as pd

    from pound_mc.errors import InputError

    if not path.is_file():
        raise InputError("no such file", file=str(path))
    table = pd.read_csv(path)
    missing = [c for c in columns if c not in table]
    if missing:
        raise InputError(f"is not the right CSV: no column {missing[0]!r}", file=str(path))
    return table


def draw(path: str | Path, kind: str, *, out=None, sel=None, record=None, sample=0, **kwargs):
    """Draw chart ``kind`` of the file at ``path`` (see the module docstring).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from pound_mc.analysis import plot, plot_numerics

    path = Path(path)
    sel = dict(sel or {})
    if kind == "work-precision":
        return plot_numerics.work_precision_chart(
            _read_csv(path, ("scene", "method", "seconds", "err_peak_force")), out
        )
    if kind == "stability":
        return plot_numerics.stability_map_chart(
            _read_csv(path, ("method", "beta", "predicted", "observed")), out
        )
    if kind == "restitution" and str(path) == "-":
        return plot.restitution_chart(out)
    if kind == "history" and path.suffix == ".toml":
        from pound_mc.scene import load_scene, simulate

        return plot_numerics.time_history_chart(simulate(load_scene(path), history=True), out)
    ds = _open_dataset(path)
    with ds:
        ds.load()
        if kind == "spectrum":
            if sel:  # held dims: the spectrum chart draws their first (here: only) value
                ds = _hold_first(ds, sel)
            return plot.spectrum_chart(
                ds, out, line=kwargs.get("line"), record=0 if record is None else record
            )
        if kind == "probability":
            return plot.probability_chart(
                ds, out, record=record, sel=sel, line=kwargs.get("line"), base_dir=path.parent
            )
        if kind == "distribution":
            return plot.distribution_chart(
                ds, out, record=0 if record is None else record, sel=sel, by=kwargs.get("by")
            )
        if kind == "restitution":
            return ds.pound.plot.restitution(out)
        if kind == "history":
            return ds.pound.plot.history(
                out, record=0 if record is None else record, sample=sample, **sel
            )
    raise ValueError(f"unknown kind {kind!r}")  # pragma: no cover - argparse checks it


def _hold_first(ds, sel):
    """``ds`` with the dims in ``sel`` reduced to the value nearest ``sel[dim]`` (kept as dims)."""
    from pound_mc.analysis.plot import _nearest_index

    return ds.isel({dim: [_nearest_index(ds, dim, v)] for dim, v in sel.items()})


def _plot(args) -> int:
    from pound_mc.errors import InputError

    path = Path(args.file)
    if args.out:
        out = Path(args.out)
    else:
        stem = "restitution" if args.file == "-" else path.stem
        out = (Path("outputs") if args.file == "-" else path.parent) / f"{stem}_{args.kind}.png"
    try:
        draw(
            path,
            args.kind,
            out=out,
            sel=_parse_sel(args.sel),
            record=_record(args.record),
            sample=args.sample,
            line=args.line,
            by=args.by,
        )
    except (ValueError, KeyError, IndexError) as exc:
        raise InputError(str(exc).strip("'\""), file=args.file) from None
    print(f"wrote {out}")
    return 0


def _report(args) -> int:
    from pound_mc.analysis.report import write_report

    path = Path(args.file)
    out = Path(args.out) if args.out else path.with_name(f"{path.stem}_report.html")
    ds = _open_dataset(path)
    with ds:
        ds.load()
        write_report(ds, out, base_dir=path.parent)
    print(f"wrote {out}")
    return 0
