"""Sobol' sensitivity indices (issue #39, point 5): Saltelli's design, the dataset, the analysis.

The Ishigami test builds a dataset the way ``pound-mc run`` does (a ``saltelli`` study, its
engine's dataset layout and sampled values, :func:`build_dataset`, :func:`write_netcdf`), fills
the Ishigami function of the sampled values in as the peak force, and reads the indices back
through ``pound-mc sensitivity --json``; a small real pounding study goes through ``pound-mc
run`` and the same command.
"""

import json
import math

import numpy as np
import pytest
import xarray as xr
from SALib.analyze import sobol as salib_analyze
from SALib.sample import sobol as salib_sample

import pound_mc  # noqa: F401  (registers ds.pound)
from pound_mc.analysis.sensitivity import MIN_BLOCKS, sobol_indices
from pound_mc.analysis.sensitivity_chart import panel_positions
from pound_mc.cli import main
from pound_mc.errors import InputErrors
from pound_mc.study import sampling
from pound_mc.study.dataset import build_dataset, write_netcdf
from pound_mc.study.definition import load_study
from pound_mc.study.engine import StudyEngine
from studies import write_study

#: Three keys sampled uniform over these ranges; each maps affinely onto [-pi, pi] (a uniform
#: variable's quantile function is affine, so the mapped values are uniform on [-pi, pi]).
ISHIGAMI_KEYS = {
    "contact.gap_m": (0.0, 0.02),
    "left.damping_ratio": (0.02, 0.08),
    "right.damping_ratio": (0.01, 0.1),
}
A, B = 7.0, 0.1


def _ishigami_indices(a: float = A, b: float = B):
    """Analytic S1 and ST of the Ishigami function on [-pi, pi]^3.

    Ishigami & Homma (1990); the partial variances as in Saltelli et al. (2008), Global
    Sensitivity Analysis: The Primer, section 4.9: V1 = b pi^4/5 + b^2 pi^8/50 + 1/2,
    V2 = a^2/8, V13 = 8 b^2 pi^8/225, V = V1 + V2 + V13.  For a = 7, b = 0.1:
    S1 = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437).
    """
    v1 = b * math.pi**4 / 5 + b**2 * math.pi**8 / 50 + 0.5
    v2 = a**2 / 8
    v13 = 8 * b**2 * math.pi**8 / 225
    v = v1 + v2 + v13
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def _dataset(directory, n: int, *, grid=None, output=None, name="ishigami"):
    """A ``saltelli`` study's dataset as ``pound-mc run`` lays it out, with no simulation run.

    The study varies :data:`ISHIGAMI_KEYS`; ``output(x, ds)`` (``x``: the sampled values mapped
    onto [-pi, pi], each ``(sample,)``) gives the peak force, broadcast over the grid; every
    run has status ok.
    """
    vary = {k: {"distribution": "uniform", "low": lo, "high": hi}
            for k, (lo, hi) in ISHIGAMI_KEYS.items()}  # fmt: skip
    path = write_study(directory, study={"name": name, "seed": 7}, grid=grid,
                       sampling={"n": n, "method": "saltelli", "vary": vary})  # fmt: skip
    study = load_study(path)
    engine = StudyEngine(study)
    results = {
        name: np.zeros((*study.shape, *tail), dtype)
        for name, (tail, dtype) in engine.result_layout().items()
    }
    ds = build_dataset(study, results, engine.dataset_parameters(), provenance=engine.provenance())
    x = [
        -math.pi + 2 * math.pi * (ds[key.replace(".", "_")] - lo) / (hi - lo)
        for key, (lo, hi) in ISHIGAMI_KEYS.items()
    ]
    y = (output or _ishigami)(x, ds)
    ds["peak_force"].values[...] = (
        y.broadcast_like(ds["peak_force"]).transpose(*ds["peak_force"].dims).values
    )
    return ds


def _ishigami(x, ds):
    return np.sin(x[0]) + A * np.sin(x[1]) ** 2 + B * x[2] ** 4 * np.sin(x[0])


