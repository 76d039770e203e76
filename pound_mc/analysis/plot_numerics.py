"""Charts of the numerics: work-precision, stability map, one simulation's time history."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from pound_mc.analysis.plot import finish_axes
from pound_mc.analysis.style import (
    MARKERS,
    PALETTE,
    chart_doc,
    legend_outside,
    line_style,
    new_axes,
    new_figure,
    save,
)
from pound_mc.scene import SimulationResult

__all__ = ["work_precision_chart", "stability_map_chart", "time_history_chart"]

_METHOD_STYLE = {
    "adaptive": (PALETTE[0], MARKERS[0]),
    "newmark": (PALETTE[1], MARKERS[1]),
    "newmark-explicit": (PALETTE[2], MARKERS[2]),
    "central-difference": (PALETTE[3], MARKERS[4]),
}


def work_precision_chart(
    table: pd.DataFrame, path: str | Path | None = None, *, quantity: str = "err_peak_force"
) -> Figure:
    """Error against time per simulation (log-log), one curve per method, one panel per scene.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`pound_mc.numerics.bench.benchmark` output.
    quantity : str
        Error column to draw.
    """
    scenes = list(dict.fromkeys(table["scene"]))
    fig = new_figure((5.2 * len(scenes), 4.2))
    axes = fig.subplots(1, len(scenes), squeeze=False)[0]
    for ax, label in zip(axes, scenes, strict=True):
        part = table[table["scene"] == label]
        for method, rows in part.groupby("method", sort=False):
            colour, marker = _METHOD_STYLE.get(method, ("k", "x"))
            err = np.maximum(rows[quantity].to_numpy(), 1e-16)
            ax.loglog(rows["seconds"] * 1e3, err, marker=marker, color=colour, label=method)
        ax.axhline(1e-4, color="0.5", lw=0.8, ls="--")
        ref = part["reference"].iloc[0] if "reference" in part else "reference"
        ax.xaxis.set_minor_formatter(NullFormatter())
        finish_axes(
            ax,
            xlabel="time per simulation [ms] (one core, median)",
            ylabel="relative error of peak force [-]",
            title=f"{label}: work-precision (against {ref})",
            title_size=10,
            grid="both",
        )
    return save(fig, path)


def stability_map_chart(table: pd.DataFrame, path: str | Path | None = None) -> Figure:
    """Largest stable ``dt omega_c`` against contact stiffness, predicted and observed.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`pound_mc.numerics.stability.stability_map` output.
    """
    fig = new_figure((6.4, 4.4))
    ax = fig.subplots()
    top = 20.0
    for method, rows in table.groupby("method", sort=False):
        colour, marker = _METHOD_STYLE.get(method, ("k", "x"))
        obs = rows["observed"].to_numpy(dtype=float)
        unbounded = ~np.isfinite(obs)
        ax.semilogx(rows["beta"][~unbounded], obs[~unbounded], marker=marker, color=colour,
                    ls="-", label=f"{method}, observed")  # fmt: skip
        if unbounded.any():
            ax.semilogx(rows["beta"][unbounded], np.full(unbounded.sum(), top), marker=marker,
                        color=colour, ls=":", label=f"{method}: stable up to {top:g}")  # fmt: skip
        pred = rows["predicted"].to_numpy(dtype=float)
        if np.isfinite(pred).all():
            ax.semilogx(rows["beta"], pred, color=colour, ls="--", label=f"{method}, predicted")
    finish_axes(
        ax,
        yscale="log",
        xlabel="impact stiffness beta [N/m^1.5]",
        ylabel="largest stable dt * omega_c [-]",
        title="Stability at an impact (v0 = 0.5 m/s, m = 1e6 kg)",
        title_size=None,
        legend_size=7,
        grid="both",
    )
    return save(fig, path)


def _contact_floors(result) -> list[tuple[str, np.ndarray, str, np.ndarray]]:
    """Per contact: the label and displacement history of its floor in each building.

    The top floors for SDOF pairs; in a row (``[[buildings]]``) the floors of the contact's
    two neighbours, named by their place in the row (from 0).
    """
    scene = getattr(result, "scene", None)
    contacts = getattr(scene, "contacts", None)
    left, right = result.disp_left_m, result.disp_right_m
    n = result.penetration_m.shape[1]
    row = getattr(scene, "row", None)
    buildings = row if row is not None else [getattr(scene, s, None) for s in ("left", "right")]
    who = ["left", "right"] if row is None else [f"building {k}" for k in range(len(row))]

    def name(k, floor):  # building k's floor (0-based); a wall, at rest with the ground, has none
        wall = getattr(buildings[k], "model", None) == "wall"
        return "wall" if wall else f"{who[k]}, floor {floor + 1}"

    if contacts is None or len(contacts) != n:
        nl, nr = left.shape[1], right.shape[1]
        return [(name(0, nl - 1), left[:, -1], name(1, nr - 1), right[:, -1])] * n
    if row is None:
        return [(name(0, c.left_floor), left[:, c.left_floor],
                 name(1, c.right_floor), right[:, c.right_floor])
                for c in contacts]  # fmt: skip
    floors = np.hstack([left, right])  # the row's buildings, left to right
    start = np.cumsum([0] + [b.n_floors for b in row])
    return [(name(c.pair, c.left_floor), floors[:, start[c.pair] + c.left_floor],
             name(c.pair + 1, c.right_floor), floors[:, start[c.pair + 1] + c.right_floor])
            for c in contacts]  # fmt: skip


def _row_floors(ax, t, floors) -> None:
    """A row's floors that meet at a contact, each once, in its building's colour.

    A floor at two contacts (a middle building's) is drawn once; a wall, at rest, is not.
    Solid the first floor drawn of a building, dashed its others.
    """
    seen: dict[str, np.ndarray] = {}
    for name_l, x_l, name_r, x_r in floors:
        for name, x in ((name_l, x_l), (name_r, x_r)):
            if name != "wall" and name not in seen:
                seen[name] = x
    drawn: dict[int, int] = {}
    for name, x in seen.items():
        k = int(name.split(",")[0].removeprefix("building "))
        colour = line_style(k)["color"]
        ls = "-" if drawn.get(k, 0) == 0 else "--"
        drawn[k] = drawn.get(k, 0) + 1
        ax.plot(t, x * 1e3, lw=0.8, color=colour, ls=ls, label=name)


@chart_doc
def time_history_chart(
    result: SimulationResult,
    path: str | Path | None = None,
    *,
    ax: Sequence[Axes] | None = None,
) -> Figure:
    """Displacements, penetration and contact force of one simulation against time.

    The top panel draws the displacements of the two floors that meet at each contact (the
    same height), in the contact's colour: left building solid, right building dashed; in a
    row, each building's floors that meet a contact once, in the building's colour.  With
    yielding buildings the run goes on after the record for ``integrator.tail_s`` (residual
    drifts): that free vibration is shaded.

    Parameters
    ----------
    result : pound_mc.scene.SimulationResult
        A result run with ``history=True``.
    %(path)s
    ax : sequence of three matplotlib.axes.Axes, optional
        Where to draw the displacements, the penetrations and the forces.
    """
    t = result.time_s
    fig, (ax1, ax2, ax3) = new_axes(ax, (9.0, 7.0), nrows=3)
    if ax is None:
        ax2.sharex(ax1)
        ax3.sharex(ax1)
    floors = _contact_floors(result)
    if getattr(result.scene, "row", None) is not None:
        _row_floors(ax1, t, floors)
    for c, (name_l, x_l, name_r, x_r) in enumerate(floors):
        style = line_style(c)
        colour = style["color"]
        many = len(floors) > 1
        where = f"contact {c + 1}: " if many else ""
        if getattr(result.scene, "row", None) is None:
            ax1.plot(t, x_l * 1e3, lw=0.8, color=colour, label=f"{where}{name_l}")
            ax1.plot(t, x_r * 1e3, lw=0.8, color=colour, ls="--", label=f"{where}{name_r}")
        ax2.plot(t, result.penetration_m[:, c] * 1e3, lw=0.8, color=colour,
                 label=f"contact {c + 1}")  # fmt: skip
        ax3.plot(t, result.force_N[:, c] / 1e6, lw=0.8, color=colour, label=f"contact {c + 1}")
    ax1.set_ylabel("displacement [mm]")
    legend_outside(ax1, size=7)
    if len(floors) > 1:
        legend_outside(ax2, size=7)
        legend_outside(ax3, size=7)
    tail = result.scene.tail_s if result.storeys is not None else 0.0
    n_tail = int(round(tail / (t[1] - t[0]))) if t.size > 1 else 0  # samples, as with_tail
    if 0 < n_tail < t.size:  # yielding buildings: free vibration after the record
        for k, a in enumerate((ax1, ax2, ax3)):
            a.axvspan(t[-1 - n_tail], t[-1], color="0.92", lw=0, zorder=0,
                      label="free vibration after the record" if k == 0 else None)  # fmt: skip
        legend_outside(ax1, size=7)
    ax2.axhline(0.0, color="0.5", lw=0.6)
    ax2.set_ylabel("penetration delta [mm]")
    ax3.set_ylabel("contact force [MN]")
    ax3.set_xlabel("time [s]")
    o = result.outputs
    file = getattr(result.scene, "file", None)
    if ax is None and file:  # a study's history names the simulation instead (accessor)
        fig.suptitle(f"scene {Path(file).name}", fontsize=9)
    ax1.set_title(
        f"peak force {o['peak_force'] / 1e6:.4g} MN (continuous maximum), "
        f"{int(o['impacts'])} impacts, status {result.status}",
        fontsize=9,
    )
    return save(fig, path)
