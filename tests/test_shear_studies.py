"""Studies of shear buildings: per-contact outputs along ``contact``, structural uncertainty."""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from pound_mc.cli import main
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from studies import SMALL_SHEAR, Whole, study_text, write_study

SDOF_6M = Whole(
    {"model": "sdof", "period_s": 0.4, "mass_kg": 2.0e6, "damping_ratio": 0.05, "height_m": 6.0}
)


def _study_text(name="shear_small", left=None, right=None, grid=None, vary=None, contact=None):
    """``studies.SMALL_SHEAR`` (3 + 5 storeys) with its name, buildings, grid, vary or contact
    replaced."""
    tables = {"left": left, "right": right, "grid": grid, "contact": contact}
    tables = {k: Whole(v) for k, v in tables.items() if v is not None}
    if vary is not None:
        tables["sampling"] = {"vary": vary}
    return study_text(SMALL_SHEAR, study={"name": name}, **tables)


@pytest.fixture(scope="module")
def shear_run(tmp_path_factory):
    """The small 3 + 5 storey study run through the command line."""
    tmp = tmp_path_factory.mktemp("shear")
    path = write_study(tmp, SMALL_SHEAR)  # shear_small.toml
    out = tmp / "out"
    assert main(["run", str(path), "--out", str(out), "--no-progress"]) == 0
    with xr.open_dataset(out / "shear_small.nc") as ds:
        yield path, out, ds.load()


def test_shear_study_runs_with_a_contact_dimension(shear_run):
    _, out, ds = shear_run
    # the pooled spectrum, the probability against the gap, the peak force per contact
    charts = ("spectrum", "required_gap", "contacts")
    assert sorted(out.glob("*.png")) == sorted(out / f"shear_small_{c}.png" for c in charts)
    assert ds.sizes["contact"] == 3
    np.testing.assert_array_equal(ds["contact"].values, [1, 2, 3])
    np.testing.assert_allclose(ds["contact_elevation"].values, [3.0, 6.0, 9.0])
    np.testing.assert_array_equal(ds["contact_left_floor"].values, [1, 2, 3])
    np.testing.assert_array_equal(ds["contact_right_floor"].values, [1, 2, 3])
    for name in ("contact", "contact_elevation", "contact_left_floor", "contact_right_floor"):
        assert name in ds.coords
        assert {"units", "long_name"} <= set(ds[name].attrs)
    assert ds["contact_elevation"].attrs["units"] == "m"
    units = {
        "contact_peak_force": "N",
        "contact_impacts": "1",
        "contact_max_penetration": "m",
        "contact_impulse": "N s",
    }
    for name, unit in units.items():
        assert ds[name].dims == ("record", "contact_gap_m", "sample", "contact")
        assert ds[name].attrs["units"] == unit
        assert ds[name].attrs["long_name"]
    assert ds["peak_force"].dims == ("record", "contact_gap_m", "sample")
    assert (ds["status"] == 0).all()
    assert (ds["impacts"] > 0).any()


def test_per_simulation_outputs_reduce_the_contacts(shear_run):
    _, _, ds = shear_run
    np.testing.assert_array_equal(ds["peak_force"], ds["contact_peak_force"].max("contact"))
    np.testing.assert_array_equal(ds["impacts"], ds["contact_impacts"].sum("contact"))
    np.testing.assert_array_equal(
        ds["max_penetration"], ds["contact_max_penetration"].max("contact")
    )
    np.testing.assert_allclose(ds["impulse"], ds["contact_impulse"].sum("contact"), rtol=1e-12)


def test_each_simulation_matches_its_scene(shear_run):
    path, _, ds = shear_run
    study = study_from_text(path.read_text(), file=path)
    for g, gap in enumerate(ds["contact_gap_m"].values):
        for s in range(study.n):
            overrides = {
                "contact.gap_m": float(gap),
                "contact.e": float(ds["e"][s]),
                "contact.beta": float(ds["beta"][s]),
            }
            scene = scene_from_dict(study.scene_dict(0, overrides), file=path)
            res = simulate(scene)
            point = ds.isel(record=0, contact_gap_m=g, sample=s)
            np.testing.assert_allclose(
                point["contact_peak_force"].values, res.contacts["peak_force"], rtol=1e-12
            )
            np.testing.assert_array_equal(point["contact_impacts"].values, res.contacts["impacts"])
            np.testing.assert_allclose(
                point["contact_impulse"].values, res.contacts["impulse"], rtol=1e-12
            )
            assert float(point["peak_force"]) == pytest.approx(res.outputs["peak_force"], rel=1e-12)


