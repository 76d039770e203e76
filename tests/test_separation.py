"""Separation-gap rules (ABS, SRSS, DDC) and the linear peak displacements behind them."""

import math

import numpy as np
import pytest

from pound_mc.analysis.gaps import study_gaps
from pound_mc.errors import InputError
from pound_mc.physics.separation import (
    cqc_correlation,
    gap_abs,
    gap_ddc,
    gap_srss,
    peak_displacements,
    required_gaps,
)
from pound_mc.study.definition import study_from_text
from studies import study_text


@pytest.mark.parametrize("zeta", [0.02, 0.05, 0.1, 0.2])
def test_rho_is_one_for_equal_periods_and_damping(zeta):
    # Der Kiureghian (1981): at r = 1, z1 = z2 = z the numerator 8 z (2 z) = 16 z^2 equals the
    # denominator 0 + 4 z^2 * 2 + 4 * 2 z^2 = 16 z^2.
    assert cqc_correlation(0.7, 0.7, zeta, zeta) == pytest.approx(1.0, abs=1e-15)


def test_rho_hand_computed():
    # z1 = z2 = 0.05, r = T1/T2 = 0.5, by hand:
    #   numerator   8 * 0.05 * (0.05 + 0.5 * 0.05) * 0.5^1.5 = 0.4 * 0.075 * 0.353553 = 0.0106066
    #   denominator (1 - 0.25)^2 + 4 * 0.0025 * 0.5 * 1.25 + 4 * 0.005 * 0.25
    #             = 0.5625 + 0.00625 + 0.005 = 0.57375
    #   rho = 0.0106066 / 0.57375 = 0.0184865
    assert cqc_correlation(0.5, 1.0, 0.05, 0.05) == pytest.approx(0.0184865, rel=1e-5)


def test_rho_equal_damping_form_and_symmetry():
    # With z1 = z2 = z the coefficient reduces to the familiar form
    # 8 z^2 (1 + r) r^1.5 / ((1 - r^2)^2 + 4 z^2 r (1 + r)^2) (Der Kiureghian 1981; Chopra 2012,
    # sec. 13.7): 4 z^2 r (1 + r^2) + 8 z^2 r^2 = 4 z^2 r (1 + r)^2.
    r = np.linspace(0.05, 3.0, 60)
    z = 0.05
    expected = 8 * z**2 * (1 + r) * r**1.5 / ((1 - r**2) ** 2 + 4 * z**2 * r * (1 + r) ** 2)
    assert np.allclose(cqc_correlation(r, 1.0, z, z), expected, rtol=1e-13)
    # a correlation coefficient: symmetric in the two buildings and within [0, 1]
    t1, t2 = np.meshgrid(np.linspace(0.1, 3, 25), np.linspace(0.1, 3, 25))
    a = cqc_correlation(t1, t2, 0.02, 0.1)
    b = cqc_correlation(t2, t1, 0.1, 0.02)
    assert np.allclose(a, b, rtol=1e-13)
    assert np.all((a >= 0) & (a <= 1 + 1e-12))


def test_rho_bad_input():
    with pytest.raises(InputError):
        cqc_correlation(-1.0, 1.0)
    with pytest.raises(InputError):
        cqc_correlation(1.0, 1.0, 0.0, 0.05)


def test_gap_rules_hand_values():
    # u1 = 0.03 m, u2 = 0.04 m: ABS = 0.07 m; SRSS = 0.05 m (3-4-5 triangle);
    # DDC = |u1 - u2| = 0.01 m for rho = 1, = SRSS for rho = 0,
    # = sqrt(0.0009 + 0.0016 - 2 * 0.5 * 0.0012) = sqrt(0.0013) for rho = 0.5.
    assert gap_abs(0.03, 0.04) == pytest.approx(0.07)
    assert gap_abs(-0.03, 0.04) == pytest.approx(0.07)
    assert gap_srss(0.03, 0.04) == pytest.approx(0.05)
    assert gap_ddc(0.03, 0.04, 1.0) == pytest.approx(0.01)
    assert gap_ddc(0.03, 0.04, 0.0) == pytest.approx(0.05)
    assert gap_ddc(0.03, 0.04, 0.5) == pytest.approx(math.sqrt(0.0013))


