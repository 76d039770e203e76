"""Charts.

Each function draws on a new :class:`matplotlib.figure.Figure` (no pyplot state)
and, given ``path``, writes it as PNG; it returns the figure so notebooks can show it and tests
can read the plotted data back from its artists.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from pound_mc.analysis.gaps import study_gaps
from pound_mc.physics import materials, relations
from pound_mc.physics.droptest import DropTestResult, drop_test

__all__ = [
    "restitution_chart",
    "restitution_ranges_chart",
    "droptest_chart",
    "spectrum_chart",
    "inelastic_chart",
    "probability_chart",
    "distribution_chart",
    "rule_gaps",
    "RULE_ATTRS",
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


def finish_axes(ax, *, title: str, title_size=9, legend_size=8, grid="major", **props) -> None:
    """Title, labels, grid and legend of one chart's axes, alike on every chart.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        The axes.
    title : str
        Axes title.
    title_size : float or None
        Title font size [pt]; None keeps matplotlib's default.
    legend_size : float
        Legend font size [pt].
    grid : {"major", "minor", "both"}
        Grid lines drawn (30 % opaque).
    **props
        More :meth:`matplotlib.axes.Axes.set` properties (``xlabel``, ``ylabel``, ``ylim``, ...).
    """
    ax.set(title=title, **props)
    if title_size is not None:
        ax.title.set_fontsize(title_size)
    ax.grid(True, which=grid, alpha=0.3)
    ax.legend(fontsize=legend_size)


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


def restitution_chart(path: str | Path | None = None, *, targets=None, samples=None) -> Figure:
    """Chart of the restitution really produced against the target, for every relation.

    Parameters
    ----------
    path : str or Path, optional
        Where to write the PNG.
    targets : array_like, optional
        Target coefficients of restitution of the curves (default 37 values in 0.1-0.99).
    samples : tuple, optional
        ``(e, e_effective, label)``: a study's sampled target restitution and the restitution
        its contact law really produces [-], drawn as points over the curves.
    """
    fig = Figure(figsize=(6.4, 5.2), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1], color="black", lw=0.8, ls=":", label="achieved = target")
    styles = ["-", "--", "-", "o", "s", "^"]
    for (label, (t, a)), style in zip(restitution_curves(targets).items(), styles, strict=True):
        if style in ("o", "s", "^"):
            ax.plot(t, a, style, ms=4, mfc="none", label=label)
        else:
            ax.plot(t, a, ls=style, lw=1.6, label=label)
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
        A study dataset (:mod:`pound_mc.study.dataset`).
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
    finish_axes(
        ax,
        xlabel=f"{xattrs.get('long_name', x)} [{xattrs.get('units', '')}]",
        ylabel="peak impact force [MN]",
        title=(
            f"Impact force spectrum ({ds.attrs.get('study_name', '')}, record "
            f"{ds['record'].values[record]}): median and 5-95 % over {ds.sizes['sample']} samples"
        ),
    )
    return save(fig, path)


def inelastic_chart(ds, path: str | Path | None = None, *, side="left", record=0) -> Figure:
    """Inelastic spectrum: median ductility demand and peak force against a grid axis.

    The horizontal axis is the first grid axis, one line per value of the second (the yield
    displacement ``{side}_yield_disp_m`` in ``studies/inelastic_spectrum.toml``); other grid
    axes are held at their first value; 5-95 % bands over the samples.  A line whose building
    never yields (ductility below 1 everywhere) is the elastic reference: its ductility demand
    is its peak displacement over the smallest yield displacement of the line axis.

    Parameters
    ----------
    ds : xarray.Dataset
        A dataset of a study with yielding buildings (``peak_ductility_left`` ...).
    path : str or Path, optional
        Where to write the PNG.
    side : {"left", "right"}
        The building whose ductility is drawn.
    record : int
        Which record (index).
    """
    x, line, others = _spectrum_selection(ds)
    hold = {"record": record, **{d: 0 for d in others}}
    duct = ds[f"peak_ductility_{side}"].isel(hold)
    disp = ds[f"peak_disp_{side}"].isel(hold)
    force = ds["peak_force"].isel(hold) / 1e6
    values = [None] if line is None else list(ds[line].values)
    u_ref = float(min(values)) if line == f"{side}_yield_disp_m" else np.nan
    fig = Figure(figsize=(9.6, 4.2), layout="constrained")
    ax_mu, ax_f = fig.subplots(1, 2, sharex=True)
    xs = ds[x].values
    for i, value in enumerate(values):
        pick = {} if value is None else {line: value}
        mu = duct.sel(pick)
        label = "median" if value is None else _value_text(ds, line, i)
        labels = (label, label)
        elastic = not bool((mu > 1.0).any())
        if elastic and np.isfinite(u_ref):
            mu = disp.sel(pick) / u_ref
            labels = (f"elastic: peak displacement / {u_ref:g} m", "elastic (never yields)")
        elif np.isfinite(u_ref):
            labels = (f"bilinear, yield displacement {value:g} m",) * 2
        style = {"color": f"C{i % 10}", "ls": "--" if elastic else "-"}
        for ax, data, text in ((ax_mu, mu, labels[0]), (ax_f, force.sel(pick), labels[1])):
            q = data.quantile([0.05, 0.5, 0.95], dim="sample").values
            ax.plot(xs, q[1], lw=1.6, label=text, **style)
            ax.fill_between(xs, q[0], q[2], color=style["color"], alpha=0.18, lw=0)
    xlabel = _axis_label(ds, x)
    name = ds.attrs.get("study_name", "")
    finish_axes(ax_mu, xlabel=xlabel, ylabel=f"ductility demand, {side} building [-]",
                title=f"Ductility demand ({name}): median and 5-95 %")  # fmt: skip
    ax_mu.axhline(1.0, color="k", lw=0.6, alpha=0.5)
    finish_axes(ax_f, xlabel=xlabel, ylabel="peak impact force [MN]",
                title=f"Peak impact force ({name}): median and 5-95 %")  # fmt: skip
    return save(fig, path)


#: Dataset attributes holding the gap a separation rule asks for [m], by rule label:
#: ``ABS`` (sum of the peak displacements), ``SRSS`` (square root of the sum of their squares),
#: ``DDC`` (double difference combination, with the correlation of the two responses).  Each is a
#: number or an array with one value per value of the chart's line axis.
RULE_ATTRS = {"ABS": "gap_rule_abs_m", "SRSS": "gap_rule_srss_m", "DDC": "gap_rule_ddc_m"}
_RULE_STYLES = {"ABS": "--", "SRSS": "-.", "DDC": ":"}
#: Dimension of the initial gap in a study dataset.
GAP_DIM = "contact_gap_m"
#: Dimension of the material grid axis (values: indices; variable ``material``: the names).
MATERIAL_DIM = "contact_material"


def rule_gaps(ds, rules="auto", *, base_dir=None) -> dict:
    """Gaps [m] the separation rules ask for, by rule label.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset.
    rules : dict, "auto" or None
        ``{label: gap}``: a number [m], an array with one value per value of the chart's line
        axis, or an :class:`xarray.DataArray` (reduced as below).  ``"auto"``: the dataset's
        attributes :data:`RULE_ATTRS` when it has any, else the gaps
        :func:`pound_mc.analysis.gaps.study_gaps` computes for every simulation of the study
        (ABS, SRSS, DDC from the linear responses of the two buildings alone).  None: no rules.
    base_dir : str or Path, optional
        Folder of relative record paths, for ``"auto"`` (default the working directory).

    Returns
    -------
    dict
        ``{label: value}`` (empty when there are none).
    """
    if rules is None:
        return {}
    if not isinstance(rules, str):
        return dict(rules)
    if rules != "auto":
        raise ValueError(f'rules must be a dict, "auto" or None, got {rules!r}')
    found = {label: ds.attrs[attr] for label, attr in RULE_ATTRS.items() if attr in ds.attrs}
    if found or "study_text" not in ds.attrs:
        return found
    gaps = study_gaps(ds, base_dir=base_dir)
    return {"ABS": gaps["gap_abs"], "SRSS": gaps["gap_srss"], "DDC": gaps["gap_ddc"]}


def _reduce_rule(value, ds, line, record, hold):
    """One gap [m], or one per value of ``line``, from a rule given as a number or array.

    A DataArray over the dataset's dims is taken at the chart's record (all records pooled for
    ``record=None``) and held dims, and its median over the samples (and over the gaps: the
    rules do not depend on the gap) is drawn.
    """
    if isinstance(value, xr.DataArray):
        if "record" in value.dims and record is not None:
            value = value.isel(record=record)
        value = value.isel({d: i for d, i in hold.items() if d in value.dims})
        over = [d for d in value.dims if d != line]
        value = value.median(over) if over else value
        if line is not None and line in value.dims:
            return value.transpose(line).values.astype(float)
        return np.asarray(value.values, dtype=float).reshape(-1)
    return np.atleast_1d(np.asarray(value, dtype=float))


def _line_label(ds, dim, i) -> str:
    return f"{ds[dim].attrs.get('long_name', dim)} = {_value_text(ds, dim, i)}"


def _axis_label(ds, dim) -> str:
    attrs = ds[dim].attrs
    return f"{attrs.get('long_name', dim)} [{attrs.get('units', '-')}]".replace("[1]", "[-]")


def _hold(ds, dims, sel):
    """Index of every dim in ``dims``: the value nearest ``sel[dim]``, else the first."""
    sel = sel or {}
    unknown = set(sel) - set(ds.dims)
    if unknown:
        raise ValueError(f"no dimension {sorted(unknown)[0]!r}; the dataset has {list(ds.dims)}")
    out = {}
    for dim in dims:
        if dim in sel:
            out[dim] = _nearest_index(ds, dim, sel[dim])
        else:
            out[dim] = 0
    return out


def _nearest_index(ds, dim, value) -> int:
    coord = ds[dim].values
    if coord.dtype.kind in "fiu":
        return int(np.argmin(np.abs(coord.astype(float) - float(value))))
    hits = np.flatnonzero(coord == value)
    if not hits.size:
        raise ValueError(f"{dim} has no value {value!r}; it has {list(coord)}")
    return int(hits[0])


def _record_index(ds, record) -> int:
    return record if isinstance(record, int | np.integer) else _nearest_index(ds, "record", record)


def _value_text(ds, dim, i) -> str:
    """The ``i``-th value of ``dim`` as text: a material's name, else the number and units."""
    if dim == MATERIAL_DIM and "material" in ds and ds["material"].dims == (dim,):
        return str(ds["material"].values[i])
    value = ds[dim].values[i]
    if not isinstance(value, float | np.floating | int | np.integer):
        return str(value)
    units = ds[dim].attrs.get("units", "")
    return f"{value:g}" + (f" {units}" if units not in ("", "1") else "")


