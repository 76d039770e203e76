"""First-run experience: the scene's cache, the compile notice, ``compile``, ``check``, ``bench``.

No timing is asserted: the notice's delay is set to zero where a test needs it shown, and the
benchmark's figures are checked for their accuracy and layout, not their speed.
"""

from __future__ import annotations

import io
import json
import re
import time
from dataclasses import replace
from pathlib import Path

import numba
import numpy as np
import pytest
from numba import types
from numba.core.caching import NullCache

from pound_mc._jit import jit
from pound_mc.cli import main
from pound_mc.errors import InputError
from pound_mc.numerics import bench
from pound_mc.scene import load_scene, simulate
from pound_mc.study import warmup
from pound_mc.study.definition import load_study
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study

B1 = Path(__file__).resolve().parents[1] / "studies" / "scenes" / "b1.toml"
#: DESIGN.md section 5: independent tight-tolerance SciPy solution of B1.
B1_PEAK_FORCE = 7.0259e6


@pytest.fixture(scope="module")
def b1_first():
    scene = load_scene(B1)
    return scene, simulate(scene)


def test_scene_caches_record_and_arrays(b1_first):
    scene, first = b1_first
    # DESIGN.md section 5: 22 impacts, peak 7.0259e6 N (adaptive's error is about 2e-5)
    assert first.outputs["impacts"] == 22
    assert first.outputs["peak_force"] == pytest.approx(B1_PEAK_FORCE, rel=1e-4)
    record = scene.record_arrays()
    assert scene.record_arrays()[1] is record[1]  # read once
    assert scene.kernel_arrays() is scene.kernel_arrays()
    again = simulate(scene)
    # bitwise the same from the cached arrays (NaN where an output does not apply)
    np.testing.assert_equal(again.outputs, first.outputs)


def test_scene_cache_follows_edits(b1_first):
    scene, first = b1_first
    scene = replace(scene)  # a fresh scene of the same values: its own, empty cache
    assert scene._cache == {}
    np.testing.assert_equal(simulate(scene).outputs, first.outputs)
    old = scene.record_arrays()[1]
    scene.record["pga_g"] = 0.6  # in place: the record table is part of the key
    doubled = scene.record_arrays()[1]
    np.testing.assert_allclose(np.abs(doubled).max(), 0.6 * 9.80665, rtol=1e-12)
    assert np.abs(old).max() == pytest.approx(0.3 * 9.80665, rel=1e-12)
    scene.record["pga_g"] = 0.3
    scene.gap_m[0] = 1.0  # no contact within 1 m of gap
    assert simulate(scene).outputs["impacts"] == 0
    scene.gap_m[0] = 0.01
    np.testing.assert_equal(simulate(scene).outputs, first.outputs)
    scene.xi = 0.1  # assigning a field drops the cache
    assert scene._cache == {}
    softer = simulate(scene)
    assert softer.outputs["peak_force"] != first.outputs["peak_force"]
    assert "record" not in replace(scene)._cache


def _compiles_a_kernel():
    """Compile a new numba function (a real compilation, whatever the cache holds)."""
    numba.njit(lambda x: x + 1.0)(1.0)


def test_compiling_notice_shown_and_not():
    stream = io.StringIO()
    with warmup.compiling_notice(stream, after_s=0.0) as state:
        _compiles_a_kernel()
    # a zero delay shows the notice as soon as a compilation has started
    assert state["shown"] and warmup.COMPILING_MESSAGE in stream.getvalue()
    quiet = io.StringIO()
    with warmup.compiling_notice(quiet, after_s=600.0) as state:
        _compiles_a_kernel()
    assert not state["shown"] and quiet.getvalue() == ""
    # a slow block that compiles nothing (kernels from the cache, a tiny step) is not compiling
    slow = io.StringIO()
    with warmup.compiling_notice(slow, after_s=0.0) as state:
        time.sleep(0.3)
    assert not state["shown"] and slow.getvalue() == ""
    # elsewhere (the Dask workers: their compilations are not seen here) the time decides
    remote = io.StringIO()
    with warmup.compiling_notice(remote, after_s=0.0, where="on the workers") as state:
        time.sleep(0.05)
    assert state["shown"] and "on the workers" in remote.getvalue()


def _compiling_engine(study, seconds: float = 0.0, compile_: bool = True) -> StudyEngine:
    """The study's engine, whose first call compiles a new kernel (and then sleeps)."""
    engine = StudyEngine(study)
    run_indices = engine.run_indices

    def first(indices):
        engine.run_indices = run_indices
        if compile_:
            _compiles_a_kernel()
        time.sleep(seconds)
        return run_indices(indices)

    engine.run_indices = first
    return engine


