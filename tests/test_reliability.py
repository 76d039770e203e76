"""Drills of the defect classes of the reliability issue (#16), one or more tests per class.

Each test names its class; each failed on the code before the fix (a silently mixed resume,
a traceback, an accepted absurd value, a missing estimate, a coordinate with ``_FillValue``).
The studies are the 48-simulation ``small`` study of ``tests/studies.py`` or smaller, so the
whole file runs in seconds once the kernels are cached.
"""

import contextlib
import errno
import io
import json
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from test_drills import _at2_text

from pound_mc.analysis.plot_numerics import time_history_chart
from pound_mc.cli import main
from pound_mc.scene import load_scene, simulate
from pound_mc.study.files import output_lock
from studies import Whole, study_text

_OPTIONS = ["--no-progress", "--no-plot"]
SHIPPED = sorted((Path(__file__).resolve().parent.parent / "studies").glob("*.toml"))


def _run(*argv: str) -> tuple[int, str, str]:
    """``pound-mc argv``: (exit status, stdout, stderr)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main([str(a) for a in argv])
    return rc, out.getvalue(), err.getvalue()


def _assert_clean_error(rc: int, err: str, *names: str) -> None:
    """Exit 2, one line, no traceback, every one of ``names`` in the message."""
    assert rc == 2, err
    assert "Traceback" not in err and err.count("\n") == 1, err
    for name in names:
        assert name in err, (name, err)


def _tiny(make_study, **tables):
    """The small study cut to 2 samples and one grid axis (4 simulations)."""
    tables.setdefault("grid", {"left.period_s": None})
    tables.setdefault("sampling", {"n": 2})
    return make_study(**tables)


# ------------------------------------------------------------ class 1: stale inputs on resume


def test_changed_record_between_interrupt_and_resume_is_refused(make_study, tmp_path):
    """Class 1: a record changed between an interrupted run and its resume was mixed in."""
    record = tmp_path / "quake.at2"
    record.write_text(_at2_text(npts=200))
    study = _tiny(make_study, record={"source": "quake.at2", "duration_s": None})
    out = tmp_path / "out"
    # an interrupted run: one chunk of two written
    from pound_mc.study.definition import load_study
    from pound_mc.study.runner import run_study

    report = run_study(load_study(study), out, chunk_size=2, max_chunks=1, progress=False)
    assert not report.complete
    # every sample doubled: the same file name, other numbers
    text = _at2_text(npts=200).splitlines()
    text[4:] = ["  ".join(f"{2 * float(v): .7E}" for v in row.split()) for row in text[4:]]
    record.write_text("\n".join(text) + "\n")
    rc, _, err = _run("run", study, "--out", out, "--chunk-size", "2", *_OPTIONS)
    # the record named as the study names it: relative to the study's folder
    _assert_clean_error(rc, err, "changed since", "record.source (quake.at2)", "--fresh")
    assert not (out / "small.nc").exists()
    # --fresh discards the old chunks and runs everything on the new record
    rc, text, err = _run("run", study, "--out", out, "--chunk-size", "2", "--fresh", *_OPTIONS)
    assert rc == 0, err
    assert "2 of 2 chunks run" in text


def test_corrupt_manifest_is_not_reported_as_a_changed_study(make_study, tmp_path):
    """Class 9 (message): a corrupt manifest was reported as "the study changed"."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    assert _run("run", study, "--out", out, *_OPTIONS)[0] == 0
    (out / "small" / "manifest.json").write_text('{"study_hash": ')
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "manifest", "corrupt", str(out / "small" / "manifest.json"))
    assert "changed" not in err


# --------------------------------------------------------------- class 2: one writer per output


