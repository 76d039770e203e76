"""Rows of buildings in studies: ``[[buildings]]``, ``"buildings.N.KEY"`` axes and sampled keys,
per-building outputs along ``building`` (DESIGN.md section 10)."""

import copy
import json

import numpy as np
import pytest
import xarray as xr

from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.study.dataset import BUILDING_VARIABLES
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from studies import dump_toml

SDOF = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
# Three SDOF buildings 3 mm apart on the first 5 s of El Centro at 0.3 g: both contacts pound.
ROW = {
    "study": {"name": "row3", "seed": 5},
    "record": {"source": "builtin:elcentro", "duration_s": 5.0, "pga_g": 0.3},
    "buildings": [
        {**SDOF, "period_s": 0.5},
        {**SDOF, "period_s": 1.0},
        {**SDOF, "period_s": 0.7, "hysteresis": "bilinear", "yield_disp_m": 0.02,
         "height_m": 3.0},
    ],  # fmt: skip
    "contact": {"model": "jankowski", "gap_m": 0.003, "beta": 2.75e9, "e": 0.65},
    "grid": {"buildings.1.period_s": [0.8, 1.2], "contact.gap_m": [0.0, 0.005]},
    "sampling": {"n": 2, "vary": {"contact.e": {"distribution": "uniform", "low": 0.5,
                                                "high": 0.8}}},
}  # fmt: skip


def _write(tmp_path, data) -> str:
    path = tmp_path / f"{data['study']['name']}.toml"
    path.write_text(dump_toml(data))
    return str(path)


