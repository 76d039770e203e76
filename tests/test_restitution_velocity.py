"""Restitution set per impact from the seed's Table 2 at each impact's prior-impact velocity.

``[contact] restitution = "velocity"``: each impact's ``e`` is Jankowski (2008) Table 2 at the
relative velocity at contact onset, at quantile ``e_quantile`` of the measured range, and its
damping comes from the relation, fixed for that impact.
"""

import math

import numpy as np
import pytest
import xarray as xr
from reference_impact import jankowski_impact

from pound_mc.errors import InputError
from pound_mc.integrators import run_kernel
from pound_mc.integrators.reference import reference_solution
from pound_mc.physics.materials import restitution_at, restitution_rows, table
from pound_mc.physics.relations import effective_restitution
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from studies import SMALL_SDOF, Whole, study_text

FREE = {"model": "sdof", "period_s": 1.0e5, "mass_kg": 1000.0, "damping_ratio": 0.0}


def free_pair(material, quantile, **contact):
    """Two free 1 t masses (T = 1e5 s, undamped) meeting once, per-impact restitution."""
    return scene_from_dict(
        {
            "record": {"source": "builtin:knet-akt013", "duration_s": 1.0},
            "left": FREE,
            "right": FREE,
            "contact": {"model": "jankowski", "beta": 2.75e9, "gap_m": 0.0,
                        "restitution": "velocity", "material": material,
                        "e_quantile": quantile, "relation": "exact", **contact},
        }
    )  # fmt: skip


def achieved_restitution(scene, v_impact, method="adaptive", dt_s=1e-3):
    """Rebound over impact velocity of one free impact at ``v_impact`` [m/s].

    256 contact sub-steps per contact duration: the rebound to 1e-8 (16: 7e-6).
    """
    arrays = scene.kernel_arrays()
    g = arrays["gamma"]
    dt = 1e-3
    res = run_kernel(np.zeros(101), dt, **arrays, model=scene.contact_model,
                     relation=scene.relation, method=method, substeps=256, dt_s=dt_s,
                     q0=[-1e-9 * g[0], 0.0], v0=[g[0] * v_impact, 0.0], history=True,
                     restitution=scene.restitution_rule())  # fmt: skip
    pen = res.history[1][:, 0]
    # free masses after separation: the penetration falls linearly (spring forces ~1e-9)
    return -(pen[-1] - pen[-2]) / dt / v_impact, res


@pytest.mark.parametrize("material", ["steel", "concrete", "timber", "ceramics"])
def test_single_impacts_reproduce_table_2_bounds(material):
    # Jankowski (2008) Table 2: at Q = 0 and Q = 1 the 'exact' relation's free impact rebounds
    # with the table's e_min and e_max at the tabulated velocities (steel: up to 2 m/s, its
    # range at 2 m/s held above by the default 'clamp')
    rows = table(2)
    rows = rows[rows["material"] == material].set_index("velocity_m_s")
    for v in (0.2, 0.5, 1.0, 2.0, 4.0):
        row = rows.loc[min(v, rows.index.max())]
        for q, bound in ((0.0, row["e_min"]), (1.0, row["e_max"])):
            e, res = achieved_restitution(free_pair(material, q), v)
            assert e == pytest.approx(bound, abs=1e-6), (material, v, q)
            assert res.outputs["impacts"] == 1
            assert res.outputs["max_impact_velocity"] == pytest.approx(v, rel=1e-9)
            assert res.outputs["median_impact_velocity"] == pytest.approx(v, rel=1e-9)
            # the law's rebound for the table's e: under 'exact' e itself, to the round trip
            # through the exact table's two interpolants (1e-9)
            assert res.outputs["peak_force_restitution"] == pytest.approx(bound, abs=1e-8)
            assert res.contacts["max_impact_velocity"][0] == pytest.approx(v, rel=1e-9)


