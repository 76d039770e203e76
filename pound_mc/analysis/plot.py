"""Charts of a study dataset: impact force spectrum, pounding probability, distribution.

Each function draws on the Axes given (``ax=``) or on a new :class:`matplotlib.figure.Figure`
(no pyplot state) and, given ``path``, writes it as PNG; it returns the figure so notebooks can
show it and tests can read the plotted data back from its artists.  Colours, units and labels
come from :mod:`pound_mc.analysis.style`; the charts of the physics (restitution relations,
the drop test) are in :mod:`pound_mc.analysis.physics_charts`.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pound_mc.analysis.gaps import RulesDoNotApply, study_gaps
from pound_mc.analysis.labels import text_of
from pound_mc.analysis.physics_charts import (  # noqa: F401  (charts of this module before)
    droptest_chart,
    restitution_chart,
    restitution_curves,
    restitution_ranges_chart,
)
from pound_mc.analysis.risk import counted as counted_mask
from pound_mc.analysis.risk import left_out_why
from pound_mc.analysis.selection import (
    MATERIAL_DIM,
    material_names,
    no_value_message,
)
from pound_mc.analysis.style import (
    axis_label,
    caption,
    chart_doc,
    coord_text,
    coords_text,
    fit_tick_labels,
    legend_outside,
    line_style,
    new_axes,
    note_left_out,
    save,
    scale_of,
    value_text,
)
from pound_mc.study.dataset import pounding_counted

__all__ = [
    "restitution_chart",
    "restitution_ranges_chart",
    "droptest_chart",
    "spectrum_chart",
    "spectrum_panels",
    "probability_chart",
    "spectrum_quantiles",
    "rule_gaps",
    "RULE_ATTRS",
    "save",
]


def finish_axes(ax, *, title: str, title_size=9, legend_size=8, grid="major", **props) -> None:
    """Title, labels, grid and legend (outside the data) of one chart's axes, alike everywhere.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    title : str
        Axes title.
    title_size : float or None
        Title font size [pt]; None keeps matplotlib's default.
    legend_size : float
        Legend font size [pt].
    grid : {"major", "minor", "both"}
        Grid lines drawn (30 % opaque).
    **props
        More :meth:`matplotlib.axes.Axes.set` properties (``xlabel``, ``ylabel``, ``ylim``, ...).
    """
    ax.set(title=title, **props)
    ax.title.set_wrap(True)  # a long title over narrow axes wraps inside the figure
    if title_size is not None:
        ax.title.set_fontsize(title_size)
    ax.grid(True, which=grid, alpha=0.3)
    legend_outside(ax, size=legend_size)


def _spectrum_selection(ds, x=None, line=None):
    """Pick the x axis and the line axis of an impact force spectrum chart."""
    grid_dims = _grid_dims(ds)
    if not grid_dims:
        raise ValueError("does not apply: the dataset has no grid axis to draw a spectrum against")
    x = x or grid_dims[0]
    if x not in grid_dims:
        raise ValueError(f"no grid dimension {x!r}; the dataset has {grid_dims}")
    rest = [d for d in grid_dims if d != x]
    line = _line_axis(rest, x, line)
    return x, line, [d for d in rest if d != line]


def _line_axis(rest, x, line):
    """The line axis: ``line``, a grid dimension other than ``x`` (default: ``rest[0]``)."""
    if line is None:
        return rest[0] if rest else None
    if line == x:
        raise ValueError(f"line names {x!r}, the chart's horizontal axis; draw lines of "
                         + (f"another grid dimension ({', '.join(rest)})" if rest else
                            "another grid dimension (the dataset has no other)"))  # fmt: skip
    if line not in rest:
        raise ValueError(f"no grid dimension {line!r}; the dataset has {[x, *rest]}")
    return line


def quantiles_over(values: xr.DataArray, levels, dims) -> xr.DataArray:
    """``values.quantile(levels, dim=dims)``, NaN without a warning where every value is NaN."""
    with warnings.catch_warnings():  # a grid point without an ok run: NaN is the answer
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        return values.quantile(list(np.atleast_1d(levels)), dim=list(dims))


def spectrum_quantiles(ds: xr.Dataset, record: int | str = "pooled") -> xr.DataArray:
    """Quantiles of peak force [N] that a spectrum chart draws (runs with status ok).

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset (its ``peak_force`` and ``status``, or ``peak_force_quantile``).
    record : "pooled", "median", "each", int or str
        ``"pooled"``: over the records and samples together (the record-to-record scatter
        included); ``"median"``: the median over the records of each record's quantiles over
        its samples; ``"each"``: every record (a ``record`` dim kept); an index or a name: that
        record.
    """
    q = ds["peak_force_quantile"]
    if isinstance(record, str) and record == "pooled":
        ok = ds["peak_force"].where(ds["status"] == 0)
        pooled = quantiles_over(ok, q["quantile"].values, ("record", "sample"))
        return pooled.transpose(*q.dims[:1], *(d for d in q.dims[1:] if d != "record"))
    if isinstance(record, str) and record == "median":
        return q.median("record")
    if isinstance(record, str) and record == "each":
        return q
    return q.isel(record=_record_index(ds, record))


@chart_doc
def spectrum_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    x: str | None = None,
    line: str | None = None,
    record: int | str = "pooled",
    sel: dict | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Impact force spectrum: median peak force against a grid axis with a 5-95 % band.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset (:mod:`pound_mc.study.dataset`).
    %(path)s
    x : str, optional
        Grid dimension on the horizontal axis (default: the first).
    line : str, optional
        Grid dimension drawn as one line per value (default: the second, if any).
    record : "pooled", "median", "each", int or str
        ``"pooled"`` (default): quantiles over every record and sample together (the
        records' own scatter in the band); ``"median"``: median over the records of each
        record's quantiles over its samples; ``"each"``: one line per record (the median over
        samples; the line axis held); an index or a name: that record alone.
    sel : dict, optional
        ``{dim: value}`` holding other grid dimensions at one value (nearest; default their
        first value).
    ax : matplotlib.axes.Axes, optional
        Where to draw (default a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[0].lines``: one line per value drawn, the medians [MN] (over the records and
        samples pooled, or as ``record`` says).
    """
    x, line, others = _spectrum_selection(ds, x, line)
    each = isinstance(record, str) and record == "each"
    sel = _checked_sel(ds, sel, x)
    if each and line is not None:
        others, line = [line, *others], None
    wanted = sel.pop(line, None) if line is not None else None
    hold = _hold(ds, others, sel)
    q = spectrum_quantiles(ds, record).isel(hold)
    fig, (ax,) = new_axes(ax, (8.4, 4.6))
    xs = ds[x].values * scale_of(ds, x) if ds[x].dtype.kind in "fiu" else np.arange(ds.sizes[x])
    if each:
        lines = [(i, {"record": i}, str(ds["record"].values[i])) for i in range(ds.sizes["record"])]
    elif line is None:
        lines = [(0, {}, "median")]
    else:
        picked = range(ds.sizes[line])
        if wanted is not None:  # the line values ``sel`` names (nearest), in its order
            picked = dict.fromkeys(_nearest_index(ds, line, v) for v in np.atleast_1d(wanted))
        lines = [(i, {line: i}, value_text(ds, line, i)) for i in picked]
    band = len(lines) <= 7
    crowd = len(lines) > 12  # too many to tell apart: thin grey lines and their median
    best = (-np.inf, None, None)  # the largest median drawn [MN], its x index and line
    for k, (_, where, label) in enumerate(lines):
        style = line_style(k)
        sq = q.isel(where)
        median = sq.sel(quantile=0.5).values / 1e6
        if not crowd and np.any(np.isfinite(median)) and np.nanmax(median) > best[0]:
            best = (float(np.nanmax(median)), int(np.nanargmax(median)), where)
        if crowd:
            first = f"each record ({len(lines)})" if k == 0 else None
            ax.plot(xs, median, color="0.6", lw=0.7, alpha=0.7, label=first)
            continue
        ax.plot(xs, median, lw=1.6, ms=4, label=label, **style)
        if band:
            ax.fill_between(
                xs,
                sq.sel(quantile=0.05).values / 1e6,
                sq.sel(quantile=0.95).values / 1e6,
                color=style["color"],
                alpha=0.15,
                lw=0,
            )
    if crowd:
        over = q.sel(quantile=0.5).median("record").values / 1e6
        ax.plot(xs, over, color="black", lw=2.0, marker="o", ms=4, label="median over records")
        if np.any(np.isfinite(over)):
            best = (float(np.nanmax(over)), int(np.nanargmax(over)), {})
    if ds[x].dtype.kind not in "fiu" or x == MATERIAL_DIM:
        ax.set_xticks(xs, [value_text(ds, x, i) for i in range(ds.sizes[x])])
        fit_tick_labels(ax, ds.sizes[x])
    finish_axes(
        ax,
        xlabel=axis_label(ds, x),
        ylabel="peak impact force [MN]",
        title=_spectrum_title(ds, x, best, hold),
    )
    caption(fig, _spectrum_caption(ds, record, band))
    if line is not None:
        ax.get_legend().set_title(axis_label(ds, line), prop={"size": 8})
    return save(fig, path)