def test_chunk_files_carry_the_contacts_and_resume(tmp_path, make_shear_study):
    path = make_shear_study(study={"name": "shear_chunks"})
    study = study_from_text(path.read_text(), file=path)
    engine = StudyEngine(study)
    layout = engine.result_layout()
    assert layout["contact_peak_force"] == ((3,), "f8")
    assert layout["peak_force"] == ((), "f8")
    first = run_study(study, tmp_path, chunk_size=3, progress=False, max_chunks=1)
    assert not first.complete
    chunk = sorted((tmp_path / "shear_chunks").glob("chunk_*.npz"))[0]
    with np.load(chunk) as data:
        assert data["contact_peak_force"].shape == (3, 3)
    report = run_study(study, tmp_path, chunk_size=3, progress=False)
    assert report.complete
    with xr.open_dataset(report.path) as ds:
        resumed = ds["contact_peak_force"].values
    whole = engine.run_range(0, study.n_simulations)["contact_peak_force"]
    np.testing.assert_array_equal(resumed.reshape(-1, 3), whole)


def test_sdof_with_height_beside_a_shear_building(tmp_path):
    path = tmp_path / "mixed.toml"
    beta = {"contact.beta": {"material": "concrete"}}
    grid = {"contact.xi": [0.2, 0.4]}  # a damping axis: [contact] without e
    contact = {k: v for k, v in SMALL_SHEAR["contact"].items() if k not in ("e", "relation")}
    path.write_text(_study_text(name="mixed", left=SDOF_6M, grid=grid, vary=beta, contact=contact))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-progress", "--no-plot"]) == 0
    with xr.open_dataset(out / "mixed.nc") as ds:
        assert ds.sizes["contact"] == 1
        assert float(ds["contact_elevation"][0]) == 6.0
        assert int(ds["contact_left_floor"][0]) == 1
        assert int(ds["contact_right_floor"][0]) == 2
        np.testing.assert_array_equal(ds["peak_force"], ds["contact_peak_force"].isel(contact=0))


def test_sdof_pair_has_no_contact_dimension(tmp_path):
    sdof = {k: v for k, v in SDOF_6M.items() if k != "height_m"}
    text = _study_text(name="sdof_pair", left=sdof, right={**sdof, "period_s": 0.9})
    study = study_from_text(text, file=tmp_path / "s.toml")
    engine = StudyEngine(study)
    assert not engine.mdof
    assert set(engine.run_range(0, 2)) == set(engine.result_layout())
    assert "contact" not in engine.dataset_parameters()


@pytest.mark.parametrize(
    ("left", "grid", "vary", "key"),
    [
        (None, {"left.period_s": [0.3, 0.5]}, None, "grid.left.period_s"),
        (
            SDOF_6M,
            None,
            {"left.storey_mass_kg": {"distribution": "uniform", "low": 1e6, "high": 2e6}},
            "sampling.vary.left.storey_mass_kg",
        ),
    ],
)
def test_a_key_of_the_other_building_model_is_refused(tmp_path, capsys, left, grid, vary, key):
    path = tmp_path / "bad.toml"
    path.write_text(_study_text(name="bad", left=left, grid=grid, vary=vary))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert key in err and "structural" in err and str(path) in err
    assert not out.exists()


# Five and eight storeys of 3 m, 1,000 t a floor, every storey 1.0e9 N/m (left: T1 about
# 0.55 s) and 1.5e9 N/m; storey stiffness lognormal with 10 % c.o.v. (sigma_ln =
# sqrt(ln(1 + 0.1^2)) = 0.0998), the same draw for every storey of a building.
SHEAR_5_8 = {
    "left": {"model": "shear", "storey_mass_kg": [1.0e6] * 5,
             "storey_stiffness_N_per_m": [1.0e9] * 5, "storey_height_m": [3.0] * 5},
    "right": {"model": "shear", "storey_mass_kg": [1.0e6] * 8,
              "storey_stiffness_N_per_m": [1.5e9] * 8, "storey_height_m": [3.0] * 8},
}  # fmt: skip
SIGMA_LN_10 = float(np.sqrt(np.log1p(0.1**2)))


