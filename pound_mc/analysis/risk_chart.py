"""Charts of the risk outputs: fragility panels and the required gap on the probability chart.

:func:`fragility_panels` draws :func:`~pound_mc.analysis.fragility_chart.fragility_chart` for
each combination of the grid axes other than the intensity (e.g. one panel per gap), over one
range of the intensity; :func:`required_gap_chart` is
:func:`~pound_mc.analysis.plot.probability_chart` (pounding probability against gap, one line
per intensity) with the target probability, the required gap of each line
(:func:`pound_mc.analysis.risk.required_gap`) and its confidence interval, the separation rules'
gaps marked on each line, and a legend that tables these gaps.
"""

from __future__ import annotations

import itertools
import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.fragility_chart import fragility_chart, stripe_counts
from pound_mc.analysis.gaps import RulesDoNotApply
from pound_mc.analysis.labels import dim_text, name_and_units
from pound_mc.analysis.plot import (
    CONTACT_DIM,
    RULE_MARKS,
    _hold,
    _line_label,
    _reduce_rule,
    probability_chart,
    rule_gaps,
    save,
)
from pound_mc.analysis.risk import GAP_DIM, _counts, _intensity_dim, left_out_why, required_gap
from pound_mc.analysis.risk import counted as counted_mask
from pound_mc.analysis.site_risk import code_gaps
from pound_mc.analysis.style import (
    axis_label,
    caption,
    chart_doc,
    coord_text,
    coords_text,
    legend_below,
    new_axes,
    note_left_out,
    value_text,
)
from pound_mc.errors import InputError

__all__ = ["fragility_panels", "required_gap_chart"]


