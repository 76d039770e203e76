"""Rows of buildings (``[[buildings]]``, left to right): contacts between neighbours, against
the independent SciPy reference.
"""

import numpy as np
import pytest

from pound_mc.analysis.plot_numerics import time_history_chart
from pound_mc.errors import InputError
from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate

SDOF = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
RECORD = {"source": "builtin:knet-akt013", "duration_s": 6.0, "pga_g": 0.5}
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
    assert list(a["side"]) == [0, 1, 1]
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {"model": "wall"})
    assert [(c.pair, c.m_eff) for c in s.contacts] == [(0, 5.0e5), (1, 1.0e6)]


@pytest.mark.slow
def test_three_buildings_against_reference():
    # a 0.5 s, a 1.0 s and a 0.7 s SDOF 3 mm apart: both contacts pound; impacts per contact
    # and peak forces as the SciPy reference (peak_disp_right: the largest of the others)
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
    assert [c["pair"] for c in res.to_json()["contacts"]] == [1, 2]


def test_row_validation():
    base = {"record": RECORD, "contact": {"xi": 0.3}}
    for data, key in (
        ({"buildings": [{**SDOF, "period_s": 0.5}], }, "buildings"),
        ({"buildings": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}],
          "left": {**SDOF, "period_s": 0.5}}, "left"),
        ({"buildings": [{**SDOF, "period_s": 0.5}, {"model": "wall"},
                        {**SDOF, "period_s": 1.0}]}, "buildings[1].model"),
        # a yielding building anywhere in a row: its storeys were taken as another's (wrong
        # stiffness, a row of three bilinear SDOFs 'unstable' at 970 m) or ignored (the middle)
        ({"buildings": [{**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0, **BILINEAR},
                        {**SDOF, "period_s": 0.7}]}, "buildings[1].hysteresis"),
        ({"buildings": [{**SDOF, "period_s": 0.5, **BILINEAR}, {**SDOF, "period_s": 1.0}]},
         "buildings[0].hysteresis"),
    ):  # fmt: skip
        with pytest.raises(InputError) as info:
            scene_from_dict({**base, **data})
        assert key in str(info.value)


def test_history_chart_draws_each_contacts_neighbours(tmp_path):
    """Contact 2 of a row redrew building 1 against building 2; building 3 was never drawn."""
    s = row({**SDOF, "period_s": 0.5}, {**SDOF, "period_s": 1.0}, {**SDOF, "period_s": 0.7})
    res = simulate(s, history=True)
    floors = np.hstack([res.disp_left_m, res.disp_right_m])  # buildings 1, 2, 3
    np.testing.assert_array_equal(floors[:, 0] - floors[:, 1] - 0.003, res.penetration_m[:, 0])
    np.testing.assert_array_equal(floors[:, 1] - floors[:, 2] - 0.003, res.penetration_m[:, 1])
    lines = time_history_chart(res, tmp_path / "row.png").axes[0].lines
    assert [ln.get_label() for ln in lines] == [
        "contact 1: building 1, floor 1", "contact 1: building 2, floor 1",
        "contact 2: building 2, floor 1", "contact 2: building 3, floor 1",
    ]  # fmt: skip
    for ln, k in zip(lines, (0, 1, 1, 2), strict=True):
        np.testing.assert_allclose(ln.get_ydata(), floors[:, k] * 1e3)


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