@pytest.fixture(scope="module")
def row_run(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("row")
    path = _write(tmp, ROW)
    assert main(["run", path, "--out", str(tmp / "out"), "--no-progress"]) == 0
    with xr.open_dataset(tmp / "out" / "row3.nc") as ds:
        yield ds.load()


def test_row_study_equals_simulate_of_its_scenes(row_run):
    """A row of three as a study with a ``"buildings.1.period_s"`` axis: every simulation's
    outputs equal ``simulate`` of the same scene, written here from the tables by hand (not
    through the study engine)."""
    ds = row_run
    assert ds.sizes["building"] == 3 and ds.sizes["contact"] == 2
    np.testing.assert_array_equal(ds["building"].values, [0, 1, 2])
    np.testing.assert_array_equal(ds["contact_pair"].values, [0, 1])
    e = ds["e"].values
    for i, period in enumerate(ROW["grid"]["buildings.1.period_s"]):
        for j, gap in enumerate(ROW["grid"]["contact.gap_m"]):
            for k in range(2):
                data = copy.deepcopy({t: ROW[t] for t in ("record", "buildings", "contact")})
                data["buildings"][1]["period_s"] = period
                data["contact"].update(gap_m=gap, e=float(e[k]))
                res = simulate(scene_from_dict(data))
                at = ds.isel(record=0, buildings_1_period_s=i, contact_gap_m=j, sample=k)
                assert int(at["status"]) == 0
                assert float(at["peak_force"]) == res.outputs["peak_force"]
                assert float(at["peak_disp_right"]) == res.outputs["peak_disp_right"]
                np.testing.assert_array_equal(at["contact_peak_force"],
                                              res.contacts["peak_force"])  # fmt: skip
                for name in BUILDING_VARIABLES:
                    np.testing.assert_array_equal(at[name], [b[name] for b in res.buildings])
    # the first and the last building: the pair names
    np.testing.assert_array_equal(ds["peak_disp"].isel(building=0), ds["peak_disp_left"])
    np.testing.assert_array_equal(ds["peak_disp"].isel(building=2), ds["peak_disp_right"])
    np.testing.assert_array_equal(ds["peak_ductility"].isel(building=2),
                                  ds["peak_ductility_right"])  # fmt: skip
    assert np.isnan(ds["peak_ductility"].isel(building=[0, 1])).all()  # elastic
    assert (ds["peak_ductility"].isel(building=2) > 0).all()
    for name, (units, long_name, _) in BUILDING_VARIABLES.items():
        assert ds[name].dims[-1] == "building"
        assert ds[name].attrs["units"] == units and ds[name].attrs["long_name"] == long_name
    assert ds["buildings_1_period_s"].attrs["long_name"] == "building 1 natural period"
    assert list(ds["building_model"].values) == ["sdof"] * 3


def test_row_of_yielding_buildings_meets_the_reference():
    """The middle building's outputs, which no pair name carries, against the independent SciPy
    reference (its own peak |x| and drifts per building) at the defaults: within 1e-5."""
    data = copy.deepcopy({t: ROW[t] for t in ("record", "buildings", "contact")})
    data["buildings"][1].update(hysteresis="bilinear", yield_disp_m=0.01, height_m=3.0)
    s = scene_from_dict({**data, "integrator": {"tail_s": 0.0}})
    record = s.record_arrays()
    ref = reference_solution(s, record)
    res = simulate(s, record=record)
    assert res.outputs["impacts"] == ref["impacts"] > 0
    for mine, theirs in zip(res.buildings, ref["buildings"], strict=True):
        for key in ("peak_disp", "peak_ductility", "peak_drift"):
            if np.isnan(theirs[key]):
                assert np.isnan(mine[key]), key
            else:
                assert mine[key] == pytest.approx(theirs[key], rel=1e-5), (mine, key)
    assert res.buildings[1]["peak_ductility"] > 1.0  # the middle one yields


@pytest.mark.parametrize(
    ("change", "key", "words"),
    [
        ({"grid": {"buildings.7.period_s": [0.5, 1.0]}}, "grid.buildings.7.period_s",
         "no such building"),
        ({"sampling": {"n": 2, "vary": {"buildings.3.mass_kg": {"distribution": "uniform",
                                                                "low": 1e5, "high": 1e6}}}},
         "sampling.vary.buildings.3.mass_kg", "no such building"),
        ({"grid": {"buildings.0.storey_mass_kg": [1e5, 2e5]}},
         "grid.buildings.0.storey_mass_kg", "not a structural key of a sdof building"),
        ({"grid": {"left.period_s": [0.5, 1.0]}}, "grid.left.period_s", "buildings.N.period_s"),
        ({"grid": {"buildings.1.period_s": [0.0, 1.0]}}, "grid.buildings.1.period_s",
         "value 0"),
        ({"grid": {"buildings.01.period_s": [0.5, 1.0]}}, "grid.buildings.01.period_s",
         "not a numeric scene key"),
    ],
)  # fmt: skip
def test_bad_row_keys_name_the_file_and_key(tmp_path, capsys, change, key, words):
    data = {**copy.deepcopy(ROW), **change}
    path = _write(tmp_path, data)
    assert main(["check", path]) == 2
    err = capsys.readouterr().err
    assert path in err and key in err and words in err, err
    assert not (tmp_path / "outputs").exists()


def test_a_wall_is_no_building(tmp_path):
    data = copy.deepcopy(ROW)
    data["buildings"][2] = {"model": "wall"}
    data["grid"] = {"buildings.2.period_s": [0.5, 1.0]}
    with pytest.raises(InputError, match="building 2 is a wall"):
        study_from_text(dump_toml(data), file=tmp_path / "row3.toml")
    data["grid"] = {"buildings.1.period_s": [0.8, 1.2]}
    engine = StudyEngine(study_from_text(dump_toml(data)))
    layout = engine.result_layout()
    assert layout["peak_disp"][0] == (2,)  # two buildings; the wall has no entry
    out = engine.run_indices(np.arange(2))
    # the last building is the one before the wall: its peak is peak_disp_right
    np.testing.assert_array_equal(out["peak_disp"][:, 1], out["peak_disp_right"])


def test_pair_keys_of_a_row_are_refused_in_a_pair_study(tmp_path):
    data = {k: v for k, v in copy.deepcopy(ROW).items() if k != "buildings"}
    data["left"], data["right"] = ROW["buildings"][0], ROW["buildings"][1]
    data["grid"] = {"buildings.1.period_s": [0.5, 1.0]}
    with pytest.raises(InputError, match=r"not \[\[buildings\]\]"):
        study_from_text(dump_toml(data), file=tmp_path / "pair.toml")


def test_simulate_json_lists_every_building(tmp_path, capsys):
    """``simulate --json`` gains ``buildings`` (DESIGN.md section 10): the pair's two, or a
    row's, with the pinned keys; a wall has no entry."""
    data = {t: ROW[t] for t in ("record", "buildings", "contact")}
    path = tmp_path / "row.toml"
    path.write_text(dump_toml(data))
    assert main(["simulate", str(path), "--json"]) in (0, 1)
    info = json.loads(capsys.readouterr().out)
    assert [b["building"] for b in info["buildings"]] == [0, 1, 2]
    for b in info["buildings"]:
        assert set(b) == {"building", "model", "peak_disp", "peak_ductility", "peak_drift",
                          "residual_drift"}  # fmt: skip
    assert info["buildings"][0]["peak_disp"] == info["peak_disp_left_m"]
    assert info["buildings"][2]["peak_disp"] == info["peak_disp_right_m"]
    pair = {"record": ROW["record"], "left": ROW["buildings"][0], "right": {"model": "wall"},
            "contact": ROW["contact"]}  # fmt: skip
    path.write_text(dump_toml(pair))
    assert main(["simulate", str(path), "--json"]) in (0, 1)
    info = json.loads(capsys.readouterr().out)
    assert [b["building"] for b in info["buildings"]] == [0]
    assert info["buildings"][0]["peak_disp"] == info["peak_disp_left_m"]
