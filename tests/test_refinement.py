"""No run leaves an analysis silently: flagged runs refined, left-out runs counted.

* A study runs the simulations its accuracy check flags ``inaccurate`` again with ``dt_s``
  halved and ``substeps`` doubled (at most three times); each keeps its last run's outputs,
  and ``run_dt_s``, ``run_substeps``, ``refinements`` say which settings gave them.  The
  reference is the scene itself: a refined run's numbers are those of
  :func:`pound_mc.scene.simulate` at its final settings, bit for bit.
* Fragility, required gap and the probability chart count the runs they leave out
  (``n_left_out``): the counts of the status flags, by construction of the dataset.
"""

import json

import numpy as np
import pytest
import xarray as xr

from pound_mc.analysis.risk import fragility, left_out, required_gap
from pound_mc.cli import main
from pound_mc.scene import simulate
from pound_mc.study.definition import load_study
from pound_mc.study.engine import StudyEngine


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    """The small SDOF study with ``newmark`` at a coarse 5 ms step: most runs flagged."""
    from studies import write_study

    folder = tmp_path_factory.mktemp("coarse")
    path = write_study(folder, study={"name": "coarse"},
                       integrator={"method": "newmark", "dt_s": 0.005},
                       grid={"left.period_s": [0.3, 0.5]}, sampling={"n": 4})  # fmt: skip
    assert main(["run", str(path), "--out", str(folder / "out"), "--no-plot",
                 "--no-progress"]) == 0  # fmt: skip
    with xr.open_dataset(folder / "out" / "coarse.nc") as ds:
        return path, ds.load()


def test_flagged_runs_are_refined_to_the_settings_they_report(coarse):
    path, ds = coarse
    refined = ds["refinements"].values.astype(np.int64)
    assert refined.max() >= 1 and refined.max() <= 3  # some runs refined, at most 3 times
    # the settings each run ended with: dt_s halved per refinement (newmark has no sub-steps
    # to double: its substeps stay the study's)
    np.testing.assert_array_equal(ds["run_dt_s"].values, 0.005 * 0.5**refined)
    np.testing.assert_array_equal(ds["run_substeps"].values, np.full(refined.shape, 16))
    assert ds["run_dt_s"].attrs["units"] == "s" and "long_name" in ds["refinements"].attrs
    # a refined run holds the numbers of its scene at its final settings
    engine = StudyEngine(load_study(path))
    # the dataset's dimensions are the engine's flat order (record, grid axes, sample)
    flat = ds["peak_force"].values.ravel()
    runs = ds["refinements"].values.ravel().astype(np.int64)
    k = int(np.flatnonzero(runs > 0)[0])
    res = simulate(engine.scene_of(k), record=engine.record_of(k), dt_s=0.005 * 0.5 ** runs[k])
    assert res.outputs["peak_force"] == flat[k]
    # the refinements cut the flagged runs: every flagged one went through all three, and
    # fewer remain flagged than the first pass flagged (those refined at least once)
    flagged = ds["status"].values == 3
    assert np.all(refined[flagged] == 3)
    assert flagged.sum() < (refined > 0).sum()


def test_run_reports_the_refined_and_the_still_flagged(coarse, tmp_path, capsys):
    from pound_mc.cli.study import status_warnings

    path, ds = coarse
    lines = status_warnings(path.parent / "out" / "coarse.nc")
    n_refined = int((ds["refinements"] > 0).sum())
    still = int(((ds["refinements"] > 0) & (ds["status"] == 3)).sum())
    assert any(f"{n_refined:,} of {ds['status'].size:,} simulations flagged" in line
               and f"{still:,} of them remain flagged" in line for line in lines)  # fmt: skip


def _with_statuses(ds, statuses):
    """``ds`` with the first simulations' statuses set to ``statuses`` (the rest ok)."""
    out = ds.copy(deep=True)
    flat = out["status"].values.reshape(-1)
    flat[:] = 0
    flat[: len(statuses)] = statuses
    return out


def test_fragility_and_required_gap_count_what_they_leave_out(coarse):
    _, ds = coarse
    # 2 unstable, 1 not converged, 3 inaccurate: pounding leaves out the 3 that failed, a
    # force event the inaccurate ones too
    ds = _with_statuses(ds, [1, 1, 2, 3, 3, 3])
    assert int(left_out(ds, "pounding", over=list(ds["status"].dims)).sum()) == 3
    assert int(left_out(ds, "peak_force>1", over=list(ds["status"].dims)).sum()) == 6
    fit = fragility(ds, "left_period_s", "peak_force>1", n_boot=0)
    assert int(fit["n_left_out"].sum()) == 6
    assert int(fit["n_total"].sum()) + 6 == ds["status"].size
    gap = required_gap(ds, 0.5, rules=False)
    assert int(gap["n_left_out"].sum()) == 3


def test_fragility_command_says_what_it_leaves_out(coarse, tmp_path, capsys):
    _, ds = coarse
    bad = _with_statuses(ds, [1, 2, 3])
    nc = tmp_path / "bad.nc"
    bad.to_netcdf(nc)
    args = ["fragility", str(nc), "--im", "left_period_s", "--n-boot", "0"]
    assert main([*args, "--event", "peak_force>1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert int(np.sum(out["n_left_out"])) == 3
    assert main([*args, "--event", "pounding"]) == 0
    text = capsys.readouterr().out
    assert "2 left out (unstable or not converged)" in text