@chart_doc
def fragility_panels(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    im: str | None = None,
    event: str = "pounding",
    sel: dict | None = None,
    max_panels: int = 6,
    n_boot: int = 1000,
    seed: int = 0,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """One fragility panel per combination of the other grid axes (at most ``max_panels``).

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with an intensity axis (or ``im``: a grid dimension with values > 0).
    %(path)s
    im, event, n_boot, seed
        As :func:`pound_mc.analysis.risk.fragility`.
    sel : dict, optional
        ``{dim: value}``: hold these grid dims at one value (nearest) instead of a panel each.
    max_panels : int
        Most panels drawn (the first combinations).
    ax : matplotlib.axes.Axes or sequence of Axes, optional
        Where to draw: one Axes per panel, or a grid of more (the spare ones hidden; default a
        new figure, three panels a row).

    Returns
    -------
    matplotlib.figure.Figure
        Every panel spans the intensities from 0 to 1.05 times the largest stripe, and gives
        theta in the intensity's units.  A panel without a fit says why; one whose bootstrap
        left resamples out (they have no fit) says how many, and has no band when more than
        half were.  The stripes' counts are the events alone when every stripe of every panel
        has the same number of simulations (the legend says it), else ``events/simulations``.
    """
    dim = _intensity_dim(ds, im)
    n_event, n_total = _counts(ds, event)
    rest = [d for d in n_event.dims if d != dim]
    held = _hold(ds, [d for d in rest if d in (sel or {})], sel)
    free = [d for d in rest if d not in held]
    combos = list(itertools.product(*(range(ds.sizes[d]) for d in free)))[:max_panels]
    ncols = min(3, len(combos))
    nrows = -(-len(combos) // ncols)
    if ax is None:
        fig, axes = new_axes(None, (4.6 * ncols, 3.6 * nrows), nrows=nrows, ncols=ncols)
    else:
        fig, axes = new_axes(ax, (0.0, 0.0), ncols=len(combos), spare=True)
    own = ax is None
    legend = None
    x = np.asarray(ds[dim].values, dtype=float)
    im_units = name_and_units(ds[dim].attrs, dim)[1]
    im_units = "" if im_units in ("", "1") else im_units  # the fit is in the stored units
    in_g = im_units == "g"
    im_label = axis_label(ds, dim) if in_g else f"{dim_text(ds, dim)} [{im_units or '-'}]"
    unit = f" {im_units}" if im_units else ""
    x_max = 1.05 * float(x.max())  # every panel over the stripes' range
    counted = np.unique(n_total.values[n_total.values > 0])
    totals = counted.size != 1  # one number of simulations everywhere: said once, in the legend
    percent = 95  # the level of fit_fragility's intervals (read from the fits)
    medians = []  # per panel with a fit: its place and theta
    no_fit = []  # per panel without: why, for the caption
    for ax, combo in zip(axes, combos, strict=False):
        where = {**held, **dict(zip(free, combo, strict=True))}
        z = n_event.isel(where).transpose(dim).values
        n = n_total.isel(where).transpose(dim).values
        title = ", ".join(_line_label(ds, d, i) for d, i in where.items())
        try:
            fit = fit_fragility(x, z, n, n_boot=n_boot, seed=seed)
        except InputError as exc:
            ax.plot(x, np.divide(z, n, out=np.full(x.shape, np.nan), where=n > 0), "o", c="k")
            why = textwrap.shorten(exc.message, 180, placeholder=" ...")
            ax.set_title(f"{title}: no fit" if title else "no fit", fontsize=8)
            no_fit.append(f"No fit at {title}: {why}" if title else f"No fit: {why}")
            ax.set_xlabel(im_label)
            ax.set_ylabel(f"P({event} | IM)")
            ax.set_xlim(0.0, x_max)
            ax.set_ylim(-0.02, 1.02)
            ax.grid(alpha=0.3)
            stripe_counts(ax, x, z, n, totals=totals)
            continue
        fragility_chart(
            fit,
            ax=ax,
            im_label=im_label,
            event_label=event,
            legend=False,
            im_units=im_units,
            x_max=x_max,
            totals=totals,
        )
        percent = round(100 * fit.ci)
        head = f"{title}: " if title else ""
        head += f"\u03b8 = {fit.theta:.3g}{unit}, \u03b2 = {fit.beta:.2g}"
        if fit.theta > x_max:
            head += " (beyond the stripes)"
        ax.set_title(head, fontsize=8)
        medians.append((where, fit.theta))
        if not legend:
            handles, labels = ax.get_legend_handles_labels()
            # the fit's numbers are per panel (in its title): the legend names the curve only
            generic = [label.split(":")[0] if label.startswith("lognormal") else label
                       for label in labels]  # fmt: skip
            if own:
                legend_below(fig, ax, handles=handles, labels=generic)
                legend = True
            else:  # a caller's figure: in the first panel, where a rising curve leaves room
                legend = ax.legend(handles, generic, loc="lower right", fontsize=7)
    for ax in axes[len(combos) :]:
        ax.set_visible(False)
    if own:  # a figure of its own: the title over the panels (not on a caller's figure)
        fig.suptitle(_fragility_title(ds, dim, event, medians, unit), fontsize=10)
    boot = f"band: {percent} % bootstrap interval of the fit" if n_boot else "no bootstrap band"
    caption(fig, f"Points: share of the simulations of each stripe with {event} (the number "
            f"beside), over records and samples; curve: lognormal fit by maximum likelihood "
            f"(\u03b8 median, \u03b2 dispersion); {boot}.")  # fmt: skip
    for text in no_fit:
        caption(fig, text if text.endswith(".") else f"{text}.")
    note_left_out(fig, counted_mask(ds, event), left_out_why(event))
    return save(fig, path)


def _fragility_title(ds, dim, event, medians, unit) -> str:
    """The fragility chart's answer: the median intensity of ``event``, first to last panel.

    ``medians``: ``(where, theta)`` of every panel with a fit, ``where`` its ``{dim: index}``.
    """
    head = f"Median {dim_text(ds, dim)} for {event}"
    if not medians:
        return f"{head}: no fit"

    def one(where, theta):
        text = f"{theta:.2g}{unit}"
        return text + (f" at {coords_text(ds, where)}" if where else "")

    if len(medians) == 1:
        return f"{head}: {one(*medians[0])}"
    return f"{head}: {one(*medians[0])} to {one(*medians[-1])}"


def _mm(value: float) -> str:
    """A gap [mm] as the table of :func:`required_gap_chart` writes it."""
    return f"{value:.0f}" if value >= 100 else f"{value:.3g}"


def _gap_text(gap: float, lo: float, hi: float, gaps_mm: np.ndarray) -> str:
    """A gap and its interval [mm] as text, ``"48.1 (46.9-58)"``.

    The narrowest gap studied is written ``<=20`` (the gap may be less), an open end
    ``112 to >300``.
    """

    def one(value):
        if not np.isfinite(value):
            return f">{_mm(gaps_mm[-1])}"
        return f"\u2264{_mm(value)}" if value <= gaps_mm[0] else _mm(value)

    dash = " to " if not np.isfinite(hi) else "\u2013"  # "112 to >200", not "112->200"
    return f"{one(gap)} ({one(lo)}{dash}{one(hi)})"


@chart_doc
def required_gap_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    probability: float = 0.1,
    line: str | None = None,
    sel: dict | None = None,
    rules="auto",
    base_dir=None,
    ax: Axes | None = None,
) -> Figure:
    """Pounding probability against gap, the target, each line's required gap and the rules.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with two or more gaps on its grid.
    %(path)s
    probability : float, default 0.1
        Target probability (a horizontal line); each line's required gap (where the line,
        joined linearly between the gaps studied, comes down to it) is marked on it with its
        Wilson confidence interval.  The lines still above the target at the widest gap are
        named in a note, with an arrow to each one's end.
    line, sel, rules, base_dir, ax
        As :func:`pound_mc.analysis.plot.probability_chart` (all records pooled); the rules'
        gaps are marked on each line (:data:`RULE_MARKS`) where they lie within the gaps
        studied, not drawn as vertical lines.

    Returns
    -------
    matplotlib.figure.Figure
        ``fig.axes[0]``: the probability lines first (as the probability chart), then the
        target line, one errorbar marker per line with a required gap and the rules' marks.
        The legend is a table: per line, its required gap [mm] with the interval (or "none")
        and the rules' gaps [mm]; ``ax.texts`` hold the notes of the lines without a gap.
    """
    if GAP_DIM not in ds.dims:
        raise InputError("does not apply: the required gap needs a study with the gap on its grid")
    fig = probability_chart(ds, None, line=line, sel=sel, rules=None, ax=ax)
    ax = ax if ax is not None else fig.axes[0]
    found = required_gap(ds, probability, rules=False)
    rest = list(found["required_gap"].dims)
    sel = dict(sel or {})
    line = line if line is not None else (rest[0] if rest else None)
    sel.pop(line, None)
    hold = _hold(ds, [d for d in rest if d != line], sel)
    labels = {"pounding probability": (hold, None)}
    if line is not None:
        labels = {value_text(ds, line, i): ({**hold, line: i}, i) for i in range(ds.sizes[line])}
    drawn = [ln for ln in ax.lines if ln.get_label() in labels]
    ruled = {}  # rule -> its gap [mm] per line index (or one for every line)
    shares = {}  # rule -> the share of runs pounding at their own rule gap, per line index
    if rules == "auto" and "study_text" in ds.attrs and CONTACT_DIM not in ds.dims:
        ruled, shares = _own_rule_gaps(ds, line, hold, base_dir)
    for name, value in ({} if shares else rule_gaps(ds, rules, base_dir=base_dir)).items():
        arr = _reduce_rule(value, ds, line, None, hold) * 1e3
        if arr.size != 1 and (line is None or arr.size != ds.sizes[line]):
            raise ValueError(
                f"separation rule {name}: {arr.size} gaps, expected 1 or one per value of {line!r}"
            )
        ruled[name] = arr
    ax.axhline(probability, color="grey", lw=0.9, ls="--", label=f"target {probability:g}")
    level = round(100 * found.attrs["ci"])
    gaps_mm = np.asarray(ds[GAP_DIM].values, dtype=float) * 1e3
    cells, short, diamonds = {}, [], False  # per line: its table cells; lines without a gap
    answers = []  # per line: its name and required gap [mm] (NaN: none within the gaps)
    for ln in drawn:
        where, i = labels[ln.get_label()]
        xs, ys = np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)
        gap = float(found["required_gap"].isel(where)) * 1e3
        if np.isfinite(gap):
            lo, hi = found["required_gap_ci"].isel(where).values * 1e3
            ax.errorbar(
                [gap],
                [probability],
                xerr=[[gap - lo], [hi - gap if np.isfinite(hi) else 0.0]],
                fmt="D",
                color=ln.get_color(),
                ms=6,
                capsize=3,
                label=f"required gap ({level} % interval)",
            )
            diamonds = True
            answers.append((i, gap))
            cell = _gap_text(gap, lo, hi, gaps_mm)
        elif np.isfinite(ys[-1]) and ys[-1] > probability:
            cell = f"none (P = {ys[-1]:.2g} at {_mm(gaps_mm[-1])})"
            short.append((ln, xs[-1], ys[-1]))
            answers.append((i, np.nan))
        else:  # no simulations counted at some gap
            cell = "none"
        rules_row = []
        for name, arr in ruled.items():
            value = float(arr[0] if arr.size == 1 else arr[i])
            share = None if name not in shares else float(shares[name][0 if i is None else i])
            text = _mm(value) if np.isfinite(value) else "-"
            rules_row.append(text if share is None else f"{text} ({100 * share:.0f}%)")
            # the mark: at the share of runs that pound at their own rule gap (each run
            # simulated there); for rules given as numbers, on the line
            y = share if share is not None else (
                np.interp(value, xs, ys) if xs[0] <= value <= xs[-1] else np.nan)  # fmt: skip
            if np.isfinite(value) and np.isfinite(y) and np.all(np.isfinite(ys)):
                ax.plot(
                    [value],
                    [y],
                    ls="none",
                    color="black",
                    mew=1.3,
                    zorder=4,
                    label=(
                        f"{name} rule: median gap"
                        if share is not None
                        else f"{name} rule's gap on each line"
                    ),
                    **RULE_MARKS.get(name, {"marker": "*"}),
                )
        cells[ln] = (ln.get_label(), cell, *rules_row)
    _short_note(ax, short, probability)
    # the legend as a table: a header row (no handle), then per line its gaps, aligned in a
    # monospaced font
    header = ("", f"P = {probability:g} at [mm]", *(f"{name}" for name in ruled))
    second = ("", f"({level} % interval)", *(["[mm]"] * len(ruled)))
    widths = [
        max(len(row[k]) for row in (header, second, *cells.values())) for k in range(len(header))
    ]

    def row_text(row):
        first = [f"{row[0]:<{widths[0]}}", f"{row[1]:<{widths[1]}}"]
        return "  ".join(first + [f"{c:>{w}}" for c, w in zip(row[2:], widths[2:], strict=True)])

    rows = {id(ln): row_text(row) for ln, row in cells.items()}
    handles, texts = [], []
    for handle, text in zip(*ax.get_legend_handles_labels(), strict=True):
        if text not in texts or id(handle) in rows:  # a rule's mark once, not once per line
            handles.append(handle)
            texts.append(rows.get(id(handle), text))
    if cells:
        head = Line2D([], [], ls="none")
        handles, texts = [head, *handles], [row_text(header) + "\n" + row_text(second), *texts]
    ax.legend(
        handles,
        texts,
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        borderaxespad=0.0,
        fontsize=8,
        title=axis_label(ds, line) if line is not None else None,
        title_fontsize=8,
        frameon=False,
    )
    for text in ax.get_legend().get_texts()[: len(cells) + 1 if cells else 0]:
        text.set_family("monospace")
    ax.set_title(_required_title(ds, line, probability, answers, gaps_mm), fontsize=9)
    if diamonds:
        marks = (
            f"Diamonds: where each line, straight between the gaps studied, falls to "
            f"{100 * probability:g} % (bars: its {level} % Wilson interval)."
        )
    else:  # no line reaches the target within the grid's gaps: say so
        marks = f"No gap studied brings the probability to {probability:g}: widen the gap range."
    if shares:
        marks += (
            " Black marks: each rule's median gap, at the share of runs that pound at their "
            "own rule gap (in brackets in the table)."
        )
    elif ruled:
        marks += " Black marks: the separation rules' gaps on each line."
    caption(fig, marks)
    return save(fig, path)


