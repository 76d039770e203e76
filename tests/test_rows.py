"""Rows of buildings (``[[buildings]]``, left to right): contacts between neighbours, against
the independent SciPy reference.
"""

import tomllib
from dataclasses import replace

import numpy as np
import pytest

from pound_mc.analysis.plot_numerics import time_history_chart
from pound_mc.errors import InputError
from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate

SDOF = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
RECORD = {"source": "builtin:elcentro", "duration_s": 6.0, "pga_g": 0.2}
BILINEAR = {"hysteresis": "bilinear", "yield_disp_m": 0.01}


def row(*buildings, **contact):
    return scene_from_dict(
        {"record": RECORD, "buildings": list(buildings),
         "contact": {"model": "jankowski", "beta": 2.75e9, "xi": 0.35, "gap_m": 0.003,
                     **contact}}
    )  # fmt: skip


def test_contacts_between_neighbours():
    # three SDOFs: contacts 1-2 and 2-3, each with m_eff = m m / (m + m) = 5e5 kg; a wall may
    # close the row
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {**SDOF, "period_s": 0.7})
    assert [(c.pair, c.m_eff) for c in s.contacts] == [(0, 5.0e5), (1, 5.0e5)]
    a = s.kernel_arrays()
    assert a["psi"].shape == (2, 3)
    # the kernels' building codes: 0 the first, 1 the last ("left" / "right"), 2 the middle
    assert list(a["side"]) == [0, 2, 1]
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {"model": "wall"})
    assert [(c.pair, c.m_eff) for c in s.contacts] == [(0, 5.0e5), (1, 1.0e6)]
    # a wall is no building: the one before it is the last
    assert list(s.kernel_arrays()["side"]) == [0, 1, 2]


@pytest.mark.slow
def test_three_buildings_against_reference():
    # a 0.5 s, a 1.0 s and a 0.7 s SDOF 3 mm apart: both contacts pound; impacts per contact,
    # peak forces and each building's peak displacement as the SciPy reference
    # (peak_disp_right: the last building's)
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {**SDOF, "period_s": 0.7})
    record = s.record_arrays()
    ref = reference_solution(s, record)
    res = simulate(s, record=record)
    assert list(res.contacts["impacts"]) == list(ref["contact_impacts"])
    assert all(res.contacts["impacts"] > 0)
    for k in range(2):
        assert res.contacts["peak_force"][k] == pytest.approx(ref["contact_peak_force"][k],
                                                              rel=1e-4)  # fmt: skip
    for side in ("left", "right"):
        assert res.outputs[f"peak_disp_{side}"] == pytest.approx(ref[f"peak_disp_{side}"],
                                                                 rel=1e-4)  # fmt: skip
    assert [b["building"] for b in res.buildings] == [0, 1, 2]
    for mine, theirs in zip(res.buildings, ref["buildings"], strict=True):
        assert mine["peak_disp"] == pytest.approx(theirs["peak_disp"], rel=1e-4)
    assert res.buildings[0]["peak_disp"] == res.outputs["peak_disp_left"]
    assert res.buildings[2]["peak_disp"] == res.outputs["peak_disp_right"]
    # the middle building is neither: it moves most here (1.0 s between 0.5 s and 0.7 s)
    assert res.buildings[1]["peak_disp"] > res.outputs["peak_disp_right"]
    assert [c["pair"] for c in res.to_json()["contacts"]] == [1, 2]


def test_row_validation():
    base = {"record": RECORD, "contact": {"xi": 0.3}}
    for data, key in (
        ({"buildings": [{**SDOF, "period_s": 0.5}], }, "buildings"),
        ({"buildings": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}],
          "left": {**SDOF, "period_s": 0.5}}, "left"),
        ({"buildings": [{**SDOF, "period_s": 0.5}, {"model": "wall"},
                        {**SDOF, "period_s": 1.0}]}, "buildings[1].model"),
        # the SDOF beside a shear building lacks its height: its own key (was buildings[1])
        ({"buildings": [{**SDOF, "period_s": 0.5},
                        {"model": "shear", "storey_mass_kg": [1e6, 1e6],
                         "storey_stiffness_N_per_m": [1e8, 1e8], "storey_height_m": [3.0, 3.0]}]},
         "buildings[0].height_m"),
    ):  # fmt: skip
        with pytest.raises(InputError) as info:
            scene_from_dict({**base, **data})
        assert key in str(info.value)


