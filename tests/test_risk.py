"""Record suites and globs in studies, intensity axes, fragility and required gap of a dataset."""

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from matplotlib.backends.backend_agg import FigureCanvasAgg

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis.fragility import fit_fragility
from pound_mc.analysis.gap_probability import wilson_interval
from pound_mc.analysis.risk_chart import required_gap_chart
from pound_mc.cli import main
from pound_mc.errors import InputError, InputErrors
from pound_mc.motions.catalogue import _builtin_path
from pound_mc.motions.intensity import sa_g
from pound_mc.study.definition import grid_values, load_study, study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from studies import counted_dataset, pounding_counted, with_flagged_runs

SCENE = """
[left]
period_s = 0.5
mass_kg = 1e6
[right]
period_s = 1.0
mass_kg = 1e6
[contact]
gap_m = 0.01
beta = 2.75e9
e = 0.65
"""


@pytest.fixture(scope="module")
def glob_study(tmp_path_factory):
    """Three built-in AT2 files behind a glob, 4 s each, Sa(1 s) axis, two gaps."""
    root = tmp_path_factory.mktemp("risk")
    (root / "records").mkdir()
    for name in ("elcentro", "elcentro-270", "loma-prieta-corralitos-000"):
        shutil.copy(_builtin_path(name), root / "records")
    text = f"""
[study]
name = "risk"
seed = 7
[[records]]
source = "records/*.AT2"
duration_s = 4.0
sa_period_s = 1.0
{SCENE}
[grid]
"record.sa_g" = [0.3, 0.6, 1.2]
"contact.gap_m" = [0.0, 0.05, 0.1, 0.3]
"""
    path = root / "risk.toml"
    path.write_text(text)
    return path


def test_glob_expands_sorted_with_table_options(glob_study):
    study = load_study(glob_study)
    assert len(study.records) == 3
    sources = [r["source"] for r in study.records]
    assert sources == sorted(sources) and all(s.startswith("records/") for s in sources)
    assert all(r["duration_s"] == 4.0 and r["sa_period_s"] == 1.0 for r in study.records)
    assert study.shape == (3, 3, 4, 1)


def test_sa_scaling_hits_the_target(glob_study):
    engine = StudyEngine(load_study(glob_study))
    targets = engine.study.grid["record.sa_g"]
    for index in range(0, engine.study.n_simulations, 4):
        dt, acc = engine.record_of(index)
        r, j = np.unravel_index(index, engine.shape)[:2]
        # the scaled record's own 5 %-damped Sa at 1 s equals the grid value
        assert sa_g(dt, acc, 1.0) == pytest.approx(targets[j], rel=1e-6)
        assert engine.scale_factors[r, j] == pytest.approx(targets[j] / engine.record_sa_g[r])


@pytest.fixture(scope="module")
def glob_dataset(glob_study, tmp_path_factory):
    report = run_study(load_study(glob_study), tmp_path_factory.mktemp("out"), progress=False)
    return xr.open_dataset(report.path).load(), report.path


def test_dataset_record_variables(glob_dataset):
    ds, _ = glob_dataset
    assert ds["scale_factor"].dims == ("record", "sa_g")
    assert ds["record_sa_g"].attrs["units"] == "1" and "long_name" in ds["record_pga_g"].attrs
    np.testing.assert_allclose(
        ds["scale_factor"].values, ds["sa_g"].values[None, :] / ds["record_sa_g"].values[:, None]
    )
    assert list(ds["record_event"].values[:2]) == ["Imperial Valley-02"] * 2


