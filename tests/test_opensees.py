"""pound-mc against OpenSees (``pound_mc.validation.opensees``) and ``bench --peers``.

The OpenSees comparisons run where openseespy is installed (the extra ``validation``) and are
skipped, saying so, where it is not; the path without openseespy is checked by hiding it.
"""

from __future__ import annotations

import json
import sys

import pytest

from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.numerics import bench
from pound_mc.scene import simulate
from pound_mc.validation import opensees
from pound_mc.validation.opensees import CASES, MISSING, case_scene, cases, convergence

#: The keys DESIGN.md section 10 pins for a validation case.
KEYS = {"case", "quantity", "value", "reference", "source", "rel_error", "tolerance", "passed"}


@pytest.fixture
def no_openseespy(monkeypatch):
    # a None entry in sys.modules makes the import raise ModuleNotFoundError, as when absent
    monkeypatch.setitem(sys.modules, "openseespy", None)
    monkeypatch.setitem(sys.modules, "openseespy.opensees", None)


def test_without_openseespy_every_case_says_why(no_openseespy):
    rows = cases()
    assert len(rows) == sum(len(spec["quantities"]) for spec in CASES.values())
    for row in rows:
        assert set(row) == KEYS | {"reason"}
        assert row["passed"] is None and row["reason"] == MISSING
        assert row["value"] is None and row["reference"] is None and row["rel_error"] is None
        assert row["tolerance"] >= 0.0


def test_a_scene_opensees_cannot_hold_is_refused_before_opensees_runs(no_openseespy):
    # JankowskiImpact ends the process on a zero gap: the check must come first
    with pytest.raises(InputError, match="zero gap"):
        opensees.opensees_run(case_scene("opensees-sdof-pair", gap_m=0.0))
    with pytest.raises(InputError, match="'kelvin' law"):
        opensees.opensees_run(case_scene("opensees-sdof-pair", model="kelvin"))


def test_bench_peers_without_openseespy_says_why_and_times_pound_mc(
    no_openseespy, monkeypatch, capsys
):
    # the SciPy reference of B1 (seconds) is not what this checks: its values from DESIGN.md
    # section 5 stand in for it
    def reference(scene, record=None):
        return {"peak_force": 7.0259e6, "impacts": 22, "peak_disp_left": 1.0,
                "peak_disp_right": 1.0}  # fmt: skip

    monkeypatch.setattr(bench, "reference_solution", reference)
    assert main(["bench", "--peers", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert f"OpenSees is not timed: {MISSING}" in out
    assert "pound-mc adaptive" in out and "OpenSees dt=" not in out
    assert main(["bench", "--peers", "--repeats", "1", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["opensees_reason"] == MISSING
    assert [r["label"] for r in info["peers"]] == ["pound-mc adaptive"]
    assert info["peers"][0]["impacts"] == 22  # B1's 22 impacts (DESIGN.md section 5)


def test_cases_agree_with_opensees_within_their_tolerance():
    pytest.importorskip("openseespy.opensees", reason="openseespy is not installed")
    rows = cases()
    assert len(rows) == 13
    for row in rows:
        assert set(row) == KEYS, row
        assert row["source"].startswith("OpenSees 3.") and "dt 0.0001 s" in row["source"]
        assert row["passed"] is True, row
    # the counts are equal, not close: every impact found in both tools
    assert all(r["value"] == r["reference"] for r in rows if r["quantity"] == "impacts")
    # yielding is compared on a scene that yields (Steel01 against the bilinear law)
    ductility = [r["reference"] for r in rows if r["quantity"].startswith("peak_ductility")]
    assert min(ductility) > 1.5


def test_opensees_converges_to_pound_mc_as_its_step_shrinks():
    pytest.importorskip("openseespy.opensees", reason="openseespy is not installed")
    # a step ten times shorter each time: every difference shrinks (docs/opensees.md has
    # the finer ladder, on which the damped law's differences fall as dt, of either sign)
    rows = convergence("opensees-sdof-pair", dts=(1e-3, 1e-4, 1e-5))
    for q in ("peak_force_N", "peak_disp_left_m", "peak_disp_right_m"):
        diff = [r["rel_diff"] for r in rows if r["quantity"] == q]
        assert diff[0] > diff[1] > diff[2], (q, diff)
    assert diff[2] < 1e-6
    force = [r["rel_diff"] for r in rows if r["quantity"] == "peak_force_N"]
    assert force[0] > 1e-4 and force[2] < 1e-5  # from about 1.5e-3 to about 4e-6
    assert {r["opensees"] for r in rows if r["quantity"] == "impacts"} == {9}
    # without impact damping the difference is Newmark's, falling as dt^2: the first-order
    # part above comes from the damping force's onset within a step
    control = convergence(case_scene("opensees-sdof-pair", xi=0.0), dts=(1e-3, 5e-4, 2.5e-4),
                          quantities=("peak_force",))  # fmt: skip
    d = [r["rel_diff"] for r in control]
    assert 3.0 < d[0] / d[1] < 5.0 and 3.0 < d[1] / d[2] < 5.0, d


def test_bench_peers_json_has_the_opensees_rows(monkeypatch, capfd):
    pytest.importorskip("openseespy.opensees", reason="openseespy is not installed")
    monkeypatch.setattr(bench, "PEER_STEPS", (1e-3, 5e-4))  # shorter than 1e-4 s for the test
    assert main(["bench", "--peers", "--repeats", "1", "--json"]) == 0
    out = capfd.readouterr().out  # the file descriptor: OpenSees's own output would show
    info = json.loads(out)
    assert info["opensees_reason"] is None
    rows = {r["label"]: r for r in info["peers"]}
    assert list(rows) == ["pound-mc adaptive", "OpenSees dt=0.001", "OpenSees dt=0.0005"]
    assert {r["impacts"] for r in rows.values()} == {info["reference_impacts"]} == {22}
    # B1's peak-force errors (DESIGN.md section 5: OpenSees 6e-4 at dt 1e-3)
    coarse, fine = (rows[f"OpenSees dt={dt}"]["err_peak_force"] for dt in ("0.001", "0.0005"))
    assert 2e-4 < coarse < 2e-3 and fine < coarse
    assert rows["pound-mc adaptive"]["err_peak_force"] < 1e-4
    assert rows["OpenSees dt=0.001"]["analyze_seconds"] <= rows["OpenSees dt=0.001"]["seconds"]
    assert rows["pound-mc adaptive"]["analyze_seconds"] is None


def test_opensees_and_pound_mc_newmark_solve_the_same_steps():
    pytest.importorskip("openseespy.opensees", reason="openseespy is not installed")
    # the same average-acceleration scheme on the same model at the same step: the two tools
    # agree to the Newton tolerances (measured 2e-10), which checks the OpenSees model itself
    # (masses, damping, record, initial state, the contact's sign and effective mass)
    scene = case_scene("opensees-sdof-pair")
    theirs = opensees.opensees_run(scene, 1e-3)
    ours = simulate(scene, method="newmark", dt_s=1e-3).outputs
    assert theirs["peak_force_steps"] == pytest.approx(ours["peak_force"], rel=1e-8)
    for q in ("peak_disp_left", "peak_disp_right"):
        assert theirs[q] == pytest.approx(ours[q], rel=1e-8)
    assert theirs["impacts"] == ours["impacts"] == 9