def test_second_run_on_the_same_output_exits_at_once(make_study, tmp_path):
    """Class 2: two runs on one ``--out`` shared temporary names and overwrote each other."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    with output_lock(out, "small") as lock:
        assert lock.read_text().strip() == str(os.getpid())
        rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
        _assert_clean_error(rc, err, f"process {os.getpid()}", str(lock))
        assert not (out / "small").exists()  # nothing written by the refused run
    # the lock is gone with its holder; a lock file left by a dead process is not in the way
    assert not lock.exists()
    lock.write_text("999999999\n")
    (out / "small").mkdir()
    stale = out / "small" / ".chunk_2_000000.npz.999999999.part"
    stale.write_bytes(b"torn")
    assert _run("run", study, "--out", out, *_OPTIONS)[0] == 0
    assert not stale.exists() and not lock.exists()


# --------------------------------------------------------------- class 3: see test_distributed

# ------------------------------------------------------------------ class 6: endless runs


def test_endless_adaptive_step_is_refused_by_check(make_study, tmp_path):
    """Class 6: ``adaptive`` with dt_s = 1e-7 ran for minutes, and ``check`` did not return.

    4 s of record at 1e-7 s is 4e7 steps per simulation, over the 3e7-step budget
    (:data:`pound_mc.study.engine.STEP_BUDGET`): refused before any simulation.
    """
    study = _tiny(make_study, integrator={"dt_s": 1e-7})
    for command in ("check", "run"):
        rc, _, err = _run(command, study, *(["--out", tmp_path / "o"] if command == "run" else []))
        _assert_clean_error(rc, err, "integrator.dt_s", "4e+07 steps", str(study))
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------- class 7: clean error paths


@pytest.mark.parametrize("kind", ["file", "loop"])
def test_wrong_type_output_path(make_study, tmp_path, kind):
    """Class 7: an output path that is a file, or a link loop, ended in a traceback."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    if kind == "file":
        out.write_text("not a folder")
    else:
        out.symlink_to(out)
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, str(out))


def test_disk_full_while_writing_chunks_and_dataset(make_study, tmp_path, monkeypatch):
    """Class 7: ENOSPC and "NetCDF: HDF error" were tracebacks and left ``.part`` files."""
    import pound_mc.study.files as files

    study = _tiny(make_study)
    out = tmp_path / "out"

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    with monkeypatch.context() as patch:
        patch.setattr(files.os, "fsync", full)
        rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "No space left on device", str(out / "small"))
    assert not list(out.rglob("*.part"))

    write = xr.Dataset.to_netcdf

    def torn(self, path=None, *args, **kwargs):
        write(self, path, *args, **kwargs)
        os.truncate(path, os.path.getsize(path) // 2)
        raise RuntimeError("NetCDF: HDF error")

    with monkeypatch.context() as patch:
        patch.setattr(xr.Dataset, "to_netcdf", torn)
        rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "NetCDF: HDF error", str(out / "small.nc"))
    assert not list(out.rglob("*.part")) and not (out / "small.nc").exists()
    assert _run("run", study, "--out", out, *_OPTIONS)[0] == 0  # resumes once there is room


@pytest.mark.parametrize(
    ("tables", "key"),
    [
        ({"study": {"name": "s" * 300}}, "study.name"),
        (
            {"record": {"source": "synthetic:clough-penzien", "duration_s": 1e9, "seed": 1}},
            "duration_s",
        ),  # fmt: skip
        ({"record": {"resample_hz": 1e7}}, "resample_hz"),
        (
            {"sampling": {"n": 2**24}, "grid": {"left.period_s": [0.1 * k for k in range(1, 101)]}},
            "sampling.n",
        ),  # fmt: skip
    ],
    ids=["long-name", "endless-synthetic", "1e7-Hz", "1.68e9-simulations"],
)
def test_oversized_studies_are_refused(tmp_path, tables, key):
    """Class 7: a 300-character name, a 1e9-s or 1e7-Hz record, 1.68e9 simulations crashed."""
    study = tmp_path / "big.toml"
    study.write_text(study_text(**tables))
    rc, _, err = _run("run", study, "--out", tmp_path / "out", *_OPTIONS)
    _assert_clean_error(rc, err, key)
    assert not list(tmp_path.glob("out/**/*"))