def test_analysis_reads_relative_records_from_the_study_folder(glob_study, glob_dataset,
                                                              tmp_path, monkeypatch):  # fmt: skip
    """The study reads records/*.AT2 beside it and its dataset lies elsewhere: report and the
    charts that run the records again (probability's rules, required gap, history) looked for
    them beside the dataset ("the pattern matches no file")."""
    ds, path = glob_dataset
    assert ds.attrs["study_dir"] == str(glob_study.parent.resolve())
    monkeypatch.chdir(tmp_path)  # neither the study's folder nor the dataset's
    assert main(["report", str(path), "--out", str(tmp_path / "r.html")]) == 0
    for kind in ("probability", "required-gap", "history"):
        assert (
            main(["plot", str(path), "--kind", kind, "--out", str(tmp_path / f"{kind}.png")]) == 0
        )
    scene = ds.pound.scene(sample=0)  # the Python API too
    assert scene.record_arrays()[1].size > 0


def test_resume_takes_the_study_by_another_path(glob_study, tmp_path, monkeypatch):
    """The manifest keyed each record file by its path as the study was given: resuming the
    same study by another path (absolute, or from its own folder) was refused as changed."""
    out = tmp_path / "o"
    monkeypatch.chdir(glob_study.parent.parent)
    relative = Path(glob_study.parent.name) / glob_study.name
    run_study(load_study(relative), out, chunk_size=8, max_chunks=1, progress=False)
    monkeypatch.chdir(glob_study.parent)
    report = run_study(load_study(glob_study.name), out, chunk_size=8, progress=False)
    done = run_study(load_study(glob_study.resolve()), tmp_path / "whole", progress=False)
    a, b = xr.load_dataset(report.path), xr.load_dataset(done.path)
    for name in ("peak_force", "impacts", "status"):
        np.testing.assert_array_equal(a[name].values, b[name].values)


def test_data_frame_holds_each_rows_scale_factor(glob_dataset):
    """to_dataframe left out scale_factor (record x intensity): a row's scaling was lost."""
    ds, _ = glob_dataset
    table = ds.pound.to_dataframe()
    assert "scale_factor" in table and "record_sa_g" in table
    assert "pounding_probability" not in table  # a summary over samples
    np.testing.assert_allclose(table["scale_factor"], table["sa_g"] / table["record_sa_g"])
    # the intensity the only grid axis: the summaries over samples (record x intensity, as
    # scale_factor) stay out too
    only = ds.isel(contact_gap_m=0, drop=True).pound.to_dataframe()
    assert "scale_factor" in only and "pounding_probability" not in only
    assert "peak_force_mean" not in only


def test_results_do_not_depend_on_chunks(glob_study, glob_dataset, tmp_path):
    ds, _ = glob_dataset
    report = run_study(load_study(glob_study), tmp_path, chunk_size=5, progress=False)
    other = xr.open_dataset(report.path).load()
    for name in ("peak_force", "impacts", "scale_factor"):
        np.testing.assert_array_equal(ds[name].values, other[name].values)


@pytest.fixture(params=["as-run", "flagged"])
def counted_runs(request, glob_dataset):
    """The study's dataset as run, and with some runs flagged inaccurate and some unstable.

    A pounding count takes the flagged runs and leaves the unstable ones out
    (``studies.POUNDING_STATUSES``); a hand count of status ok alone disagrees on the flagged
    variant, so the checks that use it can fail.
    """
    ds, _ = glob_dataset
    if request.param == "flagged":
        ds = with_flagged_runs(ds)
        ok = (ds.status == 0).sum(("record", "sample"))
        assert (ok < pounding_counted(ds).sum(("record", "sample"))).any()
    return ds


def test_fragility_accessor_matches_direct_fit(counted_runs):
    ds = counted_runs
    fit = ds.pound.fragility(im="sa_g", n_boot=50)
    assert fit["theta"].dims == ("contact_gap_m",) and fit["theta_ci"].dims[-1] == "bound"
    counted = pounding_counted(ds)
    for k in range(ds.sizes["contact_gap_m"]):
        # the stripes the fit is made from (3 records a stripe: most gaps have no fit, and
        # their message is compared instead)
        z = ((ds.impacts > 0) & counted).isel(contact_gap_m=k).sum(("record", "sample"))
        n = counted.isel(contact_gap_m=k).sum(("record", "sample"))
        assert fit["n_event"].isel(contact_gap_m=k).values.tolist() == z.values.tolist()
        assert fit["n_total"].isel(contact_gap_m=k).values.tolist() == n.values.tolist()
        try:
            ref = fit_fragility(ds.sa_g.values, z.values, n.values, n_boot=50)
        except InputError as exc:
            assert fit["fit_message"].values[k] == exc.message
            continue
        assert float(fit["theta"][k]) == ref.theta and float(fit["beta"][k]) == ref.beta


