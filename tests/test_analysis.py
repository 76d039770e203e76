"""Charts, the ``ds.pound`` accessor, the analysis notebook and the HTML report (issue 6).

Every chart is drawn from a real study dataset (a small study run here) or a real bench /
stability table, and checked for the numbers it plots, not only for a file.
"""

import base64
import html
import io
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import pytest
import xarray as xr
from browser import CHROMIUM, COMMON_FLAGS, run_chromium

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis.gaps import study_gaps
from pound_mc.cli import main
from pound_mc.cli.analysis import draw
from pound_mc.motions.catalogue import _builtin_path
from pound_mc.study.definition import load_study
from pound_mc.study.runner import run_study
from studies import study_text

ROOT = Path(__file__).resolve().parent.parent

TINY = study_text(
    study={"name": "tiny-analysis", "description": "Small study for the analysis tests"},
    grid={"left.period_s": [0.3, 0.6, 0.9], "contact.gap_m": [0.0, 0.002, 0.01]},
    sampling={"n": 6},
)


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    """Path of the small study's dataset (run once for the module)."""
    folder = tmp_path_factory.mktemp("analysis")
    study = folder / "tiny.toml"
    study.write_text(TINY)
    assert main(["run", str(study), "--out", str(folder), "--no-progress", "--no-plot"]) == 0
    return folder / "tiny-analysis.nc"


@pytest.fixture
def ds(tiny):
    with xr.open_dataset(tiny) as d:
        yield d.load()


def _band_at(collection, x):
    """y values of a fill_between polygon's vertices at abscissa ``x``."""
    v = collection.get_paths()[0].vertices
    return v[np.isclose(v[:, 0], x), 1]


# -- spectrum ----------------------------------------------------------------------------------
def test_spectrum_chart_plots_the_dataset_quantiles(ds, tiny, tmp_path):
    fig = draw(tiny, "spectrum")
    ax = fig.axes[0]
    q = ds["peak_force_quantile"].isel(record=0)
    periods = ds["left_period_s"].values
    assert len(ax.lines) == ds.sizes["contact_gap_m"]  # one line per gap (the other axis)
    for j, gap in enumerate(ds["contact_gap_m"].values):
        line = ax.lines[j]
        np.testing.assert_allclose(line.get_xdata(), periods)
        median = q.sel(quantile=0.5, contact_gap_m=gap).values / 1e6
        np.testing.assert_allclose(line.get_ydata(), median, rtol=1e-12)
        for k, x in enumerate(periods):
            ys = _band_at(ax.collections[j], x)
            for level in (0.05, 0.95):
                value = q.sel(quantile=level, contact_gap_m=gap).values[k] / 1e6
                assert np.isclose(ys, value, rtol=1e-12).any(), (gap, x, level)
    assert ax.get_xlabel() == "left natural period [s]"
    assert ax.get_ylabel() == "peak impact force [MN]"
    # the accessor's quantiles are the same numbers, computed from peak_force
    acc = ds.pound.spectrum(quantiles=(0.05, 0.5, 0.95))
    np.testing.assert_allclose(
        acc.values, ds["peak_force_quantile"].sel(quantile=[0.05, 0.5, 0.95]).values, rtol=1e-12
    )
    assert acc.attrs["units"] == "N"
    one = ds.pound.spectrum(quantiles=0.5, left_period_s=0.6000001, contact_gap_m=0.002)
    assert one.item() == pytest.approx(q.sel(quantile=0.5).values[1, 1], rel=1e-12)
    # the accessor's chart is the same chart, drawn on the Axes given and returned
    from matplotlib.figure import Figure

    mine = Figure().add_subplot()
    assert ds.pound.plot.spectrum(ax=mine) is mine
    assert np.array_equal(mine.lines[1].get_ydata(), ax.lines[1].get_ydata())


