"""The notebook API of a study dataset: every ``ds.pound.plot`` method on the Axes given, the
required gap of every study, ``sel`` as the charts document it, and the worked notebook on the
studies whose datasets it meets (the quickstart's intensity and gap axes, yielding buildings).

The datasets are the cut-down shipped studies of ``test_analysis_matrix`` (a few seconds each).
"""

import copy as copy_module
import pickle
import re
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from test_analysis import execute_notebook
from test_analysis_matrix import small_study

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis.style import write_atomically
from pound_mc.cli import main
from pound_mc.scene import simulate
from studies import pounding_counted

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    """``{study stem: path of its cut-down dataset}``, each run once when first asked for."""
    folder = tmp_path_factory.mktemp("api")
    done = {}

    def get(stem: str) -> Path:
        if stem not in done:
            study = folder / f"{stem}.toml"
            study.write_text(small_study(ROOT / "studies" / f"{stem}.toml"))
            args = ["run", str(study), "--out", str(folder), "--no-progress", "--no-plot"]
            assert main(args) == 0
            done[stem] = folder / f"{tomllib.loads(study.read_text())['study']['name']}.nc"
        return done[stem]

    return get


def _open(path):
    with xr.open_dataset(path) as ds:
        return ds.load()


def _axes(n):
    fig = Figure(figsize=(4 * n, 3), layout="constrained")
    return fig.subplots(1, n, squeeze=False).ravel()


def test_every_plot_method_draws_on_the_axes_given(small):
    ds = _open(small("quickstart"))
    n_gaps = ds.sizes["contact_gap_m"]
    for name, n, kwargs in (
        ("spectrum", 1, {}),
        ("spectrum_panels", 1, {}),  # no material axis: the one chart
        ("probability", 1, {"rules": None}),
        ("required_gap", 1, {"rules": None}),
        ("distribution", 2, {}),
        ("restitution", 1, {}),
        ("fragility", n_gaps, {"n_boot": 20}),  # a panel per gap
    ):
        given = _axes(n)
        got = getattr(ds.pound.plot, name)(ax=given if n > 1 else given[0], **kwargs)
        got = np.atleast_1d(got)
        assert [id(a) for a in got] == [id(a) for a in given], name
        assert any(a.lines or a.collections or a.patches for a in given), name
        # and on a figure of its own: the Axes it made
        own = np.atleast_1d(getattr(ds.pound.plot, name)(**kwargs))
        assert all(isinstance(a, Axes) for a in own), name
        # a panel each, without the spare Axes a grid hides (its last row)
        assert len(own) == n and all(a.get_visible() for a in own), name
    with pytest.raises(ValueError, match=f"draws {n_gaps} panel"):  # an Axes per panel
        ds.pound.plot.fragility(ax=_axes(n_gaps - 1), n_boot=20)
    # a grid of more Axes than panels (plt.subplots(2, 3) for 5 gaps) was refused: the spare
    # ones are hidden
    grid = _axes(n_gaps + 1)
    got = ds.pound.plot.fragility(ax=grid, n_boot=20)
    assert [id(a) for a in got] == [id(a) for a in grid[:n_gaps]]
    assert [a.get_visible() for a in grid] == [True] * n_gaps + [False]


def test_required_gap_chart_marks_the_gap_the_api_finds(small):
    ds = _open(small("quickstart"))
    ax = _axes(1)[0]
    ds.pound.plot.required_gap(ax=ax, rules=None, probability=0.5)
    found = ds.pound.required_gap(probability=0.5, rules=False)["required_gap"]
    # the diamonds: errorbar markers at (gap [mm], target), one per line with a finite gap
    marks = sorted(float(ln.get_xdata()[0]) for ln in ax.lines if ln.get_marker() == "D")
    expected = sorted(float(g) * 1e3 for g in found.values.ravel() if np.isfinite(g))
    assert expected  # P = 0.5 is reached within the grid's gaps: a diamond per such line
    np.testing.assert_allclose(marks, expected)
    # the title says the gap the first and the last line with a diamond need, in mm
    title = ax.get_title()
    assert title.startswith("Gap for 50 % pounding probability: ")
    first = next(float(g) * 1e3 for g in found.values.ravel() if np.isfinite(g))
    assert (f"{first:.0f}" if first >= 100 else f"{first:.3g}") + " mm at PGA " in title
    assert "diamonds" not in title  # the method is the caption's
    assert "Diamonds: where each line" in ax.figure._pound_caption_artist.get_text()


def test_required_gap_of_a_shear_study_leaves_the_rules_out(small):
    ds = _open(small("shear_spectrum"))
    found = ds.pound.required_gap(probability=0.1)
    assert "gap_abs" not in found and "SDOF" in found.attrs["rules"]
    # the probability per gap is the dataset's: simulations with an impact over those counted
    # (status ok or flagged inaccurate)
    ok = pounding_counted(ds)
    p = ((ds["impacts"] > 0) & ok).sum(("record", "sample")) / ok.sum(("record", "sample"))
    np.testing.assert_allclose(
        found["pounding_probability"].transpose(*p.dims).values, p.values, rtol=1e-12
    )


