"""Buildings whose floors are at unequal heights: a floor between the other building's floors
meets its column (displacement interpolated linearly between the floors below and above).
"""

import json

import pytest

from pound_mc.cli import main
from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate

THREE = {"model": "shear", "storey_mass_kg": [1.0e6] * 3,
         "storey_stiffness_N_per_m": [1.2e9, 1.0e9, 0.8e9], "storey_height_m": [3.0] * 3,
         "damping_ratio": 0.05}  # fmt: skip
TWO = {"model": "shear", "storey_mass_kg": [1.5e6] * 2,
       "storey_stiffness_N_per_m": [0.5e9, 0.4e9], "storey_height_m": [4.5] * 2,
       "damping_ratio": 0.05}  # fmt: skip
RECORD = {"source": "builtin:elcentro", "duration_s": 6.0, "pga_g": 0.5}


def scene(**contact):
    return scene_from_dict(
        {"record": RECORD, "left": THREE, "right": TWO,
         "contact": {"model": "jankowski", "beta": 2.75e9, "xi": 0.35, "gap_m": 0.005,
                     **contact}}
    )  # fmt: skip


def test_contacts_at_the_right_heights():
    # 3 x 3 m against 2 x 4.5 m: the 9 m roofs meet floor to floor; the right's 4.5 m slab
    # meets the left column halfway between its 3 m and 6 m floors, the left's 6 m slab the
    # right column at 1/3 of 4.5 m - 9 m; the left's 3 m slab, below the right's first floor,
    # meets nothing.  A column's effective mass 1 / sum(w^2 / m):
    # 1 / (0.5^2 / 1e6 + 0.5^2 / 1e6) = 2e6 kg; 1 / ((2/3)^2 / 1.5e6 + (1/3)^2 / 1.5e6) = 2.7e6
    cs = scene().contacts
    got = [(c.elevation_m, c.kind, c.left_floor, c.right_floor) for c in cs]
    assert got == [(4.5, "column", 0, 0), (6.0, "column", 1, 0), (9.0, "floor", 2, 1)]
    assert cs[0].left_at == ((0, 0.5), (1, 0.5))
    assert cs[0].m_left == pytest.approx(2.0e6, rel=1e-15)
    assert [f for f, _ in cs[1].right_at] == [0, 1]
    assert [w for _, w in cs[1].right_at] == pytest.approx([2 / 3, 1 / 3], rel=1e-15)
    assert cs[1].m_right == pytest.approx(2.7e6, rel=1e-14)
    assert cs[2].m_eff == pytest.approx(1.0e6 * 1.5e6 / 2.5e6, rel=1e-15)


def test_level_tolerance_makes_near_floors_meet():
    # a 5 cm offset: without tolerance the 9.05 m roof is above the left roof (no contact) and
    # the left roof meets the right column; with 0.1 m the roofs meet floor to floor
    two = {**TWO, "storey_height_m": [4.5, 4.55]}
    base = {"record": RECORD, "left": THREE, "right": two}
    off = scene_from_dict({**base, "contact": {"xi": 0.3}}).contacts
    assert [(c.elevation_m, c.kind) for c in off][-1] == (9.0, "column")
    near = scene_from_dict({**base, "contact": {"xi": 0.3, "level_tolerance_m": 0.1}}).contacts
    assert [(c.elevation_m, c.kind) for c in near][-1] == (9.0, "floor")


@pytest.mark.slow
def test_unequal_levels_against_reference():
    # the kernel against the SciPy reference, which takes each contact as weighted floors
    s = scene()
    record = s.record_arrays()
    ref = reference_solution(s, record)
    res = simulate(s, record=record)
    assert res.outputs["impacts"] == ref["impacts"] > 0
    assert list(res.contacts["impacts"]) == list(ref["contact_impacts"])
    assert all(res.contacts["impacts"] > 0)  # every contact pounds
    assert res.outputs["peak_force"] == pytest.approx(ref["peak_force"], rel=1e-4)
    for k in range(3):
        assert res.contacts["peak_force"][k] == pytest.approx(ref["contact_peak_force"][k],
                                                              rel=1e-4)  # fmt: skip
    for side in ("left", "right"):
        assert res.outputs[f"peak_disp_{side}"] == pytest.approx(ref[f"peak_disp_{side}"],
                                                                 rel=1e-4)  # fmt: skip


def test_simulate_reports_column_contacts(tmp_path, capsys):
    path = tmp_path / "levels.toml"
    path.write_text(
        '[record]\nsource = "builtin:elcentro"\nduration_s = 2.0\n'
        '[left]\nmodel = "shear"\nstorey_mass_kg = [1.0e6, 1.0e6, 1.0e6]\n'
        "storey_stiffness_N_per_m = [1.2e9, 1.0e9, 0.8e9]\nstorey_height_m = [3.0, 3.0, 3.0]\n"
        '[right]\nmodel = "shear"\nstorey_mass_kg = [1.5e6, 1.5e6]\n'
        "storey_stiffness_N_per_m = [0.5e9, 0.4e9]\nstorey_height_m = [4.5, 4.5]\n"
        "[contact]\nxi = 0.35\ngap_m = 0.05\n"
    )
    main(["simulate", str(path)])
    out = capsys.readouterr().out
    assert "contact 1 at 4.5 m: right floor 1 on the left column (0.5 x floor 1 + 0.5 x floor 2)" \
        in out  # fmt: skip
    main(["simulate", str(path), "--json"])
    info = json.loads(capsys.readouterr().out)
    assert [c["kind"] for c in info["contacts"]] == ["column", "column", "floor"]