# -- probability -------------------------------------------------------------------------------
def test_probability_chart_plots_the_pounding_probability_and_rules(ds, tiny):
    rules = {"ABS": 0.004, "SRSS": np.array([0.001, 0.002, 0.003])}
    ax = ds.pound.plot.probability(rules=rules)
    prob = ds["pounding_probability"].isel(record=0)
    data = [ln for ln in ax.lines if len(ln.get_xdata()) == ds.sizes["contact_gap_m"]]
    assert len(data) == ds.sizes["left_period_s"]
    for line, period in zip(data, ds["left_period_s"].values, strict=True):
        np.testing.assert_allclose(line.get_xdata(), ds["contact_gap_m"].values * 1e3)
        np.testing.assert_allclose(line.get_ydata(), prob.sel(left_period_s=period).values)
        assert line.get_label().endswith(f"{period:g} s")
    rest = [ln for ln in ax.lines if ln not in data]
    # ABS, one gap for every line: one grey vertical line at 4 mm
    abs_lines = [ln for ln in rest if ln.get_linestyle() == "--"]
    assert [ln.get_xdata()[0] for ln in abs_lines] == [pytest.approx(4.0)]
    # SRSS, a gap per period: a black "+" on each period's line at its gap, no vertical line
    srss = [ln for ln in rest if ln.get_marker() == "+"]
    assert [ln.get_xdata()[0] for ln in srss] == pytest.approx([1.0, 2.0, 3.0])
    for mark, line in zip(srss, data, strict=True):
        want = np.interp(mark.get_xdata()[0], line.get_xdata(), line.get_ydata())
        assert mark.get_ydata()[0] == pytest.approx(want)
    assert len(rest) == 4
    assert ax.get_xlabel() == "initial separation gap [mm]"
    assert ax.get_ylabel() == "pounding probability [-]"

    # the title says the answer (the probabilities at the narrowest and the widest gap)
    def span(values):
        lo, hi = f"{100 * values.min():.0f}", f"{100 * values.max():.0f}"
        return f"{lo} %" if lo == hi else f"{lo}-{hi} %"

    first, last = (prob.isel(contact_gap_m=k).values for k in (0, -1))
    want = f"Pounding probability: {span(first)} at gap 0 mm, {span(last)} at gap 10 mm"
    assert ax.get_title() == want
    caption = ax.figure._pound_caption_artist.get_text().replace("\n", " ")
    assert "Separation rules: their gaps (median over the samples), marked on each line" in caption
    np.testing.assert_allclose(ds.pound.probability().values, ds["pounding_probability"].values)
    # without rules: nothing but the probability lines, and no word of rules
    bare = ds.pound.plot.probability(rules=None)
    assert len(bare.lines) == len(data)
    assert "rule" not in bare.figure._pound_caption_artist.get_text()


def test_probability_rules_from_attributes_and_from_separation(ds, tiny):
    marked = ds.copy()
    marked.attrs["gap_rule_ddc_m"] = 0.0075
    ax = marked.pound.plot.probability()
    ddc = [ln for ln in ax.lines if ln.get_linestyle() == ":"]
    assert [ln.get_xdata()[0] for ln in ddc] == [pytest.approx(7.5)]
    # by default: ABS, SRSS, DDC of every simulation (pound_mc.analysis.gaps),
    # median over samples
    gaps = study_gaps(ds)
    ax = draw(tiny, "probability").axes[0]
    lines = ax.lines[: ds.sizes["left_period_s"]]
    for marker, name in (("x", "gap_abs"), ("+", "gap_srss"), ("o", "gap_ddc")):
        marks = [ln for ln in ax.lines if ln.get_marker() == marker and ln not in lines]
        expected = gaps[name].isel(record=0, contact_gap_m=0).median("sample").values * 1e3
        inside = expected[(expected >= 0.0) & (expected <= 10.0)]  # within the gaps drawn
        np.testing.assert_allclose([m.get_xdata()[0] for m in marks], inside, rtol=1e-12)


# -- distribution ------------------------------------------------------------------------------
def test_distribution_chart_plots_the_pounding_simulations(ds, tiny):
    fig = draw(tiny, "distribution")
    box_ax, hist_ax = fig.axes
    ok = (ds["status"] == 0) & (ds["impacts"] > 0)
    groups = [
        ds["peak_force"].sel(contact_gap_m=g).values[ok.sel(contact_gap_m=g).values]
        for g in ds["contact_gap_m"].values
    ]
    groups = [g for g in groups if g.size]
    assert groups, "the small study must pound"
    medians = [ln.get_ydata()[0] for ln in box_ax.lines if ln.get_color() == "C1"]
    np.testing.assert_allclose(medians, [np.median(g) / 1e6 for g in groups], rtol=1e-12)
    edges = np.histogram_bin_edges(np.concatenate(groups), bins=30)
    stairs = hist_ax.patches
    assert len(stairs) == len(groups)
    for patch, g in zip(stairs, groups, strict=True):
        values, drawn_edges, _ = patch.get_data()
        np.testing.assert_array_equal(values, np.histogram(g, bins=edges)[0])
        np.testing.assert_allclose(drawn_edges, edges / 1e6)
    assert hist_ax.get_xlabel() == "peak impact force [MN]"
    assert box_ax.get_ylabel() == "peak impact force [MN]"


