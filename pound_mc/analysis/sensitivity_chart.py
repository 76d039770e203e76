"""Bar chart of the Sobol' indices of a ``saltelli`` study (``pound-mc sensitivity --plot``).

Each panel shows, for every sampled study key, its first-order index S1 and its total-order
index ST as two bars with their bootstrap intervals
(:func:`pound_mc.analysis.sensitivity.sensitivity`).  One panel per grid point would be too
many for a spectrum's grid, so the panels run along one grid axis (``by``, default the first;
at most ``max_panels`` of its values, evenly spaced from first to last), every other grid axis
held at the value ``sel`` gives (nearest) or at its first, and one record (``record``, default
the first); the title says what is held.  A study without a grid is one panel.
"""

from __future__ import annotations

import textwrap
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pound_mc.analysis.labels import coord_text, key_text, name_and_units, text_of
from pound_mc.analysis.plot import _hold, _record_index, save
from pound_mc.analysis.sensitivity import left_out_why, sensitivity
from pound_mc.analysis.style import PALETTE, caption, chart_doc, legend_below, new_axes

__all__ = ["sensitivity_chart", "panel_positions"]

#: Bars of a panel: name, label, colour, hatch.
_BARS = (
    ("S1", "first order S1 (the key alone)", PALETTE[0], None),
    ("ST", "total order ST (with its interactions)", PALETTE[1], "//"),
)


def panel_positions(size: int, most: int) -> list[int]:
    """Up to ``most`` positions of ``size`` values, evenly spaced, the first and last among them."""
    if size <= most:
        return list(range(size))
    return sorted({int(round(i)) for i in np.linspace(0, size - 1, most)})


def _where_text(ds: xr.Dataset, where: dict) -> str:
    """``"record elcentro, left period 0.5 s"``: what a panel holds."""
    parts = []
    for dim, i in where.items():
        if dim == "record":
            parts.append(f"record {text_of(ds['record'].values[i])}")
        else:
            parts.append(coord_text(ds, dim, i))
    return ", ".join(parts)


def _panel(ax: Axes, found: xr.Dataset, where: dict) -> tuple[int, int]:
    """S1 and ST bars of every key at one grid point, with their intervals; the runs used.

    Returns the runs used and the runs left out.
    """
    keys = [str(k) for k in found["variable"].values]
    x = np.arange(len(keys))
    width = 0.38
    at = found.isel(where)
    for k, (name, label, color, hatch) in enumerate(_BARS):
        value = at[name].values
        ci = at[f"{name}_ci"].values
        err = np.abs(np.stack([value - ci[:, 0], ci[:, 1] - value]))
        ax.bar(x + (k - 0.5) * width, value, width, color=color, hatch=hatch, edgecolor="white",
               label=label, yerr=err, capsize=3, error_kw={"elinewidth": 1.0})  # fmt: skip
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xlim(-0.6, len(keys) - 0.4)
    ax.set_xticks(x, keys)
    ax.tick_params(axis="x", labelrotation=30)
    for label in ax.get_xticklabels():
        label.set_horizontalalignment("right")
        label.set_rotation_mode("anchor")
    ax.set_ylabel("Sobol' index [-]")
    ax.grid(axis="y", alpha=0.3)
    message = str(at["message"].values)
    if message:
        ax.text(0.5, 0.5, textwrap.fill("no indices: " + message, 40), transform=ax.transAxes,
                ha="center", va="center", fontsize=8)  # fmt: skip
    return int(at["n_used"]), int(at["n_left_out"])