def _grid_dims(ds) -> list[str]:
    return [d for d in ds["peak_force"].dims if d not in ("record", "sample")]


def probability_chart(
    ds,
    path: str | Path | None = None,
    *,
    line=None,
    record=None,
    sel=None,
    rules="auto",
    max_lines: int = 6,
    base_dir=None,
) -> Figure:
    """Pounding probability against the initial gap, with the separation rules marked.

    The probability is the fraction of the samples (status ok) with at least one impact:
    ``pounding_probability`` of the dataset.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset with the gap ``contact.gap_m`` as a grid axis.
    path : str or Path, optional
        Where to write the PNG.
    line : str, optional
        Grid dimension drawn as one line per value (default: the first other grid axis); at most
        ``max_lines`` values, evenly spread, are drawn.
    record : int or str, optional
        Which record (index or name); default all records pooled.
    sel : dict, optional
        ``{dim: value}`` for the other grid dimensions (nearest value; default the first), or a
        list of values of the ``line`` dimension to draw.
    rules : dict, "auto" or None
        Separation rule gaps (see :func:`rule_gaps`), drawn as vertical lines: the median over
        the samples, per line where they differ from line to line.
    max_lines : int
        Most lines drawn.
    base_dir : str or Path, optional
        Folder of relative record paths when the rules are computed.
    """
    if GAP_DIM not in ds.dims:
        raise ValueError(
            "the dataset has no gap axis: pounding probability against gap needs a study with "
            '"contact.gap_m" on its [grid]'
        )
    sel = dict(sel or {})
    rest = [d for d in _grid_dims(ds) if d != GAP_DIM]
    line = line if line is not None else (rest[0] if rest else None)
    wanted = sel.pop(line, None) if line is not None else None
    hold = _hold(ds, [d for d in rest if d != line], sel)
    if record is None:
        prob = (ds["impacts"] > 0).where(ds["status"] == 0).isel(hold).mean(("record", "sample"))
        rec_text = f"all {ds.sizes['record']} records" if ds.sizes["record"] > 1 else "record "
        rec_text += "" if ds.sizes["record"] > 1 else str(ds["record"].values[0])
    else:
        record = _record_index(ds, record)
        prob = ds["pounding_probability"].isel(record=record, **hold)
        rec_text = f"record {ds['record'].values[record]}"
    if line is None:
        line_idx = [None]
    elif wanted is not None:
        line_idx = [_nearest_index(ds, line, v) for v in np.atleast_1d(wanted)]
    else:
        n = ds.sizes[line]
        line_idx = list(
            dict.fromkeys(np.round(np.linspace(0, n - 1, min(n, max_lines))).astype(int))
        )
    gap_mm = ds[GAP_DIM].values * 1e3
    fig = Figure(figsize=(7.2, 4.6), layout="constrained")
    ax = fig.add_subplot()
    colours = {}
    for k, i in enumerate(line_idx):
        colour = f"C{k % 10}"
        colours[i] = colour
        y = prob.values if i is None else prob.isel({line: i}).values
        label = "pounding probability" if i is None else _line_label(ds, line, i)
        ax.plot(gap_mm, y, "o-", color=colour, ms=3.5, lw=1.6, label=label)
    for label, value in rule_gaps(ds, rules, base_dir=base_dir).items():
        style = _RULE_STYLES.get(label, (0, (1, 3)))
        arr = _reduce_rule(value, ds, line, record, hold)
        if arr.size == 1:
            if np.isfinite(arr[0]):
                rule_label = f"{label} rule: {arr[0] * 1e3:.3g} mm"
                ax.axvline(arr[0] * 1e3, color="black", ls=style, lw=1.1, label=rule_label)
            continue
        if line is None or arr.size != ds.sizes[line]:
            raise ValueError(
                f"separation rule {label}: {arr.size} gaps, expected 1 or one per value of {line!r}"
            )
        first = True
        for i in line_idx:
            if np.isfinite(arr[i]):
                rule_label = f"{label} rule (in each line's colour)" if first else None
                ax.axvline(arr[i] * 1e3, color=colours[i], ls=style, lw=1.1, label=rule_label)
                first = False
    finish_axes(
        ax,
        xlabel="initial gap [mm]",
        ylabel="pounding probability [-]",
        ylim=(-0.03, 1.03),
        title=(
            f"Pounding probability ({ds.attrs.get('study_name', '')}, {rec_text}): fraction of "
            f"the samples with an impact\nvertical lines: gaps the separation rules ask for "
            f"(median over samples)"
        ),
    )
    return save(fig, path)