# -- restitution -------------------------------------------------------------------------------
def test_restitution_chart_marks_the_study_samples(ds, tiny):
    fig = draw(tiny, "restitution")
    ax = fig.axes[0]
    (points,) = ax.collections
    np.testing.assert_allclose(points.get_offsets()[:, 0], ds["e"].values)
    np.testing.assert_allclose(points.get_offsets()[:, 1], ds["e_effective"].values)
    from pound_mc.physics.relations import effective_restitution

    curve = next(ln for ln in ax.lines if ln.get_label() == "Jankowski law, jankowski2008")
    np.testing.assert_allclose(
        curve.get_ydata(), effective_restitution(curve.get_xdata(), "jankowski2008")
    )


# -- work-precision and stability from their CSV tables -----------------------------------------
def test_work_precision_and_stability_charts_from_their_csv(tmp_path):
    from pound_mc.numerics.bench import benchmark
    from pound_mc.numerics.stability import stability_map

    bench = benchmark(scenes=("shear-3-5",), methods=["adaptive"], repeats=1, progress=False)
    bench.to_csv(tmp_path / "bench.csv", index=False)
    out = tmp_path / "wp.png"
    assert (
        main(["plot", str(tmp_path / "bench.csv"), "--kind", "work-precision", "--out", str(out)])
        == 0
    )
    assert out.stat().st_size > 10_000
    (line,) = draw(tmp_path / "bench.csv", "work-precision").axes[0].lines[:1]
    np.testing.assert_allclose(line.get_xdata(), bench["seconds"].to_numpy() * 1e3)
    np.testing.assert_allclose(line.get_ydata(), np.maximum(bench["err_peak_force"], 1e-16))

    table = stability_map(betas=[1e9, 1e11], methods=["central-difference"])
    table.to_csv(tmp_path / "stability.csv", index=False)
    fig = draw(tmp_path / "stability.csv", "stability")
    observed, predicted = fig.axes[0].lines[:2]
    np.testing.assert_allclose(observed.get_ydata(), table["observed"])
    np.testing.assert_allclose(predicted.get_ydata(), table["predicted"])
    assert fig.axes[0].get_xlabel() == "impact stiffness beta [N/m^1.5]"


# -- time history ------------------------------------------------------------------------------
def test_history_from_the_dataset_reproduces_the_stored_simulation(ds, tiny, tmp_path):
    out = tmp_path / "history.png"
    args = ["plot", str(tiny), "--kind", "history", "--out", str(out), "--sample", "2"]
    assert main([*args, "--sel", "left_period_s=0.6", "--sel", "contact_gap_m=0.002"]) == 0
    assert out.stat().st_size > 10_000
    # the study file's keys name the same dimensions
    keys = ["--sel", "left.period_s=0.6", "--sel", "contact.gap_m=0.002"]
    assert main([*args[:-3], str(tmp_path / "keys.png"), *args[-2:], *keys]) == 0
    assert (tmp_path / "keys.png").read_bytes() == out.read_bytes()
    result, index = ds.pound.simulate(sample=2, left_period_s=0.6, contact_gap_m=0.002)
    assert index == {"record": 0, "left_period_s": 1, "contact_gap_m": 1, "sample": 2}
    # the rerun is the dataset's simulation: same kernel, same parameters, same record
    for name in ("peak_force", "impacts", "peak_disp_left", "dissipated_energy"):
        assert result.outputs[name] == pytest.approx(float(ds[name][index]), rel=1e-12), name
    disp, pen, force = ds.pound.plot.history(sample=2, left_period_s=0.6, contact_gap_m=0.002)
    np.testing.assert_allclose(disp.lines[0].get_xdata(), result.time_s)
    np.testing.assert_allclose(disp.lines[0].get_ydata(), result.disp_left_m[:, -1] * 1e3)
    np.testing.assert_allclose(force.lines[0].get_ydata(), result.force_N[:, 0] / 1e6)
    assert force.get_ylabel() == "contact force [MN]" and force.get_xlabel() == "time [s]"


