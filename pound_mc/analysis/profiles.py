"""Charts over the height of shear buildings: peak force per contact, drift and ductility.

:func:`contacts_chart` draws each contact's peak impact force (``contact_peak_force``, along
the ``contact`` dimension of a shear-building study) against the contact's elevation;
:func:`profile_chart` draws the peak storey drift or ductility of both buildings against the
storey (the per-storey outputs ``storey_peak_drift`` / ``storey_peak_ductility`` of yielding
shear buildings, along the ``storey`` dimension, one panel per building), or, for single-storey
buildings, against the first grid axis.  Lines are medians over the records and samples (status
ok) with the 5-95 % range as a band, one per value of a grid axis; every other grid axis is held
at one value (never pooled across building variants); heights are in m, forces in MN, storey
drift ratios in %.
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
from pound_mc.analysis.plot import _grid_dims, _hold, _nearest_index

__all__ = [
    "CONTACT_DIM",
    "STOREY_DIM",
    "PROFILE_VARIABLES",
    "STOREY_VARIABLES",
    "contacts_chart",
    "profile_chart",
    "has_values",
]

#: Dimension of the contacts of a shear-building study.
CONTACT_DIM = "contact"
#: Dimension of the storeys of the inelastic outputs of shear buildings.
STOREY_DIM = "storey"
#: Per-building variables of :func:`profile_chart`, by quantity.
PROFILE_VARIABLES = {
    "drift": ("peak_drift_left", "peak_drift_right"),
    "ductility": ("peak_ductility_left", "peak_ductility_right"),
}
#: Per-storey variables of :func:`profile_chart` (shear buildings), by quantity.
STOREY_VARIABLES = {"drift": "storey_peak_drift", "ductility": "storey_peak_ductility"}
#: The buildings, in the order of the ``storey`` dimension (``storey_building``).
_SIDES = ("left", "right")
#: What the outputs of a quantity need, for the message of a dataset without them.
_NEEDS = {
    "drift": "drift ratios need storey heights: shear buildings or an SDOF with height_m",
    "ductility": "no building that can yield",
}
#: Why one building's outputs of a quantity can be NaN throughout (its panel is left out).
_WHY_EMPTY = {"drift": "no storey heights", "ductility": "it cannot yield"}


def _over_samples(ds, variable, keep, hold=None):
    """Median and 5-95 % of ``variable`` (status ok) over every dim not in ``keep``.

    ``hold`` (``{dim: index}``) first takes the held dims at one value each.
    """
    values = ds[variable].where(ds["status"] == 0)
    values = values.isel({d: i for d, i in (hold or {}).items() if d in values.dims})
    over = [d for d in values.dims if d not in keep]
    with warnings.catch_warnings():  # storeys a lower building lacks are NaN: NaN quantiles
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        return values.quantile([0.05, 0.5, 0.95], dim=over, skipna=True)


def _selection(ds, line, sel, *, x_axis: bool = False):
    """The axes of a profile chart: x, line, the held dims and the line values drawn.

    Every grid axis is the horizontal axis (``x_axis``: the first one that is not ``line``),
    the line axis (one line per value; default the first remaining grid axis) or held at one
    value (``sel``'s nearest, else the first), so no line pools building variants.  ``sel``
    on the line axis picks the lines drawn; on ``record``, the one record drawn.

    Returns
    -------
    x : str or None
    line : str or None
    hold : dict
        ``{dim: index}`` of the held dims.
    picks : list
        Indices along ``line`` of the lines drawn (``[None]`` without a line axis).
    """
    grid = _grid_dims(ds)
    if line is not None and line not in grid:
        raise ValueError(f"no grid dimension {line!r}; the dataset has {grid}")
    sel = dict(sel or {})
    x = None
    if x_axis and grid:
        rest = [d for d in grid if d != line]
        if not rest:
            raise ValueError(
                f"{line!r} is the only grid axis: none is left for the horizontal axis"
            )
        x = rest[0]
    rest = [d for d in grid if d not in (x, line)]
    line = line if line is not None else (rest.pop(0) if rest else None)
    wanted = sel.pop(line, None) if line is not None else None
    if x in sel:
        raise ValueError(f"sel names {x!r}, the chart's horizontal axis: it draws all its values")
    hold = _hold(ds, rest + (["record"] if "record" in sel else []), sel)
    if line is None:
        picks = [None]
    elif wanted is None:
        picks = list(range(ds.sizes[line]))
    else:
        picks = list(dict.fromkeys(_nearest_index(ds, line, v) for v in np.atleast_1d(wanted)))
    return x, line, hold, picks


def _held_text(ds, hold) -> str:
    """``"left yield displacement 20 mm, ..."``: what a chart holds (empty when nothing)."""
    return style.coords_text(ds, hold)


def _largest(panels, line, picks, *, across: bool):
    """The largest median drawn: ``(value, panel, line pick, point)``, value NaN if none.

    ``panels``: the Axes whose first ``len(picks)`` lines are the medians, one per pick.
    ``across``: the values are the lines' x data (profiles over the height), else their y.
    """
    best = (np.nan, None, None, None)
    for k, ax in enumerate(panels):
        for i, ln in zip(picks, ax.lines[: len(picks)], strict=True):
            values = np.asarray(ln.get_xdata() if across else ln.get_ydata(), dtype=float)
            if np.isfinite(values).any() and not (np.nanmax(values) <= best[0]):
                best = (float(np.nanmax(values)), k, i, int(np.nanargmax(values)))
    return best


def _line_where(ds, line, i) -> str:
    return "" if line is None or i is None else style.coord_text(ds, line, i)


def _draw_lines(ax, ds, q, line, picks, at, scale: float, *, across: bool) -> None:
    """One median line per index of ``line`` in ``picks``, each with its 5-95 % band.

    ``across``: the values on the horizontal axis against ``at`` up the vertical one (a
    profile over the height); else ``at`` along the horizontal axis.
    """
    for k, i in enumerate(picks):
        sq = q if i is None else q.isel({line: i})
        low, mid, high = (
            np.atleast_1d(sq.sel(quantile=level).values) * scale for level in (0.05, 0.5, 0.95)
        )
        look = style.line_style(k)
        label = "median" if i is None else style.value_text(ds, line, i)
        if across:
            ax.plot(mid, at, ms=5, label=label, **look)
            ax.fill_betweenx(at, low, high, color=look["color"], alpha=0.12, lw=0)
        else:
            ax.plot(at, mid, ms=5, label=label, **look)
            ax.fill_between(at, low, high, color=look["color"], alpha=0.12, lw=0)


def has_values(ds: xr.Dataset, quantity: str) -> bool:
    """Whether ``ds`` has a variable of ``quantity`` (:data:`PROFILE_VARIABLES`) with values.

    A variable NaN in every simulation with status ok has none (the drift ratios of SDOF
    buildings without ``height_m``, the ductility of a building that cannot yield).
    """
    names = [v for v in PROFILE_VARIABLES[quantity] if v in ds]
    return any(not style.no_values(ds, ds[v]) for v in names)


def _with_values(ds, quantity) -> tuple[list[str], list[str]]:
    """The variables of ``quantity`` in ``ds`` with values, and those NaN throughout."""
    names = [v for v in PROFILE_VARIABLES[quantity] if v in ds]
    empty = [v for v in names if style.no_values(ds, ds[v])]
    if not names:
        raise ValueError(
            f"does not apply: the dataset has no {quantity} outputs "
            f"({', '.join(PROFILE_VARIABLES[quantity])}; inelastic buildings only)"
        )
    if len(empty) == len(names):
        are = "are" if len(names) > 1 else "is"
        raise ValueError(
            f"does not apply: {' and '.join(names)} {are} NaN throughout ({_NEEDS[quantity]})"
        )
    return [v for v in names if v not in empty], empty


def _contact_axis(ds: xr.Dataset) -> tuple[np.ndarray, list[str], str]:
    """Where each contact sits up the contacts chart, its tick label and the axis label.

    Elevations where every contact has one; in a row (``contact_pair``), or where a contact
    has no elevation (SDOF buildings without heights), the contact's number, labelled with
    the buildings it lies between (from 0) and its elevation where known.
    """
    number = ds[CONTACT_DIM].values.astype(float)
    elevation = ds["contact_elevation"].values if "contact_elevation" in ds.coords else None
    known = elevation is not None and bool(np.all(np.isfinite(elevation)))
    if "contact_pair" not in ds.coords:
        if known:
            return elevation, [f"{h:g}" for h in elevation], "contact elevation [m]"
        return number, [f"{c:g}" for c in number], "contact [-]"
    ticks = []
    for k, p in enumerate(ds["contact_pair"].values.astype(int)):
        known_k = elevation is not None and np.isfinite(elevation[k])
        at = f" at {elevation[k]:g} m" if known_k else ""
        ticks.append(f"{p}|{p + 1}{at}")
    return number, ticks, "contact: buildings (from 0)"


@style.chart_doc
def contacts_chart(
    ds: xr.Dataset,
    path: str | Path | None = None,
    *,
    variable: str = "contact_peak_force",
    line: str | None = None,
    sel: dict | None = None,
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
        Grid dimension with one line per value (default the first grid axis); the records and
        samples are pooled, the other grid axes held at one value.
    sel : dict, optional
        ``{dim: value}``: the value (nearest) each other grid axis is held at (default its
        first), the values of ``line`` drawn (default all), or the one ``record`` drawn.
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
    _, line, hold, picks = _selection(ds, line, sel)
    q = _over_samples(ds, variable, [CONTACT_DIM] + ([line] if line else []), hold)
    height, ticks, ylabel = _contact_axis(ds)
    fig, (ax,) = style.new_axes(ax, (7.6, 4.8))
    _draw_lines(ax, ds, q, line, picks, height, style.scale_of(ds, variable), across=True)
    ax.set_yticks(height, ticks)
    held = _held_text(ds, hold)
    value, _, i, j = _largest([ax], line, picks, across=True)
    head = str(ds[variable].attrs.get("long_name", variable))
    head = head[:1].upper() + head[1:] + (f" ({held})" if held else "")
    if np.isfinite(value):
        units = style.chart_units(ds[variable].attrs.get("units"))[0]
        at = f"the contact at {ticks[j]} m" if ylabel.startswith("contact elevation") else (
            f"contact {ticks[j]}")  # fmt: skip
        where = ", ".join(t for t in (at, _line_where(ds, line, i)) if t)
        head += f": median up to {value:.3g}{'' if units == '-' else ' ' + units} at {where}"
    ax.set(xlabel=style.axis_label(ds, variable), ylabel=ylabel, title=head)
    ax.title.set_fontsize(9)
    style.caption(fig, "Lines: median over the records and samples (runs that ended ok); "
                  "bands: 5-95 %.")  # fmt: skip
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
    sel: dict | None = None,
    ax: Axes | Sequence[Axes] | None = None,
) -> Figure:
    """Peak storey drift or ductility of both buildings, over the height (one panel each).

    Yielding shear buildings: the per-storey outputs (:data:`STOREY_VARIABLES`, drift ratios
    in %) of each building's storeys (``storey_building``) against the storey number within
    the building (``storey_number``), both panels on one scale.  SDOF buildings: the
    per-building outputs (:data:`PROFILE_VARIABLES`) against the first grid axis.  A building
    whose outputs are NaN in every simulation (an elastic building's ductility) has no panel;
    a dataset where both are NaN throughout (the drift ratios of SDOF buildings without
    ``height_m``) raises ``ValueError("does not apply: ...")``.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with the inelastic outputs (:data:`PROFILE_VARIABLES`).
    %(path)s
    quantity : {"drift", "ductility"}
        Which outputs.
    line : str, optional
        Grid dimension with one line per value.  Per-storey outputs are drawn against the
        storey (default line: the first grid axis); the others (SDOF buildings) against the
        first grid axis that is not ``line`` (default line: the next grid axis).
        The records and samples are pooled; every other grid axis is held at one value.
    sel : dict, optional
        ``{dim: value}``: the value (nearest) each held grid axis is held at (default its
        first), the values of ``line`` drawn (default all), or the one ``record`` drawn.
    ax : sequence of matplotlib.axes.Axes, optional
        Where to draw: one Axes per building with values (left first).

    Returns
    -------
    matplotlib.figure.Figure
        ``axes[b].lines``: per line value, the medians (chart units) against the storey
        numbers or the horizontal grid axis.
    """
    if quantity not in PROFILE_VARIABLES:
        raise ValueError(f"quantity must be one of {list(PROFILE_VARIABLES)}, got {quantity!r}")
    names, empty = _with_values(ds, quantity)
    if _has_storeys(ds, quantity):
        return _storey_chart(ds, path, quantity, line, sel, ax)
    x, line, hold, picks = _selection(ds, line, sel, x_axis=True)
    fig, axes = style.new_axes(ax, (10.0 if len(names) > 1 else 7.6, 4.8), ncols=len(names))
    for ax_b, name in zip(axes, names, strict=True):
        q = _over_samples(ds, name, [d for d in (x, line) if d], hold)
        xs = ds[x].values * style.scale_of(ds, x) if x else np.zeros(1)
        _draw_lines(ax_b, ds, q, line, picks, xs, style.scale_of(ds, name), across=False)
        xlabel = style.axis_label(ds, x) if x else ""
        ax_b.set(xlabel=xlabel, ylabel=style.axis_label(ds, name))
        ax_b.set_title(ds[name].attrs.get("long_name", name), fontsize=9)
        ax_b.grid(alpha=0.3)
    style.legend_outside(axes[-1], title=style.axis_label(ds, line) if line else None)
    left_out = [(name.rsplit("_", 1)[1], name) for name in empty]
    value, k, i, j = _largest(axes, line, picks, across=False)
    where = None
    if np.isfinite(value):
        side = names[k].rsplit("_", 1)[1]
        where = ", ".join(t for t in (f"{side} building", style.coord_text(ds, x, j) if x else "",
                                      _line_where(ds, line, i)) if t)  # fmt: skip
        units = style.chart_units(ds[names[k]].attrs.get("units"))[0]
        value_text = f"{value:.3g}" + ("" if units == "-" else f" {units}")
        where = (value_text, where)
    _titles(fig, ds, quantity, hold, left_out, where)
    return style.save(fig, path)


def _titles(fig, ds, quantity, hold, left_out, largest) -> None:
    """Title and caption of a profile chart: its largest median; what it holds and leaves out.

    ``left_out``: ``(side, variable)`` of each building without values; ``largest``:
    ``(value text, where)`` of the largest median drawn, or None.
    """
    held = _held_text(ds, hold)
    head = f"Peak {quantity}" + (f" ({held})" if held else "")
    if largest is not None:
        head += f": median up to {largest[0]} ({largest[1]})"
    fig.suptitle(head, fontsize=10)
    notes = [
        f"The {side} building is left out ({name} NaN throughout: {_WHY_EMPTY[quantity]})."
        for side, name in left_out
    ]
    style.caption(fig, " ".join(["Lines: median over the records and samples (runs that ended "
                                 "ok); bands: 5-95 %.", *notes]))  # fmt: skip


def _has_storeys(ds, quantity) -> bool:
    """Whether ``ds`` has the per-storey outputs of ``quantity`` (yielding shear buildings)."""
    name = STOREY_VARIABLES[quantity]
    return name in ds and STOREY_DIM in ds[name].dims and "storey_building" in ds.coords


def _storey_units(ds, name, quantity) -> tuple[str, float]:
    """Units a storey chart draws ``name`` in and the factor to them: drift ratios in %."""
    units = str(ds[name].attrs.get("units", "")).strip()
    if quantity == "drift" and units in ("", "1"):
        return "%", 100.0
    return style.chart_units(units)


def _storey_chart(ds, path, quantity, line, sel, ax) -> Figure:
    """:func:`profile_chart` of per-storey outputs: one panel per building, storeys up the side.

    The storeys of each building (``storey_building``) are drawn against their number within
    it (``storey_number``), the panels sharing their storey and value scales.
    """
    name = STOREY_VARIABLES[quantity]
    building = ds["storey_building"].values.astype(str)
    sides = [s for s in _SIDES if (building == s).any()]
    empty = [s for s in sides if style.no_values(ds, ds[name].isel({STOREY_DIM: building == s}))]
    sides = [s for s in sides if s not in empty]
    _, line, hold, picks = _selection(ds, line, sel)
    units, scale = _storey_units(ds, name, quantity)
    fig, axes = style.new_axes(ax, (10.0 if len(sides) > 1 else 7.6, 4.8), ncols=len(sides))
    tallest = 0
    for ax_b, side in zip(axes, sides, strict=True):
        mine = ds.isel({STOREY_DIM: building == side})
        numbers = mine["storey_number"].values if "storey_number" in mine.coords else None
        numbers = np.arange(1, mine.sizes[STOREY_DIM] + 1) if numbers is None else numbers
        tallest = max(tallest, int(numbers.max()))
        q = _over_samples(mine, name, [d for d in (line, STOREY_DIM) if d], hold)
        _draw_lines(ax_b, ds, q, line, picks, numbers, scale, across=True)
        ax_b.set_yticks(numbers, [str(n) for n in numbers])
        long_name = ds[name].attrs.get("long_name", name)
        ax_b.set(xlabel=f"{long_name} [{units}]", ylabel=f"storey of the {side} building [-]")
        ax_b.set_title(f"{side} building ({len(numbers)} storeys)", fontsize=9)
        ax_b.grid(alpha=0.3)
    right = max(a.get_xlim()[1] for a in axes)
    for ax_b in axes:  # one scale for both buildings: storeys side by side, values comparable
        ax_b.set(xlim=(0.0, right), ylim=(0.5, tallest + 0.5))
    style.legend_outside(axes[-1], title=style.axis_label(ds, line) if line else None)
    value, k, i, j = _largest(axes, line, picks, across=True)
    largest = None
    if np.isfinite(value):
        storey = axes[k].lines[picks.index(i)].get_ydata()[j]
        where = ", ".join(t for t in (f"storey {int(storey)} of the {sides[k]} building",
                                      _line_where(ds, line, i)) if t)  # fmt: skip
        largest = (f"{value:.3g}" + ("" if units == "-" else f" {units}"), where)
    _titles(fig, ds, quantity, hold, [(s, name) for s in empty], largest)
    return style.save(fig, path)