@pytest.fixture(scope="module")
def ishigami(tmp_path_factory):
    """The Ishigami dataset of base N = 8192 (40,960 samples), written to netCDF."""
    folder = tmp_path_factory.mktemp("ishigami")
    ds = _dataset(folder, 8192)
    return ds, write_netcdf(ds, folder / "ishigami.nc")


# -- the design -------------------------------------------------------------------------------


def test_saltelli_design_is_salib_s_blocks_through_each_distribution(tmp_path):
    ds = _dataset(tmp_path, 8)
    study = load_study(tmp_path / "ishigami.toml")
    d = len(ISHIGAMI_KEYS)
    assert study.base_n == 8 and study.n == 8 * (d + 2) == ds.sizes["sample"]
    # SALib's own sampler, seeded as the study seeds it
    problem = {"num_vars": d, "names": list(ISHIGAMI_KEYS), "bounds": [[0.0, 1.0]] * d}
    rng = np.random.default_rng(np.random.SeedSequence(study.sampling_seed))
    u = salib_sample.sample(problem, 8, calc_second_order=False, seed=rng)
    np.testing.assert_array_equal(sampling.design(study.n, d, study.sampling_seed, "saltelli"), u)
    values = study.draw()
    for j, (key, (lo, hi)) in enumerate(ISHIGAMI_KEYS.items()):
        np.testing.assert_allclose(values[key], lo + (hi - lo) * u[:, j], rtol=1e-12)
        np.testing.assert_array_equal(ds[key.replace(".", "_")].values, values[key])
    # blocks of d + 2: A, A with column j from B (j = 1..d), B
    blocks = u.reshape(8, d + 2, d)
    for j in range(d):
        expected = blocks[:, 0].copy()
        expected[:, j] = blocks[:, d + 1, j]
        np.testing.assert_array_equal(blocks[:, j + 1], expected)
    # deterministic from the seed, another seed another design
    np.testing.assert_array_equal(study.draw()["contact.gap_m"], values["contact.gap_m"])
    other = sampling.design(study.n, d, study.sampling_seed + 1, "saltelli")
    assert not np.allclose(other, u)
    # the dataset says how it was sampled
    assert ds.attrs["sampling_method"] == "saltelli"
    assert ds.attrs["saltelli_base_n"] == 8 and ds.attrs["saltelli_n_variables"] == d
    assert ds.attrs["saltelli_variables"].split("; ") == list(ISHIGAMI_KEYS)
    assert "sample = 5 b + r" in ds["sample"].attrs["comment"]