@pytest.mark.parametrize("progress", [True, False])
def test_run_warms_up_before_the_bar(make_study, tmp_path, monkeypatch, capsys, progress):
    monkeypatch.setattr(warmup, "NOTICE_AFTER_S", 0.0)
    study = load_study(make_study())
    report = run_study(study, tmp_path / "out", threads=1, engine=_compiling_engine(study),
                       progress=progress)  # fmt: skip
    err = capsys.readouterr().err
    assert report.complete and report.warmup_compiled and report.warmup_seconds > 0.0
    # the notice and the compile report, with the bar or without it (a log still says why the
    # first seconds pass in silence); then the bar, whose first draw shows the "sim/s" rate
    notice = err.index(warmup.COMPILING_MESSAGE)
    assert notice < err.index("kernels compiled in")
    assert ("sim/s" in err) == progress and err.index("kernels compiled in") < err.find("sim/s") + (
        0 if progress else len(err) + 1
    )


def test_slow_first_simulation_from_the_cache_is_not_compiling(make_study, tmp_path, monkeypatch,
                                                                capsys):  # fmt: skip
    # a warm-up longer than the notice's delay used to be reported as compiling
    monkeypatch.setattr(warmup, "NOTICE_AFTER_S", 0.0)
    study = load_study(make_study())
    engine = _compiling_engine(study, seconds=0.3, compile_=False)
    report = run_study(study, tmp_path / "out", threads=1, engine=engine, progress=False)
    assert report.complete and not report.warmup_compiled and report.warmup_seconds >= 0.3
    assert warmup.COMPILING_MESSAGE not in capsys.readouterr().err


