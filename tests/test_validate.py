"""``pound-mc validate``: the validation cases, how they are judged, and the exit status.

The cases themselves compare the tool with closed forms, Chopra's El Centro figures, the seed's
Tables 2 and 3 and the SciPy reference (``pound_mc/validation/``); these tests check that the
command runs them, reports every row with the pinned JSON keys (DESIGN.md section 10), counts
a failure as a failure and a case that cannot run as none, and that the built-in record the
Chopra cases read is Chopra's.
"""

import json
import math
import sys
import types

import numpy as np
import pytest

import pound_mc.validation as validation
from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.motions import load_record
from pound_mc.motions.readers import read_record
from pound_mc.motions.traces import G, record_info
from pound_mc.validation import Case, case_list, judge, public

KEYS = {"case", "quantity", "value", "reference", "source", "rel_error", "tolerance", "passed"}
GROUPS = ("closed-form", "chopra", "seed", "reference")


def _run_json(capsys, *args):
    status = main(["validate", "--json", "--no-progress", *args])
    return status, json.loads(capsys.readouterr().out)


def test_quick_set_passes_with_the_pinned_keys(capsys):
    status, rows = _run_json(capsys, "--quick")
    assert status == 0
    assert isinstance(rows, list) and len(rows) >= 12
    for row in rows:
        assert KEYS <= set(row), row
        assert not any(key.startswith("_") for key in row)  # no histories in the JSON
        if row["passed"] is None:  # only OpenSees's cases may not run here, saying why
            assert row["group"] == "opensees" and row["reason"], row
            continue
        assert row["passed"] is True, row
        assert row["rel_error"] <= row["tolerance"]
    # the package's own cases, and OpenSees's where its module is there (it says whether)
    cases = {row["case"] for row in rows if row["group"] != "opensees"}
    assert cases == {c["case"] for c in case_list(quick=True)}
    # every kind of reference is in the quick set
    groups = [c["group"] for c in case_list(quick=True)]
    assert all(groups.count(g) >= 1 for g in GROUPS)
    # a range (Table 2's restitution) gives its bounds, and the value lies inside them (the
    # drop test aimed at an end lands on it to 1e-9, outside by no more than its tolerance)
    ranged = [row for row in rows if "reference_low" in row]
    assert ranged and all(row["reference"] == [row["reference_low"], row["reference_high"]]
                          for row in ranged)  # fmt: skip
    for row in ranged:
        low, high = row["reference_low"], row["reference_high"]
        assert low * (1 - 1e-6) <= row["value"] <= high * (1 + 1e-6), row
    assert any(row["source"] == "Jankowski (2008) Table 2" for row in ranged)
    # the textbook's figures are compared in its units (Chopra, Fig. 6.4.1: D = 2.67 in at 0.5 s)
    d05 = next(r for r in rows if r["case"] == "chopra-deformation" and "0.5 s" in r["quantity"])
    assert d05["reference"] == 2.67 and abs(d05["value"] - 2.67) < 0.01


def test_full_list_has_two_cases_of_each_kind_without_running():
    full, quick = case_list(), case_list(quick=True)
    names = [c["case"] for c in full]
    assert len(names) == len(set(names)) >= 12
    for group in GROUPS:
        assert sum(c["group"] == group for c in full) >= 2, group
    assert {c["case"] for c in quick} < set(names)
    assert all(c["source"] for c in full)


def test_table_and_exit_status_count_failures_not_cases_that_cannot_run(monkeypatch, capsys):
    def passing(quick):
        return [{"quantity": "x", "value": 1.0001, "reference": 1.0, "tolerance": 1e-3}]

    def failing(quick):
        return [{"quantity": "x", "value": 1.1, "reference": 1.0, "tolerance": 1e-3}]

    def broken(quick):
        raise ZeroDivisionError("division by zero")

    def cannot_run():
        return [{"case": "peer", "quantity": "-", "value": None, "reference": None,
                 "source": "OpenSees", "tolerance": None, "passed": None,
                 "reason": "openseespy is not installed"}]  # fmt: skip

    ok = Case("ok", "closed-form", "a formula", passing, quick=True)
    monkeypatch.setattr(validation, "_external", lambda quick: cannot_run())
    monkeypatch.setattr(validation, "CASES", (ok,))
    status, rows = _run_json(capsys, "--quick")
    assert status == 0  # a case that cannot run is no failure
    assert [r["passed"] for r in rows] == [True, None]
    assert rows[1]["reason"] == "openseespy is not installed" and rows[1]["rel_error"] is None

    for bad in (failing, broken):
        monkeypatch.setattr(validation, "CASES", (ok, Case("bad", "seed", "a table", bad)))
        assert main(["validate", "--quick", "--no-progress"]) == 0  # not in the quick set
        capsys.readouterr()
        status, rows = _run_json(capsys)
        assert status == 1
        assert [r["passed"] for r in rows] == [True, False, None]
        if bad is broken:
            assert rows[1]["reason"].startswith("ZeroDivisionError: division by zero")
    assert main(["validate", "--no-progress"]) == 1
    text = capsys.readouterr().out
    assert "FAIL" in text and "1 failed, 1 could not run" in text
    assert "peer: openseespy is not installed" in text