def test_non_utf8_scene_is_refused(tmp_path):
    """Class 7: a scene file that is not UTF-8 ended in a UnicodeDecodeError traceback."""
    scene = tmp_path / "scene.toml"
    scene.write_bytes(b'[left]\nmodel = "sdof\xff"\n')
    rc, _, err = _run("simulate", scene)
    _assert_clean_error(rc, err, str(scene))


def test_study_without_grid_writes_its_dataset_and_a_chart(make_study, tmp_path):
    """Class 7: a study without [grid] wrote its dataset, then the chart failed."""
    study = _tiny(make_study, grid=None)
    out = tmp_path / "out"
    rc, text, err = _run("run", study, "--out", out, "--no-progress")
    assert rc == 0, err
    assert (out / "small.nc").exists()
    charts = list(out.glob("small*.png"))
    assert charts and all(p.stat().st_size > 0 for p in charts), text


# ------------------------------------------------------- class 8: memory and disk estimates


def test_check_estimates_memory_and_disk(make_study, tmp_path):
    """Class 8: ``check`` gave no memory or disk estimate."""
    study = _tiny(make_study)
    rc, text, err = _run("check", study, "--out", tmp_path, "--calibrate", "2")
    assert rc == 0, err
    assert "memory    : about" in text and "disk      : about" in text
    assert "GiB free" in text


# ------------------------------------------------------------------ class 9: validation


@pytest.mark.parametrize(
    ("tables", "key"),
    [
        ({"record": {"demean": "false"}}, "record.demean"),
        ({"integrator": {"method": "newmark", "dt_s": 0.05}}, "integrator.dt_s"),
        ({"integrator": {"substeps": 2**70}}, "integrator.substeps"),
        ({"left": {"mass_kg": 1e308}}, "left.mass_kg"),
    ],
    ids=["demean-string", "dt-above-record-step", "substeps-2^70", "mass-1e308"],
)
def test_absurd_values_are_refused_at_check(make_study, tables, key):
    """Class 9: a string demean, a step above the record's, 2^70 substeps, 1e308 kg accepted."""
    study = make_study(**tables)
    rc, _, err = _run("check", study, "--calibrate", "1")
    _assert_clean_error(rc, err, key)


def test_symlink_loop_is_not_file_not_found(tmp_path):
    """Class 9 (message): a study file that is a link loop was reported as "no such file"."""
    study = tmp_path / "loop.toml"
    study.symlink_to(study)
    rc, _, err = _run("check", study)
    _assert_clean_error(rc, err, "symbolic link", str(study))
    assert "no such" not in err.lower()


# ---------------------------------------------------------------------------- class 10: CF


def cf_problems(ds: xr.Dataset) -> list[str]:
    """What a dataset breaks of the CF conventions (1.13) the datasets claim.

    Checked against the CF document: a coordinate variable has no missing values, so no
    ``_FillValue`` (section 2.5.1); every variable has ``units`` (3.1; "1" for a number, none
    needed for flags and strings only where flag_values/flag_meanings say what they are) and a
    ``long_name`` or ``standard_name`` (3.2, 3.3); ``flag_values`` and ``flag_meanings`` come in
    pairs of equal length (3.5); the ``Conventions`` attribute names CF (2.6.1).
    """
    problems = []
    if not str(ds.attrs.get("Conventions", "")).startswith("CF-"):
        problems.append("global: no CF Conventions attribute")
    for name, var in ds.variables.items():
        attrs = {**var.attrs, **var.encoding}
        if name in ds.coords and "_FillValue" in var.attrs:
            problems.append(f"{name}: coordinate with _FillValue")
        if "long_name" not in var.attrs and "standard_name" not in var.attrs:
            problems.append(f"{name}: no long_name or standard_name")
        strings = var.dtype.kind in "OSU"
        if "units" not in attrs and not strings and "flag_values" not in attrs:
            problems.append(f"{name}: no units")
        if "flag_values" in attrs:
            meanings = str(attrs.get("flag_meanings", "")).split()
            if len(meanings) != np.size(attrs["flag_values"]):
                problems.append(f"{name}: flag_values and flag_meanings differ in length")
    return problems


