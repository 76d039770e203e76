"""Every chart kind on a small version of every shipped study (issue 15).

The studies are found at test time (``studies/*.toml``), so a study added later is covered.
Each is cut down here (two records, three values per grid axis, four samples, a few seconds of
motion) and run once per module; every chart kind is drawn from its dataset and the plotted
data are compared with the dataset's own values.  A kind that cannot apply to a study (the
required gap without a gap axis, contacts of SDOF buildings, a bench CSV's chart of a dataset)
must say so in one line: an input error, never a traceback.
"""

import os
import re
import tomllib
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
import xarray as xr
from test_analysis import CHROMIUM, screenshot

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis import profiles, risk
from pound_mc.analysis.plot import spectrum_panels
from pound_mc.analysis.report import report_html
from pound_mc.analysis.risk_chart import fragility_panels
from pound_mc.analysis.style import axis_label
from pound_mc.cli import main
from pound_mc.cli.analysis import draw
from pound_mc.cli.commands import KINDS
from studies import dump_toml, pounding_counted

ROOT = Path(__file__).resolve().parent.parent
STUDIES = sorted((ROOT / "studies").glob("*.toml"))
CSV_KINDS = ("work-precision", "stability")


def _few(values, most: int = 3):
    """First, middle and last of a grid axis (all when there are ``most`` or fewer)."""
    if isinstance(values, dict):  # { start, stop, num }
        return {**values, "num": min(int(values["num"]), most)}
    if len(values) <= most:
        return values
    return [values[0], values[len(values) // 2], values[-1]]


def _record(table: dict) -> dict:
    table = dict(table)
    if str(table["source"]).startswith("suite:"):  # two real records in place of a suite
        table["source"] = "builtin:elcentro"
    if str(table["source"]).startswith("synthetic:"):
        table["params"] = {**table.get("params", {}), "duration_s": 4.0, "t1_s": 1.0, "t2_s": 3.0}
    else:
        table["duration_s"] = 3.0
    return table


def small_study(path: Path) -> str:
    """The study at ``path`` cut down to a few seconds of CPU."""
    data = tomllib.loads(path.read_text())
    data["study"]["name"] = data["study"]["name"] + "_small"
    if "records" in data:
        first = _record(data["records"][0])
        second = _record(data["records"][1] if len(data["records"]) > 1 else data["records"][0])
        if second["source"] == first["source"]:
            second["source"] = "builtin:knet-akt013"
        data["records"] = [first, second]
    if "record" in data:
        data["record"] = _record(data["record"])
    data["grid"] = {key: _few(values) for key, values in data.get("grid", {}).items()}
    data.setdefault("sampling", {})["n"] = 4
    return dump_toml(data)


@pytest.fixture(scope="module")
def datasets(tmp_path_factory):
    """``{study file name: path of its small dataset}``, each run once when first asked for."""
    folder = tmp_path_factory.mktemp("matrix")
    done = {}

    def get(path: Path) -> Path:
        if path.name not in done:
            study = folder / path.name
            study.write_text(small_study(path))
            args = ["run", str(study), "--out", str(folder), "--no-progress", "--no-plot"]
            assert main(args) == 0
            name = tomllib.loads(study.read_text())["study"]["name"]
            done[path.name] = folder / f"{name}.nc"
        return done[path.name]

    return get


def _grid(ds):
    return [d for d in ds["peak_force"].dims if d not in ("record", "sample")]


def _probability(ds, x):
    """Pounding probability over records and samples: the chart's line data, (x, rest...).

    Over the runs a pounding count takes: status ok or flagged inaccurate.
    """
    pounded = (ds["impacts"] > 0).where(pounding_counted(ds)).mean(("record", "sample"))
    return pounded.transpose(x, ...)


def pooled_median_mn(ds) -> xr.DataArray:
    """Median peak force [MN] of the ok runs, records and samples pooled, by numpy."""
    force = np.where(ds["status"].values == 0, ds["peak_force"].values, np.nan)
    dims = list(ds["peak_force"].dims)
    axes = (dims.index("record"), dims.index("sample"))
    rest = [d for d in dims if d not in ("record", "sample")]
    return xr.DataArray(np.nanmedian(force, axis=axes) / 1e6, dims=rest)


def _check_spectrum(ds, fig):
    # the spectrum pools records and samples (a band over only the samples of each record
    # left out the records' scatter)
    grid = _grid(ds)
    q = pooled_median_mn(ds).isel({d: 0 for d in grid[2:]})
    lines = fig.axes[0].lines
    if len(grid) == 1:
        np.testing.assert_allclose(lines[0].get_ydata(), q.values)
    else:
        assert len(lines) == ds.sizes[grid[1]]
        for k, line in enumerate(lines):
            np.testing.assert_allclose(line.get_ydata(), q.isel({grid[1]: k}).values)


def _check_probability(ds, fig):
    grid = _grid(ds)
    x = "contact_gap_m" if "contact_gap_m" in grid else grid[0]
    rest = [d for d in grid if d != x]
    p = _probability(ds, x).isel({d: 0 for d in rest[1:]})
    lines = [ln for ln in fig.axes[0].lines if len(ln.get_xdata()) == ds.sizes[x]]
    if not rest:
        np.testing.assert_allclose(lines[0].get_ydata(), p.values)
        return
    for k, line in enumerate(lines[: ds.sizes[rest[0]]]):
        np.testing.assert_allclose(line.get_ydata(), p.isel({rest[0]: k}).values)


def _check_distribution(ds, fig):
    pounded = (ds["impacts"] > 0) & (ds["status"] == 0)
    im = next((d for d in ("pga_g", "sa_g") if d in ds.dims), None)
    if im is not None:  # split by intensity: the histograms are the strongest stripe's
        pounded = pounded.isel({im: -1})
    box, hist = fig.axes
    assert sum(int(p.get_data().values.sum()) for p in hist.patches) == int(pounded.sum())
    # every box counts the runs of one value (per stripe, where split): all of them drawn
    assert len(box.lines) > 0


def _check_restitution(ds, fig):
    ax = fig.axes[0]
    points = ax.collections[-1].get_offsets()
    e, e_eff = xr.broadcast(ds["e"], ds["e_effective"])
    np.testing.assert_allclose(points[:, 0], e.values.ravel())
    np.testing.assert_allclose(points[:, 1], e_eff.values.ravel())


def _check_fragility(ds, fig):
    dim = next(d for d in risk.INTENSITY_DIMS if d in ds.dims)
    counted = pounding_counted(ds)  # status ok or flagged inaccurate
    pounded = ((ds["impacts"] > 0) & counted).sum(("record", "sample"))
    total = counted.sum(("record", "sample"))
    rest = [d for d in pounded.dims if d != dim]
    first = {d: 0 for d in rest}
    expect = (pounded.isel(first) / total.isel(first)).transpose(dim).values
    stripes = [ln for ln in fig.axes[0].lines if ln.get_linestyle() in ("None", "")][0]
    np.testing.assert_allclose(stripes.get_ydata(), expect)


def _check_required_gap(ds, fig):
    _check_probability(ds, fig)
    found = ds.pound.required_gap(0.1, rules=False)["required_gap"]
    marks = [c for c in fig.axes[0].containers]  # one errorbar per line with a required gap
    drawn = sorted(float(c.lines[0].get_xdata()[0]) for c in marks)
    values = np.asarray(found.values, float).ravel()
    grid = _grid(ds)
    rest = [d for d in grid if d != "contact_gap_m"]
    if len(rest) > 1:  # lines over the first other axis, the rest held at their first value
        values = np.asarray(found.isel({d: 0 for d in rest[1:]}).values, float).ravel()
    np.testing.assert_allclose(drawn, sorted(v * 1e3 for v in values if np.isfinite(v)))


def _check_contacts(ds, fig):
    line = _grid(ds)[0]
    ok = ds["contact_peak_force"].where(ds["status"] == 0)
    median = ok.quantile(0.5, dim=("record", "sample")).transpose(line, "contact") / 1e6
    for k, ln in enumerate(fig.axes[0].lines):
        np.testing.assert_allclose(ln.get_xdata(), median.isel({line: k}).values)
        np.testing.assert_allclose(ln.get_ydata(), ds["contact_elevation"].values)


def _check_history(ds, fig):
    selection, result = ds.pound.worst("peak_force", rerun=True)
    assert result.outputs["peak_force"] == pytest.approx(float(selection["peak_force"]), 1e-12)
    force = fig.axes[2]
    for c, ln in enumerate(force.lines):
        np.testing.assert_allclose(ln.get_ydata(), result.force_N[:, c] / 1e6)


CHECKS = {
    "spectrum": _check_spectrum,
    "probability": _check_probability,
    "distribution": _check_distribution,
    "restitution": _check_restitution,
    "fragility": _check_fragility,
    "required-gap": _check_required_gap,
    "contacts": _check_contacts,
    "history": _check_history,
}


def _applies(ds, kind) -> bool:
    grid = _grid(ds)
    if kind in CSV_KINDS:
        return False
    if kind == "fragility":
        return any(d in ds.dims for d in risk.INTENSITY_DIMS)
    if kind == "required-gap":
        return "contact_gap_m" in grid and ds.sizes["contact_gap_m"] > 1
    if kind == "contacts":
        return "contact" in ds.dims
    if kind in ("spectrum", "probability"):  # drawn against a grid axis
        return bool(grid)
    if kind in profiles.PROFILE_VARIABLES:  # present and not NaN throughout (SDOF drift)
        ok = ds["status"] == 0
        variables = [v for v in profiles.PROFILE_VARIABLES[kind] if v in ds]
        return any(bool(ds[v].where(ok).notnull().any()) for v in variables)
    return True


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("study", STUDIES, ids=[p.stem for p in STUDIES])
def test_every_chart_kind_on_every_shipped_study(study, kind, datasets, tmp_path, capsys):
    path = datasets(study)
    capsys.readouterr()  # the run's own messages, where this test is the first to ask for it
    with xr.open_dataset(path) as ds:
        ds.load()
    if _applies(ds, kind):
        kwargs = {"n_boot": 50} if kind == "fragility" else {}
        if kind == "history":
            index = ds.pound.worst_index("peak_force")
            sel = {d: ds[d].values[i] for d, i in index.items() if d not in ("record", "sample")}
            fig = draw(path, kind, record=index["record"], sample=index["sample"], sel=sel)
        elif kind == "fragility":
            fig = risk_fragility(ds, **kwargs)
        else:
            fig = draw(path, kind)
        CHECKS.get(kind, lambda ds, fig: None)(ds, fig)
        return
    # a kind that does not apply: one line naming the file and the reason, exit status 2
    with pytest.raises(ValueError):  # InputError is one
        draw(path, kind)
    assert main(["plot", str(path), "--kind", kind, "--out", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and str(path) in err and "Traceback" not in err, err
    assert "does not apply" in err or "no intensity axis" in err or "not a CSV" in err, err


def risk_fragility(ds, **kwargs):
    return fragility_panels(ds, **kwargs)


def test_small_studies_keep_each_study_s_shape():
    # the cut-down study keeps every grid axis and the record tables' kinds
    for path in STUDIES:
        full, small = tomllib.loads(path.read_text()), tomllib.loads(small_study(path))
        assert list(small.get("grid", {})) == list(full.get("grid", {})), path.name
        assert small["sampling"]["n"] == 4
        assert ("records" in small) == ("records" in full)


# -- the report of every study, in Debian's chromium --------------------------------------------
@pytest.mark.slow
@pytest.mark.skipif(
    not os.access(CHROMIUM, os.X_OK),
    reason="Debian's chromium is not installed (/usr/bin/chromium); .ci/run installs it",
)
@pytest.mark.parametrize("study", STUDIES, ids=[p.stem for p in STUDIES])
def test_report_of_every_study_renders_in_chromium(study, datasets, tmp_path):
    path = datasets(study)
    out = tmp_path / "report.html"
    assert main(["report", str(path), "--out", str(out)]) == 0
    page = out.read_text()
    with xr.open_dataset(path) as ds:
        ds.load()
    # every chart that applies is on the page
    expected = {"distribution", "history"}
    if _grid(ds):  # drawn against a grid axis
        expected |= {"spectrum", "probability"}
    if ds.attrs.get("sampling_method") == "saltelli":
        expected.add("sensitivity")
    if _applies(ds, "fragility"):
        expected.add("fragility")
    if _applies(ds, "required-gap"):
        expected.add("required-gap")
    if _applies(ds, "contacts"):
        expected.add("contacts")
    if not int(((ds["impacts"] > 0) & (ds["status"] == 0)).sum()):
        expected -= {"distribution", "history"}
    if not _applies(ds, "history"):
        expected.discard("history")
    if "peak_ductility_left" in ds and bool(ds["peak_ductility_left"].notnull().any()):
        expected.add("inelastic")  # the inelastic spectrum of a study of yielding buildings
    for key in expected:
        assert f'id="chart-{key}"' in page, key
    for kind in profiles.PROFILE_VARIABLES:  # no empty drift chart of SDOF buildings
        assert (f'id="chart-{kind}"' in page) == _applies(ds, kind), kind
    screenshot(tmp_path, out)  # no console message, not blank


def test_worst_and_to_dataframe(datasets):
    shear = next(p for p in STUDIES if p.stem == "shear_spectrum")
    with xr.open_dataset(datasets(shear)) as ds:
        ds.load()
    table = ds.pound.to_dataframe()
    assert len(table) == ds["peak_force"].size
    assert list(table.columns[:3]) == list(ds["peak_force"].dims)
    np.testing.assert_array_equal(table["peak_force"], ds["peak_force"].values.ravel())
    worst = ds.pound.worst("peak_force")
    assert float(worst["peak_force"]) == float(ds["peak_force"].where(ds.pound.ok).max())
    # a per-contact variable: its largest value over the contacts
    worst = ds.pound.worst("contact_peak_force")
    assert float(worst["contact_peak_force"].max()) == float(ds["contact_peak_force"].max())
    counts = ds.pound.status_counts()
    assert counts.index.tolist() == ["ok", "unstable", "not_converged", "inaccurate"]
    assert int(counts.sum()) == ds["status"].size


# -- the charts ``run`` draws: each study's headline charts ----------------------------------
#: PNG files ``pound-mc run`` writes for the small version of each shipped study (after
#: ``<name>_small_``): a gap axis draws the probability against the gap with the rules and the
#: required gap, several contacts the peak force per contact, an intensity axis the fragility.
RUN_CHARTS = {
    "benchmark": {"spectrum"},
    "inelastic_spectrum": {"spectrum", "inelastic"},
    "jankowski_spectrum": {"spectrum"},  # one panel per material: test below
    "materials": {"spectrum", "required_gap"},
    "quickstart": {"required_gap", "fragility"},
    "separation_gap": {"spectrum", "required_gap"},
    "sensitivity": {"sensitivity", "distribution"},  # no grid: the distribution, no spectrum
    "shear_spectrum": {"spectrum", "required_gap", "contacts"},
    "yielding_shear": {"spectrum", "inelastic", "required_gap", "contacts"},
}


@pytest.mark.parametrize("study", STUDIES, ids=[p.stem for p in STUDIES])
def test_run_draws_the_charts_each_study_is_for(study, datasets, capsys):
    assert study.stem in RUN_CHARTS, f"say which charts run draws for {study.name}"
    path = datasets(study)  # run with --no-plot: its charts are drawn here
    name = path.stem
    assert not list(path.parent.glob(f"{name}_*.png"))
    capsys.readouterr()
    # the same run again: every chunk is done, so it writes the dataset and draws the charts
    assert main(["run", str(path.parent / study.name), "--out", str(path.parent)]) == 0
    said = re.findall(r"^wrote .*/(\S+\.png)$", capsys.readouterr().out, re.M)
    found = sorted(p.name for p in path.parent.glob(f"{name}_*.png"))
    expected = sorted(f"{name}_{chart}.png" for chart in RUN_CHARTS[study.stem])
    assert found == sorted(said) == expected


def test_a_material_axis_the_spectrum_would_hold_gets_a_panel_per_material(datasets):
    path = datasets(next(p for p in STUDIES if p.stem == "jankowski_spectrum"))
    with xr.open_dataset(path) as ds:
        ds.load()
    # T1 on the horizontal axis, one line per T2: the material is the third grid axis
    assert _grid(ds) == ["left_period_s", "right_period_s", "contact_material"]
    names = [str(n) for n in ds["material"].values]
    assert len(names) == 3  # steel, timber, ceramics of the cut-down study
    fig = spectrum_panels(ds)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert len(panels) == len(names)
    median = pooled_median_mn(ds)
    for k, (ax, material) in enumerate(zip(panels, names, strict=True)):
        assert ax.get_title().startswith(f"Peak impact force, material {material}: median up to ")
        assert len(ax.lines) == ds.sizes["right_period_s"]
        for j, line in enumerate(ax.lines):
            np.testing.assert_array_equal(line.get_xdata(), ds["left_period_s"].values)
            want = median.isel(right_period_s=j, contact_material=k).values
            np.testing.assert_allclose(line.get_ydata(), want)
    # the report draws the same panels, and so does `plot --kind spectrum` without --sel
    assert "one panel per material" in report_html(ds, history=False)
    fig = draw(path, "spectrum", out=path.with_name("plot_spectrum.png"))
    assert [ax.get_title() for ax in fig.axes if ax.get_visible()] == [
        ax.get_title() for ax in panels
    ]
    # and so does the accessor, on a pyplot figure (a notebook shows it)
    axes = ds.pound.plot.spectrum_panels()
    assert [ax.get_title() for ax in axes] == [ax.get_title() for ax in panels]
    assert axes[0].figure.number in plt.get_fignums()
    one = draw(path, "spectrum", out=path.with_name("one.png"), sel={"contact_material": "timber"})
    assert len(one.axes) == 1 and "material timber" in one.axes[0].get_title()
    # a material axis on the chart's line axis (materials.toml: gap, material): one chart
    materials = datasets(next(p for p in STUDIES if p.stem == "materials"))
    with xr.open_dataset(materials) as mds:
        mds.load()
    (ax,) = spectrum_panels(mds).axes
    labels = [line.get_label() for line in ax.lines]
    assert labels == [str(n) for n in mds["material"].values]
    assert [line.get_label() for line in mds.pound.plot.spectrum_panels().lines] == labels
    assert "one panel per material" not in report_html(mds, history=False)


# -- inelastic SDOF buildings: which profiles apply, lines per building variant, --sel -------
def _inelastic_sdof(datasets):
    path = datasets(next(p for p in STUDIES if p.stem == "inelastic_spectrum"))
    with xr.open_dataset(path) as ds:
        ds.load()
    return path, ds


def _ok_quantiles(ds, name, keep):
    """5, 50 and 95 % of ``name`` (status ok) over the records and samples, (quantile, *keep)."""
    ok = ds[name].where(ds["status"] == 0)
    return ok.quantile([0.05, 0.5, 0.95], dim=("record", "sample")).transpose("quantile", *keep)


def _band(collection, xs):
    """Lowest and highest y of a ``fill_between`` band at each of ``xs``."""
    verts = collection.get_paths()[0].vertices
    at = [verts[verts[:, 0] == x, 1] for x in xs]
    return np.array([a.min() for a in at]), np.array([a.max() for a in at])


def test_drift_of_sdof_buildings_does_not_apply(datasets, tmp_path, capsys):
    path, ds = _inelastic_sdof(datasets)
    # drift ratios of SDOF buildings without height_m are NaN (pound_mc/study/dataset.py)
    assert ds["peak_drift_left"].isnull().all() and ds["peak_drift_right"].isnull().all()
    out = tmp_path / "x.png"
    assert main(["plot", str(path), "--kind", "drift", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and str(path) in err and "Traceback" not in err, err
    assert "does not apply" in err and "peak_drift_left" in err, err
    assert not out.exists()
    # the report leaves it out: test_report_of_every_study_renders_in_chromium


def test_ductility_of_sdof_buildings_is_one_line_per_yield_displacement(datasets):
    path, ds = _inelastic_sdof(datasets)
    grid = ("left_yield_disp_m", "left_period_s")
    q = _ok_quantiles(ds, "peak_ductility_left", grid)
    periods = ds["left_period_s"].values  # [s], drawn as they are
    for line in (None, "left_yield_disp_m"):  # the default line axis and asked for by name
        fig = draw(path, "ductility", line=line)
        (ax,) = fig.axes  # the right building is elastic (ductility NaN): no panel
        caption = fig._pound_caption_artist.get_text().replace("\n", " ")
        assert "The right building is left out" in caption
        assert ax.get_xlabel() == axis_label(ds, "left_period_s")
        assert ax.get_legend().get_title().get_text() == axis_label(ds, "left_yield_disp_m")
        assert len(ax.lines) == len(ax.collections) == ds.sizes["left_yield_disp_m"]
        for k, (drawn, band) in enumerate(zip(ax.lines, ax.collections, strict=True)):
            np.testing.assert_array_equal(drawn.get_xdata(), periods)
            np.testing.assert_allclose(drawn.get_ydata(), q.sel(quantile=0.5)[k].values)
            low, high = _band(band, periods)
            np.testing.assert_allclose(low, q.sel(quantile=0.05)[k].values)
            np.testing.assert_allclose(high, q.sel(quantile=0.95)[k].values)


def test_sel_picks_the_lines_and_holds_the_other_axes_of_profile_charts(datasets):
    path, ds = _inelastic_sdof(datasets)
    median = _ok_quantiles(ds, "peak_ductility_left", ("left_yield_disp_m", "left_period_s"))
    median = median.sel(quantile=0.5)
    (ax,) = draw(path, "ductility", sel={"left_yield_disp_m": 0.02}).axes
    assert [line.get_label() for line in ax.lines] == ["20 mm"]
    np.testing.assert_allclose(ax.lines[0].get_ydata(), median[0].values)
    # a third grid axis (a gap, the ductility doubled at the second) is held at one value
    sub = ds[["peak_force", "status", "peak_ductility_left", "peak_ductility_right"]]
    doubled = sub.assign(peak_ductility_left=2.0 * sub["peak_ductility_left"])
    three = xr.concat([sub, doubled], dim=pd.Index([0.01, 0.02], name="contact_gap_m"))
    three = three.transpose("record", "left_period_s", "left_yield_disp_m", "contact_gap_m", ...)
    three["contact_gap_m"].attrs = {"units": "m", "long_name": "initial gap"}
    for sel, factor, held in ((None, 1.0, "10 mm"), ({"contact_gap_m": 0.02}, 2.0, "20 mm")):
        fig = profiles.profile_chart(three, quantity="ductility", sel=sel)
        assert fig.get_suptitle().startswith(f"Peak ductility (gap {held}): median up to ")
        for k, line in enumerate(fig.axes[0].lines):
            np.testing.assert_allclose(line.get_ydata(), factor * median[k].values)
    # contacts of the shear study: the gap sel names alone
    shear = datasets(next(p for p in STUDIES if p.stem == "shear_spectrum"))
    with xr.open_dataset(shear) as sds:
        sds.load()
    gap = float(sds["contact_gap_m"].values[1])
    (ax,) = draw(shear, "contacts", sel={"contact_gap_m": gap}).axes
    force = _ok_quantiles(sds, "contact_peak_force", ("contact_gap_m", "contact"))
    assert len(ax.lines) == 1
    np.testing.assert_allclose(ax.lines[0].get_xdata(), force.sel(quantile=0.5)[1] / 1e6)
