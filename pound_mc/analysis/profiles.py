"""Charts over the height of shear buildings: peak force per contact, drift and ductility.

:func:`contacts_chart` draws each contact's peak impact force (``contact_peak_force``, along
the ``contact`` dimension of a shear-building study) against the contact's elevation;
:func:`profile_chart` draws the peak storey drift or ductility of both buildings against the
storey (variables along a ``storey`` dimension), or, for single-storey buildings, against the
first grid axis.  Lines are medians over the records and samples (status ok) with the 5-95 %
range as a band; heights are in m, drifts in mm, forces in MN.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Literal

import numpy as np
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pound_mc.analysis import style

__all__ = ["CONTACT_DIM", "STOREY_DIM", "PROFILE_VARIABLES", "contacts_chart", "profile_chart"]

#: Dimension of the contacts of a shear-building study.
CONTACT_DIM = "contact"
#: Dimension of the storeys of the inelastic outputs of shear buildings.
STOREY_DIM = "storey"
#: Per-building variables of :func:`profile_chart`, by quantity.
PROFILE_VARIABLES = {
    "drift": ("peak_drift_left", "peak_drift_right"),
    "ductility": ("peak_ductility_left", "peak_ductility_right"),
}


def _over_samples(ds, variable, keep):
    """Median and 5-95 % of ``variable`` (status ok) over every dim not in ``keep``."""
    values = ds[variable].where(ds["status"] == 0)
    over = [d for d in values.dims if d not in keep]
    with warnings.catch_warnings():  # storeys a lower building lacks are NaN: NaN quantiles
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        return values.quantile([0.05, 0.5, 0.95], dim=over, skipna=True)


def _line_dim(ds, line):
    grid = [d for d in ds["peak_force"].dims if d not in ("record", "sample")]
    if line is not None and line not in grid:
        raise ValueError(f"no grid dimension {line!r}; the dataset has {grid}")
    return line if line is not None else (grid[0] if grid else None)


def _profile_lines(ax, ds, q, line, heights, scale: float) -> None:
    """One profile per value of ``line`` (a single one where ``line`` is None).

    Each is the median of ``q`` against ``heights`` with its 5-95 % band.
    """
    values = [None] if line is None else range(ds.sizes[line])
    for k, i in enumerate(values):
        sq = q if i is None else q.isel({line: i})
        look = style.line_style(k)
        label = "median" if i is None else style.value_text(ds, line, i)
        ax.plot(sq.sel(quantile=0.5).values * scale, heights, ms=5, label=label, **look)
        low, high = (sq.sel(quantile=level).values * scale for level in (0.05, 0.95))
        ax.fill_betweenx(heights, low, high, color=look["color"], alpha=0.12, lw=0)


@style.chart_doc
def contacts_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    variable: str = "contact_peak_force",
    line: str | None = None,
    ax: Axes | None = None,
) -> Figure:
    """Peak impact force (or another per-contact result) at each contact against its elevation.

    Parameters
    ----------
    ds : xarray.Dataset
        A shear-building study dataset (a ``contact`` dimension).
    %(path)s
    variable : str
        Per-contact variable (``contact_peak_force``, ``contact_impacts``, ...).
    line : str, optional
        Grid dimension with one line per value (default the first grid axis); the others and
        the records and samples are pooled.
    ax : matplotlib.axes.Axes, optional
        Where to draw.

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[0].lines``: per line value, the medians (x, chart units) against the elevations.
    """
    if CONTACT_DIM not in ds.dims or variable not in ds:
        raise ValueError(
            f"does not apply: the dataset has no per-contact {variable!r} (shear buildings only)"
        )
    line = _line_dim(ds, line)
    keep = [CONTACT_DIM] + ([line] if line else [])
    q = _over_samples(ds, variable, keep)
    height = (
        ds["contact_elevation"].values
        if "contact_elevation" in ds.coords
        else ds[CONTACT_DIM].values.astype(float)
    )
    fig, (ax,) = style.new_axes(ax, (7.6, 4.8))
    _profile_lines(ax, ds, q, line, height, style.scale_of(ds, variable))
    ax.set_yticks(height, [f"{h:g}" for h in height])
    ax.set(
        xlabel=style.axis_label(ds, variable),
        ylabel="contact elevation [m]" if "contact_elevation" in ds.coords else "contact [-]",
        title=(
            f"{ds[variable].attrs.get('long_name', variable)} ({ds.attrs.get('study_name', '')})"
            "\nmedian over records and samples, 5-95 % band"
        ),
    )
    ax.title.set_fontsize(9)
    ax.grid(alpha=0.3)
    style.legend_outside(ax, title=style.axis_label(ds, line) if line else None)
    return style.save(fig, path)


@style.chart_doc
def profile_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    quantity: Literal["drift", "ductility"] = "drift",
    line: str | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """Peak storey drift or ductility of both buildings, over the height (one panel each).

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with the inelastic outputs (:data:`PROFILE_VARIABLES`).
    %(path)s
    quantity : {"drift", "ductility"}
        Which outputs.
    line : str, optional
        Grid dimension with one line per value (default the first grid axis).  Outputs without
        a ``storey`` dimension (SDOF buildings) are drawn against this axis instead.
    ax : sequence of two matplotlib.axes.Axes, optional
        Where to draw the left and the right building.

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[b].lines``: per line value, the medians (chart units) against the storeys.
    """
    if quantity not in PROFILE_VARIABLES:
        raise ValueError(f"quantity must be one of {list(PROFILE_VARIABLES)}, got {quantity!r}")
    names = [v for v in PROFILE_VARIABLES[quantity] if v in ds]
    if not names:
        raise ValueError(
            f"does not apply: the dataset has no {quantity} outputs "
            f"({', '.join(PROFILE_VARIABLES[quantity])}; inelastic buildings only)"
        )
    line = _line_dim(ds, line)
    fig, axes = style.new_axes(ax, (10.0, 4.8), ncols=len(names))
    for ax_b, name in zip(axes, names, strict=True):
        scale = style.scale_of(ds, name)
        if STOREY_DIM in ds[name].dims:
            q = _over_samples(ds, name, [STOREY_DIM] + ([line] if line else []))
            storeys = ds[STOREY_DIM].values
            _profile_lines(ax_b, ds, q, line, storeys, scale)
            ax_b.set_yticks(storeys, [str(s) for s in storeys])
            ax_b.set(xlabel=style.axis_label(ds, name), ylabel="storey [-]")
        else:
            med = _over_samples(ds, name, [line] if line else []).sel(quantile=0.5).values * scale
            xs = ds[line].values * style.scale_of(ds, line) if line else np.zeros(1)
            ax_b.plot(xs, np.atleast_1d(med), ms=5, label="median", **style.line_style(0))
            xlabel = style.axis_label(ds, line) if line else ""
            ax_b.set(xlabel=xlabel, ylabel=style.axis_label(ds, name))
        ax_b.set_title(ds[name].attrs.get("long_name", name), fontsize=9)
        ax_b.grid(alpha=0.3)
    style.legend_outside(axes[-1], title=style.axis_label(ds, line) if line else None)
    fig.suptitle(
        f"Peak {quantity} ({ds.attrs.get('study_name', '')}): median over records and samples, "
        "5-95 % band",
        fontsize=9,
    )
    return style.save(fig, path)
