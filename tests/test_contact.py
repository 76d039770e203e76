import math

import pytest

from pound_mc.physics import contact

# scalar contact laws: also run as plain Python (NUMBA_DISABLE_JIT=1)
pytestmark = pytest.mark.nojit


def test_jankowski_force_phases():
    beta, xi, m1, m2 = 2.75e9, 0.35, 1.0e6, 1.0e6
    m_eff = contact.effective_mass(m1, m2)
    d, v = 2e-3, 0.3
    c = 2 * xi * math.sqrt(beta * math.sqrt(d) * m1 * m2 / (m1 + m2))  # seed eq. (1.1)
    assert contact.jankowski_force(d, v, beta, xi, m_eff) == pytest.approx(beta * d**1.5 + c * v)
    assert contact.jankowski_force(d, -v, beta, xi, m_eff) == pytest.approx(beta * d**1.5)
    assert contact.jankowski_force(-1e-3, v, beta, xi, m_eff) == 0.0
    assert contact.jankowski_force(0.0, v, beta, xi, m_eff) == 0.0


def test_other_laws():
    assert contact.linear_force(1e-3, 5.0, 1e8, 0.3, 10.0) == pytest.approx(1e5)
    c = 2 * 0.2 * math.sqrt(1e8 * 10.0)
    assert contact.kelvin_force(1e-3, 0.5, 1e8, 0.2, 10.0) == pytest.approx(1e5 + c * 0.5)
    assert contact.hertz_force(4e-4, 1.0, 1e9, 0.0, 1.0) == pytest.approx(1e9 * 8e-6)
    assert contact.hertzdamp_force(4e-4, 0.5, 1e9, 2.0, 1.0) == pytest.approx(8e3 * 2.0)
    assert contact.hertzdamp_force(4e-4, -1.0, 1e9, 2.0, 1.0) == 0.0  # clipped, no adhesion


def test_rigid_wall_effective_mass():
    assert contact.effective_mass(3.0, math.inf) == 3.0
    assert contact.effective_mass(3.0, 6.0) == pytest.approx(2.0)


def test_registry_codes_unique():
    codes = [m["code"] for m in contact.CONTACT_MODELS.values()]
    assert sorted(codes) == list(range(len(codes)))