def test_history_chart_draws_each_contacts_neighbours(tmp_path):
    """Contact 2 of a row redrew building 1 against building 2; building 3 was never drawn.
    Each building's floor is now drawn once, in the building's colour (the middle one was
    drawn twice, once per contact's colour)."""
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {**SDOF, "period_s": 0.7})
    res = simulate(s, history=True)
    floors = np.hstack([res.disp_left_m, res.disp_right_m])  # buildings 1, 2, 3
    np.testing.assert_array_equal(floors[:, 0] - floors[:, 1] - 0.003, res.penetration_m[:, 0])
    np.testing.assert_array_equal(floors[:, 1] - floors[:, 2] - 0.003, res.penetration_m[:, 1])
    lines = time_history_chart(res, tmp_path / "row.png").axes[0].lines
    assert [ln.get_label() for ln in lines] == [
        "building 0, floor 1", "building 1, floor 1", "building 2, floor 1",
    ]  # fmt: skip
    assert len({ln.get_color() for ln in lines}) == 3  # one colour per building
    for ln, k in zip(lines, (0, 1, 2), strict=True):
        np.testing.assert_allclose(ln.get_ydata(), floors[:, k] * 1e3)


def test_history_chart_names_a_wall_and_the_scene(tmp_path):
    """A wall closing a row was labelled "building 3, floor 1" (it has no floors); a scene's
    history named no scene (a study's names its simulation instead, test_analysis)."""
    s = replace(row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {"model": "wall"}),
                file="studies/scenes/my_row.toml")  # fmt: skip
    fig = time_history_chart(simulate(s, history=True), tmp_path / "row.png")
    # the wall stands still: not drawn
    assert [ln.get_label() for ln in fig.axes[0].lines] == [
        "building 0, floor 1", "building 1, floor 1",
    ]  # fmt: skip
    assert fig._suptitle.get_text() == "scene my_row.toml"


@pytest.mark.parametrize(
    "contact",
    [
        {"model": "hertzdamp", "e": 0.6},
        {"restitution": "velocity", "material": "concrete", "e_quantile": 1.0},
    ],
    ids=["hertzdamp", "e_quantile"],
)
def test_row_contact_damping_reaches_the_kernel(contact):
    """A row ran hertzdamp with no force at all (xi NaN: buildings passed through each other)
    and per-impact restitution at quantile 0 whatever e_quantile: the pair's damping parameter
    now.  Reference: the SciPy solution of the same row."""
    data = {
        "record": RECORD,
        "buildings": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}],
        "contact": {"gap_m": 0.003, **contact},
    }
    if "model" not in contact:
        data["contact"].update(model="jankowski", beta=2.75e9)
    s = scene_from_dict(data)
    record = s.record_arrays()
    ref = reference_solution(s, record)
    res = simulate(s, record=record)
    assert res.status == "ok" and ref["peak_force"] > 1e6
    assert res.outputs["peak_force"] == pytest.approx(ref["peak_force"], rel=1e-4)
    assert res.outputs["max_penetration"] == pytest.approx(ref["max_penetration"], rel=1e-4)


BOUC_WEN = {"hysteresis": "bouc-wen", "yield_disp_m": 0.01, "post_yield_ratio": 0.1}
YIELDING_ROWS = {
    # the middle building yields (ductility 5.1) between two elastic ones
    "bilinear-middle": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0, **BILINEAR},
                        {**SDOF, "period_s": 0.7}],
    # the first and the last yield (ductility 4.5 and 19), elastic-perfectly plastic
    "bilinear-ends": [{**SDOF, "period_s": 0.5, **BILINEAR}, {**SDOF, "period_s": 1.0},
                      {**SDOF, "period_s": 0.7, "hysteresis": "bilinear", "yield_disp_m": 0.005}],
    # Bouc-Wen in the middle of a row closed by a wall
    "bouc-wen-wall": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0, **BOUC_WEN},
                      {"model": "wall"}],
}  # fmt: skip