def test_compile_command(capsys):
    args = ["compile", "--methods", "adaptive", "--laws", "jankowski", "--structures", "sdof"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert warmup.cache_directory() in out
    assert "1 combinations ready" in out
    assert "sdof  adaptive" in out


@pytest.mark.parametrize(
    "args, key",
    [(["--methods", "rk45"], "--methods"), (["--laws", "coulomb"], "--laws")],
)
def test_compile_command_rejects_unknown_names(args, key, capsys):
    assert main(["compile", *args]) == 2
    assert key in capsys.readouterr().err


def test_check_says_compile_time_is_excluded(make_study, capsys):
    assert main(["check", str(make_study()), "--threads", "1", "--calibrate", "4"]) == 0
    out = capsys.readouterr().out
    assert "estimated :" in out
    assert "compile time not included" in out


@jit
def _scaled(x, k):
    return x * k


@jit(entry=True)
def _shifted(x, k):
    return x + k


@jit
def _two_calls(x):
    # literal arguments 0 and 1: one compiled version of each callee, for int64
    return _scaled(x, 0) + _scaled(x, 1) + _shifted(x, 0) + _shifted(x, 1)


def test_helpers_compile_once_for_plain_types():
    for f in (_scaled, _shifted, _two_calls):  # compiled here, never loaded from a cache
        f._cache = NullCache()
        if f._called is not None:
            f._called._cache = NullCache()
    assert _two_calls(2.0) == 2.0 + 2.0 + 3.0  # 2*0 + 2*1 + (2+0) + (2+1)
    plain = (types.float64, types.int64)
    # a helper: one version, without the Python wrapper, in its twin; none for Python yet
    assert list(_scaled._called.overloads) == [plain]
    assert _scaled.overloads == {}
    assert _scaled(2.0, 3) == 6.0  # a Python call compiles the wrapped version
    assert list(_scaled.overloads) == [plain]
    # an entry: the same version for compiled callers and for Python
    assert list(_shifted.overloads) == [plain]
    assert _shifted(2.0, 3) == 5.0
    assert len(_shifted.overloads) == 1


def test_textbook_newmark_matches_the_package_scheme():
    scene = load_scene(B1)
    record = scene.record_arrays()
    peak, impacts, _, _ = bench.textbook_newmark(*bench._textbook_args(scene, record, 1e-3))
    ours = simulate(scene, method="newmark", dt_s=1e-3).outputs
    # the same average-acceleration scheme with Newton on the contact: equal to rounding
    assert peak == pytest.approx(ours["peak_force"], rel=1e-9)
    assert impacts == ours["impacts"] == 22
    # DESIGN.md section 5: Newmark at dt = 1e-3 s is about 6e-4 from the SciPy solution
    assert abs(peak - B1_PEAK_FORCE) / B1_PEAK_FORCE < 1e-3


@pytest.mark.parametrize(
    ("override", "message"),
    [
        ({"method": "newmark", "dt_s": -1.0}, "dt_s: must be in (0, 1], got -1.0"),
        ({"dt_s": 0.0}, "dt_s: must be in (0, 1], got 0.0"),  # was taken as "not given"
        ({"substeps": 0}, "substeps: must be an integer in [4, 1024], got 0"),
        ({"substeps": 2.5}, "substeps: must be an integer, got 2.5"),
        ({"method": "rk45"}, "method: unknown value 'rk45'"),
    ],
)
def test_simulate_refuses_overrides_the_scene_file_would_refuse(override, message):
    # the command line refused them (--dt, --method); from Python a negative step ran to
    # not_converged, a zero step and zero sub-steps quietly took the scene's own
    scene = load_scene(B1)
    with pytest.raises(InputError, match=re.escape(message)):
        simulate(scene, **override)


def test_bench_prints_ratios(capsys):
    assert main(["bench", "--head-to-head-only", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "load average" in out
    for label in bench.CONTENDERS:
        assert label in out
    assert "newmark dt=1e-3 / adaptive" in out
    assert "textbook dt=1e-3 / newmark dt=1e-3" in out
    assert "simulate() newmark / simulate() adaptive" in out
    assert "x adaptive" in out


def test_bench_json(capsys):
    assert main(["bench", "--head-to-head-only", "--repeats", "1", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    rows = {r["label"]: r for r in info["head_to_head"]}
    assert set(rows) == set(bench.CONTENDERS)
    # each row's x_adaptive is its median time over its baseline's (the kernel's adaptive, or
    # simulate() adaptive for the public calls), and with one repeat every paired ratio is the
    # ratio of the two timed calls themselves
    for label, row in rows.items():
        base = "simulate() adaptive" if row["call"] == "simulate" else "adaptive"
        assert row["x_adaptive"] == pytest.approx(row["seconds"] / rows[base]["seconds"],
                                                  rel=1e-12), label  # fmt: skip
    assert info["repeats"] == 1
    for name, (a, b) in {
        "newmark dt=1e-3 / adaptive": ("newmark dt=1e-3", "adaptive"),
        "newmark dt=1e-4 / adaptive": ("newmark dt=1e-4", "adaptive"),
        "textbook dt=1e-3 / newmark dt=1e-3": ("textbook newmark dt=1e-3", "newmark dt=1e-3"),
        "simulate() newmark / simulate() adaptive": ("simulate() newmark dt=1e-3",
                                                     "simulate() adaptive"),
    }.items():  # fmt: skip
        assert info["ratios"][name] == pytest.approx(
            rows[a]["seconds"] / rows[b]["seconds"], rel=1e-12
        ), name
    # the errors are against the reference's peak force, DESIGN.md section 5's 7.0259e6 N
    # (an independent SciPy solution) with its 22 impacts
    assert info["reference_peak_force"] == pytest.approx(B1_PEAK_FORCE, rel=1e-5)
    for label, row in rows.items():
        err = abs(row["peak_force"] - info["reference_peak_force"]) / info["reference_peak_force"]
        assert row["err_peak_force"] == pytest.approx(err, rel=1e-12, abs=1e-300), label
        assert row["impacts"] == 22, label
    # DESIGN.md section 5 / README: adaptive's peak-force error is about 2e-5, newmark's at
    # dt = 1e-3 s about 7e-4
    assert rows["adaptive"]["err_peak_force"] < 3e-5
    assert rows["newmark dt=1e-3"]["err_peak_force"] < 1e-3
    assert len(info["load_before"]) == 3


def test_numba_cache_dir_keeps_the_source_key(tmp_path, monkeypatch):
    """With ``NUMBA_CACHE_DIR`` set the kernels went to numba's own cache, keyed on each
    function's own file: a batch kernel kept an old copy of a helper it inlines from another
    file after that file was edited (stale results).  Now the cache moves into that folder
    and keeps the key of every compiled source (``_jit.source_key``)."""
    from numba.core import config

    from pound_mc import _jit
    from pound_mc.integrators import batch

    monkeypatch.delenv("POUND_MC_CACHE_DIR", raising=False)
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))
    func = batch._sdof_adaptive.py_func
    locator = _jit._SharedCacheLocator.from_function(func, func.__code__.co_filename)
    expected = tmp_path / "pound-mc" / "numba" / _jit.source_key() / "integrators"
    assert Path(locator.get_cache_path()) == expected
    assert locator.get_source_stamp() == _jit.source_key()