@pytest.mark.parametrize(
    ("contact", "expected"),
    [
        # Jankowski (2008) eq. 2.9 aims at Table 2's e and rebounds higher: concrete at 0.5
        # m/s, Q = 0.5 aims at 0.67195 (the row's mid-range) and rebounds with about 0.70
        ({"restitution": "velocity", "material": "concrete", "e_quantile": 0.5,
          "relation": "jankowski2008"}, None),
        # Hertz-damp with e = 0.65 for every impact rebounds with 0.63033 (ye2009) and
        # 0.77482 (muthukumar2006): an independent solve_ivp of the dimensionless impact
        # u'' = -max(u^1.5 (1 + f(e) u'), 0), DOP853 rtol 1e-12
        ({"model": "hertzdamp", "relation": "ye2009", "e": 0.65}, 0.63033),
        ({"model": "hertzdamp", "relation": "muthukumar2006", "e": 0.65}, 0.77482),
    ],
    ids=["velocity-jankowski2008", "hertzdamp-ye2009", "hertzdamp-muthukumar2006"],
)  # fmt: skip
def test_peak_force_restitution_is_the_rebound(contact, expected):
    """peak_force_restitution gave the e aimed at where the law rebounds with another (per
    impact under eq. 2.9: Table 2's e; Hertz-damp: its e), and the rebound elsewhere."""
    scene = scene_from_dict(
        {"record": {"source": "builtin:knet-akt013", "duration_s": 1.0}, "left": FREE,
         "right": FREE, "contact": {"model": "jankowski", "beta": 2.75e9, "gap_m": 0.0,
                                    **contact}}
    )  # fmt: skip
    rebound, res = achieved_restitution(scene, 0.5)
    assert res.outputs["impacts"] == 1
    assert res.outputs["peak_force_restitution"] == pytest.approx(rebound, abs=1e-6)
    if expected is None:
        # Table 2, concrete at 0.5 m/s, mid-range: eq. 2.9's xi for it (written out here),
        # and the rebound of that impact (two 1 t masses, m_eff 500 kg, at 0.5 m/s) by the
        # independent Radau solution of tests/reference_impact.py: 0.70333, 0.0314 above
        aimed = 0.5 * (0.658 + 0.6859)
        xi = math.sqrt(5.0) * (1.0 - aimed**2) / (2.0 * math.pi * aimed)
        expected, _d_max, _t_c = jankowski_impact(500.0, 0.5, 2.75e9, xi)
        assert expected == pytest.approx(0.70333, abs=1e-5)
    assert rebound == pytest.approx(expected, abs=5e-6)


@pytest.mark.parametrize("contact", [{"model": "hertzdamp", "e": 0.65},
                                     {"model": "jankowski", "xi": 0.35}])  # fmt: skip
def test_no_contact_no_restitution(contact):
    """A run without any contact reported its law's rebound (fixed restitution) where a run
    with per-impact restitution gave NaN: there is no impact that holds the peak force."""
    scene = scene_from_dict(
        {"record": {"source": "builtin:elcentro", "duration_s": 2.0}, "left": FREE,
         "right": FREE, "contact": {"beta": 2.75e9, "gap_m": 0.5, **contact}}
    )  # fmt: skip
    res = simulate(scene)
    assert res.outputs["impacts"] == 0 and res.outputs["peak_force"] == 0.0
    assert np.isnan(res.outputs["peak_force_restitution"])