def test_fragility_cli_json_and_errors(glob_dataset, capsys):
    _, path = glob_dataset
    assert main(["fragility", str(path), "--im", "sa_g", "--json", "--n-boot", "20"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert {"theta", "beta", "theta_ci", "beta_ci", "im", "event"} <= set(out)
    assert out["im"] == "sa_g" and out["event"] == "pounding"
    assert main(["fragility", str(path), "--event", "ductility>2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "ductility" in err[0]
    assert main(["fragility", str(path), "--im", "nope"]) == 2


def test_required_gap_against_hand_computation(counted_runs):
    ds = counted_runs
    found = ds.pound.required_gap(probability=0.1, rules=False)
    gaps = ds.contact_gap_m.values
    counted = pounding_counted(ds)
    for j in range(ds.sizes["sa_g"]):
        hit = ((ds.impacts > 0) & counted).isel(sa_g=j).sum(("record", "sample")).values
        n = counted.isel(sa_g=j).sum(("record", "sample")).values
        assert found["n_total"].isel(sa_g=j).values.tolist() == n.tolist()
        p = hit / n
        above = np.flatnonzero(p > 0.1)
        if above.size == 0:
            expected = gaps[0]
        elif above[-1] == gaps.size - 1:
            assert np.isnan(found["required_gap"][j])
            continue
        else:  # linear interpolation between the last gap above and the next one
            i = above[-1]
            expected = gaps[i] + (p[i] - 0.1) / (p[i] - p[i + 1]) * (gaps[i + 1] - gaps[i])
        assert float(found["required_gap"][j]) == pytest.approx(expected, rel=1e-12)
        lower, upper = wilson_interval(p, n)
        assert float(found["required_gap_ci"][j, 0]) <= float(found["required_gap"][j])


def test_identical_buildings_at_gap_zero_do_not_pound():
    # T1 from { start, stop, num } is exactly 1.0 (np.linspace gives 0.9999999999999999)
    assert grid_values(0.1, 2.0, 20)[9] == 1.0
    study = study_from_text(
        f"""
[study]
name = "identical"
seed = 1
[record]
source = "builtin:elcentro"
duration_s = 5.0
{SCENE.replace("gap_m = 0.01", "gap_m = 0.0")}
[grid]
"left.period_s" = {{ start = 0.1, stop = 2.0, num = 20 }}
"""
    )
    engine = StudyEngine(study)
    out = engine.run_indices(np.array([9]))
    assert out["impacts"][0] == 0 and out["max_penetration"][0] == 0.0


def test_suite_in_a_study_counts_without_reading():
    study = study_from_text(
        f"""
[study]
name = "suite"
seed = 1
[[records]]
source = "suite:fema-p695-farfield"
[[records]]
source = "builtin:elcentro"
{SCENE}
"""
    )
    assert len(study.records) == 45 and study.records[-1]["source"] == "builtin:elcentro"
    assert study.record_names[0] == "NORTHR/MUL009"
    assert study.record_meta[0]["event"] == "Northridge"
    with pytest.raises(InputErrors) as info:
        study_from_text(
            f'[study]\nname = "x"\nseed = 1\n[[records]]\nsource = "suite:nope"\n{SCENE}',
            file="bad.toml",
        )
    assert "bad.toml" in str(info.value) and "records[0].source" in str(info.value)


def test_intensity_axis_conflicts():
    with pytest.raises(InputErrors) as info:
        study_from_text(
            f"""
[study]
name = "x"
seed = 1
[record]
source = "builtin:elcentro"
pga_g = 0.3
{SCENE}
[grid]
"record.sa_g" = [0.1, 0.2]
""",
            file="s.toml",
        )
    text = str(info.value)
    assert "record.pga_g" in text and "record.sa_period_s" in text


def test_sa_period_longer_than_the_record_is_refused():
    # a 4-s record has no Sa at 10 s: scaling to it would multiply the record by ~1e3 (1e12 at
    # 1e6 s, every simulation unstable); refused naming the file and the key, before any run
    study = study_from_text(
        f"""
[study]
name = "x"
seed = 1
[[records]]
source = "builtin:elcentro"
duration_s = 4.0
sa_period_s = 10.0
{SCENE}
[grid]
"record.sa_g" = [0.1, 0.2]
""",
        file="s.toml",
    )
    with pytest.raises(InputError, match="longer than the record") as info:
        StudyEngine(study)
    assert info.value.file == "s.toml" and info.value.key == "records[0].sa_period_s"


def test_required_gap_chart_draws_the_dataset(counted_runs):
    ds = counted_runs
    fig = required_gap_chart(ds, probability=0.1, rules=None)
    ax = fig.axes[0]
    # one probability line per intensity, labelled with its value in g
    labels = [f"{v:g} g" for v in ds.sa_g.values]
    lines = [ln for ln in ax.lines if ln.get_label() in labels]
    assert [ln.get_label() for ln in lines] == labels
    p = ((ds.impacts > 0).where(pounding_counted(ds))).mean(("record", "sample"))
    for j, ln in enumerate(lines):
        np.testing.assert_allclose(ln.get_xdata(), ds.contact_gap_m.values * 1e3)
        np.testing.assert_allclose(ln.get_ydata(), p.isel(sa_g=j).values)


def _gap_dataset(counts, gaps, pga, n=50):
    # a study dataset reduced to what the required gap reads: n records x 1 sample, impacts in
    # the first counts[pga, gap] records
    pga_attrs = {"units": "1", "long_name": "record peak ground acceleration in units of g"}
    return counted_dataset(counts, pga, gaps, n, pga_attrs, attrs={"study_name": "gaps"})


def test_no_gap_note_keeps_clear_of_a_line_that_stays_at_one():
    # P = 1 at every gap (a gap grid too narrow: shear_spectrum.toml): the note was put in the
    # top right corner, its edge on the line and over its last point
    ds = _gap_dataset([[50, 50, 50, 50]], [0.0, 0.01, 0.02, 0.04], [0.5])
    fig = required_gap_chart(ds, probability=0.1, rules=None)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    ax = fig.axes[0]
    (note,) = [t for t in ax.texts if t.get_text().startswith("0.5 g: P = 1 > 0.1")]
    box = note.get_window_extent(renderer=canvas.get_renderer())  # the text [px]
    line = ax.lines[0]
    xs = np.linspace(0.0, 40.0, 200)  # along the line, in chart units [mm]
    on_line = ax.transData.transform(np.c_[xs, np.interp(xs, line.get_xdata(), line.get_ydata())])
    # below the line with room for the box's pad and the markers (the text's top was 0.6 px
    # under the line, its box across it)
    assert box.y1 < on_line[:, 1].min() - 10


def test_required_gap_chart_says_what_each_line_needs():
    """The quickstart's chart left its 0.8 g line (P = 0.18 at the widest gap) without a mark
    or a word, drew 15 vertical rule lines in 5 colours (DDC "under the SRSS lines"), printed
    no required gap, and called the interpolated gap "the smallest gap with P <= 0.1"."""
    gaps, pga = [0.02, 0.05, 0.1, 0.2], [0.1, 0.4, 0.8]
    counts = [[30, 3, 0, 0], [50, 40, 10, 2], [50, 50, 40, 20]]  # of 50; 0.8 g: 0.4 at 200 mm
    ds = _gap_dataset(counts, gaps, pga)
    rules = {"ABS": np.array([0.03, 0.12, 0.25]), "SRSS": np.array([0.01, 0.09, 0.18]),
             "DDC": 0.06}  # fmt: skip
    fig = required_gap_chart(ds, probability=0.1, rules=rules)
    ax = fig.axes[0]
    found = ds.pound.required_gap(probability=0.1, rules=False)
    assert np.isfinite(found["required_gap"].values[:2]).all()
    assert np.isnan(found["required_gap"].values[2])
    # the probability lines first, labelled by intensity, as the probability chart draws them
    lines = ax.lines[:3]
    assert [ln.get_label() for ln in lines] == ["0.1 g", "0.4 g", "0.8 g"]
    p = np.asarray(counts) / 50
    for ln, row in zip(lines, p, strict=True):
        np.testing.assert_allclose(ln.get_ydata(), row)
    # a note for the line that never comes down to the target, none for the others
    notes = [t.get_text() for t in ax.texts if t.get_text()]
    assert len(notes) == 1 and notes[0].startswith("0.8 g: P = 0.4 > 0.1")
    assert "no required gap" in notes[0]
    # the rules: marks on each line at its own gap (inside the gaps studied), no vertical lines
    for marker, gap_mm in (("x", [30, 120, 250]), ("+", [10, 90, 180]), ("o", [60] * 3)):
        marks = [ln for ln in ax.lines if ln.get_marker() == marker and ln not in lines]
        inside = [(g, i) for i, g in enumerate(gap_mm) if 20 <= g <= 200]
        assert [float(m.get_xdata()[0]) for m in marks] == [g for g, _ in inside], marker
        for m, (g, i) in zip(marks, inside, strict=True):
            assert float(m.get_ydata()[0]) == pytest.approx(np.interp(g, [20, 50, 100, 200], p[i]))
    assert all(len(ln.get_xdata()) == len(gaps) for ln in lines)
    assert not [ln for ln in ax.lines if len(set(np.atleast_1d(ln.get_xdata()))) == 1
                and len(ln.get_xdata()) == 2]  # fmt: skip
    # the legend: a table of the gaps [mm] per line, each entry once
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(texts) == len(set(texts))
    assert "ABS" in texts[0] and "SRSS" in texts[0] and "DDC" in texts[0]
    rows = {t.split()[0] + " g": t for t in texts[1:4]}
    for k, name in enumerate(("0.1 g", "0.4 g")):
        gap = float(found["required_gap"].values[k]) * 1e3
        assert rows[name].split()[2] == (f"{gap:.3g}" if gap < 100 else f"{gap:.0f}")
    assert "none (P = 0.4 at 200)" in rows["0.8 g"]
    assert rows["0.1 g"].split()[-3:] == ["30", "10", "60"]
    assert rows["0.8 g"].split()[-3:] == ["250", "180", "60"]
    # the title says the answer: the first and the last line's gap, and the line without one
    g = [float(found["required_gap"].values[k]) * 1e3 for k in (0, 1)]
    text = [f"{v:.3g}" if v < 100 else f"{v:.0f}" for v in g]
    assert ax.get_title() == (
        f"Gap for 10 % pounding probability: {text[0]} mm at PGA 0.1 g to {text[1]} mm at "
        "0.4 g; more than 200 mm at 0.8 g"
    )
    # the caption says what the diamonds are: the interpolated crossing, not a grid gap
    caption = fig._pound_caption_artist.get_text().replace("\n", " ")
    assert "straight between the gaps studied" in caption and "smallest gap" not in caption


@pytest.mark.slow
def test_quickstart_chart_draws_its_dataset(tmp_path):
    # the README's main job end to end: the written charts, and the required-gap chart's
    # probability lines and required-gap markers equal to the dataset's own values
    study = Path(__file__).resolve().parents[1] / "studies" / "quickstart.toml"
    assert main(["run", str(study), "--out", str(tmp_path)]) == 0
    for name in ("quickstart.nc", "quickstart_required_gap.png", "quickstart_fragility.png"):
        assert (tmp_path / name).stat().st_size > 0
    with xr.open_dataset(tmp_path / "quickstart.nc") as ds:
        ds.load()
    assert ds.sizes["record"] == 44  # FEMA P695 far field, 22 x 2 components
    fig = required_gap_chart(ds, probability=0.1, base_dir=study.parent)
    ax = fig.axes[0]
    labels = [f"{v:g} g" for v in ds.pga_g.values]  # one probability line per intensity
    lines = [ln for ln in ax.lines if ln.get_label() in labels]
    assert len(lines) == ds.sizes["pga_g"]
    p = (ds.impacts > 0).where(pounding_counted(ds)).mean(("record", "sample"))
    found = ds.pound.required_gap(probability=0.1, rules=False)
    for j, ln in enumerate(lines):
        np.testing.assert_allclose(ln.get_xdata(), ds.contact_gap_m.values * 1e3)
        np.testing.assert_allclose(ln.get_ydata(), p.isel(pga_g=j).values)
    # the probability falls with the gap and rises with the intensity: not a flat line
    assert float(p.isel(pga_g=-1, contact_gap_m=0)) > float(p.isel(pga_g=-1, contact_gap_m=-1))
    assert float(p.isel(pga_g=-1, contact_gap_m=1)) > float(p.isel(pga_g=0, contact_gap_m=1))
    # one marker per line with a required gap, at the accessor's value [mm]
    markers = sorted(float(x) for c in ax.containers for x in np.atleast_1d(c.lines[0].get_xdata()))
    expected = sorted(float(g) * 1e3 for g in found["required_gap"].values if np.isfinite(g))
    np.testing.assert_allclose(markers, expected)


def test_runs_flagged_inaccurate_count_for_the_pounding_probability(make_study, tmp_path, capsys):
    """Only a run with a contact can be flagged inaccurate, so leaving those runs out lowered
    the pounding probability (a newmark study at 5 ms, 94 % flagged: 0 where 94 % pounded) and
    the required gap with it; ``run`` said nothing of the flags.  Reference: the fraction
    counted by hand over the runs that are not unstable or not converged.  (A stiff contact,
    beta 1e12, at 10 ms steps: the study's three refinements end at 1.25 ms, still a few steps
    per contact, where runs stay flagged.)"""
    study = make_study(
        integrator={"method": "newmark", "dt_s": 0.01},
        contact={"beta": 1e12},
        grid={"left.period_s": None, "contact.gap_m": [0.02, 0.05]},
        sampling={"n": 8, "vary": {"left.period_s": {"distribution": "uniform", "low": 0.2,
                                                     "high": 1.2}}},
        record={"source": "builtin:elcentro", "duration_s": 6.0, "pga_g": 0.4},
    )  # fmt: skip
    assert main(["run", str(study), "--out", str(tmp_path / "o"), "--no-plot"]) == 0
    err = capsys.readouterr().err
    ds = xr.load_dataset(tmp_path / "o" / "small.nc")
    status = ds["status"]
    flagged = int((status == 3).sum())
    assert 0 < flagged and f"warning: {flagged} of {status.size} simulations flagged" in err
    counted = pounding_counted(ds)
    by_hand = ((ds["impacts"] > 0) & counted).sum(("record", "sample")) / counted.sum(
        ("record", "sample")
    )
    np.testing.assert_allclose(ds["pounding_probability"].squeeze("record", drop=True),
                               by_hand, rtol=1e-15)  # fmt: skip
    np.testing.assert_allclose(ds.pound.probability().values.ravel(), by_hand.values.ravel())
    gap = ds.pound.required_gap(probability=0.5, rules=False)
    assert (gap["n_total"] == counted.sum(("record", "sample"))).all()
    ax = ds.pound.plot.probability(rules=None)  # the chart counted ok runs only
    np.testing.assert_allclose(ax.lines[0].get_ydata(), by_hand.values.ravel())
    assert float(by_hand.min()) > 0.5  # pounded at both gaps, flagged or not