def _distribution_groups(ds, by, record, sel):
    """Peak forces [N] of the pounding simulations (status ok), per value of ``by``."""
    grid = _grid_dims(ds)
    held = _hold(ds, [d for d in (sel or {}) if d != by], sel)
    force = ds["peak_force"].isel(record=_record_index(ds, record), **held)
    ok = (ds["status"] == 0) & (ds["impacts"] > 0)
    ok = ok.isel(record=_record_index(ds, record), **held)
    groups, labels = [], []
    for i in range(ds.sizes[by]):
        f = force.isel({by: i}).values
        m = ok.isel({by: i}).values
        groups.append(f[m].ravel())
        labels.append(_value_text(ds, by, i))
    pooled = [d for d in grid if d != by and d not in held]
    return groups, labels, pooled


def distribution_chart(
    ds, path: str | Path | None = None, *, by=None, record=0, sel=None, bins: int = 30
) -> Figure:
    """Distribution of the peak impact force: box plot and histogram per value of a dimension.

    Only simulations that pounded (at least one impact, status ok) enter; the other grid
    dimensions are pooled unless held by ``sel``.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset.
    path : str or Path, optional
        Where to write the PNG.
    by : str, optional
        Dimension with one box and one histogram per value (default the material axis
        ``contact_material`` when the dataset has it, else the gap, else the last grid
        dimension).
    record : int or str
        Which record (index or name).
    sel : dict, optional
        ``{dim: value}`` of grid dimensions to hold at one value (nearest) instead of pooling.
    bins : int
        Number of histogram bins (common to every value).
    """
    grid = _grid_dims(ds)
    if by is None:
        by = MATERIAL_DIM if MATERIAL_DIM in grid else (GAP_DIM if GAP_DIM in grid else None)
        by = by or (grid[-1] if grid else None)
    if by is None or by not in ds.dims:
        raise ValueError(f"cannot draw the distribution per {by!r}: no such grid dimension")
    groups, labels, pooled = _distribution_groups(ds, by, record, sel)
    fig = Figure(figsize=(10.0, 4.4), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2)
    drawn = [k for k, g in enumerate(groups) if g.size]
    if drawn:
        ax1.boxplot(
            [groups[k] / 1e6 for k in drawn],
            positions=np.arange(1, len(drawn) + 1),
            tick_labels=[labels[k] for k in drawn],
            showmeans=True,
            whis=(5, 95),
            flierprops={"markersize": 2},
        )
        edges = np.histogram_bin_edges(np.concatenate([groups[k] for k in drawn]), bins=bins)
        for j, k in enumerate(drawn):
            counts, _ = np.histogram(groups[k], bins=edges)
            hist_label = f"{labels[k]} ({groups[k].size} simulations)"
            ax2.stairs(counts, edges / 1e6, color=f"C{j % 10}", lw=1.4, label=hist_label)
        ax2.legend(fontsize=8, title=_axis_label(ds, by), title_fontsize=8)
    ax1.set(xlabel=_axis_label(ds, by), ylabel="peak impact force [MN]")
    ax1.set_title("box 25-75 %, whiskers 5-95 %, triangle mean", fontsize=9)
    ax2.set(xlabel="peak impact force [MN]", ylabel="number of simulations [-]")
    for ax in (ax1, ax2):
        ax.grid(alpha=0.3)
    over = f"; pooled over {', '.join(pooled)}" if pooled else ""
    fig.suptitle(
        f"Peak impact force of the simulations that pounded ({ds.attrs.get('study_name', '')}, "
        f"record {ds['record'].values[_record_index(ds, record)]}{over})",
        fontsize=9,
    )
    return save(fig, path)
