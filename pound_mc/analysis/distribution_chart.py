"""Distribution of the peak impact force of the runs that pound: box plots and histograms.

Split by intensity where the study has an intensity axis (a multiple-stripe analysis): the
stripes are never pooled, since a wider gap pounds only under the stronger stripes and its
pooled forces would read higher for that reason alone.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pound_mc.analysis.labels import dim_text, text_of
from pound_mc.analysis.plot import GAP_DIM, _grid_dims, _hold, _record_index
from pound_mc.analysis.selection import MATERIAL_DIM
from pound_mc.analysis.style import (
    axis_label,
    caption,
    chart_doc,
    coord_text,
    fit_tick_labels,
    legend_outside,
    line_style,
    new_axes,
    save,
    value_text,
)

__all__ = ["distribution_chart"]


def _distribution_groups(ds, by, record, sel):
    """Peak forces [N] of the pounding simulations (status ok), per value of ``by``."""
    grid = _grid_dims(ds)
    held = _hold(ds, [d for d in (sel or {}) if d != by], sel)
    rec = {} if record is None else {"record": _record_index(ds, record)}
    force = ds["peak_force"].isel(**rec, **held)
    ok = (ds["status"] == 0) & (ds["impacts"] > 0)
    ok = ok.isel(**rec, **held)
    groups, labels = [], []
    for i in range(ds.sizes[by]):
        f = force.isel({by: i}).values
        m = ok.isel({by: i}).values
        groups.append(f[m].ravel())
        labels.append(value_text(ds, by, i))
    pooled = [d for d in grid if d != by and d not in held]
    return groups, labels, pooled


#: Intensity axes, by the order a chart looks for them.
_INTENSITY_DIMS = ("pga_g", "sa_g")


@chart_doc
def distribution_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    by: str | None = None,
    record: int | str | None = None,
    sel: dict | None = None,
    bins: int = 30,
    ax: Sequence[Axes] | None = None,
) -> Figure:
    """Distribution of the peak impact force: box plot and histogram per value of a dimension.

    Only simulations that pounded (at least one impact, status ok) enter; the other grid
    dimensions are pooled unless held by ``sel``, except an intensity axis (``pga_g``,
    ``sa_g``): pooling its stripes would mix weak shaking with strong (a wider gap pounds
    only in the strong stripes, so its pooled forces read higher).  With an intensity axis
    not held, the box plot has a group of boxes per intensity, and the histograms are those of
    the largest intensity.

    Parameters
    ----------
    %(ds)s
    %(path)s
    by : str, optional
        Dimension with one box and one histogram per value (default the material axis
        ``contact_material`` when the dataset has it, else the gap, else the last grid
        dimension; a study without grid: one group, its samples).
    %(record)s
    sel : dict, optional
        ``{dim: value}`` of grid dimensions to hold at one value (nearest) instead of pooling.
    bins : int
        Number of histogram bins (common to every value).
    ax : sequence of two matplotlib.axes.Axes, optional
        Where to draw the box plot and the histograms (default a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        Box plot on the first Axes (per intensity, then per value of ``by``, where split), one
        histogram (``patches``, [MN]) per value of ``by`` on the second.
    """
    grid = _grid_dims(ds)
    if not grid and by is None:  # no grid: the samples of the study's one scene, as run draws
        ds = ds[["peak_force", "status", "impacts"]].expand_dims(scene=["study scene"])
        ds["scene"].attrs = {"long_name": "scene", "units": "1"}
        grid, by = ["scene"], "scene"
    if by is None:
        by = MATERIAL_DIM if MATERIAL_DIM in grid else (GAP_DIM if GAP_DIM in grid else None)
        by = by or (grid[-1] if grid else None)
    if by is None or by not in ds.dims:
        raise ValueError(f"cannot draw the distribution per {by!r}: no such grid dimension")
    sel = dict(sel or {})
    im = next((d for d in _INTENSITY_DIMS if d in grid and d != by and d not in sel), None)
    stripes = [None] if im is None else list(range(ds.sizes[im]))
    boxes = []  # per stripe: the groups of the values of ``by``
    for j in stripes:
        at = sel if j is None else {**sel, im: ds[im].values[j]}
        groups, labels, pooled = _distribution_groups(ds, by, record, at)
        boxes.append(groups)
    fig, (ax1, ax2) = new_axes(ax, (11.0, 4.6), ncols=2)
    hist = boxes[-1]  # the histograms: of the largest intensity where split
    drawn = [k for k, g in enumerate(hist) if g.size]
    medians = _draw_boxes(ax1, ds, boxes, labels, im)
    if drawn:
        edges = np.histogram_bin_edges(np.concatenate([hist[k] for k in drawn]), bins=bins)
        for k in drawn:  # in the colours of the boxes, where split
            counts, _ = np.histogram(hist[k], bins=edges)
            style = line_style(k)
            ax2.stairs(counts, edges / 1e6, color=style["color"], linestyle=style["linestyle"],
                       lw=1.4, label=f"{labels[k]} ({hist[k].size})")  # fmt: skip
        by_label = "" if by == "scene" else f"{axis_label(ds, by)}\n"
        legend_outside(ax2, title=f"{by_label}(simulations)")
    if im is not None:
        ax2.set_title(f"at {coord_text(ds, im, stripes[-1])}", fontsize=9)
    xlabel = "" if by == "scene" else axis_label(ds, im if im is not None else by)
    ax1.set(xlabel=xlabel, ylabel="peak impact force [MN]")
    ax2.set(xlabel="peak impact force [MN]", ylabel="number of simulations [-]")
    for axis in (ax1, ax2):
        axis.grid(alpha=0.3)
    fig.suptitle(_distribution_title(ds, medians, by, im), fontsize=9)
    if record is None:
        n = ds.sizes["record"]
        rec_text = f"the {n} records" if n > 1 else f"record {text_of(ds['record'].values[0])}"
    else:
        rec_text = f"record {text_of(ds['record'].values[_record_index(ds, record)])}"
    pooled = [dim_text(ds, d) for d in pooled if d != im]
    caption(fig, f"Runs that pound (status ok, at least one impact) of {rec_text}"
            + (f", pooled over {', '.join(pooled)}" if pooled else "")
            + ". Boxes: 25-75 %, whiskers: 5-95 %, line: median, triangle: mean.")  # fmt: skip
    return save(fig, path)


def _draw_boxes(ax, ds, boxes, labels, im) -> list[tuple[float, int | None, int]]:
    """The box plot of :func:`distribution_chart`: a box per value of ``by``, per stripe.

    ``boxes``: per stripe (one, ``None`` as ``im``, when not split) the groups of forces [N].
    Returns ``(median [MN], stripe, group)`` of every box drawn.
    """
    n = len(labels)
    data, where, colours, medians = [], [], [], []
    for j, groups in enumerate(boxes):
        for k, g in enumerate(groups):
            if g.size:
                data.append(g / 1e6)
                where.append(j * (n + 1) + k + 1 if im is not None else len(data))
                colours.append(line_style(k)["color"])
                medians.append((float(np.median(g)) / 1e6, j if im is not None else None, k))
    if not data:
        ax.text(0.5, 0.5, "no simulation pounded", transform=ax.transAxes, ha="center")
        return medians
    drawn = ax.boxplot(data, positions=where, widths=0.7, showmeans=True, whis=(5, 95),
                       flierprops={"markersize": 2}, manage_ticks=im is None)  # fmt: skip
    if im is None:
        ax.set_xticks(where, [labels[k] for _, _, k in medians])
        fit_tick_labels(ax, len(data))
        return medians
    for box, colour in zip(drawn["boxes"], colours, strict=True):
        box.set_color(colour)
    centres = [j * (n + 1) + (n + 1) / 2 for j in range(len(boxes))]
    ax.set_xticks(centres, [value_text(ds, im, j) for j in range(len(boxes))])
    ax.set_xlim(0.0, len(boxes) * (n + 1))
    return medians


def _distribution_title(ds, medians, by, im) -> str:
    """The distribution chart's answer: its smallest and largest median, and where."""
    head = "Peak impact force of the runs that pound"
    if not medians:
        return f"{head}: none pounded"

    def where(j, k):
        text = coord_text(ds, by, k) if by != "scene" else ""
        return ", ".join(t for t in (coord_text(ds, im, j) if im else "", text) if t)

    low, high = min(medians, key=lambda m: m[0]), max(medians, key=lambda m: m[0])
    if len(medians) == 1 or high[0] == low[0]:
        at = where(*high[1:])
        return f"{head}: median {high[0]:.3g} MN" + (f" ({at})" if at else "")
    return (
        f"{head}: median {low[0]:.3g} MN ({where(*low[1:])}) to {high[0]:.3g} MN "
        f"({where(*high[1:])})"
    )