def test_ddc_le_srss_le_abs():
    rng = np.random.default_rng(3)
    u1, u2 = rng.uniform(0, 0.3, (2, 500))
    rho = cqc_correlation(rng.uniform(0.1, 3, 500), rng.uniform(0.1, 3, 500), 0.05, 0.05)
    ddc, srss, ab = gap_ddc(u1, u2, rho), gap_srss(u1, u2), gap_abs(u1, u2)
    assert np.all(ddc <= srss + 1e-15) and np.all(srss <= ab + 1e-15)


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.2])
def test_peak_displacement_of_a_step_load(zeta):
    # Constant ground acceleration a0 from rest: u(t) = -(a0/w^2) (1 - e^{-z w t}(cos wd t + ...)),
    # peak at t = pi/wd: (a0/w^2) (1 + exp(-z pi / sqrt(1 - z^2))) (Chopra 2012, sec. 4.3,
    # step force overshoot); 2 a0/w^2 undamped.
    a0, period = 2.0, 0.8
    omega = 2 * math.pi / period
    expected = a0 / omega**2 * (1 + math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2)))
    u = peak_displacements(0.01, np.full(201, a0), [period], zeta)
    assert u[0] == pytest.approx(expected, rel=1e-4)


def test_substeps_catch_the_peak_between_samples():
    # T = 1 s undamped step response peaks at t = 0.5 s, between the samples 0.3 and 0.6 s;
    # exact peak 2 a0 / w^2 (Chopra 2012, sec. 4.3).
    a0, period = 1.0, 1.0
    exact = 2 * a0 / (2 * math.pi / period) ** 2
    coarse = peak_displacements(0.3, np.full(5, a0), [period], 0.0, substeps=1)[0]
    fine = peak_displacements(0.3, np.full(5, a0), [period], 0.0, substeps=16)[0]
    assert coarse < 0.95 * exact
    assert fine == pytest.approx(exact, rel=2e-3)


def test_required_gaps_for_a_record():
    from pound_mc.motions import load_record, record_arrays

    dt, acc = record_arrays(load_record("builtin:elcentro", duration_s=20.0))
    g = required_gaps(dt, acc, 0.5, 1.0)
    assert g.u1 > 0 and g.u2 > 0
    assert g.rho == pytest.approx(0.0184865, rel=1e-5)  # the hand value above
    assert g.ddc <= g.srss <= g.abs
    assert g.abs == pytest.approx(g.u1 + g.u2)
    same = required_gaps(dt, acc, 0.7, 0.7)  # identical buildings move together
    assert same.rho == pytest.approx(1.0) and same.ddc == pytest.approx(0.0, abs=1e-9)


STUDY = study_text(
    study={"name": "gaps", "seed": 1},
    record=None,
    records=[
        {"source": "synthetic:clough-penzien", "seed": 1, "params": {"duration_s": 5.0}},
        {"source": "builtin:elcentro", "duration_s": 5.0},
    ],
    right={"damping_ratio": 0.03},
    contact={"gap_m": 0.01},
    grid={"left.period_s": None, "contact.gap_m": [0.0, 0.05]},
    sampling={
        "n": 4,
        "method": None,
        "vary": {"left.period_s": {"distribution": "lognormal", "median": 0.5, "sigma_ln": 0.2}},
    },
)


def test_study_gaps_match_required_gaps():
    from pound_mc.study.engine import StudyEngine

    study = study_from_text(STUDY)
    g = study_gaps(study)
    assert g["gap_abs"].shape == study.shape
    engine = StudyEngine(study)
    periods = engine.samples["left.period_s"]
    dt, acc = engine.records[1]
    one = required_gaps(dt, acc, periods[2], 1.0, 0.05, 0.03)
    cell = g.isel(record=1, contact_gap_m=1, sample=2)
    for name, value in (("linear_disp_left", one.u1), ("linear_disp_right", one.u2),
                        ("rho", one.rho), ("gap_abs", one.abs), ("gap_srss", one.srss),
                        ("gap_ddc", one.ddc)):  # fmt: skip
        assert float(cell[name]) == pytest.approx(value, rel=1e-12), name
    # the gaps do not depend on the gap axis
    assert np.array_equal(g["gap_abs"].isel(contact_gap_m=0), g["gap_abs"].isel(contact_gap_m=1))