def test_rows_of_the_opensees_module_are_judged_and_counted(monkeypatch, capsys):
    # pound_mc.validation.opensees (merged separately) gives rows through cases(quick)
    module = types.ModuleType(validation.EXTERNAL)
    module.cases = lambda quick: [
        {"case": "opensees-pair", "quantity": "peak_force", "value": 1.0 + 1e-5,
         "reference": 1.0, "source": "OpenSees JankowskiImpact", "tolerance": 1e-3},
        {"case": "opensees-wall", "quantity": "peak_force", "value": None, "reference": None,
         "source": "OpenSees", "tolerance": None, "passed": None,
         "reason": "openseespy is not installed"},
    ]  # fmt: skip
    monkeypatch.setitem(sys.modules, validation.EXTERNAL, module)
    monkeypatch.setattr(validation, "CASES", ())
    status, rows = _run_json(capsys)
    assert status == 0
    assert rows[0]["passed"] is True and rows[0]["rel_error"] == pytest.approx(1e-5)
    assert rows[0]["group"] == "opensees"
    assert rows[1]["passed"] is None and rows[1]["reason"]


def test_judge_points_and_ranges():
    point = judge({"value": 2.0, "reference": 4.0, "tolerance": 0.5})
    assert point["rel_error"] == 0.5 and point["passed"] is True
    assert judge({"value": 2.0, "reference": 4.0, "tolerance": 0.49})["passed"] is False
    rng = {"reference_low": 0.5, "reference_high": 0.6, "tolerance": 0.01}
    inside = judge({**rng, "value": 0.55})
    assert inside["rel_error"] == 0.0 and inside["passed"] and inside["reference"] == [0.5, 0.6]
    below = judge({**rng, "value": 0.45})  # 0.05 under the lower bound: 10 % of it
    assert below["rel_error"] == pytest.approx(0.1) and below["passed"] is False
    above = judge({**rng, "value": 0.603})  # 0.003 over the upper bound: 0.5 % of it
    assert above["rel_error"] == pytest.approx(0.005) and above["passed"] is True
    # nothing to compare is a failure, not a pass
    for row in ({"value": math.nan, "reference": 1.0, "tolerance": 1.0},
                {"value": None, "reference": 1.0, "tolerance": 1.0},
                {"value": 1.0, "reference": 0.0, "tolerance": 1.0}):  # fmt: skip
        judged = judge(row)
        assert judged["passed"] is False and judged["rel_error"] is None
    # the JSON form: pinned keys first, no histories, no NaN
    out = public({**judge({"value": math.nan, "reference": 1.0, "tolerance": 1.0}),
                  "case": "c", "_plot": {}})  # fmt: skip
    assert list(out)[:8] == ["case", "quantity", "value", "reference", "source", "rel_error",
                             "tolerance", "passed"]  # fmt: skip
    assert "_plot" not in out and out["value"] is None
    json.dumps(out, allow_nan=False)


@pytest.mark.slow
def test_full_set_passes(capsys):
    status, rows = _run_json(capsys)
    assert status == 0, [r for r in rows if r["passed"] is False]
    cases = {r["case"] for r in rows}
    assert len(cases) >= 12 and cases >= {c["case"] for c in case_list()}
    for group in GROUPS:
        assert len({r["case"] for r in rows if r["group"] == group}) >= 2, group


# --------------------------------------------------------------------- Chopra's El Centro record


def test_builtin_elcentro_chopra_is_the_textbook_record():
    tr = load_record("builtin:elcentro-chopra", demean=False)
    info = record_info(tr)
    # Chopra, Appendix 6: 0.02 s samples of El Centro 1940 N-S, in g, peak 0.319 g
    assert (info["npts"], info["dt_s"], info["component"]) == (1560, 0.02, "NS")
    assert info["pga_g"] == pytest.approx(0.31882, abs=1e-12)
    assert info["source_units"] == "g" and info["format"] == "CSV"
    assert tr.data[0] == 0.0 and tr.data[1] == pytest.approx(0.0063 * G, rel=1e-15)


def test_time_acceleration_csv_reader(tmp_path):
    path = tmp_path / "motion.csv"
    path.write_text("time,acc (m/s^2)\n0,0\n0.01,1.5\n0.02,-2.0\n0.03,0.5\n")
    tr = read_record(path)
    assert tr.stats.delta == 0.01
    np.testing.assert_array_equal(tr.data, [0.0, 1.5, -2.0, 0.5])
    path.write_text("t (s), a (gal)\n0.0, 100\n0.005, -200\n")
    assert read_record(path).data[1] == pytest.approx(-2.0)
    bad = {
        "time,acc\n0,0\n0.01,1\n": "record.units",  # no units: the units key must say
        "time,acc (furlong/fortnight^2)\n0,0\n0.01,1\n": "line 1",
        "time,acc (g)\n0,0\n0.01,1\n0.03,1\n": None,  # uneven steps
        "time,acc (g)\n0,0\n0.01,x\n": "line 3",
    }
    for text, key in bad.items():
        path.write_text(text)
        with pytest.raises(InputError) as err:
            read_record(path)
        assert err.value.key == key, text
    path.write_text("time,acc\n0,0\n0.01,1\n")
    assert read_record(path, units="g").data[1] == pytest.approx(G)