def test_spectrum_sel_picks_lines_and_refuses_what_it_cannot_hold(small):
    ds = _open(small("quickstart"))
    gaps = ds["contact_gap_m"].values
    ax = ds.pound.plot.spectrum(sel={"contact_gap_m": [gaps[-1], gaps[0]]})
    assert [ln.get_label() for ln in ax.lines] == [f"{g * 1e3:g} mm" for g in (gaps[-1], gaps[0])]
    # the lines are the median over records and samples pooled [MN] (numpy, ok runs)
    force = np.where(ds["status"].values == 0, ds["peak_force"].values, np.nan)
    dims = list(ds["peak_force"].dims)
    pooled = np.nanmedian(force, axis=(dims.index("record"), dims.index("sample"))) / 1e6
    gap_axis = [d for d in dims if d not in ("record", "sample")].index("contact_gap_m")
    np.testing.assert_allclose(ax.lines[1].get_ydata(), np.take(pooled, 0, axis=gap_axis))
    # record="median": the median over records of each record's median over samples
    ax = ds.pound.plot.spectrum(sel={"contact_gap_m": [gaps[0]]}, record="median")
    q = ds["peak_force_quantile"].sel(quantile=0.5).median("record") / 1e6
    np.testing.assert_allclose(ax.lines[0].get_ydata(), q.isel(contact_gap_m=0).values)
    with pytest.raises(ValueError, match="horizontal axis"):
        ds.pound.plot.spectrum(line=ds.pound.grid_dims[0])
    with pytest.raises(ValueError, match="no dimension 'colour'"):
        ds.pound.plot.spectrum(sel={"colour": 1})
    with pytest.raises(ValueError, match="horizontal axis"):
        ds.pound.plot.spectrum(sel={ds.pound.grid_dims[0]: 0.2})


def test_python_sel_takes_study_keys_and_material_names(small):
    """``sel=`` and the coordinates of ``simulate`` / ``history`` take what ``--sel`` takes: a
    study key for its dimension, a material by name.  ``sel={"right.period_s": 1.0}`` said "no
    dimension", a material name failed to convert to float, and ``simulate(...,
    contact_material="steel")`` raised a pandas TypeError."""
    ds = _open(small("jankowski_spectrum"))
    names = [str(n) for n in ds["material"].values]
    periods = ds["right_period_s"].values
    by_key = ds.pound.plot.spectrum(sel={"right.period_s": periods[-1]})
    by_dim = ds.pound.plot.spectrum(sel={"right_period_s": periods[-1]})
    for a, b in zip(by_key.lines, by_dim.lines, strict=True):
        np.testing.assert_array_equal(a.get_ydata(), b.get_ydata())
    k = len(names) - 1  # the last material, by name and by its coordinate value
    by_name = ds.pound.spectrum(contact_material=names[k])
    by_value = ds.pound.spectrum(contact_material=ds["contact_material"].values[k])
    np.testing.assert_array_equal(by_name.values, by_value.values)
    result, index = ds.pound.simulate(contact_material=names[k], sample=0)
    assert index["contact_material"] == k
    assert result.outputs["peak_force"] == pytest.approx(
        float(ds["peak_force"][tuple(index.values())]), rel=1e-12
    )
    ds.pound.plot.history(contact_material=names[k], sample=0)
    with pytest.raises(ValueError, match="material has no value 'glass'"):
        ds.pound.spectrum(contact_material="glass")


def test_a_material_axis_out_of_table_order(tmp_path, capsys):
    """A material grid not in the tables' order (timber, ceramics, steel: coordinate 2, 3, 0)
    failed with "index must be monotonic" in simulate, spectrum and history, and a material
    number off the axis (concrete, 1) drew the nearest one (timber) without a word."""
    from studies import SMALL_SDOF, write_study

    by_grid = {"contact.e": {"material": "grid"}, "contact.beta": {"material": "grid"}}
    grid = {"contact.material": ["timber", "ceramics", "steel"], "contact.gap_m": [0.0, 0.002],
            "left.period_s": None}  # fmt: skip
    study = write_study(tmp_path, SMALL_SDOF, study={"name": "mat", "seed": 3}, grid=grid,
                        sampling={"n": 4, "vary": by_grid})  # fmt: skip
    assert main(["run", str(study), "--out", str(tmp_path), "--no-progress", "--no-plot"]) == 0
    ds = _open(tmp_path / "mat.nc")
    assert ds["contact_material"].values.tolist() == [2.0, 3.0, 0.0]
    result, index = ds.pound.simulate(sample=1, contact_material="steel")
    assert index["contact_material"] == 2
    assert result.outputs["peak_force"] == pytest.approx(
        float(ds["peak_force"][tuple(index.values())]), rel=1e-12
    )
    steel = ds.pound.spectrum(**{"contact.material": "steel"})
    np.testing.assert_array_equal(steel.values, ds.pound.spectrum(contact_material=0).values)
    ds.pound.plot.history(sample=1, contact_material="steel")
    # a list of names: a line each, in the order given
    ax = ds.pound.plot.spectrum(sel={"contact.material": ["steel", "timber"]})
    assert [ln.get_label() for ln in ax.lines] == ["steel", "timber"]
    two = ds.pound.spectrum(contact_material=["steel", "timber"])
    assert two["contact_material"].values.tolist() == [0.0, 2.0]
    for value in (1, 1.0):  # concrete is not on this axis
        with pytest.raises(ValueError, match="has no value 1.*; it has timber, ceramics, steel"):
            ds.pound.plot.probability(sel={"contact.material": value})
    args = ["plot", str(tmp_path / "mat.nc"), "--out", str(tmp_path / "x.png")]
    assert main([*args, "--kind", "probability", "--sel", "contact.material=1"]) == 2
    assert "contact_material has no value 1.0; it has timber" in capsys.readouterr().err


