"""Fragility chart: the stripes' event fractions, the fitted lognormal curve and its band.

Draws on a given :class:`matplotlib.axes.Axes` or on a new :class:`matplotlib.figure.Figure`
(no pyplot state), and returns the Axes so tests can read the plotted data back from its
artists.
"""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes

from pound_mc.analysis.fragility import FragilityFit
from pound_mc.analysis.style import PALETTE, legend_outside, new_figure

__all__ = ["fragility_chart"]


def fragility_chart(
    fit: FragilityFit,
    *,
    ax: Axes | None = None,
    im_label: str = "intensity measure",
    event_label: str = "event",
    band: bool = True,
    counts: bool = True,
    num: int = 200,
    legend: bool = True,
    im_units: str = "",
    x_max: float | None = None,
    totals: bool | None = None,
) -> Axes:
    """Plot a fitted fragility: points per stripe, the fitted curve and the bootstrap band.

    Parameters
    ----------
    fit : FragilityFit
        From :func:`pound_mc.analysis.fragility.fit_fragility`.
    ax : matplotlib.axes.Axes, optional
        Where to draw; default a new figure's single Axes.
    im_label : str, default "intensity measure"
        x-axis label (name and units of the IM, e.g. ``"PGA [g]"``).
    event_label : str, default "event"
        What the probability is of (``"pounding"``).
    band : bool, default True
        Shade the pointwise bootstrap band of the curve at ``fit.ci`` (when the fit has
        intervals: not when more than half of the resamples had no fit).
    counts : bool, default True
        Write each stripe's count beside its point (:func:`stripe_counts`).
    num : int, default 200
        Points along the curve.
    legend : bool, default True
        Draw the legend (right of the axes, outside the data).
    im_units : str, default ""
        Units of the IM written after theta in the legend (``"g"``).
    x_max : float, optional
        Right end of the x axis, where the curve stops (default: past the widest stripe and
        ``theta exp(2.5 beta)``, where the curve is near 1; panels of one study share the
        stripes' range instead).
    totals : bool, optional
        Write the counts as ``events/simulations``; default only when the stripes have
        different numbers of simulations, else the events alone, the number of simulations
        once in the stripes' legend entry.

    Returns
    -------
    matplotlib.axes.Axes
        Artists, in order: the band (a ``PolyCollection``, if drawn), the curve (``lines[0]``)
        and the stripes (``lines[1]``, markers only); the counts are ``ax.texts``.
    """
    if ax is None:
        ax = new_figure((6.4, 4.2)).add_subplot()
    im = fit.im
    fraction = np.divide(
        fit.n_event, fit.n_total, out=np.full(im.shape, np.nan), where=fit.n_total > 0
    )
    if x_max is None:
        x_max = 1.05 * max(float(im.max()), fit.theta * np.exp(2.5 * fit.beta))
    x = np.linspace(0.0, x_max, num)[1:]
    counted = np.unique(fit.n_total[fit.n_total > 0])
    if totals is None:
        totals = counted.size != 1
    if totals or not counts:
        stripes = "stripes: fraction of simulations" + (" (events/simulations)" if counts else "")
    else:
        stripes = (
            f"stripes: fraction of the {int(counted[0])} simulations of a stripe (the number "
            f"with {event_label} written beside)"
        )
    unit = f" {im_units}" if im_units else ""
    percent = round(100 * fit.ci)
    if band and np.all(np.isfinite(fit.theta_ci)):
        lower, upper = fit.band(x)
        ax.fill_between(
            x, lower, upper, color=PALETTE[0], alpha=0.2, lw=0, label=f"{percent} % bootstrap band"
        )
    ax.plot(
        x,
        fit.probability(x),
        color=PALETTE[0],
        label=f"lognormal fit: theta = {fit.theta:.3g}{unit}, beta = {fit.beta:.3g}",
    )
    ax.plot(im, fraction, "o", color="black", ms=5, label=stripes)
    ax.axvline(fit.theta, color=PALETTE[0], lw=0.8, ls=":")
    ax.set_xlim(0.0, x[-1])
    if counts:
        ax.set_ylim(-0.02, 1.02)
        stripe_counts(ax, im, fit.n_event, fit.n_total, totals=totals)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(im_label)
    ax.set_ylabel(f"P({event_label} | IM)")
    ax.grid(alpha=0.3)
    if legend:
        legend_outside(ax)
    return ax


