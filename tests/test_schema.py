"""The declared tables: generated reference files, JSON Schema, validator and scene_of."""

import math
import tomllib
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from pound_mc.errors import InputError, InputErrors
from pound_mc.physics.relations import xi_from_e
from pound_mc.scene import scene_from_dict, schema, simulate
from pound_mc.study.definition import NUMERIC_SCENE_KEYS, study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.schema import json_schema, reference_markdown, write_reference

STUDIES = Path(__file__).resolve().parents[1] / "studies"
SHIPPED = sorted(STUDIES.glob("*.toml")) + sorted((STUDIES / "scenes").glob("*.toml"))

SCENE = {
    "record": {"source": "builtin:knet-akt013", "duration_s": 2.0},
    "left": {"period_s": 0.5, "mass_kg": 1.0e6},
    "right": {"period_s": 1.0, "mass_kg": 1.0e6},
    "contact": {"gap_m": 0.01, "beta": 2.75e9, "e": 0.65},
}


def test_checked_in_reference_is_up_to_date():
    stale = write_reference(STUDIES, check=True)
    assert not stale, f"run `python -m pound_mc.study` to regenerate {stale}"


def test_reference_lists_every_declared_key():
    page = reference_markdown()
    for table in (schema.RECORD, schema.SDOF, schema.SHEAR, schema.WALL, schema.CONTACT,
                  schema.INTEGRATOR):  # fmt: skip
        for f in table.fields:
            assert f"| `{f.name}` |" in page, (table.name, f.name)


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_files_match_the_json_schema(path):
    assert len(SHIPPED) >= 8  # six studies and two scenes ship today
    jsonschema.Draft202012Validator.check_schema(json_schema())
    jsonschema.validate(tomllib.loads(path.read_text()), json_schema())


def test_json_schema_takes_walls_and_rows():
    """A wall on the right and a row (``[[buildings]]``) run (``scene_from_dict`` takes them)
    but the JSON Schema refused both; it now refuses a file with a row and a pair at once.
    A study file may give a row too (DESIGN.md section 10)."""
    sdof = {"model": "sdof", "period_s": 0.5, "damping_ratio": 0.05, "mass_kg": 1.0e6}
    wall = {**SCENE, "right": {"model": "wall"}}
    row = {k: v for k, v in SCENE.items() if k not in ("left", "right")}
    row["buildings"] = [sdof, {**sdof, "period_s": 1.0}, {"model": "wall", "height_m": 3.0}]
    for data in (wall, row):
        scene_from_dict(data, file="s.toml")
        jsonschema.validate(data, json_schema())
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate({**row, "left": sdof, "right": sdof}, json_schema())
    study = {**row, "study": {"name": "s", "seed": 1}, "grid": {"buildings.1.period_s": [1, 2]}}
    jsonschema.validate(study, json_schema())
    with pytest.raises(jsonschema.ValidationError):  # a key no building has
        jsonschema.validate({**study, "grid": {"buildings.1.heigth_m": [1, 2]}}, json_schema())
    for bad in (
        {**row, "buildings": [sdof]},  # one building
        {**row, "left": sdof},  # a row and half a pair
        {**row, "buildings": [{"model": "wall"}, sdof]},  # a wall first
    ):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, json_schema())


@pytest.mark.parametrize(
    ("patch", "where"),
    [
        ({"left": {"period_s": -0.5, "mass_kg": 1.0e6}}, "period_s"),
        ({"contact": {"model": "hertzdamp", "e": 0.6, "relation": "jankowski2008"}}, "relation"),
        ({"contact": {"model": "jankowski", "xi": 0.3, "colour": "red"}}, "colour"),
        ({"integrator": {"substeps": 2}}, "substeps"),
    ],
)
def test_json_schema_refuses_what_the_validator_refuses(patch, where):
    data = {**SCENE, **patch}
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(data, json_schema())
    with pytest.raises(InputError) as info:
        scene_from_dict(data, file="s.toml")
    assert where in str(info.value)


def test_varied_keys_are_the_numeric_scene_keys():
    # the keys a study could vary before the tables were declared (DESIGN.md section 6)
    assert NUMERIC_SCENE_KEYS == {
        "left.period_s", "left.damping_ratio", "left.mass_kg", "right.period_s",
        "right.damping_ratio", "right.mass_kg", "contact.gap_m", "contact.beta",
        "contact.k_N_per_m", "contact.xi", "contact.e", "integrator.dt_s",
        "contact.e_quantile",  # restitution set per impact (issue 14)
        # the buildings' yield keys and a shear building's storey lists (issue #13)
        *(f"{side}.{name}" for side in ("left", "right") for name in (
            "yield_disp_m", "post_yield_ratio", "storey_mass_kg", "storey_stiffness_N_per_m",
            "storey_yield_disp_m")),
    }  # fmt: skip


def test_scene_reports_every_problem_at_once():
    data = {
        **SCENE,
        "left": {"period_s": -1.0, "mass_kg": 1.0e6, "width_m": 3.0},
        "contact": {"gap_m": -0.01, "beta": 2.75e9, "e": 1.5},
        "integrator": {"method": "euler"},
    }
    with pytest.raises(InputErrors) as info:
        scene_from_dict(data, file="s.toml")
    keys = {e.key for e in info.value.errors}
    assert keys == {"left.period_s", "left.width_m", "contact.gap_m", "contact.e",
                    "integrator.method"}  # fmt: skip
    assert all(e.file == "s.toml" for e in info.value.errors)


