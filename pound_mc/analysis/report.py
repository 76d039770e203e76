"""A study's results page: one self-contained HTML file (``pound-mc report``).

The page holds the charts as inline PNG (``data:`` URIs), the study text, the provenance
(the dataset's global attributes) and a summary of the simulations' status and energy balance
residual.  It loads nothing from anywhere (no scripts, fonts, style sheets or images outside
the file), so it can be mailed or archived as it is.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from pound_mc.analysis import (
    accessor,  # noqa: F401  (registers ds.pound)
    plot,
    profiles,
    risk,
    risk_chart,
)
from pound_mc.analysis.distribution_chart import distribution_chart
from pound_mc.analysis.inelastic_chart import inelastic_chart, yielding_sides
from pound_mc.analysis.labels import coord_text, value_text
from pound_mc.analysis.sensitivity_chart import sensitivity_chart
from pound_mc.analysis.site_chart import risk_chart as site_risk_chart
from pound_mc.analysis.style import (
    output_path,
    pyplot_figures,
    require_simulations,
    take_caption,
    write_atomically,
)
from pound_mc.study.dataset import pounding_counted, study_file

__all__ = ["chart_png", "report_html", "write_report"]

_CSS = """
body { font-family: sans-serif; margin: 16px 24px; color: #222; max-width: 1100px; }
h1 { font-size: 1.5em; margin: 0 0 4px 0; }
h2 { font-size: 1.15em; margin: 28px 0 8px 0; border-bottom: 1px solid #ccc; }
p.lead { margin: 0 0 12px 0; color: #555; }
table { border-collapse: collapse; font-size: 0.9em; }
td, th { border: 1px solid #ccc; padding: 3px 8px; text-align: left; vertical-align: top; }
th { background: #f2f2f2; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
figure { margin: 10px 0 18px 0; }
figcaption { font-size: 0.9em; color: #444; max-width: 936px; }
img { max-width: 100%; height: auto; display: block; }
pre { background: #f7f7f7; border: 1px solid #ddd; padding: 8px; font-size: 0.85em;
      overflow-x: auto; }
""".strip()


def chart_png(fig: Figure, dpi: int = 100) -> tuple[bytes, int, int]:
    """PNG bytes of ``fig`` and its width and height [px]."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = buf.getvalue()
    width = int.from_bytes(data[16:20], "big")  # IHDR chunk
    height = int.from_bytes(data[20:24], "big")
    return data, width, height


def _figure_html(key: str, fig, caption: str) -> str:
    """The chart ``fig`` as an HTML figure: ``caption`` and the chart's own caption under it.

    The chart's caption (:func:`~pound_mc.analysis.style.caption`: its method) is taken out
    of the picture and written as text.
    """
    method = take_caption(fig)
    caption = f"{caption} {method}" if method else caption
    data, width, height = chart_png(fig)
    uri = "data:image/png;base64," + base64.b64encode(data).decode("ascii")
    return (
        f'<figure id="{key}"><img id="chart-{key}" src="{uri}" width="{width}" '
        f'height="{height}" alt="{html.escape(caption)}">'
        f"<figcaption>{html.escape(caption)}</figcaption></figure>"
    )


def _row(*cells, header=False) -> str:
    tag = "th" if header else "td"
    out = []
    for cell in cells:
        cls = ' class="num"' if isinstance(cell, int | float | np.number) else ""
        text = f"{cell:.3g}" if isinstance(cell, float | np.floating) else str(cell)
        out.append(f"<{tag}{cls}>{html.escape(text)}</{tag}>")
    return "<tr>" + "".join(out) + "</tr>"


def _summary_html(ds) -> str:
    counts = ds.pound.status_counts()
    total = int(ds["status"].size)
    rows = [_row("status", "simulations", "share", header=True)]
    for name, n in counts.items():
        rows.append(_row(name, int(n), f"{100.0 * n / total:.2f} %"))
    energy = ds.pound.energy_summary()
    ok = ds.pound.ok
    pounded = int(((ds["impacts"] > 0) & ok).sum())
    erows = [
        _row("quantity", "value", header=True),
        _row("simulations with status ok", int(energy["n"])),
        _row("median |energy residual| [-]", energy["median"]),
        _row("95th percentile |energy residual| [-]", energy["p95"]),
        _row("largest |energy residual| [-]", energy["max"]),
        _row("simulations that pounded (status ok)", pounded),
    ]
    return (
        "<h2>Simulations: status and energy balance</h2>"
        f"<p>{total:,} simulations ({_shape_text(ds)}). The energy residual is the energy "
        "balance error relative to the energy put in by the ground motion; a simulation whose "
        "balance is broken by more than half the input energy is flagged unstable and its "
        "numbers are NaN.</p>"
        f'<table id="status">{"".join(rows)}</table><br>'
        f'<table id="energy">{"".join(erows)}</table>'
    )


def _shape_text(ds) -> str:
    dims = ds["peak_force"].dims
    return " x ".join(f"{ds.sizes[d]} {d}" for d in dims)


def _provenance_html(ds) -> str:
    rows = [_row("attribute", "value", header=True)]
    for key, value in ds.attrs.items():
        if key == "study_text":
            continue
        rows.append(_row(key, value if not isinstance(value, np.ndarray) else list(value)))
    return f'<h2>Provenance</h2><table id="provenance">{"".join(rows)}</table>'


def report_html(
    ds: xr.Dataset,
    *,
    base_dir: str | Path | None = None,
    history: bool = True,
    site: tuple[xr.Dataset, xr.Dataset | None] | None = None,
) -> str:
    """The results page of a study dataset as one HTML string.

    Parameters
    ----------
    ds : xarray.Dataset
        A study dataset (:mod:`pound_mc.study.dataset`).
    base_dir : str or Path, optional
        Folder of relative record paths (for the separation rules and the time history).
    history : bool
        Include the time history of the simulation with the largest peak force (rebuilt from
        the study text and run again).
    site : tuple, optional
        ``(risk, gaps)`` of :func:`pound_mc.analysis.site_risk.site_assessment`: a section on
        the risk at the site (the chart of the annual rate against the gap, a table per gap,
        the risk-targeted gap and the codes' gaps).
    """
    require_simulations(ds)
    name = ds.attrs.get("study_name", "study")
    description = ""
    if bool(ds.pound.ok.any()):
        figures = _figures(ds, base_dir, history)
    elif bool(pounding_counted(ds["status"]).any()):
        # runs flagged inaccurate count for the pounding probability (as in ``pound-mc plot``),
        # not for their peak forces: the charts of forces would be blank
        figures = [
            "<p>(No simulation ended with status ok: the charts of peak forces are left out; "
            "the pounding probability counts the runs flagged inaccurate.)</p>",
            *_figures(ds, base_dir, False, forces=False),
        ]
    else:  # every chart would be blank: the summary below says what happened
        figures = ["<p>(No charts: no simulation ended with status ok or inaccurate.)</p>"]
    for line in str(ds.attrs.get("study_text", "")).splitlines():
        if line.strip().startswith("description"):
            description = line.split("=", 1)[1].strip().strip('"')
    body = [
        f"<h1>pound-mc results: {html.escape(name)}</h1>",
        f'<p class="lead">{html.escape(description)}</p>',
        "<h2>Charts</h2>",
        *figures,
        *([] if site is None else _site_html(*site)),
        _summary_html(ds),
        "<h2>Study</h2>",
        f'<pre id="study-text">{html.escape(str(ds.attrs.get("study_text", "")))}</pre>',
        _provenance_html(ds),
    ]
    return (
        "<!DOCTYPE html>\n"
        '<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>pound-mc results: {html.escape(name)}</title>"
        f"<style>{_CSS}</style></head>\n<body>\n" + "\n".join(body) + "\n</body></html>\n"
    )


def _mm(value) -> str:
    """A gap in mm for the page (a dash where it is not a number)."""
    value = float(value)
    return "-" if not np.isfinite(value) else f"{1e3 * value:.0f} mm"


def _site_html(out: xr.Dataset, gaps: xr.Dataset | None) -> list[str]:
    """The risk section: chart, annual rate per gap, risk-targeted gap, the codes' gaps."""
    with pyplot_figures(False):  # into the page, not pyplot
        fig = site_risk_chart(out, code=gaps)
        parts = ["<h2>Risk at the site</h2>",
                 f"<p>Hazard: {html.escape(str(out.attrs['hazard']))}; event: "
                 f"{html.escape(str(out.attrs['event']))}; intensity "
                 f"{html.escape(str(out.attrs['im']))}.</p>",
                 _figure_html("site-risk", fig, "Mean annual rate of the event against the "
                              "gap.")]  # fmt: skip
    rate = out["annual_rate"]
    gap_dim = rate.dims[0]
    others = [d for d in rate.dims if d != gap_dim]
    cells = ["" if not others else "where", "gap", "annual rate [1/year]", "interval", "note"]
    rows = [_row(*cells, header=True)]
    for index in np.ndindex(*rate.shape):
        point = dict(zip(rate.dims, index, strict=True))
        where = ", ".join(coord_text(out, d, point[d]) for d in others)
        lo, hi = (float(v) for v in out["annual_rate_ci"].isel(point).values)
        value = float(rate.values[index])
        note = str(out["rate_message"].isel(point).values) if "rate_message" in out else ""
        rows.append(_row(where, value_text(out, gap_dim, point[gap_dim]),
                         value if np.isfinite(value) else "-",
                         f"{lo:.3g} - {hi:.3g}" if np.isfinite(value) else "-",
                         note))  # fmt: skip
    parts.append(f'<table id="site-rates">{"".join(rows)}</table>')
    if "required_gap" in out:
        target = out.attrs["target_rate"]
        lines = []
        for index in np.ndindex(*out["required_gap"].shape):
            point = dict(zip(out["required_gap"].dims, index, strict=True))
            lo, hi = (float(v) for v in out["required_gap_ci"].isel(point).values)
            message = str(out["gap_message"].isel(point).values)
            lines.append(_row(_mm(out["required_gap"].values[index]), f"{_mm(lo)} - {_mm(hi)}",
                              message))  # fmt: skip
        parts.append(f"<p>Gap for an annual rate of {target:.3g}:</p>"
                     f'<table id="site-gap">{_row("gap", "interval", "note", header=True)}'
                     f'{"".join(lines)}</table>')  # fmt: skip
    if gaps is not None:
        rows = [_row("rule", "gap", "runs pounding at their own gap", header=True)]
        for rule in gaps["rule"].values:
            g = gaps.sel(rule=rule)
            share = np.asarray(g["code_gap_exceedance"].values, float).ravel()
            rows.append(_row(str(rule), ", ".join(_mm(v) for v in np.ravel(g["code_gap"].values)),
                             ", ".join(f"{100 * v:.0f} %" for v in share)))  # fmt: skip
        parts.append(f'<table id="site-codes">{"".join(rows)}</table>')
    return parts


def _figures(ds: xr.Dataset, base_dir, history: bool, forces: bool = True) -> list[str]:
    """The charts of the page that apply to ``ds``, as HTML.

    ``forces``: also the charts of peak forces, drifts and the time history (False: only the
    pounding probability, the required gap and the fragility).
    """
    figures = []
    if forces and plot._grid_dims(ds):
        panels = plot.MATERIAL_DIM in plot._spectrum_selection(ds)[2]
        figures.append(
            _figure_html(
                "spectrum",
                plot.spectrum_panels(ds),
                "Impact force spectrum: the peak impact force against the first grid axis, one "
                "line per value of the second" + (", one panel per material." if panels else "."),
            )
        )
    sides = yielding_sides(ds) if forces and plot._grid_dims(ds) else []
    if sides:
        figures.append(
            _figure_html(
                "inelastic",
                inelastic_chart(ds, side=sides[0]),
                f"Inelastic spectrum of the {sides[0]} building: ductility demand and peak "
                "impact force against the first grid axis, one line per value of the second; "
                "first record, other grid axes at their first value.",
            )
        )
    if plot.GAP_DIM in ds.dims:
        caption = (
            "Pounding probability against the initial gap"
            + ("." if plot.CONTACT_DIM in ds.dims else ", with the gaps the ABS, SRSS and DDC "
               "separation rules ask for.")
        )  # fmt: skip
    else:
        caption = "Pounding probability against the first grid axis (the study has no gap axis)."
    if plot._grid_dims(ds):
        figures.append(
            _figure_html("probability", plot.probability_chart(ds, base_dir=base_dir), caption)
        )
    intensity = [d for d in risk.INTENSITY_DIMS if d in ds.dims]
    if plot.GAP_DIM in ds.dims and ds.sizes[plot.GAP_DIM] > 1:
        figures.append(
            _figure_html(
                "required-gap",
                risk_chart.required_gap_chart(ds, base_dir=base_dir),
                "Required gap: the gap at which the pounding probability falls to 0.1, one line "
                "per value of the other grid axis, with the separation rules where they apply.",
            )
        )
    if intensity:
        figures.append(
            _figure_html(
                "fragility",
                risk_chart.fragility_panels(ds),
                "Fragility: the probability of pounding against the intensity, a panel per "
                "combination of the other grid axes.",
            )
        )
    if not forces:
        return figures
    if ds.attrs.get("sampling_method") == "saltelli":
        figures.append(
            _figure_html(
                "sensitivity",
                sensitivity_chart(ds),
                "Sobol' indices of the peak impact force: first order S1 (the sampled key "
                "alone) and total order ST (with its interactions) of every sampled key; a "
                "panel per value of the first grid axis (at most six), first record, other grid "
                "axes at their first value.",
            )
        )
    if int(((ds["impacts"] > 0) & ds.pound.ok).sum()):
        figures.append(
            _figure_html(
                "distribution",
                distribution_chart(ds),
                "Distribution of the peak impact force of the simulations that pounded.",
            )
        )
    if plot.CONTACT_DIM in ds.dims and "contact_peak_force" in ds:
        figures.append(
            _figure_html(
                "contacts",
                profiles.contacts_chart(ds),
                "Peak impact force at each contact against the contact's elevation, one line "
                "per value of the first grid axis.",
            )
        )
    for quantity in profiles.PROFILE_VARIABLES:
        if profiles.has_values(ds, quantity):
            figures.append(
                _figure_html(
                    quantity,
                    profiles.profile_chart(ds, quantity=quantity),
                    f"Peak {quantity} of each building (per storey for shear buildings), one "
                    "line per value of a grid axis, the other grid axes held at the value the "
                    "title names; a building whose values are NaN throughout has no panel.",
                )
            )
    if history:
        try:
            index = ds.pound.worst_index("peak_force")
        except ValueError:
            index = None
        if index is not None and float(ds["peak_force"].isel(index)) > 0:
            coords = {d: ds[d].values[i] for d, i in index.items() if d not in ("record", "sample")}
            try:
                with pyplot_figures(False):  # into the page, not pyplot
                    fig = (
                        ds.pound.plot.history(
                            record=index["record"],
                            sample=index["sample"],
                            study_path=study_file(ds, base_dir),
                            **coords,
                        )
                        .ravel()[0]
                        .figure
                    )
            except ValueError as exc:  # records not readable here: say so
                figures.append(f"<p>(No time history: {html.escape(str(exc))})</p>")
            else:
                figures.append(
                    _figure_html(
                        "history",
                        fig,
                        "Time history of the simulation with the largest peak impact force, "
                        "run again from the study text: displacements of the floors that meet, "
                        "penetration and contact force.",
                    )
                )
    return figures


def write_report(
    ds: xr.Dataset,
    path: str | Path,
    *,
    base_dir: str | Path | None = None,
    history: bool = True,
    site: tuple[xr.Dataset, xr.Dataset | None] | None = None,
) -> Path:
    """Write the results page (:func:`report_html`) to ``path`` atomically."""
    path = output_path(path)  # before the charts are drawn
    text = report_html(ds, base_dir=base_dir, history=history, site=site)
    return write_atomically(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