@chart_doc
def sensitivity_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    output: str = "peak_force",
    by: str | None = None,
    sel: dict | None = None,
    record: int | str | None = None,
    max_panels: int = 6,
    n_boot: int = 1000,
    indices: xr.Dataset | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """S1 and ST of every sampled key, with intervals: a panel per value of ``by``.

    Parameters
    ----------
    %(ds)s
    %(path)s
    output : str, default "peak_force"
        The output whose indices are drawn (:func:`~pound_mc.analysis.sensitivity.sensitivity`).
    by : str, optional
        Grid dimension with a panel per value (default the first grid axis).
    sel : dict, optional
        ``{dim: value}``: where the other grid axes are held (nearest; default their first).
    record : int or str, optional
        Which record (index or name; default the first).
    max_panels : int, default 6
        Most panels: that many values of ``by``, evenly spaced, first and last among them.
    n_boot : int, default 1000
        Bootstrap resamples of the intervals.
    indices : xarray.Dataset, optional
        :func:`~pound_mc.analysis.sensitivity.sensitivity` of ``ds`` for ``output``, when
        computed already.
    ax : matplotlib.axes.Axes or sequence of Axes, optional
        One Axes per panel (or a grid of more, the spare ones hidden).

    Returns
    -------
    matplotlib.figure.Figure
        Per panel the bars ``S1`` then ``ST`` (``ax.patches``) and their error bars; its title
        names the grid point, and a panel without indices says why; the caption gives the
        runs used and left out.
    """
    found = indices if indices is not None else sensitivity(ds, output, n_boot=n_boot)
    grid = [d for d in found["S1"].dims if d not in ("record", "variable")]
    if by is not None and by not in grid:
        raise ValueError(f"no grid dimension {by!r}; the grid has {grid}")
    by = by if by is not None else (grid[0] if grid else None)
    held = {"record": 0 if record is None else _record_index(ds, record)}
    held |= _hold(ds, [d for d in grid if d != by], sel)
    combos = panel_positions(ds.sizes[by], max_panels) if by else [None]
    ncols = min(3, len(combos))
    nrows = -(-len(combos) // ncols)
    width = max(4.8, 0.55 * found.sizes["variable"] + 1.6)
    if ax is None:
        fig, axes = new_axes(None, (width * ncols, 3.9 * nrows + 0.5), nrows=nrows, ncols=ncols)
    else:
        fig, axes = new_axes(ax, (0.0, 0.0), ncols=len(combos), spare=True)
    used = []
    for panel, i in zip(axes, combos, strict=False):
        where = held | ({by: i} if by else {})
        used.append(_panel(panel, found, where))
        if by:
            panel.set_title(_where_text(ds, {by: i}), fontsize=8)
    for extra in axes[len(combos) :]:
        extra.set_visible(False)
    # one scale for every panel, 0 to 1 at least, and every interval drawn whole
    shown = found.isel(held | ({by: combos} if by else {}))
    ends = np.concatenate([shown["S1_ci"].values.ravel(), shown["ST_ci"].values.ravel()])
    ends = ends[np.isfinite(ends)]
    low = min(-0.05, float(ends.min()) - 0.02) if ends.size else -0.05
    high = max(1.0, float(ends.max()) + 0.02) if ends.size else 1.0
    for panel in axes[: len(combos)]:
        panel.set_ylim(low, high)
    if ax is not None:  # a caller's figure: the legend in the first panel, no title over all
        axes[0].legend(fontsize=7, loc="upper left")
        return save(fig, path)
    handles, labels = axes[0].get_legend_handles_labels()
    legend_below(fig, axes[0], handles=handles, labels=labels, ncols=2)
    chars = int(fig.get_figwidth() * 72 / (10 * 0.6))  # characters of 10 pt text a line holds
    fig.suptitle(textwrap.fill(_sensitivity_title(found, shown), chars), fontsize=10)
    percent = round(100 * found.attrs["conf_level"])
    some = ""
    if by and len(combos) < ds.sizes[by]:
        some = f" Panels: {len(combos)} of the {ds.sizes[by]} values of {key_text(_key(ds, by))}."
    held_text = _where_text(ds, {d: i for d, i in held.items() if d != "record" or
                                 ds.sizes["record"] > 1})  # fmt: skip
    runs = sorted({n for n, _ in used})
    n_out = sum(n for _, n in used)
    text = (f"Sobol' indices (SALib) from N = {found.attrs['base_n']} base points of "
            f"Saltelli's design ({'-'.join(f'{n:,}' for n in runs[:: max(1, len(runs) - 1)])} "
            f"runs a panel); bars: {percent} % bootstrap intervals.{some}"
            + (f" Held: {held_text}." if held_text else ""))  # fmt: skip
    if n_out:  # no analysis leaves runs out without saying which
        text += f" {n_out:,} runs left out: {left_out_why(found.attrs['output'])}."
    caption(fig, text)
    return save(fig, path)


def _key(ds: xr.Dataset, dim: str) -> str:
    return str(ds[dim].attrs.get("scene_key", dim))


def _sensitivity_title(found: xr.Dataset, shown: xr.Dataset) -> str:
    """The sensitivity chart's answer: the key with the largest total-order index shown."""
    name, _ = name_and_units(
        {"long_name": found.attrs["output_long_name"], "units": found.attrs["output_units"]}, ""
    )
    total = shown["ST"].transpose("variable", ...).values.reshape(shown.sizes["variable"], -1)
    name = name.split(" (")[0]  # "peak impact force (continuous-time maximum)": the first part
    if not np.isfinite(total).any():
        return f"What drives the {name}: no indices"
    k, j = np.unravel_index(np.nanargmax(total), total.shape)
    key = str(shown["variable"].values[k])
    return (
        f"{name[:1].upper()}{name[1:]} depends most on {key_text(key)} ({key}): "
        f"total-order index up to {total[k, j]:.2f}"
    )
