"""The studies shipped in ``studies/``: each validates as is; shrunken copies run end to end."""

import os
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pound_mc.analysis.gaps import study_gaps
from pound_mc.cli import main
from pound_mc.errors import InputErrors
from pound_mc.physics import materials
from pound_mc.study.definition import load_study, study_from_text
from pound_mc.study.runner import run_study
from studies import Whole, study_text

STUDIES = Path(__file__).resolve().parent.parent / "studies"
SHIPPED = sorted(STUDIES.glob("*.toml"))


def _tree(path: Path) -> list[str]:
    return sorted(str(p.relative_to(path)) for p in path.rglob("*"))


def test_the_issue_s_studies_are_shipped():
    names = {p.name for p in SHIPPED}
    assert {
        "quickstart.toml",
        "jankowski_spectrum.toml",
        "materials.toml",
        "separation_gap.toml",
    } <= names


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_shipped_study_checks_and_writes_nothing(path, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    outputs = STUDIES.parent / "outputs"
    before = _tree(outputs) if outputs.exists() else None
    assert main(["check", str(path), "--calibrate", "4"]) == 0
    out = capsys.readouterr().out
    assert "nothing written" in out
    assert os.listdir(tmp_path) == []
    assert (_tree(outputs) if outputs.exists() else None) == before
    # the size stated in the file's header comment is the plan's
    study = load_study(path)
    stated = re.search(r"= ([\d,]+) simulations", path.read_text())
    if stated:
        assert int(stated.group(1).replace(",", "")) == study.n_simulations


def _shrunken_separation_study() -> str:
    text = (STUDIES / "separation_gap.toml").read_text()
    text = text.replace('name = "separation_gap"', 'name = "separation_gap_small"')
    # short motions: 8 s with a 1-5 s strong phase
    short = 'params = { soil = "firm", duration_s = 8.0, t1_s = 1.0, t2_s = 5.0 }'
    assert text.count('params = { soil = "firm" }') == 20
    text = text.replace('params = { soil = "firm" }', short)
    text, count = re.subn(r"(?m)^n = \d+$", "n = 16", text)
    assert count == 1
    return text


@pytest.mark.slow
def test_separation_study_shrunken_runs_and_obeys_the_abs_bound(tmp_path, capsys):
    study = study_from_text(_shrunken_separation_study(), file=STUDIES / "separation_gap.toml")
    report = run_study(study, tmp_path, progress=False)
    assert report.complete
    with xr.open_dataset(report.path) as ds:
        ds = ds.load()
    gaps = study_gaps(ds)  # the same records, periods and damping, rebuilt from the dataset
    assert int(ds["status"].max()) == 0
    gap = ds["contact_gap_m"]
    pounded = ds["impacts"] > 0

    # for one record and sample, a motion that does not close gap g cannot close a larger one:
    # pounding is non-increasing along the gap axis, per simulation and so per record
    along = pounded.transpose(..., "contact_gap_m").values
    assert np.all(np.diff(along.astype(int), axis=-1) <= 0)
    p = ds["pounding_probability"]
    assert np.all(p.diff("contact_gap_m") <= 0)

    # a gap wider than |u1|max + |u2|max of the linear responses can never close (ABS rule)
    abs_gap = gaps["gap_abs"]
    assert not bool((pounded & (gap > abs_gap * (1 + 1e-6))).any())
    above = gap > float(abs_gap.max())
    assert bool(above.any()), "the gap axis must reach beyond the largest ABS gap"
    assert np.all(p.sel(contact_gap_m=gap[above]) == 0)
    assert float(p.isel(contact_gap_m=0).mean()) > 0.9

    # without an impact the engine's peak displacements are the linear ones
    for side in ("left", "right"):
        linear = gaps[f"linear_disp_{side}"]
        err = abs(ds[f"peak_disp_{side}"] - linear) / linear
        assert float(err.where(~pounded).max()) < 1e-3

    # the three rules for the chart: means over records and samples
    rules = (
        gaps[["gap_ddc", "gap_srss", "gap_abs"]].isel(contact_gap_m=0).mean(("record", "sample"))
    )
    with capsys.disabled():
        print(
            "\nseparation_gap (shrunken): required gaps, mean over records and samples: "
            + ", ".join(f"{k[4:].upper()} {float(v) * 1e3:.1f} mm" for k, v in rules.items())
            + "; pounding probability by gap: "
            + " ".join(
                f"{g * 1e3:.0f}:{v:.2f}"
                for g, v in zip(gap.values, p.mean("record").values, strict=True)
            )
        )
    assert float(rules["gap_ddc"]) <= float(rules["gap_srss"]) <= float(rules["gap_abs"])


MATERIAL_AXIS = study_text(
    study={"name": "material_axis", "seed": 5},
    contact={"gap_m": 0.0},
    grid=Whole(
        {
            "contact.material": ["timber", "steel", "ceramics", "concrete"],
            "contact.gap_m": [0.0, 0.002],
        }
    ),
    sampling={
        "method": None,
        "vary": {"contact.e": {"material": "grid"}, "contact.beta": {"material": "grid"}},
    },
)


def test_material_axis_takes_each_material_s_ranges(tmp_path):
    study = study_from_text(MATERIAL_AXIS)
    assert study.shape == (1, 4, 2, 8)
    assert list(study.grid["contact.material"]) == [2.0, 0.0, 3.0, 1.0]  # MATERIALS indices
    report = run_study(study, tmp_path, progress=False)
    with xr.open_dataset(report.path) as ds:
        ds = ds.load()
    assert list(ds["material"].values) == ["timber", "steel", "ceramics", "concrete"]
    assert ds["e"].dims == ("contact_material", "sample")
    assert ds["beta"].dims == ("contact_material", "sample")
    units = []
    for m, name in enumerate(ds["material"].values):
        ranges = materials.material_ranges(str(name))
        for key, var in (("e", "e"), ("beta", "beta")):
            lo, hi = ranges[key]
            values = ds[var].isel(contact_material=m).values
            assert np.all((values >= lo) & (values <= hi)), (name, key)
            units.append((values - lo) / (hi - lo))
    # common random numbers: every material maps the same design points
    for u in units[2::2]:
        assert np.allclose(u, units[0])
    assert np.all(ds["status"] == 0)
    assert np.all(ds["pounding_probability"].sel(contact_gap_m=0.0) == 1)
    # the runs really used each material's stiffness: softer timber, lower peak force
    force = ds["peak_force_mean"].sel(contact_gap_m=0.0).isel(record=0)
    by_name = dict(zip(ds["material"].values, force.values, strict=True))
    assert by_name["timber"] < by_name["concrete"] < by_name["steel"]


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ('"contact.material" = ["timber", "steel", "ceramics", "concrete"]',
         '"contact.material" = ["timber", "glass"]', "grid.contact.material"),
        ('"contact.material" = ["timber", "steel", "ceramics", "concrete"]',
         '"contact.material" = ["timber", "timber"]', "grid.contact.material"),
        ('"contact.material" = ["timber", "steel", "ceramics", "concrete"]',
         '"contact.material" = [1, 2]', "grid.contact.material"),
        ('"contact.material" = ["timber", "steel", "ceramics", "concrete"]\n', "",
         "sampling.vary.contact.e.material"),
        ('"contact.e" = { material = "grid" }\n"contact.beta" = { material = "grid" }',
         '"contact.e" = { material = "concrete" }', "grid.contact.material"),
    ],
)  # fmt: skip
def test_material_axis_errors(old, new, key):
    assert old in MATERIAL_AXIS
    with pytest.raises(InputErrors) as info:
        study_from_text(MATERIAL_AXIS.replace(old, new), file="m.toml")
    assert key in [e.key for e in info.value.errors]