def test_history_title_names_the_record(small):
    path = small("quickstart")
    ds = _open(path)
    name = str(ds["record"].values[1])
    axes = ds.pound.plot.history(record=name, sample=0)
    assert f"record {name}" in axes[0].figure._suptitle.get_text()


@pytest.mark.slow
@pytest.mark.parametrize("stem", ["quickstart", "inelastic_spectrum"])
def test_analysis_notebook_runs_on_the_studies_it_meets(stem, small, monkeypatch):
    outputs = execute_notebook(small(stem), monkeypatch)
    assert not [o for o in outputs if o.output_type == "error"]
    text = "".join(o.get("text", "") for o in outputs)
    images = [o for o in outputs if "image/png" in o.get("data", {})]
    if stem == "quickstart":  # intensity and gap axes: the fragility and required-gap cell
        assert "required_gap" in text and "theta" in text
        assert len(images) == 4  # spectrum, probability, required gap, history
        rerun, stored = re.search(r"rerun: ([\d.e+-]+) MN; dataset: ([\d.e+-]+) MN", text).groups()
        assert float(rerun) == pytest.approx(float(stored), rel=1e-12)
    else:  # yielding buildings: no intensity axis, no fragility cell
        assert "no intensity axis" in text and "no history for this study" not in text
        assert len(images) == 3  # spectrum, probability, history


def test_a_rule_hidden_under_another_says_so(small):
    ds = _open(small("quickstart"))
    span = float(np.ptp(ds["contact_gap_m"].values)) * 1e3  # the gap axis [mm]
    near = 0.03 + 0.005 * span * 1e-3  # half of 1 % of the axis from SRSS: drawn under it
    ax = ds.pound.plot.probability(rules={"ABS": 0.05, "SRSS": 0.03, "DDC": near})
    labels = [ln.get_label() for ln in ax.lines if "rule" in ln.get_label()]
    assert labels == [
        "ABS rule: 50 mm",
        "SRSS rule: 30 mm",
        f"DDC rule: {near * 1e3:.3g} mm (under the SRSS line)",
    ]


def test_sel_of_a_dimension_off_the_grid_and_a_failed_write_leave_nothing(small, tmp_path, capsys):
    path = small("quickstart")
    # quantile is a dimension of the dataset, not of its grid: refused, not ignored
    assert main(["plot", str(path), "--kind", "spectrum", "--sel", "quantile=0.5"]) == 2
    err = capsys.readouterr().err
    assert "--sel" in err and "no grid dimension 'quantile'" in err, err
    # a write that fails with something other than an OSError leaves no temporary file

    def fail(tmp):
        tmp.write_text("half")
        raise ValueError("not a PNG")

    with pytest.raises(ValueError, match="not a PNG"):
        write_atomically(tmp_path / "x.png", fail)
    assert list(tmp_path.iterdir()) == []


def test_the_scene_of_a_simulation_on_an_intensity_axis_reproduces_it(small):
    """``simulate(ds.pound.scene(...))`` ran the record unscaled on a study with an intensity
    axis (peak force 37.1 MN for the dataset's 35.4 MN): the scene now holds the record as the
    study ran it, and drops it only when the record table changes."""
    ds = _open(small("quickstart"))
    top = float(ds["pga_g"].values[-1])
    point = {"pga_g": top, "contact_gap_m": float(ds["contact_gap_m"].values[0])}
    scene = ds.pound.scene(record=0, sample=0, **point)
    stored = float(ds["peak_force"].sel(point).isel(record=0, sample=0))
    assert stored > 0 and simulate(scene).outputs["peak_force"] == stored
    scene.gap_m = scene.gap_m * 1.0  # another field: the held record stays
    assert simulate(scene).outputs["peak_force"] == stored
    scene.record = {**scene.record}  # the same table: still held
    assert simulate(scene).outputs["peak_force"] == stored
    for copy in (replace(scene, gap_m=scene.gap_m), copy_module.deepcopy(scene),
                 pickle.loads(pickle.dumps(scene))):  # fmt: skip
        assert simulate(copy).outputs["peak_force"] == stored  # copies keep it
    scene.record["duration_s"] = 5.0  # another record: read again (unscaled, cut)
    assert simulate(scene).outputs["peak_force"] != stored