def _required_title(ds, line, probability, answers, gaps_mm) -> str:
    """The required-gap chart's answer: the gap each line needs, first to last.

    ``answers``: ``(line index or None, required gap [mm] or NaN)`` per line drawn.
    """
    head = f"Gap for {100 * probability:g} % pounding probability"
    named = [(i, g) for i, g in answers if np.isfinite(g)]
    none = [i for i, g in answers if not np.isfinite(g)]

    def at(i, first=True):
        if i is None:
            return ""
        return f" at {coord_text(ds, line, i) if first else value_text(ds, line, i)}"

    if named:
        (i0, g0), (i1, g1) = named[0], named[-1]
        text = f"{_mm(g0)} mm{at(i0)}"
        text += f" to {_mm(g1)} mm{at(i1, False)}" if len(named) > 1 else ""
    else:
        text = "none within the gaps studied"
    if none and named:
        where = ", ".join(value_text(ds, line, i) for i in none) if line is not None else ""
        text += f"; more than {_mm(gaps_mm[-1])} mm" + (f" at {where}" if where else "")
    elif none:
        text = f"more than {_mm(gaps_mm[-1])} mm, the widest gap studied"
        text += f", for every {dim_text(ds, line)}" if line is not None and len(none) > 1 else ""
    return f"{head}: {text}"