@pytest.mark.parametrize("name", list(YIELDING_ROWS))
def test_rows_of_yielding_buildings_match_the_reference(name):
    """Each building's storeys in its own modes, wherever it stands in the row (they were
    taken from the first and last buildings only, then refused).  Reference: the SciPy solution
    of the row in physical coordinates with located yield and unload events (Bouc-Wen: its
    ODE), on the same samples; newmark at 1e-4 s is within 1.1e-4 of it here (its error on a
    peak force, read at the steps: about 1e-4, as in test_inelastic's bilinear B1)."""
    s = row(*YIELDING_ROWS[name])
    s = replace(s, tail_s=0.0)  # the reference runs the record alone
    record = s.record_arrays()
    ref = reference_solution(s, record)
    out = simulate(s, record=record, method="newmark", dt_s=1e-4).outputs
    assert out["status"] == 0 and ref["impacts"] >= 8
    assert out["impacts"] == ref["impacts"]
    assert np.nanmax([b["peak_ductility"] for b in ref["buildings"]]) > 2.0  # one yields
    for key in ("peak_force", "peak_disp_left", "peak_disp_right", "peak_ductility_left",
                "peak_ductility_right", "hysteretic_energy"):  # fmt: skip
        if np.isnan(ref[key]):  # an elastic end building: no ductility
            assert np.isnan(out[key]), key
        else:
            assert out[key] == pytest.approx(ref[key], rel=3e-4), key
    # each storey named by its building's place in the row (a wall: "wall")
    res = simulate(s, record=record, method="newmark", dt_s=1e-4)
    names = [b.get("model") == "wall" and "wall" or f"building {k}"
             for k, b in enumerate(YIELDING_ROWS[name])]  # fmt: skip
    assert res.storeys["building"].tolist() == names and res.storeys["storey"].tolist() == [1] * 3
    for b in res.buildings:  # an SDOF building has one storey: its ductility is the building's
        mine = res.storeys["peak_ductility"][res.storeys["building"] == f"building {b['building']}"]
        np.testing.assert_array_equal(mine, [b["peak_ductility"]])


@pytest.mark.parametrize("name", list(YIELDING_ROWS))
def test_yielding_rows_run_adaptive_at_defaults(name):
    """``adaptive`` ran a yielding SDOF pair only (a row was refused); at its defaults it now
    meets the SciPy reference (module docstring) to 1e-5 on every compared output, with the
    same impacts."""
    s = replace(row(*YIELDING_ROWS[name]), tail_s=0.0)
    record = s.record_arrays()
    ref = reference_solution(s, record)
    res = simulate(s, record=record)
    out = res.outputs
    assert out["status"] == 0 and out["impacts"] == ref["impacts"] >= 8
    for key in ("peak_force", "peak_disp_left", "peak_disp_right", "peak_ductility_left",
                "peak_ductility_right", "hysteretic_energy", "max_penetration"):  # fmt: skip
        if np.isnan(ref[key]):
            assert np.isnan(out[key]), key
        else:
            assert out[key] == pytest.approx(ref[key], rel=1e-5), key
    # every building's, the middle one's included (a wall is none)
    assert len(res.buildings) == len(ref["buildings"])
    for mine, theirs in zip(res.buildings, ref["buildings"], strict=True):
        assert mine["building"] == theirs["building"]
        for key in ("peak_disp", "peak_ductility"):
            if np.isnan(theirs[key]):  # an elastic building: no ductility
                assert np.isnan(mine[key]), key
            else:
                assert mine[key] == pytest.approx(theirs[key], rel=1e-5), key


def test_simulate_command_shows_the_yielding_demands(tmp_path, capsys):
    """``pound-mc simulate`` printed no ductility or hysteretic energy for yielding buildings
    (and the peak force's time with 16 digits of round-off)."""
    from pound_mc.cli import main

    lines = ['[record]\nsource = "builtin:knet-akt013"\nduration_s = 6.0\npga_g = 0.5\n']
    for b in YIELDING_ROWS["bilinear-middle"]:
        lines.append("[[buildings]]\n" + "".join(f"{k} = {v!r}\n".replace("'", '"')
                                                  for k, v in b.items()))  # fmt: skip
    lines.append('[contact]\nmodel = "jankowski"\nbeta = 2.75e9\nxi = 0.35\ngap_m = 0.003\n')
    lines.append('[integrator]\nmethod = "newmark"\ndt_s = 1e-3\n')
    path = tmp_path / "row.toml"
    path.write_text("\n".join(lines))
    assert main(["simulate", str(path)]) == 0
    text = capsys.readouterr().out
    res = simulate(scene_from_dict(tomllib.loads(path.read_text())))
    out = res.outputs
    # every building of the row, left to right (the first and the last are elastic)
    for b in res.buildings:
        assert (
            f"building {b['building']}       peak disp {b['peak_disp']:.6g} m, ductility "
            f"{b['peak_ductility']:.4g} (sdof)\n"
        ) in text
    assert "ductility 3." in text or "ductility 2." in text or "ductility 4." in text
    assert f"hysteresis       {out['hysteretic_energy']:.6g} J" in text
    assert f"at t = {out['peak_force_time']:.6g} s\n" in text
    # a method given on the command line runs the row too (central-difference refused
    # yielding buildings): the same impacts, its own demands
    assert main(["simulate", str(path), "--method", "central-difference"]) == 0
    text = capsys.readouterr().out
    cd = simulate(scene_from_dict(tomllib.loads(path.read_text())), method="central-difference")
    assert cd.outputs["impacts"] == out["impacts"]
    assert f"hysteresis       {cd.outputs['hysteretic_energy']:.6g} J" in text
