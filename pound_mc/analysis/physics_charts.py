"""Charts of the contact physics: restitution relations, Table 2 ranges, the virtual drop test.

Each function draws on a new :class:`matplotlib.figure.Figure` (or the Axes given) and, given
``path``, writes it as PNG; it returns the figure.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from pound_mc.analysis.style import (
    PALETTE,
    chart_doc,
    legend_outside,
    line_style,
    new_axes,
    new_figure,
    save,
)
from pound_mc.physics import materials, relations
from pound_mc.physics.droptest import DropTestResult, drop_test

__all__ = [
    "restitution_curves",
    "restitution_chart",
    "restitution_ranges_chart",
    "droptest_chart",
]

_MATERIAL_COLOURS = {
    "steel": PALETTE[0],
    "concrete": PALETTE[6],
    "timber": PALETTE[1],
    "ceramics": PALETTE[3],
}


def restitution_curves(
    targets: ArrayLike | None = None,
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Restitution each xi-e relation really produces against its target.

    Jankowski-law relations read the ``exact`` table; the Kelvin and Hertz-damp relations run
    the virtual drop test with their own force law (1.35 kg concrete ball at 1 m/s).

    Returns
    -------
    dict
        ``{label: (target e, achieved e)}``.
    """
    targets = np.linspace(0.1, 0.99, 37) if targets is None else np.asarray(targets, float)
    curves = {}
    for name in ("jankowski2008", "jankowski2006", "exact"):
        curves[f"Jankowski law, {name}"] = (targets, relations.effective_restitution(targets, name))
    coarse = targets[::3]
    for model, stiffness, rel in (
        ("kelvin", 1.0e7, "kelvin"),
        ("hertzdamp", 7.9e9, "ye2009"),
        ("hertzdamp", 7.9e9, "muthukumar2006"),
    ):
        achieved = [
            drop_test(1.35, 1.0, stiffness, e=e, model=model, relation=rel, n_history=4).restitution
            for e in coarse
        ]
        law = "Kelvin law" if model == "kelvin" else "Hertz-damp law"
        curves[f"{law}, {rel}"] = (coarse, np.asarray(achieved))
    return curves


@chart_doc
def restitution_chart(
    path: str | Path | None = None,
    *,
    targets: ArrayLike | None = None,
    samples: tuple | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Chart of the restitution really produced against the target, for every relation.

    Parameters
    ----------
    %(path)s
    targets : array_like, optional
        Target coefficients of restitution of the curves (default 37 values in 0.1-0.99).
    samples : tuple, optional
        ``(e, e_effective, label)``: a study's sampled target restitution and the restitution
        its contact law really produces [-], drawn as points over the curves.
    ax : matplotlib.axes.Axes, optional
        Where to draw (default a new figure).
    """
    fig, (ax,) = new_axes(ax, (8.6, 5.0))
    ax.plot([0, 1], [0, 1], color="0.5", lw=0.8, ls=":", label="achieved = target")
    styles = ["-", "--", "-.", "o", "s", "^"]
    for k, ((label, (t, a)), style) in enumerate(
        zip(restitution_curves(targets).items(), styles, strict=True)
    ):
        colour = line_style(k)["color"]
        if style in ("o", "s", "^"):
            ax.plot(t, a, style, color=colour, ms=4, mfc="none", label=label)
        else:
            ax.plot(t, a, ls=style, color=colour, lw=1.6, label=label)
    if samples is not None:
        e, e_eff, label = samples
        ax.scatter(
            np.ravel(e), np.ravel(e_eff), s=10, color="black", zorder=3, label=label, marker="x"
        )
    ax.set(
        xlabel="target coefficient of restitution e [-]",
        ylabel="restitution really produced [-]",
        xlim=(0, 1),
        ylim=(0, 1.02),
        title="Damping-restitution relations: one free impact",
    )
    ax.title.set_fontsize(9)
    ax.grid(alpha=0.3)
    legend_outside(ax)
    return save(fig, path)


def restitution_ranges_chart(path: str | Path | None = None) -> Figure:
    """Jankowski (2008) Table 2: measured restitution range against impact velocity."""
    fig = new_figure((6.4, 4.6))
    ax = fig.add_subplot()
    t2 = materials.table(2)
    for material in materials.MATERIALS:
        rows = t2[t2["material"] == material].sort_values("velocity_m_s")
        v = rows["velocity_m_s"].to_numpy()
        lo, hi = rows["e_min"].to_numpy(), rows["e_max"].to_numpy()
        colour = _MATERIAL_COLOURS[material]
        ax.fill_between(v, lo, hi, color=colour, alpha=0.25, lw=0, label=f"{material} (range)")
        ax.plot(v, 0.5 * (lo + hi), "o-", color=colour, ms=3, lw=1.2)
    ax.set(
        xlabel="prior-impact velocity [m/s]",
        ylabel="coefficient of restitution e [-]",
        title="Measured restitution (Jankowski 2008, Table 2)",
    )
    ax.grid(alpha=0.3)
    legend_outside(ax)
    return save(fig, path)


def droptest_chart(result: DropTestResult, path: str | Path | None = None) -> Figure:
    """Force against time and against penetration for one virtual drop test."""
    fig = new_figure((9.6, 4.0))
    ax1, ax2 = fig.subplots(1, 2)
    t_ms = result.time_s * 1e3
    ax1.plot(t_ms, result.force_N / 1e3, color=PALETTE[3])
    ax1.set(xlabel="time [ms]", ylabel="impact force [kN]", title="Impact force")
    ax2.plot(result.penetration_m * 1e3, result.force_N / 1e3, color=PALETTE[0])
    ax2.set(xlabel="penetration delta [mm]", ylabel="impact force [kN]", title="Force-penetration")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    fig.suptitle(
        f"Virtual drop test ({result.model}): m = {result.mass_kg:g} kg, "
        f"v0 = {result.velocity_m_s:g} m/s, beta = {result.beta:.3g}, xi = {result.xi:.4f} -> "
        f"e = {result.restitution:.4f}, peak {result.peak_force_N / 1e3:.2f} kN, "
        f"t_c = {result.contact_duration_s * 1e3:.3f} ms",
        fontsize=9,
    )
    return save(fig, path)