def _spectrum_title(ds, x, best, hold) -> str:
    """The spectrum chart's answer: its largest median peak force, and where it is."""
    held = coords_text(ds, hold)
    head = "Peak impact force" + (f", {held}" if held else "")
    value, j, where = best
    if j is None:
        return f"{head}: no simulation ended ok"
    if value <= 0.0:
        return f"{head}: no pounding in most runs (median 0 everywhere)"
    at = [coord_text(ds, x, j)]
    at += [f"record {text_of(ds['record'].values[i])}" if d == "record" else coord_text(ds, d, i)
           for d, i in where.items()]  # fmt: skip
    return f"{head}: median up to {value:.3g} MN at {', '.join(at)}"


def _spectrum_caption(ds, record, band: bool) -> str:
    """How the spectrum chart's lines were made (its caption)."""
    n_rec, n_smp = ds.sizes["record"], ds.sizes["sample"]
    if isinstance(record, str) and record == "each":
        over = f"each record's median over its {n_smp} samples"
    elif isinstance(record, str) and record in ("pooled", "median") and n_rec == 1:
        over = f"the median over the {n_smp} samples of record {text_of(ds['record'].values[0])}"
    elif isinstance(record, str) and record == "pooled":
        over = f"the median over the {n_rec} records and {n_smp} samples together"
    elif isinstance(record, str) and record == "median":
        over = f"the median over the {n_rec} records of each record's median over its samples"
    else:
        name = text_of(ds["record"].values[_record_index(ds, record)])
        over = f"the median over the {n_smp} samples of record {name}"
    return (
        f"Lines: {over}" + ("; bands: 5-95 %" if band else "")
        + ". Runs that do not pound count as 0; runs that did not end ok are left out."
    )  # fmt: skip


