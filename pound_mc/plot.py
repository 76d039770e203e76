"""Charts.

Each function draws on a new :class:`matplotlib.figure.Figure` (no pyplot state)
and, given ``path``, writes it as PNG; it returns the figure so notebooks can show it and tests
can read the plotted data back from its artists.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from pound_mc import materials, relations
from pound_mc.droptest import DropTestResult, drop_test

__all__ = [
    "restitution_chart",
    "restitution_ranges_chart",
    "droptest_chart",
    "spectrum_chart",
    "save",
]

_MATERIAL_COLOURS = {
    "steel": "tab:blue",
    "concrete": "tab:grey",
    "timber": "tab:brown",
    "ceramics": "tab:red",
}


def save(fig: Figure, path: str | Path | None) -> Figure:
    """Write ``fig`` as PNG to ``path`` (parent folders created) and return it."""
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".part")
        fig.savefig(tmp, dpi=130, format="png")
        tmp.replace(path)
    return fig


def restitution_curves(targets=None) -> dict[str, tuple[np.ndarray, np.ndarray]]:
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


def restitution_chart(path: str | Path | None = None, *, targets=None) -> Figure:
    """Chart of the restitution really produced against the target, for every relation."""
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1], color="black", lw=0.8, ls=":", label="achieved = target")
    styles = ["-", "--", "-", "o", "s", "^"]
    for (label, (t, a)), style in zip(restitution_curves(targets).items(), styles, strict=True):
        if style in ("o", "s", "^"):
            ax.plot(t, a, style, ms=4, mfc="none", label=label)
        else:
            ax.plot(t, a, ls=style, lw=1.6, label=label)
    ax.set(
        xlabel="target coefficient of restitution e [-]",
        ylabel="restitution really produced [-]",
        xlim=(0, 1),
        ylim=(0, 1.02),
        title="Damping-restitution relations: one free impact",
    )
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    return save(fig, path)


def restitution_ranges_chart(path: str | Path | None = None) -> Figure:
    """Jankowski (2008) Table 2: measured restitution range against impact velocity."""
    fig = Figure(figsize=(6.4, 4.6), layout="constrained")
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
    ax.legend(fontsize=8)
    return save(fig, path)


def droptest_chart(result: DropTestResult, path: str | Path | None = None) -> Figure:
    """Force against time and against penetration for one virtual drop test."""
    fig = Figure(figsize=(9.6, 4.0), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    t_ms = result.time_s * 1e3
    ax1.plot(t_ms, result.force_N / 1e3, color="tab:red")
    ax1.set(xlabel="time [ms]", ylabel="impact force [kN]", title="Impact force")
    ax2.plot(result.penetration_m * 1e6, result.force_N / 1e3, color="tab:blue")
    ax2.set(xlabel="penetration delta [um]", ylabel="impact force [kN]", title="Force-penetration")
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


def _spectrum_selection(ds, x=None, line=None):
    """Pick the x axis and the line axis of an impact force spectrum chart."""
    grid_dims = [d for d in ds["peak_force"].dims if d not in ("record", "sample")]
    if not grid_dims:
        raise ValueError("the dataset has no grid axis to draw a spectrum against")
    x = x or grid_dims[0]
    rest = [d for d in grid_dims if d != x]
    line = line if line is not None else (rest[0] if rest else None)
    return x, line, [d for d in rest if d != line]


def spectrum_chart(ds, path: str | Path | None = None, *, x=None, line=None, record=0) -> Figure:
    """Impact force spectrum: median peak force against a grid axis with a 5-95 % band.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset (:mod:`pound_mc.dataset`).
    path : str or Path, optional
        Where to write the PNG.
    x : str, optional
        Grid dimension on the horizontal axis (default: the first).
    line : str, optional
        Grid dimension drawn as one line per value (default: the second, if any); other grid
        dimensions are held at their first value.
    record : int
        Which record (index).
    """
    x, line, others = _spectrum_selection(ds, x, line)
    q = ds["peak_force_quantile"].isel(record=record, **{d: 0 for d in others})
    fig = Figure(figsize=(7.2, 4.6), layout="constrained")
    ax = fig.add_subplot()
    line_values = [None] if line is None else list(ds[line].values)
    colours = [f"C{i % 10}" for i in range(len(line_values))]
    for value, colour in zip(line_values, colours, strict=True):
        sel = q if value is None else q.sel({line: value})
        xs = ds[x].values
        if value is None:
            label = "median"
        else:
            lattrs = ds[line].attrs
            units = lattrs.get("units", "")
            label = f"{lattrs.get('long_name', line)} = {value:g}" + (
                f" {units}" if units not in ("", "1") else ""
            )
        ax.plot(xs, sel.sel(quantile=0.5).values / 1e6, color=colour, lw=1.6, label=label)
        ax.fill_between(
            xs,
            sel.sel(quantile=0.05).values / 1e6,
            sel.sel(quantile=0.95).values / 1e6,
            color=colour,
            alpha=0.18,
            lw=0,
        )
    xattrs = ds[x].attrs
    ax.set(
        xlabel=f"{xattrs.get('long_name', x)} [{xattrs.get('units', '')}]",
        ylabel="peak impact force [MN]",
        title=(
            f"Impact force spectrum ({ds.attrs.get('study_name', '')}, record "
            f"{ds['record'].values[record]}): median and 5-95 % over {ds.sizes['sample']} samples"
        ),
    )
    ax.title.set_fontsize(9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return save(fig, path)