def test_history_from_a_scene_file(tmp_path):
    from pound_mc.scene import load_scene, simulate

    scene = ROOT / "studies" / "scenes" / "b1.toml"
    fig = draw(scene, "history")
    result = simulate(load_scene(scene), history=True)
    np.testing.assert_allclose(fig.axes[2].lines[0].get_ydata(), result.force_N[:, 0] / 1e6)


def test_every_kind_writes_a_png_from_the_command_line(tiny, tmp_path):
    for kind in ("spectrum", "probability", "distribution", "restitution", "history"):
        out = tmp_path / f"{kind}.png"
        assert main(["plot", str(tiny), "--kind", kind, "--out", str(out)]) == 0
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000


def test_accessor_charts_are_pyplot_figures_unless_written_to_a_file(ds, tiny, tmp_path):
    # drawn for a person (no path, no ax): pyplot's figure, which a notebook and plt.show()
    # display; written to a file, or drawn by the command line: no pyplot figure left open
    plt.close("all")
    try:
        ax = ds.pound.plot.spectrum()
        assert plt.get_fignums() == [ax.figure.number] and plt.gcf() is ax.figure
        axes = ds.pound.plot.distribution()
        assert axes[0].figure is plt.gcf() and len(plt.get_fignums()) == 2
        plt.close("all")
        ds.pound.plot.probability(tmp_path / "p.png")
        ds.pound.plot.restitution(tmp_path / "r.png")
        assert (
            main(["plot", str(tiny), "--kind", "spectrum", "--out", str(tmp_path / "s.png")]) == 0
        )
        assert main(["report", str(tiny), "--out", str(tmp_path / "r.html")]) == 0
        assert (tmp_path / "p.png").is_file() and plt.get_fignums() == []
        _, given = plt.subplots()
        assert ds.pound.plot.spectrum(ax=given) is given and len(plt.get_fignums()) == 1
    finally:
        plt.close("all")


def test_analysis_names_the_study_file_the_dataset_ran_from(tmp_path, capsys):
    # a study file named otherwise than its study, reading a record beside it: the scene and
    # the error once the record is gone name that file (they named ".../study.toml")
    folder = tmp_path / "st"
    folder.mkdir()
    shutil.copy(_builtin_path("elcentro"), folder / "elc.AT2")
    text = study_text(record={"source": "elc.AT2"}, grid={"contact.gap_m": None},
                      sampling={"n": 2})  # fmt: skip
    (folder / "pair.toml").write_text(text)
    report = run_study(load_study(folder / "pair.toml"), tmp_path / "out", progress=False)
    with xr.open_dataset(report.path) as ds:
        assert ds.attrs["study_name"] == "small" and ds.attrs["study_file"] == "pair.toml"
        assert ds.pound.scene(sample=0).file == str(folder.resolve() / "pair.toml")
    (folder / "elc.AT2").unlink()
    out = tmp_path / "h.png"
    assert main(["plot", str(report.path), "--kind", "history", "--out", str(out)]) == 2
    assert f"{folder.resolve() / 'pair.toml'}: record.source" in capsys.readouterr().err
    assert not out.exists()


def test_plot_errors_are_input_errors(tiny, tmp_path, capsys):
    assert main(["plot", str(tmp_path / "missing.nc"), "--kind", "spectrum"]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["plot", str(tiny), "--kind", "history", "--sel", "colour=3"]) == 2
    assert "colour" in capsys.readouterr().err


def test_distribution_by_record(tiny, tmp_path):
    """``--by record`` (one group per record) was refused when --by learnt the study keys."""
    out = tmp_path / "by-record.png"
    assert (
        main(["plot", str(tiny), "--kind", "distribution", "--by", "record", "--out", str(out)])
        == 0
    )


