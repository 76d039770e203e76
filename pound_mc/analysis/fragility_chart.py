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
        Write ``events/simulations`` beside each stripe's point.
    num : int, default 200
        Points along the curve.
    legend : bool, default True
        Draw the legend (right of the axes, outside the data).

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
    upper_im = max(float(im.max()), fit.theta * np.exp(2.5 * fit.beta))
    x = np.linspace(0.0, 1.05 * upper_im, num)[1:]
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
        label=f"lognormal fit: theta = {fit.theta:.3g}, beta = {fit.beta:.3g}",
    )
    ax.plot(im, fraction, "o", color="black", ms=5, label="stripes (fraction of simulations)")
    ax.axvline(fit.theta, color=PALETTE[0], lw=0.8, ls=":")
    ax.set_xlim(0.0, x[-1])
    if counts:
        stripe_counts(ax, im, fit.n_event, fit.n_total)
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(im_label)
    ax.set_ylabel(f"P({event_label} | IM)")
    ax.grid(alpha=0.3)
    if legend:
        legend_outside(ax)
    return ax


def stripe_counts(ax: Axes, im, n_event, n_total) -> None:
    """Label each stripe's point with its count, ``z/n``, inside the axes' horizontal range.

    Labels of stripes closer than a label's width at about the same height are stacked (low
    intensities on an axis stretched to a high median crowd together).
    """
    im = np.asarray(im, dtype=float)
    n_event, n_total = np.asarray(n_event), np.asarray(n_total)
    left, right = ax.get_xlim()
    width_pt = ax.get_position().width * ax.figure.get_figwidth() * 72.0
    placed = []  # (x [pt], fraction, stacking level) of the labels drawn
    for xi, zi, ni in zip(im, n_event, n_total, strict=True):
        if ni <= 0:
            continue
        fi = zi / ni
        text = f"{int(zi)}/{int(ni)}"
        x_pt = (xi - left) / (right - left) * width_pt
        near = [
            lv for px, pf, lv in placed if abs(px - x_pt) < 5.0 * len(text) and abs(pf - fi) < 0.1
        ]
        level = max(near) + 1 if near else 0
        placed.append((x_pt, fi, level))
        at_right = xi >= left + 0.9 * (right - left)  # the label goes left of the point
        ax.annotate(
            text,
            (xi, fi),
            textcoords="offset points",
            xytext=(-4 if at_right else 4, -11 - 9 * level if fi > 0.9 else 5 + 9 * level),
            ha="right" if at_right else "left",
            fontsize=7,
        )
