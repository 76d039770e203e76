"""Sub-commands that look at results: ``plot`` and ``report``.

Their arguments are declared in :mod:`pound_mc.cli.commands` (``pound-mc plot --help`` lists
what ``FILE`` is for each chart kind); :func:`draw` is ``pound-mc plot`` as a function.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import xarray as xr

from pound_mc.analysis import plot, plot_numerics
from pound_mc.analysis.report import write_report
from pound_mc.errors import InputError
from pound_mc.scene import load_scene, simulate


def _parse_sel(items) -> dict:
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
    if not path.is_file():
        raise InputError("no such file", file=str(path))
    try:
        return xr.open_dataset(path)
    except (OSError, ValueError) as exc:
        raise InputError(f"not a readable netCDF dataset: {exc}", file=str(path)) from None


def _read_csv(path: Path, columns):
    if not path.is_file():
        raise InputError("no such file", file=str(path))
    table = pd.read_csv(path)
    missing = [c for c in columns if c not in table]
    if missing:
        raise InputError(f"is not the right CSV: no column {missing[0]!r}", file=str(path))
    return table


def draw(path: str | Path, kind: str, *, out=None, sel=None, record=None, sample=0, **kwargs):
    """Draw chart ``kind`` of the file at ``path``.

    ``pound-mc plot --help`` says which file each kind reads.

    Returns
    -------
    matplotlib.figure.Figure
    """
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
    return ds.isel({dim: [plot._nearest_index(ds, dim, v)] for dim, v in sel.items()})


def plot_command(args) -> int:
    """``pound-mc plot``: draw one chart (:func:`draw`)."""
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


def report_command(args) -> int:
    """``pound-mc report``: the HTML results page of a study dataset."""
    path = Path(args.file)
    out = Path(args.out) if args.out else path.with_name(f"{path.stem}_report.html")
    ds = _open_dataset(path)
    with ds:
        ds.load()
        write_report(ds, out, base_dir=path.parent)
    print(f"wrote {out}")
    return 0
