"""Study runner: reproducibility, resume, change detection, Ctrl-C, ``check``."""

import os
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numba
import numpy as np
import pytest
import xarray as xr

from pound_mc.cli import main
from pound_mc.errors import InputError, InputErrors
from pound_mc.integrators.reference import reference_solution
from pound_mc.study.dataset import RESULT_VARIABLES
from pound_mc.study.definition import load_study, study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import (
    CHUNKS_PER_THREAD,
    chunk_ranges,
    default_chunk_size,
    plan_text,
    run_study,
)
from studies import study_text

# studies.SMALL_SDOF: T = 0.3, 0.5, 0.7 s x gap 0, 2 mm x 8 concrete samples
STUDY = study_text()
N = 3 * 2 * 8


@pytest.fixture
def study_file(make_study):
    return make_study()  # tmp_path / "small.toml", the text of STUDY


def _data(path) -> dict[str, bytes]:
    """Bytes of every data variable of a dataset file."""
    with xr.open_dataset(path) as ds:
        return {name: ds[name].values.tobytes() for name in ds.data_vars}


def _assert_identical(a, b):
    da, db = _data(a), _data(b)
    assert da.keys() == db.keys()
    for name in da:
        assert da[name] == db[name], name


@pytest.fixture
def reference(study_file, tmp_path):
    """The study run once in one chunk with one thread: the dataset every variant must equal."""
    report = run_study(
        load_study(study_file), tmp_path / "ref", threads=1, chunk_size=N, progress=False
    )
    assert report.complete and report.chunks_total == 1
    return report.path


def test_dataset_layout(reference):
    with xr.open_dataset(reference) as ds:
        assert ds.attrs["Conventions"] == "CF-1.13"
        assert ds.attrs["study_text"] == STUDY
        assert ds["peak_force"].dims == ("record", "left_period_s", "contact_gap_m", "sample")
        assert ds["peak_force"].shape == (1, 3, 2, 8)
        for name in [*RESULT_VARIABLES, "e", "beta", "xi", "e_effective"]:
            assert "units" in ds[name].attrs and "long_name" in ds[name].attrs, name
        for name in ("peak_force_mean", "peak_force_quantile", "pounding_probability"):
            assert ds[name].attrs["units"] in ("N", "1")
        assert ds["e"].dims == ("sample",) and ds["beta"].dims == ("sample",)
        assert np.all(ds["status"].values == 0)
        # gap 0 at T = 0.3 s against 1.0 s pounds for every sample
        assert np.all(ds["impacts"].sel(contact_gap_m=0.0).values > 0)
        assert np.all(ds["peak_force"].values >= 0)


def test_one_vs_two_threads_identical(study_file, reference, tmp_path):
    report = run_study(load_study(study_file), tmp_path / "w2", threads=2, progress=False)
    _assert_identical(reference, report.path)


@pytest.mark.parametrize("chunk_size", [5, 17])
def test_chunk_size_does_not_change_results(study_file, reference, tmp_path, chunk_size):
    report = run_study(
        load_study(study_file), tmp_path / "c", threads=2, chunk_size=chunk_size, progress=False
    )
    assert report.chunks_total == len(chunk_ranges(N, chunk_size))
    _assert_identical(reference, report.path)


def test_whole_chunks_on_threads_identical_and_drained_by_ctrl_c(study_file, reference,
                                                                 tmp_path):  # fmt: skip
    # 16 chunks of 3 on 2 threads: CHUNKS_PER_THREAD (8) chunks per thread, so each thread
    # runs whole chunks on one numba thread of its own
    assert len(chunk_ranges(N, 3)) >= CHUNKS_PER_THREAD * 2
    study = load_study(study_file)
    engine = StudyEngine(study)
    run_range = engine.run_range
    calls = []

    def recording(start, stop):
        calls.append((threading.current_thread().name, numba.get_num_threads()))
        if len(calls) == 3:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while chunks are in flight
        return run_range(start, stop)

    engine.run_range = recording
    out = tmp_path / "threads"
    first = run_study(study, out, threads=2, chunk_size=3, engine=engine, progress=False)
    assert first.interrupted and not first.complete
    # every chunk started before the Ctrl-C was finished and kept, and none after it started
    assert first.chunks_run == len(calls) < first.chunks_total
    assert len(list((out / "small").glob("chunk_*.npz"))) == len(calls)
    assert {n_threads for _, n_threads in calls} == {1}
    assert threading.main_thread().name not in {name for name, _ in calls}
    engine.run_range = run_range
    second = run_study(study, out, threads=2, chunk_size=3, engine=engine, progress=False)
    assert second.complete and second.chunks_run == second.chunks_total - len(calls)
    _assert_identical(reference, second.path)