def test_cf_check_of_a_written_dataset(make_study, tmp_path):
    """Class 10: coordinates carried ``_FillValue``; ``record`` had no units or long_name."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    assert _run("run", study, "--out", out, *_OPTIONS)[0] == 0
    with xr.open_dataset(out / "small.nc", decode_cf=False) as ds:
        assert cf_problems(ds) == []
        assert set(ds.coords) >= {"record", "contact_gap_m", "sample"}
    manifest = json.loads((out / "small" / "manifest.json").read_text())
    assert set(manifest["inputs"]) >= {"study"}


@pytest.mark.parametrize("path", SHIPPED, ids=[p.stem for p in SHIPPED])
def test_cf_check_of_the_shipped_studies_datasets(path, tmp_path):
    """Class 10: the shipped studies' datasets, as written, break no checked CF rule.

    The layout is the real one (every variable, coordinate and attribute a run writes); the
    values are zeros, which the checked metadata do not depend on, so no simulation runs.
    """
    from pound_mc.study.dataset import build_dataset, write_netcdf
    from pound_mc.study.definition import load_study
    from pound_mc.study.engine import StudyEngine

    study = load_study(path)
    engine = StudyEngine(study)
    results = {
        name: np.zeros((*study.shape, *tail), dtype)
        for name, (tail, dtype) in engine.result_layout().items()
    }
    ds = build_dataset(study, results, engine.dataset_parameters(), provenance=engine.provenance())
    written = write_netcdf(ds, tmp_path / f"{study.name}.nc")
    with xr.open_dataset(written, decode_cf=False) as ds:
        assert cf_problems(ds) == []


# ---------------------------------------------------------- classes 4 and 5: accuracy flags


def test_shortest_contact_is_the_hertz_closed_form():
    """Class 5: the duration behind the ``inaccurate`` flag is the elastic Hertz duration.

    Source: ``contact_duration_hertz`` (t_c = 2.943 delta_max / v0, DESIGN.md section 4) at the
    penetration ``max_penetration_elastic`` of the same impact; the kernel's duration uses the
    rounded 3.218 (m/beta)^0.4 v0^-0.2, hence 1e-3.
    """
    from pound_mc.integrators.accuracy import shortest_contact_s
    from pound_mc.physics.contact import contact_duration_hertz, max_penetration_elastic

    v0, beta, m = np.array([0.01, 0.3, 2.0]), 2.75e9, 5.0e5
    d = max_penetration_elastic(v0, beta, m)
    got = shortest_contact_s("jankowski", d, beta, m)
    np.testing.assert_allclose(got, contact_duration_hertz(v0, beta, m), rtol=1e-3)
    assert shortest_contact_s("hertz", [0.0, np.nan], beta, m).tolist() == [np.inf, np.inf]
    # linear spring: half its period, pi sqrt(m / k), whatever the impact
    np.testing.assert_allclose(shortest_contact_s("linear", [1e-3], 1e8, 1e4), np.pi * 1e-2)


def test_under_resolved_fixed_step_contacts_are_flagged_inaccurate():
    """Classes 4 and 5: fixed-step runs with contacts of a few steps read ``ok``.

    The small study's buildings (T = 0.3 and 1.0 s, 1,000 t each, zero gap, concrete beta) on
    4 s of AKT013 at 0.3 g: contacts last about 0.1 s.  ``newmark`` at 0.01 s (a handful of
    steps a contact) is flagged; at 0.001 s it is ``ok`` and within 1 % of the converged peak
    force (``adaptive`` at 0.001 s, which sub-steps every contact).
    """
    import pound_mc.integrators as integrators
    from pound_mc.motions import load_record, record_arrays

    dt_rec, acc = record_arrays(load_record("builtin:knet-akt013", duration_s=4.0, pga_g=0.3))
    pair = dict(
        left_period_s=0.3, right_period_s=1.0, left_mass_kg=1e6, right_mass_kg=1e6,
        left_damping_ratio=0.05, right_damping_ratio=0.05, gap_m=0.0, xi=0.35, beta=2.75e9,
        contact_model="jankowski",
    )  # fmt: skip
    runs = {
        (method, dt): integrators.simulate_sdof_pairs(acc, dt_rec, dt_s=dt, method=method, **pair)
        for method, dt in [
            ("adaptive", 1e-3),
            ("newmark", 1e-2),
            ("newmark", 1e-3),
            ("central-difference", 1e-2),
        ]  # fmt: skip
    }
    converged = runs["adaptive", 1e-3]
    assert converged["status"][0] == 0 and converged["impacts"][0] > 0
    for coarse in (runs["newmark", 1e-2], runs["central-difference", 1e-2]):
        assert coarse["status"][0] == 3  # inaccurate
    fine = runs["newmark", 1e-3]
    assert fine["status"][0] == 0
    np.testing.assert_allclose(fine["peak_force"], converged["peak_force"], rtol=0.01)


@pytest.mark.parametrize("period_s", [0.01, 0.005])
def test_adaptive_very_stiff_building_is_not_unstable(period_s):
    """Class 4: ``adaptive`` flagged a building of T <= 0.015 s on a 100-Hz record unstable.

    With a 1-m gap there is no contact: the peak displacement of the stiff building is its
    linear spectral displacement PSA / omega^2, from the exact piecewise-linear recurrence of
    ``pound_mc.physics.spectra.response_spectrum`` (Nigam & Jennings 1969).
    """
    import pound_mc.integrators as integrators
    from pound_mc.motions import load_record, record_arrays
    from pound_mc.physics.spectra import response_spectrum

    dt_rec, acc = record_arrays(load_record("builtin:knet-akt013", duration_s=4.0, pga_g=0.5))
    assert dt_rec == pytest.approx(0.01)  # the period is below the record's step
    out = integrators.simulate_sdof_pairs(
        acc, dt_rec, left_period_s=period_s, right_period_s=1.0, left_mass_kg=1e6,
        right_mass_kg=1e6, left_damping_ratio=0.05, right_damping_ratio=0.05, gap_m=1.0,
        xi=0.35, beta=2.75e9, dt_s=0.01, method="adaptive",
    )  # fmt: skip
    assert out["status"][0] == 0 and out["impacts"][0] == 0
    # the exact recurrence on the record linearly resampled 1000 times finer (the same
    # piecewise-linear excitation): its peak at the fine samples is the continuous peak to
    # (omega dt / 2)^2 / 2 <= 2e-5 (the kernel sub-steps such buildings and finds the peak
    # between the record's samples, above the peak at them)
    fine = np.linspace(0.0, (acc.size - 1) * dt_rec, 1000 * (acc.size - 1) + 1)
    acc_fine = np.interp(fine, np.arange(acc.size) * dt_rec, acc)
    sd = response_spectrum(dt_rec / 1000, acc_fine, [period_s], 0.05) / (2 * np.pi / period_s) ** 2
    np.testing.assert_allclose(out["peak_disp_left"], np.ravel(sd)[:1], rtol=1e-4)


# ------------------------------------------- class 7: every error names the study or scene file


#: A contact the kernels' settings refuse: restitution set per impact on a law without damping
_UNDAMPED_PER_IMPACT = dict(
    contact={"e": None, "model": "hertz", "restitution": "velocity", "material": "concrete",
             "e_quantile": 0.5},
    sampling={"n": 2, "vary": None},
)  # fmt: skip


def test_kernel_settings_refusal_names_the_study_file(make_study, tmp_path):
    """Class 7: what the kernels' settings refuse (a law a method could not step, once) was
    refused without the study file's name."""
    study = _tiny(make_study, **_UNDAMPED_PER_IMPACT)
    for command in ("check", "run"):
        rc, _, err = _run(command, study, *(["--out", tmp_path / "o"] if command == "run" else []))
        _assert_clean_error(rc, err)
        assert err == (
            f"pound-mc {command}: error: {study}: contact.restitution: the 'hertz' law has no "
            "damping to set per impact\n"
        )
    # refused at its first simulation, after the manifest: the run left it behind
    assert not (tmp_path / "o" / study.stem).exists()


