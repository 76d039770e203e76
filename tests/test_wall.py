"""A building against a rigid, immovable wall (``[right] model = "wall"``): closed forms and the
independent SciPy reference.
"""

import math

import numpy as np
import pytest
import xarray as xr
from scipy.special import gamma

from pound_mc.errors import InputError
from pound_mc.integrators import run_kernel
from pound_mc.integrators.reference import reference_solution
from pound_mc.scene import scene_from_dict, simulate
from pound_mc.study.definition import study_from_text
from pound_mc.study.engine import StudyEngine
from pound_mc.study.runner import run_study
from studies import SMALL_SDOF, Whole, study_text

M, BETA = 1000.0, 2.75e9
FREE = {"model": "sdof", "period_s": 1.0e5, "mass_kg": M, "damping_ratio": 0.0}


def against_wall(contact, left=FREE, **extra):
    return scene_from_dict(
        {
            "record": {"source": "builtin:knet-akt013", "duration_s": 6.0, "pga_g": 0.5},
            "left": left,
            "right": {"model": "wall"},
            "contact": {"gap_m": 0.0, "beta": BETA, **contact},
            **extra,
        }
    )


def single_impact(scene, v, model):
    """One impact of the free mass at ``v`` [m/s] (256 sub-steps per contact duration)."""
    arrays = scene.kernel_arrays()
    g = arrays["gamma"][0]
    dt = 1e-3
    res = run_kernel(np.zeros(101), dt, **arrays, model=model, relation=scene.relation,
                     substeps=256, q0=[-1e-9 * g], v0=[g * v], history=True)  # fmt: skip
    pen = res.history[1][:, 0]
    return res, -(pen[-1] - pen[-2]) / dt / v


@pytest.mark.parametrize("v", [0.2, 1.0, 4.0])
def test_hertz_impact_on_a_wall_matches_closed_forms(v):
    # Hertz impact of a mass m on a rigid wall (m_eff = m): maximum compression
    # d = (5 m v^2 / (4 beta))^0.4, peak force beta d^1.5, contact duration
    # t_c = 2 (d / v) sqrt(pi) Gamma(7/5) / Gamma(9/10) (symmetric, peak at t_c / 2), an
    # elastic rebound (e = 1) and impulse 2 m v
    scene = against_wall({"model": "hertz"})
    assert scene.kernel_arrays()["meff"][0] == M
    res, e = single_impact(scene, v, "hertz")
    d = (5.0 * M * v * v / (4.0 * BETA)) ** 0.4
    t_c = 2.0 * d / v * math.sqrt(math.pi) * gamma(1.4) / gamma(0.9)
    o = res.outputs
    assert o["impacts"] == 1
    assert o["peak_force"] == pytest.approx(BETA * d**1.5, rel=1e-6)
    assert o["max_penetration"] == pytest.approx(d, rel=1e-6)
    # onset at 1e-9 m / v; the peak at half the contact duration
    assert (o["peak_force_time"] - 1e-9 / v) == pytest.approx(0.5 * t_c, rel=1e-6)
    assert o["impulse"] == pytest.approx(2.0 * M * v, rel=1e-6)
    assert e == pytest.approx(1.0, abs=1e-6)
    assert o["peak_disp_right"] == 0.0


@pytest.mark.parametrize("e_target", [0.4, 0.65, 0.9])
def test_jankowski_impact_on_a_wall_rebounds_with_e(e_target):
    # Jankowski's law with xi from the 'exact' relation rebounds with e (seed eq. 2.5: the
    # rebound speed follows from the energy stored at maximum compression), any mass
    scene = against_wall({"model": "jankowski", "e": e_target, "relation": "exact"})
    res, e = single_impact(scene, 1.0, "jankowski")
    assert e == pytest.approx(e_target, abs=1e-6)
    assert res.outputs["impulse"] == pytest.approx(M * (1.0 + e_target), rel=1e-6)


def test_base_isolated_building_against_a_moat_wall_matches_reference():
    # a long-period (isolated) SDOF against a moat wall 5 cm away under 6 s of K-NET AKT013 at
    # 0.5 g: impacts and peak force as the SciPy reference
    left = {"model": "sdof", "period_s": 2.5, "mass_kg": 1.0e6, "damping_ratio": 0.1}
    scene = against_wall({"model": "jankowski", "xi": 0.35, "gap_m": 0.01}, left=left)
    record = scene.record_arrays()
    ref = reference_solution(scene, record)
    res = simulate(scene, record=record)
    assert res.outputs["impacts"] == ref["impacts"] > 0
    assert res.outputs["peak_force"] == pytest.approx(ref["peak_force"], rel=1e-4)
    assert res.outputs["peak_disp_left"] == pytest.approx(ref["peak_disp_left"], rel=1e-4)
    assert res.outputs["max_impact_velocity"] == pytest.approx(
        max(ref["impact_velocities"]), rel=1e-4
    )


def test_wall_only_on_the_right():
    with pytest.raises(InputError) as info:
        scene_from_dict(
            {"record": {"source": "builtin:knet-akt013"}, "left": {"model": "wall"},
             "right": FREE, "contact": {"xi": 0.3}}
        )  # fmt: skip
    assert "left.model" in str(info.value)


def test_study_against_a_wall(tmp_path):
    # a study of an SDOF against a wall runs through the scene batch; each simulation of the
    # dataset is the scene the engine names for it
    text = study_text(SMALL_SDOF, study={"name": "wall"}, right=Whole({"model": "wall"}),
                      grid={"left.period_s": None}, sampling={"n": 2})  # fmt: skip
    study = study_from_text(text, file=tmp_path / "wall.toml")
    ds = xr.load_dataset(run_study(study, tmp_path, progress=False).path)
    engine = StudyEngine(study)
    peak = ds["peak_force"].values.ravel()
    assert (ds["impacts"].values > 0).all()
    for i in range(peak.size):
        assert simulate(engine.scene_of(i)).outputs["peak_force"] == peak[i]


def test_history_chart_names_the_wall(tmp_path):
    """A wall on the right was labelled "right, floor 1" (it has no floors)."""
    from pound_mc.analysis.plot_numerics import time_history_chart

    sdof = {"model": "sdof", "period_s": 0.5, "mass_kg": 1.0e6, "damping_ratio": 0.05}
    res = simulate(against_wall({"model": "jankowski", "xi": 0.35}, left=sdof), history=True)
    labels = [ln.get_label() for ln in time_history_chart(res).axes[0].lines]
    assert labels == ["left, floor 1", "wall"]
