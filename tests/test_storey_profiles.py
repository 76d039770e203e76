"""Drift and ductility charts of yielding shear buildings: profiles over the storeys.

A small real study (a 3- and a 5-storey bilinear shear building, three gaps, two post-yield
ratios of the right building, four samples, 3 s of El Centro) is run once; the charts must draw,
per building, the median over the records and samples of the per-storey outputs
(``storey_peak_drift``, ``storey_peak_ductility``, pound_mc/study/dataset.py STOREY_VARIABLES)
of that building's storeys against their storey numbers.
"""

import numpy as np
import pytest
import xarray as xr

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis import profiles
from pound_mc.analysis.report import report_html
from pound_mc.cli import main
from pound_mc.study.definition import load_study
from pound_mc.study.runner import run_study
from studies import SMALL_SHEAR, write_study

GAPS = [0.0, 0.01, 0.04]
HELD = "right_post_yield_ratio"
STOREYS = {"left": [1, 2, 3], "right": [1, 2, 3, 4, 5]}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """Path and dataset of the small study of two yielding shear buildings (24 simulations)."""
    folder = tmp_path_factory.mktemp("storeys")
    path = write_study(
        folder,
        SMALL_SHEAR,
        study={"name": "shear_yield"},
        record={"duration_s": 3.0},
        left={"hysteresis": "bilinear", "storey_yield_disp_m": [0.006, 0.005, 0.004],
              "post_yield_ratio": 0.05},
        right={"hysteresis": "bilinear", "storey_yield_disp_m": [0.008, 0.007, 0.006, 0.005,
               0.004], "post_yield_ratio": 0.05},
        # charts of the storeys, not accuracy: no step doubling (some runs are flagged at 2 ms)
        integrator={"method": "newmark", "dt_s": 0.002, "tail_s": 0.5, "accuracy_check": False},
        grid={"contact.gap_m": GAPS, "right.post_yield_ratio": [0.05, 0.2]},
    )  # fmt: skip
    report = run_study(load_study(path), folder / "out", progress=False)
    with xr.open_dataset(report.path) as ds:
        ds.load()
    assert (ds["status"] == 0).all()
    assert (ds["storey_peak_ductility"] > 1.0).any()  # the buildings yield
    return report.path, ds


def _median(ds, name, side, held: int):
    """Median over records and samples of ``name`` at ``side``'s storeys, (gap, storey)."""
    ok = ds[name].where(ds["status"] == 0).isel({HELD: held})
    mine = ok.isel(storey=ds["storey_building"].values == side)
    return mine.median(("record", "sample")).transpose("contact_gap_m", "storey")


@pytest.mark.parametrize("quantity, scale, unit", [("drift", 100.0, "%"), ("ductility", 1.0, "-")])
def test_storey_profiles_draw_the_median_of_each_building_s_storeys(study, quantity, scale, unit):
    _, ds = study
    name = f"storey_peak_{quantity}"
    assert ds[name].attrs["units"] == "1"  # drift ratio and ductility: drawn in % and as is
    for sel, held in ((None, 0), ({HELD: 0.2}, 1)):
        axes = getattr(ds.pound.plot, quantity)(sel=sel)  # the Axes, left building's first
        fig = axes[0].figure
        assert len(axes) == len(fig.axes) == 2
        # the title: the largest median drawn, where it is, and the value the chart holds
        title = fig.get_suptitle()
        ratio = [0.05, 0.2][held]
        assert title.startswith(f"Peak {quantity} (right post-yield ratio {ratio:g}): median")
        medians = [_median(ds, name, s, held).values.max() * scale for s in ("left", "right")]
        shown = f"{max(medians):.3g}" + ("" if unit == "-" else f" {unit}")  # a ratio: no unit
        assert f"median up to {shown} (" in title
        for ax, side in zip(axes, ("left", "right"), strict=True):
            median = _median(ds, name, side, held)
            assert [line.get_label() for line in ax.lines] == ["0 mm", "10 mm", "40 mm"]
            for k, line in enumerate(ax.lines):
                np.testing.assert_allclose(line.get_xdata(), median[k].values * scale)
                np.testing.assert_array_equal(line.get_ydata(), STOREYS[side])
            assert ax.get_xlabel().endswith(f"[{unit}]") and side in ax.get_ylabel()
            assert ax.get_ylim() == (0.5, 5.5)  # both buildings on one storey scale
        assert axes[0].get_xlim() == axes[1].get_xlim()
        assert axes[1].get_legend().get_title().get_text() == "initial separation gap [mm]"


def test_storey_band_is_the_5_to_95_percent_range(study):
    _, ds = study
    ok = ds["storey_peak_drift"].where(ds["status"] == 0).isel({HELD: 0})
    right = ok.isel(storey=ds["storey_building"].values == "right", contact_gap_m=1)
    low, high = (right.quantile(q, ("record", "sample")).values * 100 for q in (0.05, 0.95))
    ax = ds.pound.plot.drift()[1]
    verts = ax.collections[1].get_paths()[0].vertices  # the band of the second line (10 mm)
    for storey, lo, hi in zip(STOREYS["right"], low, high, strict=True):
        at = verts[verts[:, 1] == storey, 0]
        np.testing.assert_allclose([at.min(), at.max()], [lo, hi])


def test_a_building_that_cannot_yield_has_no_ductility_panel(study):
    _, ds = study
    # an elastic right building's storey ductilities are NaN (tests/test_inelastic.py)
    left_only = ds["storey_peak_ductility"].where(ds["storey_building"] == "left")
    fig = profiles.profile_chart(ds.assign(storey_peak_ductility=left_only), quantity="ductility")
    (ax,) = fig.axes
    caption = fig._pound_caption_artist.get_text().replace("\n", " ")
    assert "The right building is left out" in caption
    np.testing.assert_array_equal(ax.lines[0].get_ydata(), STOREYS["left"])


def test_cli_plot_and_report_draw_the_storey_profiles(study, tmp_path):
    path, ds = study
    for kind in ("drift", "ductility"):
        assert main(["plot", str(path), "--kind", kind, "--out", str(tmp_path / "x.png")]) == 0
    page = report_html(ds, history=False)
    assert 'id="chart-drift"' in page and 'id="chart-ductility"' in page