def test_interrupted_run_resumes_identically(study_file, reference, tmp_path):
    study = load_study(study_file)
    out = tmp_path / "resume"
    first = run_study(study, out, chunk_size=7, max_chunks=3, progress=False)
    assert not first.complete and first.path is None and first.chunks_run == 3
    assert not (out / "small.nc").exists()
    assert len(list((out / "small").glob("chunk_*.npz"))) == 3
    second = run_study(load_study(study_file), out, chunk_size=7, progress=False)
    assert second.complete and second.chunks_run == second.chunks_total - 3
    _assert_identical(reference, second.path)
    third = run_study(load_study(study_file), out, chunk_size=7, progress=False)
    assert third.chunks_run == 0  # every chunk already done
    _assert_identical(reference, third.path)


def test_run_resumed_with_another_chunk_size_keeps_its_chunks(study_file, reference, tmp_path,
                                                              capsys):  # fmt: skip
    out = tmp_path / "resize"
    first = run_study(load_study(study_file), out, chunk_size=7, max_chunks=3, progress=False)
    assert first.chunks_run == 3
    second = run_study(load_study(study_file), out, chunk_size=5, progress=False)
    # the three chunks of 7 are kept: the rest is cut to 7 as well, not everything run again
    assert second.complete and second.chunks_total == len(chunk_ranges(N, 7))
    assert second.chunks_run == second.chunks_total - 3
    assert "holds 3 finished chunks of 7 simulations" in capsys.readouterr().err
    assert not list((out / "small").glob("chunk_5_*.npz"))
    _assert_identical(reference, second.path)


_KILLED_RUN = """
import sys, time
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from pound_mc.study.definition import load_study

study = load_study(sys.argv[1])
engine = StudyEngine(study)
run_range = engine.run_range

def slow(start, stop):  # slow the chunks down so the process is killed mid-way
    out = run_range(start, stop)
    time.sleep(0.15)
    return out

engine.run_range = slow
run_study(study, sys.argv[2], chunk_size=4, engine=engine, progress=False)
"""


@pytest.mark.slow
def test_killed_process_resumes_identically(study_file, reference, tmp_path):
    out = tmp_path / "killed"
    log = open(tmp_path / "killed.log", "wb")  # noqa: SIM115
    proc = subprocess.Popen(
        [sys.executable, "-c", _KILLED_RUN, str(study_file), str(out)],
        stdout=subprocess.DEVNULL,
        stderr=log,
    )
    try:
        deadline = time.monotonic() + 120
        chunks = []
        while time.monotonic() < deadline and proc.poll() is None:
            chunks = list((out / "small").glob("chunk_*.npz"))
            if len(chunks) >= 2:
                break
            time.sleep(0.02)
        assert proc.poll() is None, (tmp_path / "killed.log").read_text()
        proc.kill()  # SIGKILL: no chance to clean up
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(30)
        log.close()
    done = list((out / "small").glob("chunk_*.npz"))
    assert 2 <= len(done) < N // 4
    assert not (out / "small.nc").exists()
    report = run_study(load_study(study_file), out, chunk_size=4, progress=False)
    assert report.complete and report.chunks_run <= report.chunks_total - len(done)
    _assert_identical(reference, report.path)


def test_ctrl_c_stops_between_chunks(study_file, reference, tmp_path):
    study = load_study(study_file)
    engine = StudyEngine(study)
    run_range = engine.run_range
    calls = []

    def interrupting(start, stop):
        calls.append(start)
        if len(calls) == 2:
            os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while the second chunk runs
        return run_range(start, stop)

    engine.run_range = interrupting
    out = tmp_path / "ctrlc"
    report = run_study(study, out, chunk_size=6, engine=engine, progress=False)
    assert report.interrupted and not report.complete
    assert report.chunks_run == 2  # the chunk in flight was finished and kept
    assert len(list((out / "small").glob("chunk_*.npz"))) == 2
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    resumed = run_study(load_study(study_file), out, chunk_size=6, progress=False)
    assert resumed.chunks_run == resumed.chunks_total - 2
    _assert_identical(reference, resumed.path)