#: Where a count may go, in order of preference, for a point below (``"low"``) or above half:
#: (dx, dy) [pt] from the point to the label's anchor, horizontal and vertical alignment.  A
#: rising curve leaves the space above-left of a point and below-right of it free.
_PLACES = {
    "low": (
        (-4, 4, "right", "bottom"), (0, 5, "center", "bottom"), (4, 4, "left", "bottom"),
        (-6, 0, "right", "center"), (6, 0, "left", "center"), (0, -5, "center", "top"),
    ),
    "high": (
        (4, -4, "left", "top"), (0, -5, "center", "top"), (-4, -4, "right", "top"),
        (6, 0, "left", "center"), (-6, 0, "right", "center"), (0, 5, "center", "bottom"),
    ),
}  # fmt: skip
#: Label size [pt], width of a character of it [em] (digits and "/" of DejaVu Sans, rounded
#: up) and the points' radius [pt] with a margin.
_COUNT_SIZE, _CHAR_EM, _POINT_RADIUS = 7.0, 0.65, 4.0


def _box(x, y, width, height, place):
    """``(x0, y0, x1, y1)`` [pt] of a label of ``width`` x ``height`` placed at ``place``."""
    dx, dy, ha, va = place
    x0 = x + dx - {"left": 0.0, "center": 0.5, "right": 1.0}[ha] * width
    y0 = y + dy - {"bottom": 0.0, "center": 0.5, "top": 1.0}[va] * height
    return x0, y0, x0 + width, y0 + height


def _overlap(a, b) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def stripe_counts(ax: Axes, im, n_event, n_total, *, totals: bool = True) -> None:
    """Label each stripe's point with its count where the label meets no point and no label.

    The count is ``z/n`` (``totals``) or ``z`` alone (the caller says ``n`` elsewhere).  Each
    label takes the first place of :data:`_PLACES` that stays inside the axes and clears every
    point and the labels placed before it (the first place inside the axes if none does), in
    the axes' size and limits as they are when called (set the limits first).
    """
    im = np.asarray(im, dtype=float)
    n_event, n_total = np.asarray(n_event), np.asarray(n_total)
    (left, right), (bottom, top) = ax.get_xlim(), ax.get_ylim()
    box = ax.get_position()
    width_pt = box.width * ax.figure.get_figwidth() * 72.0
    height_pt = box.height * ax.figure.get_figheight() * 72.0
    shown = n_total > 0
    fraction = np.divide(n_event, n_total, out=np.zeros(im.shape), where=shown)
    xs = (im - left) / (right - left) * width_pt
    ys = (fraction - bottom) / (top - bottom) * height_pt
    r = _POINT_RADIUS
    taken = [(x - r, y - r, x + r, y + r) for x, y, s in zip(xs, ys, shown, strict=True) if s]
    for xi, x, y, zi, ni, fi, s in zip(im, xs, ys, n_event, n_total, fraction, shown, strict=True):
        if not s:
            continue
        text = f"{int(zi)}/{int(ni)}" if totals else f"{int(zi)}"
        size = (_CHAR_EM * _COUNT_SIZE * len(text), _COUNT_SIZE)
        places = _PLACES["high" if fi >= 0.5 else "low"]
        inside = [
            p for p in places
            if (b := _box(x, y, *size, p))[0] >= 0 and b[2] <= width_pt
            and b[1] >= 0 and b[3] <= height_pt
        ] or list(places)  # fmt: skip
        free = [p for p in inside if not any(_overlap(_box(x, y, *size, p), t) for t in taken)]
        place = (free or inside)[0]
        taken.append(_box(x, y, *size, place))
        ax.annotate(
            text,
            (xi, fi),
            textcoords="offset points",
            xytext=place[:2],
            ha=place[2],
            va=place[3],
            fontsize=_COUNT_SIZE,
        )