def _uncertain_5_8(tmp_path) -> Path:
    vary = {
        f"{side}.storey_stiffness_N_per_m": {
            "distribution": "lognormal",
            "median": SHEAR_5_8[side]["storey_stiffness_N_per_m"][0],
            "sigma_ln": SIGMA_LN_10,
        }
        for side in ("left", "right")
    }
    text = study_text(
        SMALL_SHEAR,
        study={"name": "uncertain_5_8"},
        record={"duration_s": 2.0},
        left=Whole(SHEAR_5_8["left"]),
        right=Whole(SHEAR_5_8["right"]),
        grid={"contact.gap_m": [0.005]},
        sampling=Whole({"n": 3, "method": "sobol", "vary": vary}),
    )
    path = tmp_path / "uncertain_5_8.toml"
    path.write_text(text)
    return path


@pytest.mark.slow  # five 5 + 8 storey simulations, each run three times
def test_storey_stiffness_uncertainty_is_reproducible_across_threads_and_chunks(tmp_path):
    path = _uncertain_5_8(tmp_path)
    study = study_from_text(path.read_text(), file=path)
    engine = StudyEngine(study)
    assert engine.per_scene and engine.n_contacts == 5
    one = run_study(study, tmp_path / "a", threads=1, chunk_size=3, progress=False)
    two = run_study(study, tmp_path / "b", threads=2, chunk_size=2, progress=False)
    with xr.open_dataset(one.path) as a, xr.open_dataset(two.path) as b:
        assert (a["status"] == 0).all()
        for name in ("peak_force", "impacts", "peak_disp_left", "contact_peak_force"):
            assert np.array_equal(a[name].values, b[name].values), name
        k = a["left_storey_stiffness_N_per_m"].values
        assert k.shape == (3,) and np.unique(k).size == 3
        # simulation 1 is its own scene: every storey at the sampled stiffness
        scene = engine.scene_of(1)
        np.testing.assert_array_equal(scene.left.storey_stiffness_N_per_m, [k[1]] * 5)
        alone = simulate(scene, record=engine.record_of(1))
        point = a.isel(record=0, contact_gap_m=0, sample=1)
        assert float(point["peak_disp_left"]) == alone.outputs["peak_disp_left"]
        # the first mode follows the stiffness: T1 scales as 1 / sqrt(k) (a closed form)
        t1 = [2 * np.pi / engine.scene_of(s).left.omega[0] for s in range(2)]
        assert t1[0] / t1[1] == pytest.approx(np.sqrt(k[1] / k[0]), rel=1e-9)


def test_shipped_shear_study_validates():
    studies = Path(__file__).resolve().parent.parent / "studies"
    study = study_from_text(
        (studies / "shear_spectrum.toml").read_text(), file=studies / "shear_spectrum.toml"
    )
    engine = StudyEngine(study)
    assert engine.mdof and engine.n_contacts == 3
    assert study.shape == (1, 4, 64)


def test_flagged_runs_report_their_rebound_as_simulate_does(tmp_path):
    """A shear study took the restitution after flagging runs inaccurate, so those kept the
    kernel's raw value (Table 2's e per impact, NaN with fixed e) where simulate() gives the
    law's rebound; both give the rebound now."""
    text = study_text(
        SMALL_SHEAR,
        study=Whole(name="flagged", seed=5),
        record={"duration_s": 4.0},
        contact=Whole(
            model="jankowski", gap_m=0.0, beta=2.75e9, restitution="velocity", material="concrete"
        ),  # fmt: skip
        integrator=Whole(method="newmark", dt_s=0.01),
        grid=None,
        sampling=Whole(
            n=3, vary={"contact.e_quantile": {"distribution": "uniform", "low": 0.0, "high": 1.0}}
        ),  # fmt: skip
    )
    study = study_from_text(text, file=tmp_path / "flagged.toml")
    ds = xr.load_dataset(run_study(study, tmp_path, progress=False).path)
    # dt 0.01 s steps over these contacts: every run was flagged, and refined; each holds the
    # numbers of its last run, flagged or not
    assert (ds["refinements"] > 0).all()
    engine = StudyEngine(study)
    steps = ds["run_dt_s"].values.ravel()
    for i, value in enumerate(ds["peak_force_restitution"].values.ravel()):
        res = simulate(engine.scene_of(i), record=engine.record_of(i), dt_s=steps[i])
        assert value == pytest.approx(res.outputs["peak_force_restitution"], rel=1e-12)
        assert np.isfinite(value)