def test_refused_run_keeps_earlier_results(make_study, tmp_path):
    """A refused run removes only what it wrote itself: earlier results stay."""
    study = _tiny(make_study)
    rc, _, err = _run("run", study, "--out", tmp_path / "o", "--no-plot")
    assert rc == 0, err
    work = tmp_path / "o" / study.stem
    before = sorted(p.name for p in work.iterdir())
    assert "manifest.json" in before and any(p.startswith("chunk_") for p in before)
    _tiny(make_study, **_UNDAMPED_PER_IMPACT)
    # refused as it loads (per-impact restitution on an undamped law), before the earlier
    # results are looked at: with --fresh too, nothing is discarded for a run that cannot start
    for fresh in ([], ["--fresh"]):
        rc, _, err = _run("run", study, "--out", tmp_path / "o", *fresh)
        _assert_clean_error(rc, err, "damping", "contact.restitution")
        assert sorted(p.name for p in work.iterdir()) == before


@pytest.mark.parametrize("fresh", [[], ["--fresh"]], ids=["resume", "fresh"])
def test_a_folder_of_the_users_is_never_taken(make_study, tmp_path, fresh):
    """``--fresh`` removed any folder ``<out>/<study name>`` (a user's thesis.tex went with it);
    without it the run wrote its chunks and manifest among the user's files."""
    study = _tiny(make_study)
    work = tmp_path / "o" / study.stem
    work.mkdir(parents=True)
    (work / "thesis.tex").write_text("precious")
    rc, _, err = _run("run", study, "--out", tmp_path / "o", *fresh, *_OPTIONS)
    _assert_clean_error(rc, err, str(work), "thesis.tex", "no pound-mc results folder")
    assert sorted(p.name for p in work.iterdir()) == ["thesis.tex"]
    assert (work / "thesis.tex").read_text() == "precious"