def test_hertzdamp_takes_its_own_relations():
    assert set(schema.allowed_relations("hertzdamp")) == {"muthukumar2006", "ye2009"}
    assert schema.default_relation("hertzdamp") == "ye2009"  # Ye et al. (2009), the default
    assert "jankowski2008" in schema.allowed_relations("jankowski")
    contact = {"model": "hertzdamp", "beta": 7.9e9, "e": 0.6, "relation": "jankowski2008"}
    with pytest.raises(InputError) as info:
        scene_from_dict({**SCENE, "contact": contact}, file="s.toml")
    assert info.value.key == "contact.relation" and "ye2009" in info.value.message
    contact.pop("relation")
    scene = scene_from_dict({**SCENE, "contact": contact})
    # the kernel takes e itself; no constant xi is reported for a law without one
    # no constant damping ratio: hertzdamp sets zeta per impact from e and the impact velocity
    assert scene.relation == "ye2009" and np.isnan(scene.xi)
    assert scene.modal_arrays()["xi"][0] == 0.6


def test_relation_sets_xi_of_the_jankowski_law():
    contact = {**SCENE["contact"], "relation": "jankowski2006"}
    scene = scene_from_dict({**SCENE, "contact": contact})
    # Jankowski (2006): xi = 9 sqrt5 (1 - e^2) / (2 e (e (9 pi - 16) + 16))
    e = 0.65
    expected = 9 * math.sqrt(5) * (1 - e**2) / (2 * e * (e * (9 * math.pi - 16) + 16))
    assert scene.xi == pytest.approx(expected, rel=1e-12)


def test_missing_record_file_is_found_without_reading_records():
    data = {**SCENE, "record": {"source": "nope/missing.AT2"}}
    with pytest.raises(InputError) as info:
        scene_from_dict(data, file="/tmp/s.toml")
    assert info.value.key == "record.source" and "missing.AT2" in info.value.message


STUDY = """
[study]
name = "probe"
seed = 3
[record]
source = "builtin:knet-akt013"
duration_s = 3.0
pga_g = 0.3
[left]
period_s = 0.5
mass_kg = 1.0e6
[right]
period_s = 1.0
mass_kg = 1.0e6
[contact]
beta = 2.75e9
e = 0.65
[integrator]
dt_s = 0.01
[grid]
"left.period_s" = [0.3, 0.6]
"contact.gap_m" = [0.0, 0.002, 0.004]
[sampling]
n = 4
[sampling.vary]
"contact.e" = { material = "concrete" }
"contact.beta" = { distribution = "lognormal", median = 2.75e9, sigma_ln = 0.3 }
"""


def test_records_are_read_by_the_engine_with_file_and_key(tmp_path):
    path = tmp_path / "long.toml"
    study = study_from_text(STUDY.replace("duration_s = 3.0", "duration_s = 1.0e4"), file=path)
    with pytest.raises(InputError) as info:  # valid keys: only reading finds it too long
        StudyEngine(study)
    errors = getattr(info.value, "errors", [info.value])
    assert [(e.file, e.key) for e in errors] == [(str(path), "record.duration_s")]


def test_scene_of_is_what_the_kernels_get():
    engine = StudyEngine(study_from_text(STUDY))
    indices = np.arange(engine.study.n_simulations)
    p = engine.parameters(indices)
    for i in (0, 5, 13, 23):
        scene = engine.scene_of(i)
        assert 2 * np.pi / scene.left.omega[0] == pytest.approx(p["left.period_s"][i], 1e-14)
        assert scene.gap_m[0] == p["contact.gap_m"][i]
        assert scene.stiffness == p["contact.beta"][i]
        assert scene.xi == p["contact.xi"][i] == xi_from_e(scene.e, "jankowski2008")
        assert scene.dt_s == p["integrator.dt_s"][i] == 0.01


@pytest.mark.parametrize("shear", [False, True], ids=["sdof", "shear"])
@pytest.mark.parametrize("law", ["jankowski", "hertzdamp"])
def test_batch_runs_are_the_scenes_they_describe(law, shear, tmp_path):
    """A hertzdamp study ran every batch simulation with the kernels' damping parameter NaN
    (the dataset's reported xi, not e): no contact force at all, status ok.  Each batch run
    now equals its scene run alone (:meth:`StudyEngine.scene_of`, :func:`simulate`)."""
    text = STUDY.replace("[contact]\n", f'[contact]\nmodel = "{law}"\n')
    if shear:  # the scene-batch path: 2 + 3 storeys, a contact at each of the 2 shared floors
        shear_text = (
            '\nmodel = "shear"\nstorey_mass_kg = [1.0e6, 1.0e6{more}]\n'
            "storey_stiffness_N_per_m = [1.0e9, 0.8e9{stiff}]\nstorey_height_m = [3.0, 3.0{h}]\n"
        )
        text = text.replace(
            "[left]\nperiod_s = 0.5\nmass_kg = 1.0e6\n",
            "[left]" + shear_text.format(more="", stiff="", h=""),
        )
        text = text.replace("[right]\nperiod_s = 1.0\nmass_kg = 1.0e6\n",
                            "[right]" + shear_text.format(more=", 1.0e6", stiff=", 0.6e9",
                                                          h=", 3.0"))  # fmt: skip
        text = text.replace('"left.period_s" = [0.3, 0.6]\n', "")
    engine = StudyEngine(study_from_text(text, file=tmp_path / "probe.toml"))
    indices = np.arange(engine.study.n_simulations)
    out = engine.run_indices(indices)
    assert (out["peak_force"][out["impacts"] > 0] > 0).all() and out["impacts"].max() > 0
    for i in indices[:: max(1, indices.size // 6)]:
        alone = simulate(engine.scene_of(int(i))).outputs
        for name in ("peak_force", "impacts", "max_penetration", "peak_disp_left"):
            assert out[name][i] == pytest.approx(alone[name], rel=1e-12), (i, name)
