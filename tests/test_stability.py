"""Stability exactly where methods fail: just inside and just beyond each explicit limit."""

import math

import pytest

from pound_mc.numerics import stability as S

# a few steps of the explicit kernels: also run with NUMBA_DISABLE_JIT=1
pytestmark = pytest.mark.nojit


def test_predicted_limits_from_the_amplification_matrix():
    # Central differences on x'' = -w^2 x: |z| = 1 up to dt w = 2 (classical limit); the flag's
    # 50 % energy allowance per contact moves it by less than 1 %.
    assert S.predicted_limit("central-difference") == pytest.approx(2.0, rel=1e-2)
    # Lagged-force Newmark: root |z| ~ sqrt(1 + W^2), so energy over pi/W steps grows as
    # (1 + W^2)^(pi/W) ~ exp(pi W): 1.5 at W = ln(1.5)/pi = 0.129 (to leading order).
    assert S.predicted_limit("newmark-explicit") == pytest.approx(math.log(1.5) / math.pi, rel=0.05)
    assert math.isinf(S.predicted_limit("newmark"))
    assert math.isinf(S.predicted_limit("adaptive"))


@pytest.mark.parametrize("beta", [1e9, 1e11])
def test_newmark_explicit_fails_just_beyond_its_limit(beta):
    scene = S.impact_scene(beta)
    wc = S.contact_frequency(beta, scene.contacts[0].m_eff, 0.5)
    lim = S.predicted_limit("newmark-explicit")
    inside = S.run_impact(scene, "newmark-explicit", 0.8 * lim / wc)
    beyond = S.run_impact(scene, "newmark-explicit", 1.5 * lim / wc)
    assert int(inside["status"]) == 0
    assert int(beyond["status"]) == 1  # flagged unstable
    assert math.isnan(beyond["peak_force"])  # and never returned as a plain number
    # adaptive at the same dt_s stays stable and keeps its energy balance
    ok = S.run_impact(scene, "adaptive", 1.5 * lim / wc)
    assert int(ok["status"]) == 0 and abs(ok["energy_residual"]) < 1e-3


@pytest.mark.parametrize("beta", [1e9, 1e10])
def test_central_difference_fails_beyond_its_limit(beta):
    scene = S.impact_scene(beta)
    wc = S.contact_frequency(beta, scene.contacts[0].m_eff, 0.5)
    inside = S.run_impact(scene, "central-difference", 0.8 * 2.0 / wc)
    beyond = S.run_impact(scene, "central-difference", 4.0 * 2.0 / wc)
    # stable inside the limit, yet a contact of two steps: inaccurate (3), not unstable
    assert int(inside["status"]) == 3 and abs(inside["energy_residual"]) < 0.05
    assert int(beyond["status"]) == 1
    assert math.isnan(beyond["peak_force"])
    # adaptive sizes its contact sub-steps from the contact duration, not from dt_s
    out = S.run_impact(scene, "adaptive", 4.0 * 2.0 / wc)
    assert int(out["status"]) == 0 and abs(out["energy_residual"]) < 1e-3


def test_contact_frequency_is_the_hertz_tangent_at_peak_penetration():
    # seed eq. 2.5: delta_max = (5 m v0^2 / (4 beta))^0.4; k = 1.5 beta delta_max^0.5
    beta, m, v0 = 2.75e9, 5e5, 0.5
    d = (5 * m * v0**2 / (4 * beta)) ** 0.4
    assert S.contact_frequency(beta, m, v0) == pytest.approx(math.sqrt(1.5 * beta * d**0.5 / m))