def test_line_and_by_take_the_study_files_keys(tiny, tmp_path):
    # --line and --by name a grid dimension as --sel does: by its name or its study key
    for option, kind in (("--line", "probability"), ("--by", "distribution")):
        pngs = []
        for name in ("left_period_s", "left.period_s"):
            out = tmp_path / f"{kind}-{name}.png"
            assert main(["plot", str(tiny), "--kind", kind, option, name, "--out", str(out)]) == 0
            pngs.append(out.read_bytes())
        assert pngs[0] == pngs[1]


# -- notebook ----------------------------------------------------------------------------------
def execute_notebook(dataset, monkeypatch) -> list:
    """The outputs of ``studies/analysis.ipynb`` run headless on ``dataset``, in cell order."""
    nbformat = pytest.importorskip("nbformat")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("POUND_MC_DATASET", str(dataset))
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(ROOT / "studies" / "analysis.ipynb", as_version=4)
    client = nbclient.NotebookClient(
        nb, kernel_name="python3", timeout=300, resources={"metadata": {"path": str(ROOT)}}
    )
    client.execute()
    return [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]


@pytest.mark.slow
def test_analysis_notebook_runs_headless(tiny, monkeypatch):
    outputs = execute_notebook(tiny, monkeypatch)
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    assert "tiny-analysis" in text  # it read the dataset it was pointed at
    rerun, stored = re.search(r"rerun: ([\d.e+-]+) MN; dataset: ([\d.e+-]+) MN", text).groups()
    assert float(rerun) == pytest.approx(float(stored), rel=1e-12)
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    assert len(images) == 3  # spectrum, probability, history


# -- report ------------------------------------------------------------------------------------
def _report(tiny, tmp_path):
    out = tmp_path / "report.html"
    assert main(["report", str(tiny), "--out", str(out)]) == 0
    return out


def test_report_is_self_contained(ds, tiny, tmp_path):
    page = _report(tiny, tmp_path).read_text()
    for attr in re.findall(r'(?:src|href)="([^"]*)"', page):
        assert attr.startswith("data:image/png;base64,"), attr[:60]
    assert "<script" not in page and "url(" not in page and "@import" not in page
    for key in ("spectrum", "probability", "distribution", "history"):
        assert f'id="chart-{key}"' in page
    assert html.escape(ds.attrs["study_text"]) in page
    assert ds.attrs["study_hash"] in page and ds.attrs["numba_version"] in page
    counts = ds.pound.status_counts()
    assert f'<td>ok</td><td class="num">{counts["ok"]}</td>' in page
    assert f"{ds.pound.energy_summary()['max']:.3g}" in page


_FLAGS = ["--headless", *COMMON_FLAGS, "--window-size=1200,3000"]


def _chromium(tmp_path, *args):
    return run_chromium(tmp_path, _FLAGS, *args, timeout=90)


