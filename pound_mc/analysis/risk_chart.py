"""Charts of the risk outputs: fragility panels and the required gap on the probability chart.

:func:`fragility_panels` draws :func:`~pound_mc.analysis.fragility_chart.fragility_chart` for
each combination of the grid axes other than the intensity (e.g. one panel per gap);
:func:`required_gap_chart` is :func:`~pound_mc.analysis.plot.probability_chart` (pounding
probability against gap, one line per intensity, the separation rules marked) with the target
probability and the required gap of each line (:func:`pound_mc.analysis.risk.required_gap`)
and its confidence interval.
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

from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.fragility_chart import fragility_chart, stripe_counts
from pound_mc.analysis.plot import _hold, _line_label, probability_chart, save
from pound_mc.analysis.risk import GAP_DIM, _counts, _intensity_dim, required_gap
from pound_mc.analysis.style import axis_label, chart_doc, legend_outside, new_axes, value_text
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
        A panel without a fit says why; one whose bootstrap left resamples out (they have no
        fit) says how many, and has no band when more than half were.
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
    im_label = axis_label(ds, dim)
    for ax, combo in zip(axes, combos, strict=False):
        where = {**held, **dict(zip(free, combo, strict=True))}
        z = n_event.isel(where).transpose(dim).values
        n = n_total.isel(where).transpose(dim).values
        title = ", ".join(_line_label(ds, d, i) for d, i in where.items()) or "all simulations"
        try:
            fit = fit_fragility(x, z, n, n_boot=n_boot, seed=seed)
        except InputError as exc:
            ax.plot(x, np.divide(z, n, out=np.full(x.shape, np.nan), where=n > 0), "o", c="k")
            why = textwrap.shorten(exc.message, 180, placeholder=" ...")
            ax.set_title(f"{title}\n" + textwrap.fill(f"no fit: {why}", 60), fontsize=7)
            ax.set_xlabel(im_label)
            ax.set_ylabel(f"P({event} | IM)")
            ax.set_ylim(-0.02, 1.02)
            stripe_counts(ax, x, z, n)
            continue
        fragility_chart(fit, ax=ax, im_label=im_label, event_label=event, legend=False)
        head = f"{title}\ntheta = {fit.theta:.3g}, beta = {fit.beta:.3g}"
        note = f"\n{textwrap.fill(fit.bootstrap_note, 64)}" if fit.bootstrap_note else ""
        ax.set_title(head + note, fontsize=8)
        if not legend:
            handles, labels = ax.get_legend_handles_labels()
            generic = [label.split(":")[0] for label in labels]  # the fit's numbers: per panel
            if own:
                legend = fig.legend(
                    handles, generic, loc="outside lower center", ncols=3, fontsize=8
                )
            else:  # a caller's figure: in the first panel, where a rising curve leaves room
                legend = ax.legend(handles, generic, loc="lower right", fontsize=7)
    for ax in axes[len(combos) :]:
        ax.set_visible(False)
    if own:  # a figure of its own: the title over the panels (not on a caller's figure)
        fig.suptitle(
            f"Fragility ({ds.attrs.get('study_name', '')}): P({event}) over records and "
            f"samples, lognormal fit by maximum likelihood, {n_boot} bootstrap replicates",
            fontsize=9,
        )
    return save(fig, path)


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
    """Pounding probability against gap, the rules, the target and the required gap per line.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with two or more gaps on its grid.
    %(path)s
    probability : float, default 0.1
        Target probability (a horizontal line); each line's required gap is marked on it with
        its Wilson confidence interval.
    line, sel, rules, base_dir, ax
        As :func:`pound_mc.analysis.plot.probability_chart` (all records pooled).

    Returns
    -------
    matplotlib.figure.Figure
        ``fig.axes[0]``: the probability lines first (as the probability chart), then the
        rules, then the target line and one errorbar marker per line with a required gap.
    """
    if GAP_DIM not in ds.dims:
        raise InputError("does not apply: the required gap needs a study with the gap on its grid")
    fig = probability_chart(ds, None, line=line, sel=sel, rules=rules, base_dir=base_dir, ax=ax)
    ax = ax if ax is not None else fig.axes[0]
    found = required_gap(ds, probability, rules=False)
    ax.axhline(probability, color="grey", lw=0.9, ls="--", label=f"target {probability:g}")
    rest = list(found["required_gap"].dims)
    sel = dict(sel or {})
    line = line if line is not None else (rest[0] if rest else None)
    sel.pop(line, None)
    hold = _hold(ds, [d for d in rest if d != line], sel)
    labels = {"pounding probability": hold}
    if line is not None:
        labels = {value_text(ds, line, i): {**hold, line: i} for i in range(ds.sizes[line])}
    drawn = [ln for ln in ax.lines if ln.get_label() in labels]
    first = True
    for ln in drawn:
        where = labels.get(ln.get_label())
        if where is None:
            continue
        gap = float(found["required_gap"].isel(where))
        if not np.isfinite(gap):
            continue
        lo, hi = found["required_gap_ci"].isel(where).values
        err = [[(gap - lo) * 1e3], [(hi - gap) * 1e3 if np.isfinite(hi) else 0.0]]
        ax.errorbar(
            [gap * 1e3],
            [probability],
            xerr=err,
            fmt="D",
            color=ln.get_color(),
            ms=6,
            capsize=3,
            label=f"required gap at P = {probability:g} (Wilson {found.attrs['ci']:g} CI)"
            if first
            else None,
        )
        first = False
    legend_outside(ax, title=axis_label(ds, line) if line is not None else None)
    if first:  # no line reaches the target within the grid's gaps: say so, not a silent chart
        marks = f"no gap of the grid brings P to {probability:g} or less: widen the gap range"
    else:
        marks = f"diamonds: smallest gap with P <= {probability:g} (bars: Wilson interval)"
    ax.set_title(ax.get_title() + "\n" + marks, fontsize=8)
    return save(fig, path)