def test_an_unknown_option_shows_its_command_usage(study_file, tmp_path, capsys):
    # the program's usage ("usage: pound-mc [-h] [--version] COMMAND ...") named no option
    with pytest.raises(SystemExit) as exit_info:
        main(["run", str(study_file), "--out", str(tmp_path / "o"), "--bogus"])
    err = capsys.readouterr().err
    assert exit_info.value.code == 2
    assert (
        "usage: pound-mc run " in err
        and "pound-mc run: error: unrecognized arguments: --bogus" in err
    )
    assert not (tmp_path / "o").exists()


def test_out_naming_a_file_says_so(study_file, tmp_path, capsys):
    # "cannot write: File exists"
    taken = tmp_path / "results"
    taken.write_text("mine")
    assert main(["run", str(study_file), "--out", str(taken), "--no-progress"]) == 2
    assert f"{taken}: is a file, not a folder: give --out a folder" in capsys.readouterr().err
    assert taken.read_text() == "mine"


def test_run_summary_counts_in_the_singular(make_study, tmp_path, capsys):
    # "1 simulations, 1 of 1 chunks run"
    one = make_study(grid=None, sampling={"n": 1})
    assert main(["run", str(one), "--out", str(tmp_path), "--no-progress", "--no-plot"]) == 0
    assert "1 simulation, 1 of 1 chunk run in " in capsys.readouterr().out


def test_changed_study_refused_unless_fresh(study_file, tmp_path):
    out = tmp_path / "changed"
    run_study(load_study(study_file), out, chunk_size=16, max_chunks=1, progress=False)
    study_file.write_text(STUDY.replace("seed = 11", "seed = 12"))
    with pytest.raises(InputError, match="--fresh"):
        run_study(load_study(study_file), out, chunk_size=16, progress=False)
    rc = main(["run", str(study_file), "--out", str(out), "--no-progress", "--no-plot"])
    assert rc == 2
    # which keys changed (the message said "the study file" alone)
    edited = STUDY.replace("seed = 11", "seed = 12").replace("n = 8", "n = 4")
    study_file.write_text(edited + "# a comment\n")
    with pytest.raises(InputError, match=re.escape("(study.seed: 11 -> 12, sampling.n: 8 -> 4)")):
        run_study(load_study(study_file), out, chunk_size=16, progress=False)
    study_file.write_text(STUDY + "# a comment\n")
    with pytest.raises(InputError, match=re.escape("the study file (comments or layout only)")):
        run_study(load_study(study_file), out, chunk_size=16, progress=False)
    study_file.write_text(STUDY.replace("seed = 11", "seed = 12"))
    report = run_study(load_study(study_file), out, chunk_size=16, fresh=True, progress=False)
    assert report.complete and report.chunks_run == report.chunks_total
    with xr.open_dataset(report.path) as ds:
        assert ds.attrs["seed"] == 12


def test_cli_run_writes_dataset_and_chart(study_file, tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["run", str(study_file), "--out", str(out), "--threads", "2"]) == 0
    text = capsys.readouterr()
    assert "simulations/s" in text.out
    assert (out / "small.nc").is_file() and (out / "small_spectrum.png").is_file()
    assert (out / "small_required_gap.png").is_file()  # two gaps on the grid
    assert "sim/s" in text.err or "it/s" in text.err  # tqdm's rate