@pytest.mark.parametrize(
    ("grid", "vary"),
    [
        ({"left.damping_ratio": [0.05, 0.3]}, None),
        (None, {"left.post_yield_ratio": {"distribution": "uniform", "low": 1e-4, "high": 0.004}}),
    ],
    ids=["grid", "sampled"],
)  # fmt: skip
def test_a_branch_without_stiffness_runs_adaptive(make_study, tmp_path, grid, vary):
    """A grid damping ratio of 0.3 (0.09 > post_yield_ratio 0.05), or a post_yield_ratio drawn
    below 0.05^2 = 0.0025, was refused (``adaptive``'s exact branch steps need an underdamped
    yielding branch); those simulations now run with the error-controlled steps, the others
    with the exact ones, in one study: every run ok and stored."""
    left = {"hysteresis": "bilinear", "yield_disp_m": 0.02, "post_yield_ratio": 0.05}
    tables = {"left": left, "grid": {"left.period_s": None, **(grid or {})}}
    if vary:
        tables["sampling"] = {"n": 8, "vary": vary}
    study = _tiny(make_study, **tables)
    rc, _, err = _run("run", study, "--out", tmp_path / "o", "--chunk-size", "1", *_OPTIONS)
    assert rc == 0, err
    with xr.open_dataset(tmp_path / "o" / f"{study.stem}.nc") as ds:
        assert int((ds["status"] == 0).sum()) == ds["status"].size


def test_a_study_or_scene_file_with_a_bom_reads(make_study, tmp_path):
    """An editor's UTF-8 byte-order mark read as "not valid TOML (at line 1, column 1)"."""
    study = _tiny(make_study)
    study.write_bytes(b"\xef\xbb\xbf" + study.read_bytes())
    rc, _, err = _run("check", study)
    assert rc == 0, err
    scene = tmp_path / "b1.toml"
    b1 = Path(__file__).resolve().parent.parent / "studies" / "scenes" / "b1.toml"
    scene.write_bytes(b"\xef\xbb\xbf" + b1.read_bytes())
    assert load_scene(scene).contact_model == "jankowski"