@pytest.mark.parametrize("n", [100, 1, 6])
def test_a_base_n_that_is_not_a_power_of_two_is_one_clear_error(make_study, n, capsys):
    path = make_study(sampling={"n": n, "method": "saltelli"})
    for command in ("check", "run"):
        assert main([command, str(path), "--out", str(path.parent / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1, err
        assert str(path) in err[0] and "sampling.n" in err[0] and "power of two" in err[0]
    assert not (path.parent / "out").exists()


def test_a_refused_base_n_is_reported_with_the_other_problems(make_study):
    path = make_study(sampling={"n": 100, "method": "saltelli"}, contact={"e": 2.0})
    with pytest.raises(InputErrors) as info:
        load_study(path)
    assert {"sampling.n", "contact.e"} <= {e.key for e in info.value.errors}


def test_saltelli_needs_a_sampled_key(make_study, capsys):
    path = make_study(sampling={"n": 8, "method": "saltelli", "vary": None})
    assert main(["check", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(path) in err and "sampling.vary" in err and "saltelli" in err


def test_the_plan_states_the_base_n_and_the_samples(make_study, capsys):
    path = make_study(sampling={"n": 8, "method": "saltelli"})
    study = load_study(path)
    assert study.n == 8 * (2 + 2) and study.n_simulations == 3 * 2 * 32
    from pound_mc.study.runner import plan_text

    assert "n = 32 (base N = 8 x 4), method saltelli" in plan_text(study)


# -- the Ishigami function through the tool's own path ------------------------------------------


def test_ishigami_indices_through_the_dataset_and_the_command(ishigami, capsys):
    """Acceptance: within 0.02 of the analytic indices, through ``pound-mc sensitivity``."""
    _, path = ishigami
    s1, st = _ishigami_indices()
    np.testing.assert_allclose(s1, [0.3139, 0.4424, 0.0], atol=5e-5)  # the figures
    np.testing.assert_allclose(st, [0.5576, 0.4424, 0.2437], atol=5e-5)
    assert main(["sensitivity", str(path), "--json", "--n-boot", "200"]) == 0
    out = json.loads(capsys.readouterr().out)
    pinned = {"output", "variables", "dims", "coords", "S1", "S1_ci", "ST", "ST_ci", "n_left_out"}
    assert pinned <= set(out)
    assert out["output"] == "peak_force" and out["variables"] == list(ISHIGAMI_KEYS)
    assert out["dims"] == ["record"] and out["coords"] == {"record": ["builtin:elcentro"]}
    assert out["n_left_out"] == [0] and out["base_n"] == 8192
    got_s1, got_st = np.array(out["S1"][0]), np.array(out["ST"][0])
    np.testing.assert_allclose(got_s1, s1, atol=0.02)
    np.testing.assert_allclose(got_st, st, atol=0.02)
    for name, exact in (("S1", s1), ("ST", st)):
        ci = np.array(out[f"{name}_ci"][0])
        assert ci.shape == (3, 2)  # an interval is [lo, hi]
        assert np.all(ci[:, 0] <= np.array(out[name][0])) and np.all(
            np.array(out[name][0]) <= ci[:, 1]
        )
        assert np.all((ci[:, 0] <= exact) & (exact <= ci[:, 1])), (name, ci, exact)
    print(f"Ishigami N = 8192: S1 {np.round(got_s1, 4)}, ST {np.round(got_st, 4)}")


def test_the_accessor_gives_the_command_s_numbers_with_cf_attributes(ishigami, capsys):
    ds, path = ishigami
    found = ds.pound.sensitivity(n_boot=200)
    assert main(["sensitivity", str(path), "--json", "--n-boot", "200"]) == 0
    out = json.loads(capsys.readouterr().out)
    np.testing.assert_array_equal(found["S1"].values, out["S1"])
    np.testing.assert_array_equal(found["ST_ci"].values, out["ST_ci"])
    assert [str(k) for k in found["variable"].values] == list(ISHIGAMI_KEYS)
    for name in ("S1", "S1_ci", "ST", "ST_ci", "n_used", "n_left_out"):
        assert found[name].attrs["units"] == "1" and found[name].attrs["long_name"], name
    assert found.attrs["output_units"] == "N"


# -- runs left out ----------------------------------------------------------------------------


def test_runs_not_counted_take_their_whole_block_out(tmp_path):
    ds = _dataset(tmp_path, 64)
    d = len(ISHIGAMI_KEYS)
    width = d + 2
    status = ds["status"].values  # (record, sample)
    status[0, 0 * width + 3] = 1  # unstable: block 0
    status[0, 10 * width + 2] = 3  # inaccurate: block 10 (its peak force in doubt)
    status[0, 20 * width] = 2  # not converged: block 20
    ds["peak_force"].values[0, 30 * width + 4] = np.nan  # no value: block 30
    ds["impacts"].values[...] = (ds["peak_force"].values > 3.5).astype(np.int32)
    found = ds.pound.sensitivity(n_boot=50)
    assert found["n_left_out"].item() == 4 * width and found["n_used"].item() == 60 * width
    # the estimate is SALib's over the complete blocks alone
    keep = np.ones(64, bool)
    keep[[0, 10, 20, 30]] = False
    y = ds["peak_force"].values[0].reshape(64, width)[keep].ravel()
    direct = sobol_indices(y, d, n_boot=50)
    np.testing.assert_array_equal(found["S1"].values[0], direct["S1"])
    np.testing.assert_array_equal(found["ST_ci"].values[0], direct["ST_ci"])
    # pounding counts the inaccurate run (its impacts stand) and has no NaN: blocks 0, 20 out
    pounding = ds.pound.sensitivity("pounding", n_boot=50)
    assert pounding["n_left_out"].item() == 2 * width
    assert pounding.attrs["output_units"] == "1"


def test_too_few_complete_blocks_or_no_variance_give_no_indices(tmp_path, capsys):
    ds = _dataset(tmp_path, 8)
    width = len(ISHIGAMI_KEYS) + 2
    ds["status"].values[0, : (8 - MIN_BLOCKS + 1) * width] = 1
    found = ds.pound.sensitivity(n_boot=20)
    assert np.isnan(found["S1"].values).all() and np.isnan(found["ST_ci"].values).all()
    assert "design blocks complete" in str(found["message"].values[0])
    assert found["n_left_out"].item() == (8 - MIN_BLOCKS + 1) * width
    ds["status"].values[...] = 0
    ds["peak_force"].values[...] = 2.0e6
    found = ds.pound.sensitivity(n_boot=20)
    assert np.isnan(found["S1"].values).all()
    assert "no variance" in str(found["message"].values[0])
    path = write_netcdf(ds, tmp_path / "flat.nc")
    assert main(["sensitivity", str(path)]) == 0
    assert "no indices (the output is 2e+06 at every A and B sample" in capsys.readouterr().out


def test_datasets_and_outputs_the_analysis_cannot_take_are_refused(make_study, tmp_path, capsys):
    path = make_study(grid={"left.period_s": None})  # a sobol study: no Saltelli design
    study = load_study(path)
    engine = StudyEngine(study)
    results = {n: np.zeros((*study.shape, *t), dt) for n, (t, dt) in engine.result_layout().items()}
    ds = build_dataset(study, results, engine.dataset_parameters())
    sobol = write_netcdf(ds, tmp_path / "sobol.nc")
    ishigami = write_netcdf(_dataset(tmp_path, 4), tmp_path / "ishigami.nc")
    for args, words in (
        ([str(sobol)], ("saltelli", "sampling.method", "'sobol'")),
        ([str(ishigami), "--output", "nope"], ("--output", "unknown output 'nope'", "impacts")),
        ([str(ishigami), "--output", "ductility"], ("--output", "elastic")),
        ([str(ishigami), "--n-boot", "1"], ("--n-boot",)),
    ):
        assert main(["sensitivity", *args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and all(w in err[0] for w in words), err
        assert "Traceback" not in err[0]


# -- a real pounding study --------------------------------------------------------------------


@pytest.fixture(scope="module")
def pounding(tmp_path_factory):
    """A small ``saltelli`` pounding study run by ``pound-mc run``: N = 32, D = 4, 2 grid points.

    The B1-like pair under 4 s of El Centro at 0.3 g, T2 = 0.8 and 1.2 s on the grid, e and
    beta of concrete, the gap 0-150 mm and T1 0.3-0.9 s sampled: 384 simulations.
    """
    folder = tmp_path_factory.mktemp("pounding")
    vary = {
        "contact.e": {"material": "concrete"},
        "contact.beta": {"material": "concrete"},
        "contact.gap_m": {"uniform": [0.0, 0.15]},
        "left.period_s": {"uniform": [0.3, 0.9]},
    }
    path = write_study(folder, study={"name": "sens_small", "seed": 3},
                       grid={"left.period_s": None, "contact.gap_m": None,
                             "right.period_s": [0.8, 1.2]},
                       sampling={"n": 32, "method": "saltelli", "vary": vary})  # fmt: skip
    assert main(["run", str(path), "--out", str(folder), "--no-progress"]) == 0
    return folder / "sens_small.nc"


def _json(capsys, *args):
    assert main(["sensitivity", *map(str, args)]) == 0
    return json.loads(capsys.readouterr().out)


def test_pounding_study_indices_with_their_intervals(pounding, capsys):
    assert (pounding.parent / "sens_small_sensitivity.png").is_file()  # run drew the bars
    out = _json(capsys, pounding, "--json", "--n-boot", "200")
    keys = ["contact.e", "contact.beta", "contact.gap_m", "left.period_s"]
    assert out["variables"] == keys and out["dims"] == ["record", "right_period_s"]
    assert out["coords"]["right_period_s"] == [0.8, 1.2]
    with xr.open_dataset(pounding) as ds:
        ds.load()
    n_bad = (ds["status"] != 0).sum("sample").values.tolist()
    assert out["n_left_out"] == n_bad == [[0, 0]]  # every run ok here
    s1, st = np.array(out["S1"]), np.array(out["ST"])
    s1_ci, st_ci = np.array(out["S1_ci"]), np.array(out["ST_ci"])
    assert s1.shape == (1, 2, 4) and s1_ci.shape == st_ci.shape == (1, 2, 4, 2)
    assert np.all(np.isfinite(s1_ci)) and np.all(s1_ci[..., 0] < s1_ci[..., 1])
    assert np.all((s1_ci[..., 0] <= s1) & (s1 <= s1_ci[..., 1]))
    assert np.all((st_ci[..., 0] <= st) & (st <= st_ci[..., 1]))
    # S1 <= ST, within their intervals
    assert np.all(s1_ci[..., 0] <= st_ci[..., 1])
    # the gap drives the peak force most, e least: their intervals do not overlap
    assert np.all(st_ci[..., 2, 0] > st_ci[..., 0, 1])
    # the command's numbers are SALib's on the dataset's own peak forces, point by point
    for k in range(2):
        y = ds["peak_force"].isel(record=0, right_period_s=k).values
        problem = {"num_vars": 4, "names": keys, "bounds": [[0.0, 1.0]] * 4}
        rng = np.random.default_rng(np.random.SeedSequence(0))
        direct = salib_analyze.analyze(problem, y, calc_second_order=False, num_resamples=200,
                                       seed=rng)  # fmt: skip
        np.testing.assert_allclose(s1[0, k], direct["S1"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(st_ci[0, k, :, 1] - st[0, k], direct["ST_conf"], atol=1e-12)


def test_pounding_output_does_not_depend_on_the_contact_law(pounding, capsys):
    """Whether two buildings meet is decided before their first contact: e and beta play no part.

    So the indices of the pounding indicator are exactly 0 for e and beta (every AB row of
    theirs repeats its A row's outcome), with intervals [0, 0].
    """
    out = _json(capsys, pounding, "--json", "--output", "pounding", "--n-boot", "100")
    s1, st = np.array(out["S1"]), np.array(out["ST"])
    assert out["message"] == [["", ""]]
    np.testing.assert_array_equal(s1[..., :2], 0.0)
    np.testing.assert_array_equal(st[..., :2], 0.0)
    np.testing.assert_array_equal(np.array(out["ST_ci"])[..., :2, :], 0.0)
    assert np.all(st[..., 2] > 0.5)  # the gap decides


def test_chart_panels_along_the_first_grid_axis(tmp_path):
    grid = {"contact.gap_m": None, "left.period_s": [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9]}
    ds = _dataset(tmp_path, 16, grid=grid,
                  output=lambda x, ds: _ishigami(x, ds) * (1 + ds["left_period_s"]) +
                  10 * ds["left_period_s"] * x[2])  # fmt: skip
    found = ds.pound.sensitivity(n_boot=50)
    assert found["S1"].dims == ("record", "left_period_s", "variable")
    axes = ds.pound.plot.sensitivity(n_boot=50)
    assert panel_positions(8, 6) == [0, 1, 3, 4, 6, 7]
    assert len(axes) == 6
    fig = axes[0].figure
    caption = fig._pound_caption_artist.get_text().replace("\n", " ")
    assert "Panels: 6 of the 8 values of left period." in caption
    assert "(80 runs a panel)" in caption
    # the title says which key drives the output most, with its total-order index
    st = found["ST"].isel(record=0, left_period_s=panel_positions(8, 6))
    k = int(np.argmax(st.max("left_period_s").values))
    key = str(found["variable"].values[k])
    assert (
        fig.get_suptitle()
        .replace("\n", " ")
        .endswith(f"({key}): total-order index up to {float(st.max()):.2f}")
    )
    for ax, i in zip(axes, panel_positions(8, 6), strict=True):
        assert ax.get_title() == f"left period {ds['left_period_s'].values[i]:.4g} s"
        heights = [p.get_height() for p in ax.patches]
        np.testing.assert_allclose(heights[:3], found["S1"].values[0, i])
        np.testing.assert_allclose(heights[3:], found["ST"].values[0, i])
        assert ax.get_ylim() == axes[0].get_ylim()  # one scale for every panel
    labels = [t.get_text() for t in axes[0].get_xticklabels()]
    assert labels == list(ISHIGAMI_KEYS)
