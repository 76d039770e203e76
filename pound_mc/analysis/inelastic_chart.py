"""Inelastic spectrum: ductility demand and peak impact force of a yielding building.

:func:`inelastic_chart` draws, against the first grid axis of a study with yielding buildings
(``studies/inelastic_spectrum.toml``: the left building's period), the median ductility demand
and the median peak impact force over the samples, one line per yield displacement, with the
never-yielding building as the elastic reference.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pound_mc.analysis.labels import text_of
from pound_mc.analysis.plot import (
    _record_index,
    _spectrum_selection,
)
from pound_mc.analysis.style import (
    axis_label,
    caption,
    chart_doc,
    coord_text,
    legend_below,
    line_style,
    new_figure,
    no_values,
    save,
    scale_of,
    value_text,
)

__all__ = ["inelastic_chart", "yielding_sides"]


@chart_doc
def inelastic_chart(ds, path: str | Path | None = None, *, side="left", record=0) -> Figure:
    """Inelastic spectrum: median ductility demand and peak force against a grid axis.

    The horizontal axis is the first grid axis, one line per value of the second (the yield
    displacement ``{side}_yield_disp_m`` in ``studies/inelastic_spectrum.toml``); other grid
    axes are held at their first value; medians and 5-95 % bands over the samples that ended
    ``ok`` (as the force spectrum: a run flagged ``inaccurate`` is left out).  A line whose building
    never yields (ductility below 1 everywhere) is the elastic reference: its ductility demand
    is its peak displacement over the smallest yield displacement of the line axis.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of a study with yielding buildings (``peak_ductility_left`` ...).
    %(path)s
    side : {"left", "right"}
        The building whose ductility is drawn.
    record : int or str
        Which record (index or name).
    """
    x, line, others = _spectrum_selection(ds)
    hold = {"record": _record_index(ds, record), **{d: 0 for d in others}}
    # status ok only, as the force spectrum and the ductility profiles (a run flagged
    # inaccurate has its forces and displacements in doubt)
    ok = (ds["status"] == 0).isel(hold)
    duct = ds[f"peak_ductility_{side}"].isel(hold).where(ok)
    disp = ds[f"peak_disp_{side}"].isel(hold).where(ok)
    force = ds["peak_force"].isel(hold).where(ok) / 1e6
    values = [None] if line is None else list(ds[line].values)
    u_ref = float(min(values)) if line == f"{side}_yield_disp_m" else np.nan
    ref_text = value_text(ds, line, int(np.argmin(values))) if np.isfinite(u_ref) else ""
    fig = new_figure((9.6, 4.6))
    ax_mu, ax_f = fig.subplots(1, 2, sharex=True)
    xs = ds[x].values * scale_of(ds, x)
    best = (-np.inf, 0, None)  # the largest median ductility demand of a yielding line
    for i, value in enumerate(values):
        pick = {} if value is None else {line: value}
        mu = duct.sel(pick)
        label = "median" if value is None else value_text(ds, line, i)
        elastic = not bool((mu > 1.0).any())
        if elastic and np.isfinite(u_ref):
            mu = disp.sel(pick) / u_ref
            label = f"elastic (never yields; ductility demand: peak displacement / {ref_text})"
        elif np.isfinite(u_ref):
            label = f"bilinear, yield displacement {value_text(ds, line, i)}"
        look = line_style(i)
        look["linestyle"] = "--" if elastic else "-"
        for ax, data, text in ((ax_mu, mu, label), (ax_f, force.sel(pick), f"_{label}")):
            q = data.quantile([0.05, 0.5, 0.95], dim="sample").values
            if (
                ax is ax_mu
                and not elastic
                and np.isfinite(q[1]).any()
                and np.nanmax(q[1]) > best[0]
            ):
                best = (
                    float(np.nanmax(q[1])),
                    int(np.nanargmax(q[1])),
                    None if value is None else i,
                )
            ax.plot(xs, q[1], lw=1.6, ms=4, label=text, **look)
            ax.fill_between(xs, q[0], q[2], color=look["color"], alpha=0.15, lw=0)
    ax_mu.axhline(1.0, color="k", lw=0.6, alpha=0.5)
    for ax, ylabel, title in (
        (ax_mu, f"ductility demand, {side} building [-]", f"Ductility demand, {side} building"),
        (ax_f, "peak impact force [MN]", "Peak impact force"),
    ):
        ax.set(xlabel=axis_label(ds, x), ylabel=ylabel, title=title)
        ax.title.set_fontsize(9)
        ax.grid(True, alpha=0.3)
    rec = _record_index(ds, record)
    held = ", ".join([f"record {text_of(ds['record'].values[rec])}"]
                     + [coord_text(ds, d, 0) for d in others])  # fmt: skip
    head = f"Ductility demand of the {side} building"
    if np.isfinite(best[0]):
        at = coord_text(ds, x, best[1])
        at += f", {coord_text(ds, line, best[2])}" if best[2] is not None else ""
        head += f": median up to {best[0]:.2g} at {at}"
    fig.suptitle(head, fontsize=10)
    caption(fig, f"Lines: median over the runs that ended ok of the {ds.sizes['sample']} samples "
            f"({held}); bands: 5-95 %. A building that never yields is drawn dashed, its demand "
            f"its peak displacement over the smallest yield displacement.")  # fmt: skip
    legend_below(fig, ax_mu, title=axis_label(ds, line) if line is not None else None)
    return save(fig, path)


def yielding_sides(ds) -> list[str]:
    """Buildings with a ductility value per simulation, those with a yield-displacement axis first.

    The sides :func:`inelastic_chart` can draw (``pound-mc run`` and the report draw the
    first): ``peak_ductility_{side}`` over the dims of ``peak_force``, not NaN throughout.
    """
    sides = [
        s
        for s in ("left", "right")
        if f"peak_ductility_{s}" in ds
        and ds[f"peak_ductility_{s}"].dims == ds["peak_force"].dims
        and not no_values(ds, ds[f"peak_ductility_{s}"])
    ]
    return sorted(sides, key=lambda s: f"{s}_yield_disp_m" not in ds.dims)
