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
            text = f"{str(rule).upper()} {g:.0f} mm: {share:.0f} % of runs pound at their own"
            ax.axvline(g, color=style.line_style(k + 1)["color"], lw=1.0, ls=":", label=text)
    where = style.coords_text(out, held)
    ax.set(xlabel="initial separation gap [mm]", ylabel="mean annual rate [1/year]",
           title=_risk_title(out, sel, gaps, rate, target, where))  # fmt: skip
    ax.title.set_fontsize(9)
    ax.title.set_wrap(True)
    why = str(sel["gap_message"].values) if "gap_message" in sel else ""
    if why:
        style.caption(fig, f"No risk-targeted gap: {why}.")
    style.caption(fig, f"Hazard: {out.attrs['hazard']}. Line: the mean annual rate of "
                  f"{out.attrs['event']} at each gap studied; band: "
                  f"{round(100 * out.attrs['ci'])} % bootstrap interval.")  # fmt: skip
    ax.grid(alpha=0.3, which="both")
    style.legend_outside(ax, size=7)
    counted = np.ones(int(out["n_total"].sum() + out["n_left_out"].sum()), bool)
    if out.attrs.get("extrapolation"):
        style.caption(fig, out.attrs["extrapolation"])
    counted[: int(out["n_left_out"].sum())] = False
    style.note_left_out(fig, counted, left_out_why(out.attrs["event"]))
    return style.save(fig, path)


def _risk_title(out, sel, gaps, rate, target, where) -> str:
    """The site risk chart's answer: the risk-targeted gap, or the rates at the ends."""
    event = out.attrs["event"]
    head = f"Annual rate of {event}" + (f" ({where})" if where else "")
    if np.isfinite(target) and "required_gap" in sel:
        gap = float(sel["required_gap"])
        if np.isfinite(gap):
            return f"Gap for {target:.2g} {event} a year at the site: {1e3 * gap:.0f} mm" + (
                f" ({where})" if where else "")  # fmt: skip
        return f"Gap for {target:.2g} {event} a year at the site: none found" + (
            f" ({where})" if where else "")  # fmt: skip
    return f"{head}: {rate[0]:.2g} at gap {gaps[0]:.0f} mm, {rate[-1]:.2g} at {gaps[-1]:.0f} mm"