def _own_rule_gaps(ds, line, hold, base_dir) -> tuple[dict, dict]:
    """The rules' median gaps [mm] per line and the share of runs pounding at their own.

    :func:`pound_mc.analysis.site_risk.code_gaps` (every run simulated again at each rule's
    gap); ``{}`` twice where the rules do not describe the study (shear buildings, a wall).
    """
    try:
        table = code_gaps(ds, base_dir=base_dir)
    except RulesDoNotApply:
        return {}, {}
    picked = {d: i for d, i in hold.items() if d in table.dims}
    table = table.isel(picked)
    gaps, shares = {}, {}
    for rule in table["rule"].values:
        g, e = table["code_gap"].sel(rule=rule), table["code_gap_exceedance"].sel(rule=rule)
        name = str(rule).upper()
        gaps[name] = np.atleast_1d(g.values if line is None else g.transpose(line).values) * 1e3
        shares[name] = np.atleast_1d(e.values if line is None else e.transpose(line).values)
    return gaps, shares


#: Where the note of :func:`_short_note` may go: anchor (axes fraction), alignment; in order
#: of preference (ties keep the first).  ``None`` as height: just above the target line.
_NOTE_PLACES = (
    ((0.98, 0.97), "right", "top"), ((0.98, 0.5), "right", "center"),
    ((0.98, None), "right", "bottom"), ((0.5, 0.97), "center", "top"),
    ((0.5, 0.5), "center", "center"), ((0.5, None), "center", "bottom"),
    ((0.02, 0.97), "left", "top"), ((0.02, 0.5), "left", "center"),
)  # fmt: skip
_NOTE_SIZE = 7.5  # [pt]
#: Margin around the note [axes fraction] within which a line's point counts as covered.
_NOTE_CLEARANCE = 0.03