def test_check_prints_plan_and_writes_nothing(study_file, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    assert main(["check", str(study_file), "--calibrate", "8"]) == 0
    text = capsys.readouterr().out
    # one chunk holds the 48 simulations: "1 chunk of 48" (it read "1 chunks of 256")
    assert f"simulations: {N} in 1 chunk of {N}\n" in text and "estimated" in text
    assert "grid      : left.period_s = 3 values 0.3 .. 0.7" in text
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_calibrate_times_the_count_asked_or_enough_for_min_s(make_study):
    # 3 periods x 2 gaps x 64 samples = 384 simulations of a 4-s record
    engine = StudyEngine(load_study(make_study(sampling={"n": 64})))
    per_sim, _, timed = engine.calibrate(workers=1, n=4)
    assert timed == 4 and per_sim > 0.0
    # no count: 64, then more until the run lasts min_s (here never: the whole study)
    _, _, timed = engine.calibrate(workers=1, min_s=600.0)
    assert timed == 384
    # ... and no more than min_s needs (the first 64 already last a microsecond)
    _, _, timed = engine.calibrate(workers=1, min_s=1e-6)
    assert timed == 64
    # a budget below one simulation's time runs one
    _, _, timed = engine.calibrate(workers=1, min_s=600.0, budget_s=1e-9)
    assert timed == 1


def test_default_chunk_size():
    assert default_chunk_size(10) == 256
    assert default_chunk_size(100_000) == 2000
    assert default_chunk_size(10**8) == 8192


def test_shear_study_refuses_a_structural_axis():
    text = STUDY.replace(
        'model = "sdof"\nperiod_s = 0.5\ndamping_ratio = 0.05\nmass_kg = 1.0e6',
        'model = "shear"\nstorey_mass_kg = [1.0e6, 1.0e6]\n'
        "storey_stiffness_N_per_m = [1.0e8, 1.0e8]\nstorey_height_m = [3.0, 3.0]",
        1,
    )
    with pytest.raises(InputErrors) as info:
        study_from_text(text, file="shear.toml")
    # the modes of a shear building are computed once per study: no structural axes
    errors = {e.key: e.message for e in info.value.errors}
    assert "structural" in errors["grid.left.period_s"]


@pytest.mark.nojit  # the threaded batch kernel on four simulations
def test_grid_study_without_base_value(tmp_path):
    # the grid axis supplies a value the scene does not give itself
    text = STUDY.replace("period_s = 0.5\n", "", 1)
    study = study_from_text(text, file=tmp_path / "nobase.toml")
    result = StudyEngine(study).run_range(0, 4)
    assert np.all(result["status"] == 0)


def test_linear_law_study(tmp_path):
    text = textwrap.dedent(STUDY).replace('model = "jankowski"', 'model = "kelvin"')
    text = text.replace("beta = 2.75e9", "k_N_per_m = 1.0e9").replace(
        '"contact.beta" = { material = "concrete" }', ""
    )
    path = tmp_path / "kelvin.toml"
    path.write_text(text)
    study = load_study(path)
    report = run_study(study, tmp_path / "k", progress=False)
    with xr.open_dataset(report.path) as ds:
        ds.load()
    assert float(ds["k_N_per_m"]) == 1.0e9
    assert np.all(ds["status"].values == 0)
    # the Kelvin law's damping from each sampled e by Anagnostopoulos (1992),
    # xi = -ln e / sqrt(pi^2 + ln^2 e), written out here
    e = ds["e"].values
    assert e.min() < e.max()  # sampled over concrete's Table 2 range
    np.testing.assert_allclose(ds["xi"].values, -np.log(e) / np.sqrt(np.pi**2 + np.log(e) ** 2),
                               rtol=1e-12)  # fmt: skip
    # the runs against the independent SciPy reference (the Kelvin law written out there):
    # the strongest pounding run and one at the other gap, impacts and peak force as in
    # test_laws_vs_reference (adaptive at its defaults: 1e-4)
    engine = StudyEngine(study)
    impacts = ds["impacts"].values.ravel()
    force = ds["peak_force"].values.ravel()
    assert (impacts > 0).sum() > 8  # the study pounds
    gap_axis = ds["peak_force"].dims.index("contact_gap_m")
    at_gap = np.unravel_index(np.arange(impacts.size), ds["peak_force"].shape)[gap_axis]
    for gap in (0, 1):
        mine = np.flatnonzero(at_gap == gap)
        i = int(mine[np.argmax(force[mine])])
        ref = reference_solution(engine.scene_of(i), engine.record_of(i))
        assert impacts[i] == ref["impacts"] > 0
        assert force[i] == pytest.approx(ref["peak_force"], rel=1e-4)


def test_plan_names_the_materials_of_a_material_axis():
    """``check`` listed the material axis by its indices ("4 values 0 .. 3")."""
    study = load_study(Path(__file__).resolve().parents[1] / "studies" / "jankowski_spectrum.toml")
    text = plan_text(study)
    assert "  grid      : contact.material = 4 values steel, concrete, timber, ceramics\n" in text