@pytest.mark.parametrize("command", ["stability", "bench"])
def test_an_unwritable_out_is_refused_before_the_work(tmp_path, monkeypatch, command):
    """bench and stability computed for 6-13 s, then failed on --out."""
    import pound_mc.cli.scene as cli_scene

    def no_work(*args, **kwargs):
        raise AssertionError("computed before --out was checked")

    monkeypatch.setattr(cli_scene, "head_to_head", no_work)
    monkeypatch.setattr(cli_scene, "stability_map", no_work)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    rc, _, err = _run(command, "--out", blocker / "sub")
    _assert_clean_error(rc, err, "--out", str(blocker / "sub"))


def test_simulate_names_the_scene_file_with_its_records_error(tmp_path):
    """Class 7: ``simulate`` reported a record's error without the scene file's name."""
    scene = tmp_path / "s.toml"
    scene.write_text(
        '[record]\nsource = "suite:fema-p695-farfield"\nduration_s = 1.0\n'
        "[left]\nperiod_s = 0.5\nmass_kg = 1.0e6\n[right]\nperiod_s = 1.0\nmass_kg = 1.0e6\n"
        "[contact]\ne = 0.65\n"
    )
    rc, out, err = _run("simulate", scene)
    _assert_clean_error(rc, err)
    assert not out
    # was "suite:fema-p695-farfield: record.component: a suite is ..."
    assert err == (
        f"pound-mc simulate: error: {scene}: record.component: suite:fema-p695-farfield: a "
        "suite is one record per component: a study's [[records]] expands it, a single record "
        'names the component (e.g. component = "NORTHR/MUL009")\n'
    )


# ------------------------------------------------- bad input of one scene (simulate, check)

#: studies/scenes/b1.toml on 3 s of El Centro, the gap closed (impacts from the start).
_SCENE = {
    "record": {"source": "builtin:elcentro", "duration_s": 3.0, "pga_g": 0.3},
    "left": {"model": "sdof", "period_s": 0.5, "mass_kg": 1.0e6},
    "right": {"model": "sdof", "period_s": 1.0, "mass_kg": 1.0e6},
    "contact": {"gap_m": 0.0, "beta": 2.75e9, "xi": 0.35},
    "integrator": {"method": "adaptive", "dt_s": 0.01},
}


def _scene(tmp_path, **tables) -> Path:
    """``_SCENE`` with ``tables`` merged in (``studies.study_data``), written to a file."""
    path = tmp_path / "scene.toml"
    path.write_text(study_text(_SCENE, **tables))
    return path


@pytest.mark.parametrize(
    ("tables", "argv", "status"),
    [
        ({"contact": {"beta": 1e16}, "integrator": {"method": "central-difference",
                                                    "dt_s": 0.02}}, [], "unstable"),
        ({}, ["--dt", "1e-12"], "not_converged"),
    ],
    ids=["unstable", "not-converged"],
)  # fmt: skip
def test_simulate_reports_a_run_that_is_not_ok(tmp_path, tables, argv, status):
    """``simulate`` crashed formatting the NaN outputs of an unstable or not converged run.

    Central difference is stable for omega dt < 2: a contact of beta = 1e16 at dt = 0.02 s is
    far beyond; 3 s at 1e-12 s is over the kernels' step budget.
    """
    scene = _scene(tmp_path, **tables)
    rc, text, err = _run("simulate", scene, *argv)
    assert rc == 1 and "Traceback" not in err, err
    assert f"status           {status}" in text and "peak force       nan N" in text
    rc, text, _ = _run("simulate", scene, *argv, "--json")
    info = json.loads(text)
    assert rc == 1 and info["status"] == status and info["peak_force_N"] is None
    if status == "not_converged":  # no count of the impacts either
        assert info["contacts"][0]["impacts"] is None


