"""Chart of the annual rate of pounding against the gap, with the target and the code gaps."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pound_mc.analysis import style
from pound_mc.analysis.risk import GAP_DIM, left_out_why

__all__ = ["risk_chart"]


def risk_chart(
    out: xr.Dataset,
    path: str | Path | None = None,
    *,
    code: xr.Dataset | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Mean annual rate of the event against the gap, its band, the target and the codes.

    Parameters
    ----------
    out : xarray.Dataset
        :func:`pound_mc.analysis.site_risk.risk`'s result (a gap axis; other grid axes are
        drawn at their first value and named).
    path : str or Path, optional
        Where to save the PNG.
    code : xarray.Dataset, optional
        The rules' and codes' gaps at their design intensities (``pound-mc risk``): each a
        vertical line labelled with how often runs pound at their own rule gap.
    ax : matplotlib.axes.Axes, optional
        Where to draw.

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[0].lines[0]``: the rates [1/year] against the gaps [mm].
    """
    if GAP_DIM not in out["annual_rate"].dims:
        raise ValueError("does not apply: the risk has no gap axis (contact.gap_m)")
    held = {d: 0 for d in out["annual_rate"].dims if d != GAP_DIM}
    sel = out.isel(held)
    gaps = 1e3 * np.asarray(out[GAP_DIM].values, float)
    rate = np.asarray(sel["annual_rate"].values, float)
    lo, hi = np.asarray(sel["annual_rate_ci"].values, float).T
    fig, (ax,) = style.new_axes(ax, (7.6, 4.8))
    ax.semilogy(gaps, rate, "o-", color="C0", label=f"annual rate of {out.attrs['event']}")
    ax.fill_between(gaps, lo, hi, color="C0", alpha=0.15, lw=0,
                    label=f"{round(100 * out.attrs['ci'])} % bootstrap band")  # fmt: skip
    target = out.attrs.get("target_rate", math.nan)
    if np.isfinite(target):
        ax.axhline(target, color="k", lw=0.8, ls="--", label=f"target {target:.3g}/year")
        if "required_gap" in sel and np.isfinite(sel["required_gap"]):
            g = 1e3 * float(sel["required_gap"])
            ax.plot([g], [target], "D", color="k", ms=7,
                    label=f"risk-targeted gap {g:.0f} mm")  # fmt: skip
    if code is not None:
        c = code.isel({d: 0 for d in code["code_gap"].dims if d != "rule"})
        for k, rule in enumerate(c["rule"].values):
            g = 1e3 * float(c["code_gap"].sel(rule=rule))
            share = 100 * float(c["code_gap_exceedance"].sel(rule=rule))
            text = f"{rule} {g:.0f} mm: {share:.0f} % of runs pound at their own"
            ax.axvline(g, color=style.line_style(k + 1)["color"], lw=1.0, ls=":", label=text)
    where = ", ".join(f"{d} = {style.value_text(out, d, 0)}" for d in held)
    ax.set(xlabel="initial gap [mm]", ylabel="mean annual rate [1/year]",
           title=f"{out.attrs['event']} at the site (hazard {out.attrs['hazard']})"
           + (f"\n{where}" if where else ""))  # fmt: skip
    ax.title.set_fontsize(9)
    ax.grid(alpha=0.3, which="both")
    style.legend_outside(ax, size=7)
    counted = np.ones(int(out["n_total"].sum() + out["n_left_out"].sum()), bool)
    counted[: int(out["n_left_out"].sum())] = False
    style.note_left_out(fig, counted, left_out_why(out.attrs["event"]))
    if out.attrs.get("extrapolation"):
        fig.text(0.005, 0.03, out.attrs["extrapolation"], fontsize=7, color="dimgray")
    return style.save(fig, path)