def test_between_rows_and_outside():
    # linear in velocity between Table 2's rows; below 0.2 m/s the 0.2 m/s range ('clamp'),
    # or the first segment continued ('extrapolate'); concrete rows 0.2: 0.723-0.784,
    # 0.5: 0.658-0.6859
    assert restitution_at("concrete", 0.35, 0.5) == pytest.approx(
        0.5 * (0.5 * (0.723 + 0.658) + 0.5 * (0.784 + 0.6859)), abs=1e-15
    )
    assert restitution_at("concrete", 0.05, 0.0) == 0.723
    assert restitution_at("concrete", 0.05, 0.0, outside="extrapolate") == pytest.approx(
        0.723 + (0.723 - 0.658) / 0.3 * 0.15, abs=1e-12
    )
    v, lo, hi = restitution_rows("concrete")
    assert v[0] == 0.2 and lo[0] == 0.723 and hi[0] == 0.784
    for v_imp, outside in ((0.35, "clamp"), (0.1, "clamp"), (0.1, "extrapolate")):
        e, res = achieved_restitution(free_pair("concrete", 0.3, outside=outside), v_imp)
        want = restitution_at("concrete", v_imp, 0.3, outside=outside)
        assert res.outputs["peak_force_restitution"] == pytest.approx(want, abs=1e-9)
        assert e == pytest.approx(want, abs=1e-5)  # the relation's table: 2e-8 in xi


@pytest.mark.parametrize("method", ["newmark", "newmark-explicit", "central-difference"])
def test_fixed_step_methods_set_restitution_per_impact(method):
    # the fixed-step methods take the rate at the last step point before contact (steps of
    # 1e-5 s, a contact of about 2 ms): Table 2 at it (concrete, 1 m/s, Q = 1: 0.5981), the
    # rebound within their step error
    e, res = achieved_restitution(free_pair("concrete", 1.0), 1.0, method=method, dt_s=1e-5)
    assert res.outputs["peak_force_restitution"] == pytest.approx(0.5981, abs=1e-4)
    assert res.outputs["max_impact_velocity"] == pytest.approx(1.0, abs=1e-3)
    assert e == pytest.approx(0.5981, abs=5e-3)


def test_validation():
    base = {"record": {"source": "builtin:knet-akt013"}, "left": FREE, "right": FREE}
    for contact, key in (
        ({"restitution": "velocity", "e_quantile": 0.5}, "contact.material"),
        ({"restitution": "velocity", "material": "concrete", "e_quantile": 0.5, "e": 0.6},
         "contact.e"),
        ({"xi": 0.3, "material": "concrete"}, "contact.material"),
        ({"model": "hertz", "restitution": "velocity", "material": "concrete",
          "e_quantile": 0.5}, "contact.restitution"),
        ({"restitution": "velocity", "material": "concrete", "e_quantile": 1.5},
         "contact.e_quantile"),
    ):  # fmt: skip
        with pytest.raises(InputError) as info:
            scene_from_dict({**base, "contact": contact})
        assert key in str(info.value)


@pytest.mark.slow
def test_b1_velocity_restitution_against_reference():
    # B1's SDOF pair with concrete restitution set per impact at Q = 0.5 against the SciPy
    # reference that applies the same rule with its own Table 2 and eq. 2.9 (not
    # materials.restitution_at and relations.xi_from_e) at every onset event; the first 6 s
    # of its record at 0.5 g and gap 5 mm (as
    # test_laws_vs_reference) for a short run with several impacts
    sdof = {"model": "sdof", "damping_ratio": 0.05, "mass_kg": 1.0e6}
    scene = scene_from_dict(
        {
            "record": {"source": "builtin:knet-akt013", "duration_s": 6.0, "pga_g": 0.5},
            "left": {**sdof, "period_s": 0.5},
            "right": {**sdof, "period_s": 1.0},
            "contact": {"model": "jankowski", "gap_m": 0.005, "beta": 2.75e9,
                        "restitution": "velocity", "material": "concrete", "e_quantile": 0.5},
        }
    )  # fmt: skip
    record = scene.record_arrays()
    ref = reference_solution(scene, record)
    res = simulate(scene, record=record)
    assert res.outputs["impacts"] == ref["impacts"] > 2
    assert res.outputs["peak_force"] == pytest.approx(ref["peak_force"], rel=1e-4)
    velocities = np.asarray(ref["impact_velocities"])
    assert res.outputs["max_impact_velocity"] == pytest.approx(velocities.max(), rel=1e-4)
    assert res.outputs["median_impact_velocity"] == pytest.approx(np.median(velocities),
                                                                  rel=1e-4)  # fmt: skip
    assert res.outputs["peak_force_restitution"] == pytest.approx(
        ref["peak_force_restitution"], abs=1e-5
    )
    # the impacts really had different e: velocities spread over Table 2's rows
    assert velocities.min() < 0.5 * velocities.max()