def test_histories_of_a_run_that_stopped_end_where_it_stopped(tmp_path):
    """After an unstable stop the histories read 0 (a penetration of 0: touching), now NaN."""
    method = {"method": "central-difference", "dt_s": 0.02}
    scene = load_scene(_scene(tmp_path, contact={"beta": 1e16}, integrator=method))
    res = simulate(scene, history=True)
    assert res.status == "unstable"
    reached = np.isfinite(res.penetration_m[:, 0])
    stop = int(np.argmin(reached))  # the first sample not reached
    assert 0 < stop < reached.size and not reached[stop:].any() and reached[:stop].all()
    assert np.isnan(res.disp_left_m[stop:]).all() and np.isnan(res.force_N[stop:]).all()
    time_history_chart(res, tmp_path / "stopped.png")  # draws what was reached


_SHEAR_1KG = {"model": "shear", "storey_mass_kg": [1.0], "storey_stiffness_N_per_m": [1.0e9],
              "storey_height_m": [3.0]}  # fmt: skip


@pytest.mark.parametrize(
    ("tables", "argv", "key"),
    [
        ({"left": {"period_s": 1e-7}}, [], "left.period_s"),
        ({"left": Whole(_SHEAR_1KG), "right": {"height_m": 3.0}}, [],
         "left.storey_stiffness_N_per_m"),
        ({"contact": {"xi": 100.0}}, [], "contact.xi"),
        ({"contact": {"model": "hertz"}}, [], "contact.xi"),
        ({"contact": {"model": "linear", "beta": None, "xi": None, "e": 0.5,
                      "k_N_per_m": 1e9}}, [], "contact.e"),
        ({}, ["--dt", "inf"], "--dt"),
        ({}, ["--dt", "5"], "--dt"),
    ],
    ids=["period-1e-7", "shear-period-2e-4", "xi-100", "hertz-xi", "linear-e", "dt-inf",
         "dt-5"],
)  # fmt: skip
def test_simulate_refuses_what_cannot_run(tmp_path, tables, argv, key):
    """Refused before the run, naming the file and key.

    T = 1e-7 s ran for minutes; 1 kg on 1e9 N/m has T = 2 pi sqrt(m / k) = 2e-4 s; xi = 100
    is beyond the exact table's 71.17; the elastic hertz and linear laws ignored xi and e;
    ``--dt inf`` and ``--dt 5`` were clamped while the file's integrator.dt_s takes (0, 1].
    """
    scene = _scene(tmp_path, **tables)
    rc, _, err = _run("simulate", scene, *argv)
    _assert_clean_error(rc, err, key, *([] if argv else [str(scene)]))


@pytest.mark.parametrize(
    ("tables", "key"),
    [
        ({"contact": {"e": None, "xi": 1e6}, "sampling": Whole(
            {"n": 2, "vary": {"contact.beta": {"material": "concrete"}}})}, "contact.xi"),
        ({"contact": {"e": None, "xi": 0.3}, "sampling": {"vary": Whole(
            {"contact.xi": {"distribution": "uniform", "low": 0.1, "high": 1e6}})}},
         "sampling.vary.contact.xi"),
        ({"grid": {"left.period_s": [0.5, 1e-9]}}, "grid.left.period_s"),
    ],
    ids=["xi-fixed", "xi-sampled", "period-grid"],
)  # fmt: skip
def test_study_refuses_xi_and_period_out_of_range_at_check(make_study, tmp_path, tables, key):
    """xi = 1e6 failed after every simulation (writing e_effective); T = 1e-9 s hung a run."""
    study = make_study(**tables)
    for command in ("check", "run"):
        rc, _, err = _run(command, study, *(["--out", tmp_path / "o"] if command == "run" else []))
        assert rc == 2 and "Traceback" not in err, err
        assert key in err and str(study) in err, err
    assert not (tmp_path / "o").exists()
