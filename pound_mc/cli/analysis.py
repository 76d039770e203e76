"""Sub-commands that look at results: ``plot``, ``report`` and ``fragility``.

Their arguments are declared in :mod:`pound_mc.cli.commands` (``pound-mc plot --help`` lists
what ``FILE`` is for each chart kind); :func:`draw` is ``pound-mc plot`` as a function.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from pound_mc.analysis import distribution_chart, plot, plot_numerics, profiles, risk_chart
from pound_mc.analysis.hazard import power_law, read_hazard
from pound_mc.analysis.labels import dim_text
from pound_mc.analysis.report import write_report
from pound_mc.analysis.risk import counted, fragility, left_out_why
from pound_mc.analysis.selection import MATERIAL_DIM, dim_name, selection
from pound_mc.analysis.site_risk import site_assessment
from pound_mc.analysis.style import output_path, require_simulations
from pound_mc.errors import InputError, OutputError
from pound_mc.scene import load_scene, simulate
from pound_mc.study.dataset import open_dataset, study_folder


def _parse_sel(items) -> dict:
    """``--sel DIM=VALUE`` items as ``{dim: text}`` (:func:`_typed_sel` reads the values)."""
    out = {}
    for item in items:
        dim, sep, value = item.partition("=")
        if not sep or not dim:
            raise InputError(f"expected DIM=VALUE, got {item!r}", key="--sel")
        out[dim] = value
    return out


def _grid_dim(ds, name: str, key: str) -> str:
    """The grid dimension ``name`` given to option ``key``, or the study file's key of one.

    ``left.period_s`` names ``left_period_s``; anything else that is not a grid dimension is
    refused, naming the option and the grid.
    """
    grid = ds.pound.grid_dims
    name = dim_name(ds, name)
    if name not in grid:
        raise InputError(f"no grid dimension {name!r}; the grid has {grid}", key=key)
    return name


def _typed_sel(ds, sel: dict) -> dict:
    """``sel``'s text values as the dimension's coordinate holds them: numbers, or names.

    A dimension may be named by the study file's key (``left.period_s`` for
    ``left_period_s``).  A material axis takes its materials' names too, as the charts'
    ``sel`` does (:func:`~pound_mc.analysis.selection.selection`).  ``record`` and ``sample`` are
    ``--record`` and ``--sample``: they are refused here.
    """
    out = {}
    for dim, value in sel.items():
        if dim in ("record", "sample"):
            raise InputError(f"{dim} is not held with --sel; use --{dim}", key="--sel")
        dim = _grid_dim(ds, dim, "--sel")
        if not isinstance(value, str):
            out[dim] = value
            continue
        names = [str(n) for n in ds["material"].values] if dim == MATERIAL_DIM else []
        if value in names or ds[dim].dtype.kind not in "fiu":  # a name: selection() reads it
            out[dim] = value
        else:
            try:
                out[dim] = float(value)
            except ValueError:
                out[dim] = math.nan
            if not math.isfinite(out[dim]):
                allowed = f"one of {', '.join(names)} or a number" if names else "a number"
                raise InputError(f"{dim}={value!r}: {dim} takes {allowed}", key="--sel")
    return selection(ds, out)


def _record(value):
    if value is None:
        return None
    return int(value) if value.lstrip("-").isdigit() else value


def _no_file(path: Path, what: str) -> InputError:
    """The error for a ``path`` that is not a file: a folder, or nothing."""
    if path.is_dir():
        return InputError(f"is a folder; give {what}", file=str(path))
    return InputError("no such file", file=str(path))


def _open_dataset(path: Path):
    """The study dataset at ``path``, or an :class:`InputError` saying what is wrong with it."""
    if not path.is_file():
        raise _no_file(path, "a study dataset (pound-mc run writes OUT/NAME.nc)")
    ds = open_dataset(path)
    try:
        require_simulations(ds, file=str(path))
    except InputError:
        ds.close()
        raise
    return ds


def _read_csv(path: Path, columns, numbers=()):
    """The CSV table at ``path`` with ``columns``, those in ``numbers`` numeric, or an error."""
    if not path.is_file():
        raise _no_file(path, f"a CSV table with the columns {', '.join(columns)}")
    try:
        table = pd.read_csv(path)
    except (UnicodeDecodeError, pd.errors.ParserError, pd.errors.EmptyDataError, OSError):
        raise InputError(
            f"is not a CSV table (expected the columns {', '.join(columns)})", file=str(path)
        ) from None
    missing = [c for c in columns if c not in table]
    if missing:
        raise InputError(f"is not the right CSV: no column {missing[0]!r}", file=str(path))
    if table.empty:
        raise InputError("has no rows: nothing to draw", file=str(path))
    for column in numbers:
        values = pd.to_numeric(table[column], errors="coerce")
        bad = np.flatnonzero(values.isna() & table[column].notna())
        if bad.size:
            text = table[column].iloc[bad[0]]
            raise InputError(f"row {bad[0] + 1}: {text!r} is not a number", file=str(path),
                             key=column)  # fmt: skip
        table[column] = values
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
    wp_numbers, st_numbers = ("seconds", "err_peak_force"), ("beta", "predicted", "observed")
    if kind == "work-precision":
        return plot_numerics.work_precision_chart(
            _read_csv(path, ("scene", "method", "seconds", "err_peak_force"), wp_numbers), out
        )
    if kind == "stability":
        return plot_numerics.stability_map_chart(
            _read_csv(path, ("method", "beta", "predicted", "observed"), st_numbers), out
        )
    if kind == "restitution" and str(path) == "-":
        return plot.restitution_chart(out)
    if kind == "history" and path.suffix == ".toml":
        return plot_numerics.time_history_chart(simulate(load_scene(path), history=True), out)
    ds = _open_dataset(path)
    with ds:
        ds.load()
        sel = _typed_sel(ds, sel)
        for option in ("line", "by"):  # a grid dimension, or the study file's key of one
            value = kwargs.get(option)
            if value is not None and not (option == "by" and value == "record"):
                kwargs[option] = _grid_dim(ds, value, f"--{option}")
        # the runs the chart counts are those of its event: pounding for the probability and
        # the required gap, --event for the fragility, forces for the others
        event = "pounding" if kind in ("probability", "required-gap") else "peak_force"
        if kind == "fragility":
            event = kwargs.get("event") or "pounding"
        if kind not in ("history", "restitution") and not bool(counted(ds, event).any()):
            counts = ", ".join(f"{n} {s}" for s, n in ds.pound.status_counts().items() if n)
            raise InputError(f"nothing to draw: no simulation ended with status ok ({counts})")
        if kind == "spectrum" and not sel and record is None and kwargs.get("line") is None:
            return plot.spectrum_panels(ds, out)  # as run draws it: a panel per material
        if kind == "spectrum":
            return plot.spectrum_chart(
                ds,
                out,
                line=kwargs.get("line"),
                record="pooled" if record is None else record,
                sel=sel,
            )
        if kind in ("contacts", "drift", "ductility") and record is not None:  # one record
            sel["record"] = ds["record"].values[plot._record_index(ds, record)]
        if kind == "contacts":
            return profiles.contacts_chart(ds, out, line=kwargs.get("line"), sel=sel)
        if kind in ("drift", "ductility"):
            return profiles.profile_chart(ds, out, quantity=kind, line=kwargs.get("line"), sel=sel)
        if kind == "probability":
            return plot.probability_chart(
                ds,
                out,
                record=record,
                sel=sel,
                line=kwargs.get("line"),
                base_dir=study_folder(ds, path.parent),
            )
        if kind == "distribution":
            return distribution_chart.distribution_chart(
                ds, out, record=record, sel=sel, by=kwargs.get("by")
            )
        if kind == "restitution":
            return ds.pound.plot.restitution(out).figure
        if kind == "history":
            axes = ds.pound.plot.history(
                out, record=0 if record is None else record, sample=sample, **sel
            )
            return np.ravel(axes)[0].figure
        if kind == "fragility":
            return risk_chart.fragility_panels(
                ds, out, im=kwargs.get("im"), event=kwargs.get("event") or "pounding", sel=sel
            )
        if kind == "required-gap":
            return risk_chart.required_gap_chart(
                ds,
                out,
                probability=_probability(kwargs.get("probability")),
                line=kwargs.get("line"),
                sel=sel,
                base_dir=study_folder(ds, path.parent),
            )
    raise ValueError(f"unknown kind {kind!r}")  # pragma: no cover - argparse checks it


def _probability(value) -> float:
    """The target probability of the required-gap chart: 0.1, or ``value`` in (0, 1)."""
    if value is None:
        return 0.1
    if not 0.0 < value < 1.0:
        raise InputError(f"must lie in (0, 1), got {value}", key="--probability")
    return float(value)


#: The options each chart reads besides FILE, ``--kind`` and ``--out``; another is refused
#: (silently ignored, it would leave the user believing the chart shows what it does not).
PLOT_OPTIONS = {
    "spectrum": ("sel", "record", "line"),
    "probability": ("sel", "record", "line"),
    "distribution": ("sel", "record", "by"),
    "restitution": (),
    "work-precision": (),
    "stability": (),
    "history": ("sel", "record", "sample"),
    "contacts": ("sel", "record", "line"),
    "drift": ("sel", "record", "line"),
    "ductility": ("sel", "record", "line"),
    "fragility": ("sel", "im", "event"),
    "required-gap": ("sel", "line", "probability"),
}


def _refuse_foreign_options(args) -> None:
    """An option given that chart ``args.kind`` does not read: an error naming it."""
    scene = args.kind == "history" and Path(args.file).suffix == ".toml"  # one run: no axes
    reads = () if scene else PLOT_OPTIONS[args.kind]
    for name in ("sel", "record", "sample", "line", "by", "im", "event", "probability"):
        if getattr(args, name) in (None, []) or name in reads:
            continue
        users = [kind for kind, options in PLOT_OPTIONS.items() if name in options]
        where = "a scene file's history" if scene else f"--kind {args.kind}"
        raise InputError(f"does not apply to {where} (only to {', '.join(users)})",
                         key=f"--{name}")  # fmt: skip


def plot_command(args) -> int:
    """``pound-mc plot``: draw one chart (:func:`draw`)."""
    path = Path(args.file)
    _refuse_foreign_options(args)
    if args.out:
        out = Path(args.out)
    else:
        stem = "restitution" if args.file == "-" else path.stem
        name = args.kind.replace("-", "_")  # as run names them: NAME_required_gap.png
        out = (Path("outputs") if args.file == "-" else path.parent) / f"{stem}_{name}.png"
    output_path(out, key="--out", suffix=".png")  # before anything is read or drawn
    try:
        draw(
            path,
            args.kind,
            out=out,
            sel=_parse_sel(args.sel),
            record=_record(args.record),
            sample=args.sample or 0,
            line=args.line,
            by=args.by,
            im=args.im,
            event=args.event,
            probability=args.probability,
        )
    except OutputError:
        raise
    except InputError as exc:
        raise InputError(exc.message, file=args.file, key=exc.key) from None
    except (ValueError, KeyError, IndexError) as exc:
        message = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
        text = message.splitlines()
        raise InputError(text[0] if text else type(exc).__name__, file=args.file) from None
    print(f"wrote {out}")
    return 0


def report_command(args) -> int:
    """``pound-mc report``: the HTML results page of a study dataset."""
    path = Path(args.file)
    out = Path(args.out) if args.out else path.with_name(f"{path.stem}_report.html")
    output_path(out, key="--out")
    hazard = None if args.hazard is None and args.hazard_power is None else hazard_of(args)
    ds = _open_dataset(path)
    with ds:
        ds.load()
        try:
            site = None
            if hazard is not None:  # the risk section, as pound-mc risk gives it
                site = site_assessment(ds, hazard, codes_of(args), im=args.im, event=args.event,
                                       target_rate=args.target_rate,
                                       target_probability=args.target_probability,
                                       years=args.years)  # fmt: skip
            write_report(ds, out, base_dir=study_folder(ds, path.parent), site=site)
        except OutputError:
            raise
        except InputError as exc:
            raise InputError(exc.message, file=str(path), key=exc.key) from None
    print(f"wrote {out}")
    return 0


def numbers_of(text: str | None, key: str, count: tuple[int, ...]) -> list[float] | None:
    """``"8,5.5,1"`` as numbers > 0 (``count``: how many are allowed)."""
    if text is None:
        return None
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in count or not all(math.isfinite(v) and v > 0 for v in values):
        raise InputError(f"give {' or '.join(map(str, count))} numbers > 0 separated by commas, "
                         f"got {text!r}", key=key)  # fmt: skip
    return values


def codes_of(args) -> dict:
    """The ``code_gaps`` factors the options give (none: the rules only)."""
    asce = numbers_of(args.asce, "--asce", (3,))
    ec8 = numbers_of(args.ec8, "--ec8", (1, 2))
    return {
        "asce": None if asce is None else tuple(asce),
        "ec8": None if ec8 is None else (ec8[0], ec8[1] if len(ec8) > 1 else None,
                                         bool(args.same_levels)),
    }  # fmt: skip


def hazard_of(args):
    """The hazard curve ``--hazard FILE.csv`` or ``--hazard-power K0,K`` gives."""
    if args.hazard is not None:
        return read_hazard(args.hazard)
    k0, k = numbers_of(args.hazard_power, "--hazard-power", (2,))
    return power_law(k0, k)


def _jsonable(value):
    """Floats, with NaN and infinities as None (JSON has neither)."""
    array = np.asarray(value, dtype=float)
    out = np.where(np.isfinite(array), array, np.nan).tolist()
    if isinstance(out, float):
        return None if math.isnan(out) else out
    return json.loads(json.dumps(out).replace("NaN", "null"))


def _where(ds, dim: str, value: float) -> str:
    """``"gap 20 mm"``: a grid value as people write it (a gap in mm)."""
    if dim == "contact_gap_m":
        return f"{dim_text(ds, dim)} {1e3 * value:g} mm"
    return f"{dim_text(ds, dim)} {value:g}"


def fragility_command(args) -> int:
    """``pound-mc fragility``: lognormal fragility per combination of the other grid axes."""
    path = Path(args.file)
    if args.n_boot < 0:
        raise InputError(f"must be >= 0, got {args.n_boot}", key="--n-boot")
    ds = _open_dataset(path)
    with ds:
        ds.load()
        try:
            fit = fragility(ds, args.im, args.event, n_boot=args.n_boot)
        except InputError as exc:
            raise InputError(exc.message, file=str(path), key=exc.key) from None
    rest = list(fit["theta"].dims)
    units = fit["theta"].attrs.get("units", "1")
    im_units = "g" if fit.attrs["im"] in ("sa_g", "pga_g") or units == "1" else units
    out = {
        "im": fit.attrs["im"],
        "im_units": im_units,
        "event": fit.attrs["event"],
        "dims": rest,
        "coords": {d: np.asarray(fit[d].values).tolist() for d in rest},
        "theta": _jsonable(fit["theta"].values),
        "beta": _jsonable(fit["beta"].values),
        "theta_ci": _jsonable(fit["theta_ci"].values),
        "beta_ci": _jsonable(fit["beta_ci"].values),
        "ci": fit.attrs["ci"],
        "message": np.asarray(fit["fit_message"].values, dtype=object).tolist(),
        "n_boot_discarded": np.asarray(fit["n_boot_discarded"].values).tolist(),
        "bootstrap_note": np.asarray(fit["bootstrap_note"].values, dtype=object).tolist(),
        # the stripes fitted: per combination of ``dims``, one count per intensity
        "intensities": np.asarray(fit[fit.attrs["im"]].values).tolist(),
        "n_event": fit["n_event"].transpose(*rest, fit.attrs["im"]).values.tolist(),
        "n_total": fit["n_total"].transpose(*rest, fit.attrs["im"]).values.tolist(),
        # per combination and intensity: the runs the fit leaves out (not counted)
        "n_left_out": fit["n_left_out"].transpose(*rest, fit.attrs["im"]).values.tolist(),
    }
    if args.json:
        print(json.dumps(out, indent=1))
        return 0
    print(f"fragility of {out['event']} against {out['im']} ({path.name}); "
          f"{round(100 * fit.attrs['ci'])} % bootstrap intervals")  # fmt: skip
    n_used = int(fit["n_total"].sum())
    n_out = int(fit["n_left_out"].sum())
    why = left_out_why(out["event"])
    print(f"  {n_used:,} simulations counted, "
          + (f"{n_out:,} left out ({why})" if n_out else "none left out"))  # fmt: skip
    flat_theta = np.atleast_1d(fit["theta"].values).ravel()
    flat_beta = np.atleast_1d(fit["beta"].values).ravel()
    tci = fit["theta_ci"].values.reshape(-1, 2)
    bci = fit["beta_ci"].values.reshape(-1, 2)
    msgs = np.atleast_1d(np.asarray(fit["fit_message"].values, dtype=object)).ravel()
    notes = np.atleast_1d(np.asarray(fit["bootstrap_note"].values, dtype=object)).ravel()
    grids = np.meshgrid(*(fit[d].values for d in rest), indexing="ij") if rest else []
    for k in range(flat_theta.size):
        where = ", ".join(
            _where(fit, d, float(g.ravel()[k])) for d, g in zip(rest, grids, strict=True)
        )
        head = f"  {where or 'all'}: "
        if msgs[k]:
            print(head + f"no fit ({msgs[k]})")
        else:
            runs = np.asarray(out["n_total"]).reshape(flat_theta.size, -1)[k]
            print(head + f"theta = {flat_theta[k]:.4g} {im_units} [{tci[k, 0]:.4g}, "
                  f"{tci[k, 1]:.4g}], beta = {flat_beta[k]:.3g} [{bci[k, 0]:.3g}, "
                  f"{bci[k, 1]:.3g}]; runs per stripe {', '.join(map(str, runs))}")  # fmt: skip
            if notes[k]:
                print(f"    {notes[k]}")
    return 0