def _short_note(ax: Axes, short, probability: float) -> None:
    """One note for the lines still above the target at the widest gap, arrows to their ends.

    ``short``: ``(line, widest gap [mm], its probability)`` each.  The note goes where it
    covers the fewest points along the lines drawn (:data:`_NOTE_PLACES`).
    """
    if not short:
        return
    widest = _mm(short[0][1])
    names = ", ".join(ln.get_label() for ln, _, _ in short)
    ends = ", ".join(f"{y:.2g}" for _, _, y in short)
    text = (
        f"{names}: P = {ends} > {probability:g} even\nat the widest gap studied ({widest} mm):\n"
        "no required gap, widen the gap range"
    )
    to_axes = ax.transData + ax.transAxes.inverted()
    box = ax.get_position()
    size_pt = (
        np.array([box.width * ax.figure.get_figwidth(), box.height * ax.figure.get_figheight()])
        * 72
    )
    lines = text.split("\n")  # the box's size in axes fractions, estimated
    w, h = (np.array([0.55 * max(map(len, lines)), 1.25 * len(lines)]) * _NOTE_SIZE + 8) / size_pt
    points = []  # along every line drawn, densely
    for ln in ax.lines:
        xy = np.c_[np.asarray(ln.get_xdata(), float), np.asarray(ln.get_ydata(), float)]
        xy = xy[np.all(np.isfinite(xy), axis=1)]
        for a, b in zip(xy[:-1], xy[1:], strict=True):
            points.append(a + np.linspace(0, 1, 40)[:, None] * (b - a))
    points = to_axes.transform(np.concatenate(points)) if points else np.empty((0, 2))
    target = float(to_axes.transform([[0.0, probability]])[0, 1])

    def covered(place):
        (x, y), ha, va = place
        y = target + 0.04 if y is None else y
        x0 = x - {"left": 0.0, "center": 0.5, "right": 1.0}[ha] * w
        y0 = y - {"bottom": 0.0, "center": 0.5, "top": 1.0}[va] * h
        # a point just outside the box still meets it: markers and line widths have a size
        m = _NOTE_CLEARANCE
        inside = (points[:, 0] > x0 - m) & (points[:, 0] < x0 + w + m)
        return int(np.sum(inside & (points[:, 1] > y0 - m) & (points[:, 1] < y0 + h + m)))

    (x, y), ha, va = min(_NOTE_PLACES, key=covered)
    y = target + 0.04 if y is None else y
    note = ax.annotate(
        text,
        (x, y),
        xycoords="axes fraction",
        ha=ha,
        va=va,
        fontsize=_NOTE_SIZE,
        bbox={"boxstyle": "round,pad=0.4", "fc": "white", "ec": "0.4", "alpha": 0.95},
        zorder=5,
    )
    for _, x_end, y_end in short:  # from the note's edge nearest the line's end
        end = to_axes.transform([[x_end, y_end]])[0]
        ax.annotate(
            "",
            (x_end, y_end),
            xytext=(0.97 if ha == "right" else 0.5, 0.0 if end[1] < y else 1.0),
            textcoords=note,
            arrowprops={"arrowstyle": "->", "color": "0.3", "lw": 1.0, "shrinkB": 4},
            zorder=5,
        )