def test_study_samples_the_quantile(tmp_path):
    # a study with restitution set per impact and e_quantile sampled uniform over [0, 1]: each
    # simulation of the dataset is the scene the engine names for it (scene_of), and the
    # rebound at the peak force is eq. 2.9's for an e in concrete's Table 2 band at that
    # impact's velocity (the band's ends rebound with effective_restitution of them)
    text = study_text(
        SMALL_SDOF,
        study={"name": "quantile"},
        grid={"left.period_s": [0.3, 0.5]},
        contact=Whole({"model": "jankowski", "gap_m": 0.002, "beta": 2.75e9,
                       "restitution": "velocity", "material": "concrete", "e_quantile": 0.5}),
        sampling=Whole({"n": 4, "method": "sobol", "vary": {
            "contact.e_quantile": {"distribution": "uniform", "low": 0.0, "high": 1.0}}}),
    )  # fmt: skip
    study = study_from_text(text, file=tmp_path / "quantile.toml")
    ds = xr.load_dataset(run_study(study, tmp_path, progress=False).path)
    engine = StudyEngine(study)
    flat = {
        k: ds[k].values.ravel()
        for k in (
            "peak_force",
            "impacts",
            "max_impact_velocity",
            "median_impact_velocity",
            "peak_force_restitution",
        )
    }
    assert (flat["impacts"] > 0).any()
    # no one xi or e: set at every impact (they read 0 and 1.0, an elastic contact)
    assert np.isnan(ds["xi"]).all() and np.isnan(ds["e_effective"]).all()
    assert "e_quantile" in ds.variables or "contact_e_quantile" in ds.variables
    for i in range(flat["impacts"].size):
        res = simulate(engine.scene_of(i))
        for key, values in flat.items():
            assert res.outputs[key] == pytest.approx(values[i], rel=1e-12, nan_ok=True), key
        if flat["impacts"][i]:
            lo = restitution_at("concrete", flat["max_impact_velocity"][i], 0.0)
            low = effective_restitution(min(lo, 0.4278))  # the peak-force impact may be slower
            assert low - 1e-9 <= flat["peak_force_restitution"][i]
            assert flat["peak_force_restitution"][i] <= effective_restitution(0.784) + 1e-9


def test_per_impact_material_variable():
    # contact.e = { material = "concrete", per_impact = true }: the scene takes restitution =
    # "velocity" with concrete, and the quantile is sampled uniform over [0, 1]
    text = study_text(
        SMALL_SDOF,
        study={"name": "per_impact"},
        sampling={"vary": {"contact.e": {"material": "concrete", "per_impact": True},
                           "contact.beta": {"material": "concrete"}}},
    )  # fmt: skip
    study = study_from_text(text)
    assert [v.key for v in study.variables] == ["contact.beta", "contact.e_quantile"]
    q = study.variables[1]
    assert (q.kind, q.a, q.b) == ("uniform", 0.0, 1.0)
    engine = StudyEngine(study)
    quantiles = engine.parameters(np.arange(8))["contact.xi"]  # the kernels' xi: the quantile
    for i in range(8):
        scene = engine.scene_of(i)
        assert (scene.restitution, scene.material, scene.e) == ("velocity", "concrete", None)
        assert scene.e_quantile == quantiles[i]
        assert 0.0 <= scene.e_quantile <= 1.0
    with pytest.raises(InputError):
        study_from_text(text.replace("per_impact = true", "per_impact = false"))