def _console_messages(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


def screenshot(tmp_path, page: Path) -> np.ndarray:
    """The page as chromium shows it (RGB), after checking it logged no console message."""
    from PIL import Image

    shot = tmp_path / "shot.png"
    run = _chromium(
        tmp_path, "--enable-logging=stderr", "--v=0", f"--screenshot={shot}", page.as_uri()
    )
    assert run.returncode == 0, run.stderr[-2000:]
    assert _console_messages(run.stderr) == []
    screen = np.asarray(Image.open(shot).convert("RGB")).astype(int)
    assert (screen != 255).any(axis=2).mean() > 0.05  # not blank
    return screen


@pytest.mark.skipif(
    not os.access(CHROMIUM, os.X_OK),
    reason="Debian's chromium is not installed (/usr/bin/chromium); .ci/run installs it",
)
def test_report_renders_in_headless_chromium(tiny, tmp_path):
    from PIL import Image

    report = _report(tiny, tmp_path)
    page = report.read_text()
    # the console check can fail: a page with a script error is caught
    bad = tmp_path / "bad.html"
    bad.write_text("<html><body><script>undefinedFunction();</script></body></html>")
    run = _chromium(tmp_path, "--enable-logging=stderr", "--v=0", "--dump-dom", bad.as_uri())
    assert any("undefinedFunction" in m for m in _console_messages(run.stderr))

    # the report itself: no console messages at all (it has no scripts, loads nothing)
    screen = screenshot(tmp_path, report)
    assert screen.shape == (3000, 1200, 3)

    # where the spectrum's <img> is laid out: the same page plus a script that writes the box
    probe = tmp_path / "probe.html"
    script = (
        "<script>var r=document.getElementById('chart-spectrum').getBoundingClientRect();"
        "document.body.setAttribute('data-box',JSON.stringify([r.left,r.top,r.width,r.height]));"
        "</script></body>"
    )
    probe.write_text(page.replace("</body>", script))
    dom = _chromium(tmp_path, "--dump-dom", probe.as_uri()).stdout
    left, top, width, height = (round(v) for v in json.loads(html.unescape(
        re.search(r'data-box="([^"]*)"', dom).group(1))))  # fmt: skip
    uri = re.search(r'id="chart-spectrum" src="data:image/png;base64,([^"]+)"', page).group(1)
    chart = np.asarray(Image.open(io.BytesIO(base64.b64decode(uri))).convert("RGB")).astype(int)
    assert (height, width) == chart.shape[:2]  # drawn at its own size
    assert top + height <= 3000
    region = screen[top : top + height, left : left + width]
    # the screenshot shows the chart there: nearly every pixel as in the PNG ...
    assert (np.abs(region - chart).max(axis=2) <= 8).mean() > 0.98
    # ... including the median lines in their colours (Okabe-Ito #0072b2, #e69f00)
    for rgb in ((0x00, 0x72, 0xB2), (0xE6, 0x9F, 0x00)):
        near = (np.abs(region - np.array(rgb)).max(axis=2) <= 12).sum()
        assert near > 200, rgb


def test_package_import_registers_the_accessor():
    code = "import xarray as xr, pound_mc; print(hasattr(xr.Dataset(), 'pound'))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "True"


# -- bad input: one line naming the file and the option, exit status 2, nothing left behind ----
def _fails(capsys, *argv, names=()) -> str:
    """Run ``pound-mc argv``; check a clean input error (status 2, one line, no traceback)."""
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for name in names:
        assert str(name) in err, (name, err)
    return err


def _left(folder: Path) -> list[str]:
    """Names under ``folder`` other than the datasets a test wrote itself."""
    return sorted(p.name for p in folder.rglob("*") if p.suffix != ".nc")


def test_report_and_distribution_of_a_study_without_grid(tmp_path):
    # a study without [grid]: the report crashed on the spectrum, plot --kind distribution
    # refused the chart run draws
    study = tmp_path / "nogrid.toml"
    study.write_text(study_text(study={"name": "nogrid"}, grid=None, sampling={"n": 6}))
    assert main(["run", str(study), "--out", str(tmp_path), "--no-progress", "--no-plot"]) == 0
    nogrid = tmp_path / "nogrid.nc"
    page = tmp_path / "nogrid.html"
    assert main(["report", str(nogrid), "--out", str(page)]) == 0
    text = page.read_text()
    assert 'id="chart-distribution"' in text and 'id="chart-spectrum"' not in text
    # the chart run drew: one group, the samples that pounded
    fig = draw(nogrid, "distribution")
    with xr.open_dataset(nogrid) as ds:
        pounded = int(((ds["impacts"] > 0) & (ds["status"] == 0)).sum())
    assert pounded > 0 and fig.axes[1].patches[0].get_data().values.sum() == pounded


def test_dataset_with_an_empty_dimension_is_an_input_error(ds, tmp_path, capsys):
    empty = tmp_path / "empty.nc"
    ds.isel(sample=slice(0, 0)).to_netcdf(empty, unlimited_dims=["sample"])
    _fails(capsys, "report", empty, "--out", tmp_path / "r.html", names=(empty, "'sample'"))
    _fails(capsys, "plot", empty, "--kind", "spectrum", "--out", tmp_path / "s.png")
    assert _left(tmp_path) == []


def test_sel_values_are_read_against_the_coordinate(tiny, tmp_path, capsys):
    out = tmp_path / "x.png"
    for item, hint in (("sample=0", "--sample"), ("record=builtin:elcentro", "--record")):
        _fails(capsys, "plot", tiny, "--kind", "history", "--sel", item, "--out", out,
               names=(tiny, "--sel", hint))  # fmt: skip
    for kind in ("spectrum", "probability", "distribution", "contacts", "history"):
        for value in ("abc", ""):
            _fails(capsys, "plot", tiny, "--kind", kind, "--sel", f"contact_gap_m={value}",
                   "--out", out, names=(tiny, "--sel", "contact_gap_m"))  # fmt: skip
    assert _left(tmp_path) == []


def test_sel_takes_a_material_name_on_a_material_axis():
    from pound_mc.cli.analysis import _typed_sel
    from pound_mc.errors import InputError

    grid = {"contact_material": [0.0, 1.0], "record": ["a"], "sample": [0]}
    ds = xr.Dataset(
        {"peak_force": (("record", "contact_material", "sample"), np.zeros((1, 2, 1))),
         "material": ("contact_material", ["steel", "concrete"])},
        coords=grid,
    )  # fmt: skip
    assert _typed_sel(ds, {"contact_material": "concrete"}) == {"contact_material": 1.0}
    assert _typed_sel(ds, {"contact_material": "0"}) == {"contact_material": 0.0}
    with pytest.raises(InputError, match="--sel: contact_material='wood'.*steel, concrete"):
        _typed_sel(ds, {"contact_material": "wood"})


def test_output_path_is_checked_before_drawing(tiny, tmp_path, capsys):
    from matplotlib.figure import Figure

    from pound_mc.analysis.style import save
    from pound_mc.errors import OutputError

    folder = tmp_path / "adir.png"
    folder.mkdir()
    afile = tmp_path / "afile"
    afile.write_text("keep")
    _fails(capsys, "plot", tiny, "--kind", "spectrum", "--out", folder, names=(folder,))
    _fails(capsys, "plot", tiny, "--kind", "spectrum", "--out", afile / "x.png",
           names=(afile / "x.png", "is a file"))  # fmt: skip
    _fails(capsys, "plot", tiny, "--kind", "spectrum", "--out", tmp_path / "x.txt",
           names=("--out", ".png"))  # fmt: skip
    _fails(capsys, "report", tiny, "--out", folder, names=(folder, "--out"))
    scene = ROOT / "studies" / "scenes" / "b1.toml"
    for argv in (["simulate", scene], ["materials"], ["droptest"]):
        _fails(capsys, *argv, "--plot", folder, names=(folder, "--plot"))
        _fails(capsys, *argv, "--plot", tmp_path / "x.txt", names=("--plot", ".png"))
    with pytest.raises(OutputError, match=f"^{re.escape(str(folder))}: is a folder"):
        save(Figure(), folder)
    assert _left(tmp_path) == ["adir.png", "afile"] and afile.read_text() == "keep"


def test_required_gap_probability_must_lie_between_0_and_1(tiny, tmp_path, capsys):
    out = tmp_path / "gap.png"
    for value in ("0", "1", "1.5", "-0.1", "nan"):
        _fails(capsys, "plot", tiny, "--kind", "required-gap", "--probability", value,
               "--out", out, names=(tiny, "--probability"))  # fmt: skip
    assert not out.exists()
    assert main(["plot", str(tiny), "--kind", "required-gap", "--probability", "0.25",
                 "--out", str(out)]) == 0  # fmt: skip
    labels = [t.get_label() for t in draw(tiny, "required-gap", probability=0.25).axes[0].lines]
    assert "target 0.25" in labels


@pytest.mark.parametrize(
    ("kind", "text", "names"),
    [
        ("work-precision", "scene,method,seconds,err_peak_force\nB1,adaptive,abc,xyz\n",
         ("seconds", "'abc'")),
        ("work-precision", "scene,method,seconds,err_peak_force\n", ("no rows",)),
        ("work-precision", "", ("not a CSV",)),
        ("stability", "method,beta,predicted,observed\nnewmark,abc,1,2\n", ("beta", "'abc'")),
        ("stability", "method,beta,predicted,observed\n", ("no rows",)),
    ],
)  # fmt: skip
def test_bad_numerics_tables_are_input_errors(tmp_path, capsys, kind, text, names):
    table = tmp_path / "table.csv"
    table.write_text(text)
    _fails(capsys, "plot", table, "--kind", kind, "--out", tmp_path / "x.png",
           names=(table, *names))  # fmt: skip
    assert _left(tmp_path) == ["table.csv"]


def test_plot_refuses_options_its_chart_does_not_read(tiny, tmp_path, capsys):
    from pound_mc.cli.analysis import PLOT_OPTIONS
    from pound_mc.cli.commands import KINDS

    assert set(PLOT_OPTIONS) == set(KINDS)
    out = tmp_path / "x.png"
    for argv, names in (
        (("--kind", "spectrum", "--im", "pga_g"), ("--im", "--kind spectrum", "only to fragility")),
        (("--kind", "fragility", "--by", "record"), ("--by", "only to distribution")),
        (("--kind", "probability", "--sample", "0"), ("--sample", "only to history")),
        (("--kind", "spectrum", "--probability", "0.2"), ("--probability", "required-gap")),
        (("--kind", "restitution", "--sel", "gap_m=0"), ("--sel",)),
        (("--kind", "required-gap", "--event", "pounding"), ("--event", "only to fragility")),
    ):
        _fails(capsys, "plot", tiny, *argv, "--out", out, names=names)
    assert not out.exists()
    # the history of a scene file is one run: no record, sample or grid to choose
    scene = ROOT / "studies" / "scenes" / "b1.toml"
    _fails(capsys, "plot", scene, "--kind", "history", "--record", "0", "--out", out,
           names=("--record", "a scene file's history"))  # fmt: skip


def test_analysis_options_out_of_range_are_input_errors(tiny, ds, tmp_path, capsys):
    out = tmp_path / "x.png"
    _fails(capsys, "plot", tiny, "--kind", "history", "--record", "5", "--out", out,
           names=(tiny, "record must be in 0..0, got 5"))  # fmt: skip
    # a record name the dataset lacks: its names as text (they were np.str_ reprs)
    _fails(capsys, "plot", tiny, "--kind", "history", "--record", "each", "--out", out,
           names=(tiny, "record has no value 'each'; it has builtin:"))  # fmt: skip
    for option, kind in (("--line", "spectrum"), ("--by", "distribution")):
        for name in ("foo", "sample"):
            _fails(capsys, "plot", tiny, "--kind", kind, option, name, "--out", out,
                   names=(tiny, option, f"no grid dimension '{name}'"))  # fmt: skip
    _fails(capsys, "plot", tmp_path, "--kind", "spectrum", "--out", out,
           names=(tmp_path, "is a folder"))  # fmt: skip
    # every simulation unstable (numbers NaN): no blank chart; the report still says so
    unstable = tmp_path / "unstable.nc"
    ds.assign(status=ds["status"] * 0 + 1, peak_force=ds["peak_force"] * np.nan).to_netcdf(unstable)
    for kind in ("spectrum", "probability", "distribution", "required-gap"):
        _fails(capsys, "plot", unstable, "--kind", kind, "--out", out,
               names=(unstable, "no simulation ended with status ok"))  # fmt: skip
    assert _left(tmp_path) == []
    page = tmp_path / "unstable.html"
    assert (
        main(
            [
                "report",
                str(unstable),
                "--out",
                str(page),
            ]
        )
        == 0
    )
    assert "No charts: no simulation ended with status ok or inaccurate" in page.read_text()
    # every run flagged inaccurate: the pounding probability counts them (as plot draws it),
    # the charts of peak forces are left out, and the page says so
    flagged = tmp_path / "flagged.nc"
    ds.assign(status=ds["status"] * 0 + 3).to_netcdf(flagged)
    page = tmp_path / "flagged.html"
    assert main(["report", str(flagged), "--out", str(page)]) == 0
    text = page.read_text()
    assert "the charts of peak forces are left out" in text
    assert '<figure id="probability">' in text and '<figure id="spectrum">' not in text
    for kind in ("probability", "required-gap"):  # plot counts them as the report does
        assert main(["plot", str(flagged), "--kind", kind, "--out", str(out)]) == 0
    assert main(["plot", str(flagged), "--kind", "spectrum", "--out", str(out)]) == 2


def test_separation_rule_of_infinite_peaks_is_nan_without_warning():
    import warnings

    from pound_mc.physics.separation import gap_ddc

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert np.isnan(gap_ddc(np.inf, np.inf, 0.5)) and np.isnan(gap_ddc(np.nan, 1.0, 0.5))
        assert gap_ddc(3.0, 4.0, 0.0) == 5.0  # sqrt(3^2 + 4^2) with rho = 0 (the SRSS rule)
