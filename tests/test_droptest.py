import math

import numpy as np
import pytest
from reference_impact import jankowski_impact

from pound_mc.errors import InputError
from pound_mc.physics.contact import HERTZ_DURATION_INTEGRAL, contact_duration_hertz
from pound_mc.physics.droptest import drop_test
from pound_mc.physics.relations import restitution_of_xi

# single impacts through the contact laws: also run with NUMBA_DISABLE_JIT=1
pytestmark = pytest.mark.nojit


def test_elastic_peak_penetration_eq_2_5_and_duration():
    m, v0, beta = 1.35, 1.0, 7.9e9  # Table 1/3: 103 mm concrete ball, mean beta
    r = drop_test(m, v0, beta, xi=0.0)
    # Seed eq. (2.5) with e = 1 (delta_f = v0): delta_max = (5 m v0^2 / (4 beta))^(2/5)
    d_max = (5.0 * m * v0**2 / (4.0 * beta)) ** 0.4
    assert r.max_penetration_m == pytest.approx(d_max, rel=1e-6)
    # Hertz contact duration: 2 * 0.4 B(0.4, 0.5) = 2.943 ... times delta_max / v0
    assert 2 * HERTZ_DURATION_INTEGRAL == pytest.approx(2.943, abs=5e-4)
    assert r.contact_duration_s == pytest.approx(2.943 * d_max / v0, rel=1e-4)
    assert r.contact_duration_s == pytest.approx(contact_duration_hertz(v0, beta, m), rel=1e-8)
    # DESIGN.md section 4: t_c = 3.218 (m/beta)^0.4 v0^-0.2
    assert r.contact_duration_s == pytest.approx(3.218 * (m / beta) ** 0.4 * v0**-0.2, rel=1e-4)
    assert r.restitution == pytest.approx(1.0, abs=1e-9)
    assert r.peak_force_N == pytest.approx(beta * d_max**1.5, rel=1e-6)


def test_damped_impact_matches_independent_solution():
    m, v0, beta, xi = 2.0, 1.5, 6.0e9, 0.4
    r = drop_test(m, v0, beta, xi=xi)
    e, d_max, t_c = jankowski_impact(m, v0, beta, xi)
    assert r.restitution == pytest.approx(e, abs=1e-8)
    assert r.max_penetration_m == pytest.approx(d_max, rel=1e-7)
    assert r.contact_duration_s == pytest.approx(t_c, rel=1e-7)
    # Peak force exceeds the elastic force at maximum compression (damping adds while approaching)
    assert r.peak_force_N > beta * r.max_penetration_m**1.5
    assert r.peak_force_N == pytest.approx(r.force_N.max(), rel=1e-3)


def test_restitution_independent_of_mass_beta_velocity():
    # Property of the model (dimensionless form depends on xi only): four orders of magnitude
    # of each of mass, beta and velocity change the achieved restitution by < 1e-6.
    xi = 0.35
    expected = restitution_of_xi(xi)
    values = [
        drop_test(m, v, b, xi=xi, n_history=4).restitution
        for m in (1e-2, 1e0, 1e2)
        for b in (1e7, 1e9, 1e11)
        for v in (1e-2, 1e0, 1e2)
    ]
    values += [drop_test(1e6, 0.3, 2.75e9, xi=xi, n_history=4).restitution]
    assert np.ptp(values) < 1e-6
    assert np.max(np.abs(np.asarray(values) - expected)) < 1e-6


def test_two_finite_masses_use_effective_mass():
    a = drop_test(3.0, 1.0, 5e9, xi=0.2, mass2_kg=6.0)
    b = drop_test(2.0, 1.0, 5e9, xi=0.2)  # m_eff = 3*6/9 = 2
    assert a.max_penetration_m == pytest.approx(b.max_penetration_m, rel=1e-10)


def test_kelvin_law_relation_is_exact():
    # Kelvin-Voigt element with the Anagnostopoulos relation rebounds with exactly e
    # (linear damped oscillator, separation at delta = 0).
    r = drop_test(1.0, 1.0, 1e7, e=0.42, model="kelvin")
    assert r.restitution == pytest.approx(0.42, abs=1e-8)
    assert r.contact_duration_s == pytest.approx(math.pi / math.sqrt(1e7 * (1 - r.xi**2)), rel=1e-8)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"mass_kg": -1.0, "velocity_m_s": 1.0, "beta": 1e9, "xi": 0.1}, "mass_kg"),
        ({"mass_kg": 1.0, "velocity_m_s": 0.0, "beta": 1e9, "xi": 0.1}, "velocity_m_s"),
        ({"mass_kg": 1.0, "velocity_m_s": 1.0, "beta": float("inf"), "xi": 0.1}, "beta"),
        ({"mass_kg": 1.0, "velocity_m_s": 1.0, "beta": 1e9}, "xi"),
        ({"mass_kg": 1.0, "velocity_m_s": 1.0, "beta": 1e9, "xi": 0.1, "model": "x"}, "model"),
    ],
)
def test_bad_parameters(kwargs, key):
    with pytest.raises(InputError) as info:
        drop_test(**kwargs)
    assert info.value.key == key
