"""Charts of the numerics: work-precision, stability map, one simulation's time history."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from pound_mc.analysis.plot import finish_axes, save

__all__ = ["work_precision_chart", "stability_map_chart", "time_history_chart"]

_METHOD_STYLE = {
    "adaptive": ("C0", "o"),
    "newmark": ("C1", "s"),
    "newmark-explicit": ("C2", "^"),
    "central-difference": ("C3", "v"),
}


def work_precision_chart(table, path=None, *, quantity: str = "err_peak_force") -> Figure:
    """Error against time per simulation (log-log), one curve per method, one panel per scene.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`pound_mc.numerics.bench.benchmark` output.
    quantity : str
        Error column to draw.
    """
    scenes = list(dict.fromkeys(table["scene"]))
    fig = Figure(figsize=(5.2 * len(scenes), 4.2), layout="constrained")
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


def stability_map_chart(table, path=None) -> Figure:
    """Largest stable ``dt omega_c`` against contact stiffness, predicted and observed.

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`pound_mc.numerics.stability.stability_map` output.
    """
    fig = Figure(figsize=(6.4, 4.4), layout="constrained")
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


def time_history_chart(result, path=None) -> Figure:
    """Displacements, penetration and contact force of one simulation against time.

    Parameters
    ----------
    result : pound_mc.scene.SimulationResult
        A result run with ``history=True``.
    """
    t = result.time_s
    fig = Figure(figsize=(8.0, 7.0), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(3, 1, sharex=True)
    ax1.plot(t, result.disp_left_m[:, -1] * 1e3, lw=0.8, label="left (top floor)")
    ax1.plot(t, result.disp_right_m[:, -1] * 1e3, lw=0.8, label="right (top floor)")
    ax1.set_ylabel("displacement [mm]")
    ax1.legend(fontsize=8)
    for c in range(result.penetration_m.shape[1]):
        ax2.plot(t, result.penetration_m[:, c] * 1e3, lw=0.8, label=f"contact {c + 1}")
        ax3.plot(t, result.force_N[:, c] / 1e6, lw=0.8, label=f"contact {c + 1}")
    ax2.axhline(0.0, color="0.5", lw=0.6)
    ax2.set_ylabel("penetration delta [mm]")
    ax3.set_ylabel("contact force [MN]")
    ax3.set_xlabel("time [s]")
    o = result.outputs
    ax1.set_title(
        f"peak force {o['peak_force'] / 1e6:.4g} MN (continuous maximum), "
        f"{int(o['impacts'])} impacts, status {result.status}"
    )
    return save(fig, path)