@chart_doc
def spectrum_panels(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    by: str = MATERIAL_DIM,
    ax: Sequence[Axes] | None = None,
) -> Figure:
    """Impact force spectrum with one panel per value of ``by`` where the chart would hold it.

    :func:`spectrum_chart` draws its first grid axis against its second and holds every other
    grid axis at its first value.  Where ``by`` (default the material axis) is such a held axis
    (``studies/jankowski_spectrum.toml``: T1, one line per T2, four materials), this draws one
    spectrum panel per value of ``by``, so that none is left out; otherwise it is
    :func:`spectrum_chart` itself.  ``pound-mc run`` and ``pound-mc report`` draw the spectrum
    with it.

    Parameters
    ----------
    %(ds)s
    %(path)s
    by : str
        Grid dimension with one panel per value when the spectrum chart would hold it.
    ax : sequence of matplotlib.axes.Axes, optional
        One per value of ``by`` (default a new figure, two panels a row).

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[k]``: the spectrum chart at the ``k``-th value of ``by`` (its lines, title and
        legend), in the order of ``by``; spare Axes of a new figure's last row are hidden.
    """
    _, _, held = _spectrum_selection(ds)
    if by not in held:
        return spectrum_chart(ds, path, ax=ax)
    n = ds.sizes[by]
    if ax is None:
        ncols = min(n, 2)
        nrows = -(-n // ncols)
        fig, axes = new_axes(None, (8.4 * ncols, 4.6 * nrows), nrows=nrows, ncols=ncols)
        for spare in axes[n:]:
            spare.set_visible(False)
    else:
        fig, axes = new_axes(ax, (8.4, 4.6), ncols=n)
    for k in range(n):
        spectrum_chart(ds, sel={by: ds[by].values[k]}, ax=axes[k])
    return save(fig, path)


#: Dataset attributes holding the gap a separation rule asks for [m], by rule label:
#: ``ABS`` (sum of the peak displacements), ``SRSS`` (square root of the sum of their squares),
#: ``DDC`` (double difference combination, with the correlation of the two responses).  Each is a
#: number or an array with one value per value of the chart's line axis.
RULE_ATTRS = {"ABS": "gap_rule_abs_m", "SRSS": "gap_rule_srss_m", "DDC": "gap_rule_ddc_m"}
_RULE_STYLES = {"ABS": "--", "SRSS": "-.", "DDC": ":"}
#: Dimension of the initial gap in a study dataset.
GAP_DIM = "contact_gap_m"
#: Dimension of the contacts of a shear-building pair (one per pair of floors that can meet).
CONTACT_DIM = "contact"


@chart_doc
def rule_gaps(
    ds: xr.Dataset, rules: dict | str | None = "auto", *, base_dir: str | Path | None = None
) -> dict:
    """Gaps [m] the separation rules ask for, by rule label.

    Parameters
    ----------
    %(ds)s
    rules : dict, "auto" or None
        ``{label: gap}``: a number [m], an array with one value per value of the chart's line
        axis, or an :class:`xarray.DataArray` (reduced as below).  ``"auto"``: the dataset's
        attributes :data:`RULE_ATTRS` when it has any, else the gaps
        :func:`pound_mc.analysis.gaps.study_gaps` computes for every simulation of the study
        (ABS, SRSS, DDC from the linear responses of the two buildings alone).  None: no rules.
    base_dir : str or Path, optional
        Folder of relative record paths, for ``"auto"`` (default the working directory).

    Returns
    -------
    dict
        ``{label: value}`` (empty when there are none).
    """
    if rules is None:
        return {}
    if not isinstance(rules, str):
        return dict(rules)
    if rules != "auto":
        raise ValueError(f'rules must be a dict, "auto" or None, got {rules!r}')
    found = {label: ds.attrs[attr] for label, attr in RULE_ATTRS.items() if attr in ds.attrs}
    if found or "study_text" not in ds.attrs or CONTACT_DIM in ds.dims:
        return found  # the rules' linear SDOF responses do not describe shear buildings
    try:
        gaps = study_gaps(ds, base_dir=base_dir)
    except RulesDoNotApply:
        return {}  # nor a wall
    return {"ABS": gaps["gap_abs"], "SRSS": gaps["gap_srss"], "DDC": gaps["gap_ddc"]}


def _reduce_rule(value, ds, line, record, hold):
    """One gap [m], or one per value of ``line``, from a rule given as a number or array.

    A DataArray over the dataset's dims is taken at the chart's record (all records pooled for
    ``record=None``) and held dims, and its median over the samples (and over the gaps: the
    rules do not depend on the gap) is drawn.
    """
    if isinstance(value, xr.DataArray):
        if "record" in value.dims and record is not None:
            value = value.isel(record=record)
        value = value.isel({d: i for d, i in hold.items() if d in value.dims})
        over = [d for d in value.dims if d != line]
        value = value.median(over) if over else value
        if line is not None and line in value.dims:
            return value.transpose(line).values.astype(float)
        return np.asarray(value.values, dtype=float).reshape(-1)
    return np.atleast_1d(np.asarray(value, dtype=float))


def _line_label(ds, dim, i) -> str:
    return coord_text(ds, dim, i)


def _hold(ds, dims, sel):
    """Index of every dim in ``dims``: the value nearest ``sel[dim]``, else the first."""
    sel = sel or {}
    unknown = set(sel) - set(ds.dims)
    if unknown:
        raise ValueError(f"no dimension {sorted(unknown)[0]!r}; the dataset has {list(ds.dims)}")
    out = {}
    for dim in dims:
        if dim in sel:
            out[dim] = _nearest_index(ds, dim, sel[dim])
        else:
            out[dim] = 0
    return out


def _hidden_under(gaps, drawn: dict, span: float) -> str:
    """``under the R lines`` where every gap is within 1 % of the axis of rule R's, else ``""``.

    ``gaps``: a rule's gaps [mm] (one, or one per line); ``drawn``: the rules drawn before it;
    ``span``: the axis' extent [mm] (0: not numeric, nothing said).
    """
    for other, prev in drawn.items():
        both = np.isfinite(gaps) & np.isfinite(prev) if prev.shape == gaps.shape else None
        if span > 0.0 and both is not None and both.any():
            if np.all(np.abs(gaps[both] - prev[both]) <= 0.01 * span):
                return f"under the {other} line{'s' if gaps.size > 1 else ''}"
    return ""


def _checked_sel(ds, sel, x) -> dict:
    """A copy of ``sel`` after refusing a dimension the dataset lacks or the horizontal axis."""
    sel = dict(sel or {})
    _hold(ds, [], sel)  # unknown dimensions
    if x in sel:
        raise ValueError(f"sel names {x!r}, the chart's horizontal axis: it draws all its values")
    return sel


def _nearest_index(ds, dim, value) -> int:
    coord = ds[dim].values
    if coord.dtype.kind in "fiu" and dim != MATERIAL_DIM:  # materials: exactly, as names are
        return int(np.argmin(np.abs(coord.astype(float) - float(value))))
    hits = np.flatnonzero(coord == value)
    if not hits.size:
        names = material_names(ds) if dim == MATERIAL_DIM else coord
        raise ValueError(no_value_message(dim, value, names))
    return int(hits[0])


def _record_index(ds, record) -> int:
    if isinstance(record, int | np.integer):
        n = ds.sizes["record"]
        if not -n <= record < n:
            raise ValueError(f"record index {record} out of range: the dataset has {n} records")
        return int(record) % n
    return _nearest_index(ds, "record", record)


def _grid_dims(ds) -> list[str]:
    return [d for d in ds["peak_force"].dims if d not in ("record", "sample")]


@chart_doc
def probability_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    line: str | None = None,
    record: int | str | None = None,
    sel: dict | None = None,
    rules: dict | str | None = "auto",
    max_lines: int = 7,
    base_dir: str | Path | None = None,
    x: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Pounding probability against the initial gap, with the separation rules marked.

    The probability is the fraction of the samples (status ok or inaccurate,
    :func:`~pound_mc.study.dataset.pounding_counted`) with at least one impact:
    ``pounding_probability`` of the dataset.  A study without the gap on its grid draws the
    probability against its first grid axis instead (no rules then).

    Parameters
    ----------
    %(ds)s
    %(path)s
    line : str, optional
        Grid dimension drawn as one line per value (default: the first other grid axis); at most
        ``max_lines`` values, evenly spread, are drawn.
    %(record)s
    sel : dict, optional
        ``{dim: value}`` for the other grid dimensions (nearest value; default the first), or a
        list of values of the ``line`` dimension to draw.
    rules : dict, "auto" or None
        Separation rule gaps (see :func:`rule_gaps`), drawn as vertical lines: the median over
        the samples, per line where they differ from line to line.  Shear buildings: none.
    max_lines : int
        Most lines drawn.
    base_dir : str or Path, optional
        Folder of relative record paths when the rules are computed.
    x : str, optional
        Grid dimension on the horizontal axis (default the gap, else the first grid axis).
    ax : matplotlib.axes.Axes, optional
        Where to draw (default a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[0].lines``: the probability lines first (x in chart units), then the rules.
    """
    grid = _grid_dims(ds)
    if not grid:
        raise ValueError("does not apply: the dataset has no grid axis to draw against")
    x = x or (GAP_DIM if GAP_DIM in grid else grid[0])
    if x not in grid:
        raise ValueError(f"no grid dimension {x!r}; the dataset has {grid}")
    sel = _checked_sel(ds, sel, x)
    rest = [d for d in grid if d != x]
    line = _line_axis(rest, x, line)
    wanted = sel.pop(line, None) if line is not None else None
    hold = _hold(ds, [d for d in rest if d != line], sel)
    if record is None:
        counted = pounding_counted(ds["status"])
        prob = (ds["impacts"] > 0).where(counted).isel(hold).mean(("record", "sample"))
        n_rec = ds.sizes["record"]
        over = (
            f"the {n_rec} records and {ds.sizes['sample']} samples"
            if n_rec > 1
            else f"the {ds.sizes['sample']} samples of record {text_of(ds['record'].values[0])}"
        )
    else:
        record = _record_index(ds, record)
        prob = ds["pounding_probability"].isel(record=record, **hold)
        over = f"the samples of record {text_of(ds['record'].values[record])}"
    if line is None:
        line_idx = [None]
    elif wanted is not None:
        line_idx = [_nearest_index(ds, line, v) for v in np.atleast_1d(wanted)]
    else:
        n = ds.sizes[line]
        line_idx = list(
            dict.fromkeys(np.round(np.linspace(0, n - 1, min(n, max_lines))).astype(int))
        )
    numeric = ds[x].dtype.kind in "fiu" and x != MATERIAL_DIM
    xs = ds[x].values * scale_of(ds, x) if numeric else np.arange(ds.sizes[x])
    fig, (ax,) = new_axes(ax, (8.4, 4.6))
    curves = {}  # line index -> its probabilities
    for k, i in enumerate(line_idx):
        style = line_style(k)
        y = prob.transpose(x, ...).values if i is None else prob.isel({line: i}).values
        curves[i] = np.asarray(y, dtype=float)
        label = "pounding probability" if i is None else value_text(ds, line, i)
        ax.plot(xs, y, ms=4, lw=1.6, label=label, **style)
    if not numeric:
        ax.set_xticks(xs, [value_text(ds, x, i) for i in range(ds.sizes[x])])
        fit_tick_labels(ax, ds.sizes[x])
    found = rule_gaps(ds, rules, base_dir=base_dir) if x == GAP_DIM else {}
    _draw_rules(ax, ds, found, line, line_idx, curves, xs, record, hold)
    finish_axes(
        ax,
        xlabel=axis_label(ds, x),
        ylabel="pounding probability [-]",
        ylim=(-0.03, 1.03),
        title=_probability_title(ds, x, curves, hold),
    )
    text = f"Lines: share of the runs with at least one impact, over {over}."
    if x != GAP_DIM:
        text += " The study has no gap axis: drawn against its first grid axis."
    elif CONTACT_DIM in ds.dims:
        text += " No separation rules: they assume SDOF buildings."
    elif found:
        where = "records and samples" if record is None and ds.sizes["record"] > 1 else "samples"
        text += f" Separation rules: their gaps (median over the {where}), marked on each line."
    caption(fig, text)
    if line is not None:
        ax.get_legend().set_title(axis_label(ds, line), prop={"size": 8})
    note_left_out(fig, counted_mask(ds, "pounding").values, left_out_why("pounding"))
    return save(fig, path)


#: Marks of the separation rules' gaps on each probability line: black, and unlike the lines'
#: own (filled) markers; DDC's ring around SRSS's plus stays readable when the two gaps agree.
RULE_MARKS = {
    "ABS": {"marker": "x", "ms": 7},
    "SRSS": {"marker": "+", "ms": 9},
    "DDC": {"marker": "o", "ms": 9, "mfc": "none"},
}


def _draw_rules(ax, ds, found, line, line_idx, curves, xs, record, hold) -> None:
    """The separation rules' gaps of :func:`probability_chart`.

    A rule with one gap for every line is a vertical line (grey, a dash pattern per rule); a
    rule with a gap per line is a black mark on each line at that gap (:data:`RULE_MARKS`),
    where the gap lies within the gaps drawn: a few marks, not a vertical line per line.
    """
    drawn = {}  # rule -> its gap [mm], to say which rule's line hides another's
    for name, value in found.items():
        arr = _reduce_rule(value, ds, line, record, hold) * 1e3
        if arr.size == 1:
            under = _hidden_under(arr, drawn, float(np.ptp(xs)))
            drawn[name] = arr
            if np.isfinite(arr[0]):
                text = f"{name} rule: {arr[0]:.3g} mm" + (f" ({under})" if under else "")
                style = _RULE_STYLES.get(name, (0, (1, 3)))
                ax.axvline(arr[0], color="0.3", ls=style, lw=1.1, label=text)
            continue
        if line is None or arr.size != ds.sizes[line]:
            raise ValueError(
                f"separation rule {name}: {arr.size} gaps, expected 1 or one per value of {line!r}"
            )
        first = True
        for i in line_idx:
            y = curves[i]
            if not (np.isfinite(arr[i]) and xs[0] <= arr[i] <= xs[-1] and np.isfinite(y).all()):
                continue
            ax.plot([arr[i]], [np.interp(arr[i], xs, y)], ls="none", color="black", mew=1.3,
                    zorder=4, label=f"{name} rule's gap on each line" if first else None,
                    **RULE_MARKS.get(name, {"marker": "*"}))  # fmt: skip
            first = False


def _percent_range(values) -> str:
    """``"14-100 %"`` (or ``"18 %"``): the range of probabilities ``values``."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    if not values.size:
        return "no run counted"
    lo, hi = (f"{100 * v:.0f}" for v in (values.min(), values.max()))
    return f"{lo} %" if lo == hi else f"{lo}-{hi} %"


def _probability_title(ds, x, curves, hold) -> str:
    """The probability chart's answer: the probabilities at its first and its last x value."""
    held = coords_text(ds, hold)
    ys = np.array(list(curves.values()))
    first, last = coord_text(ds, x, 0), coord_text(ds, x, ds.sizes[x] - 1)
    return (
        "Pounding probability" + (f" ({held})" if held else "")
        + f": {_percent_range(ys[:, 0])} at {first}, {_percent_range(ys[:, -1])} at {last}"
    )  # fmt: skip
