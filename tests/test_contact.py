import math

import pytest

from pound_mc.errors import InputError
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


def test_registry_declares_relations_and_units():
    laws = contact.CONTACT_MODELS
    assert list(laws) == ["jankowski", "linear", "kelvin", "hertz", "hertzdamp"]
    assert contact.allowed_relations("hertzdamp") == ("ye2009", "muthukumar2006")
    assert contact.default_relation("hertzdamp") == "ye2009"
    assert contact.default_relation("jankowski") == "jankowski2008"  # the seed's eq. (2.9)
    assert contact.default_relation("kelvin") == "kelvin"
    assert contact.allowed_relations("hertz") == () and contact.default_relation("linear") is None
    assert laws["linear"]["stiffness_units"] == "N m-1"  # mapping access kept
    assert laws["jankowski"]["force"] is contact.jankowski_force


@pytest.mark.parametrize("law", ["jankowski", "linear", "kelvin", "hertz", "hertzdamp"])
@pytest.mark.parametrize("phase", [1, 2])
def test_kernel_force_equals_public_force(law, phase):
    # the kernels' force of each law against its public twin; c0 = 2 xi sqrt(beta m_eff)
    # (seed eq. (1.1) with delta^0.25 factored out), zeta passed as the hertzdamp constant
    spec = contact.CONTACT_MODELS[law]
    d, dd, beta, xi, m_eff = 2e-3, 0.3 if phase == 1 else -0.3, 2.75e9, 0.35, 5e5
    c0 = 2 * xi * math.sqrt(beta * m_eff)
    damping = 2.0 if law == "hertzdamp" else xi
    kernel = spec.kernel.force(d, dd, beta, c0, damping, phase)
    public = spec.force(d, dd, beta, damping, m_eff)
    assert kernel == pytest.approx(public, rel=1e-12)
    f, fd, fdd = spec.kernel.grad(d, dd, beta, c0, damping, phase)
    assert f == pytest.approx(kernel, rel=1e-12)
    h = 1e-9  # central differences of the public force
    assert fd == pytest.approx((spec.force(d + h, dd, beta, damping, m_eff)
                                - spec.force(d - h, dd, beta, damping, m_eff)) / (2 * h),
                               rel=1e-5)  # fmt: skip


def test_relation_of_another_law_is_refused():
    with pytest.raises(InputError) as err:
        contact.check_relation("hertzdamp", "jankowski2008")
    assert err.value.key == "contact.relation"
    assert "ye2009" in str(err.value)
    with pytest.raises(InputError):
        contact.check_relation("jankowski", "ye2009")
    assert math.isnan(contact.reported_xi("hertzdamp", 0.6, "ye2009"))
    # seed eq. (2.9): xi = sqrt(5) (1 - e^2) / (2 pi e)
    assert contact.reported_xi("jankowski", 0.6, None) == pytest.approx(
        math.sqrt(5) * 0.64 / (2 * math.pi * 0.6)
    )


def test_registry_parameters_and_stored_energy_follow_each_law():
    # the scene keys each law takes (stiffness, then its damping parameter), and the stored elastic
    # energy of each kernel the integral of its elastic force (phase 2, dd = 0): beta d^2.5 / 2.5
    # for the Hertz-type laws, k d^2 / 2 for the springs, checked by quadrature
    from scipy.integrate import quad

    keys = {
        name: tuple(p.key for p in law.parameters) for name, law in contact.CONTACT_MODELS.items()
    }
    assert keys == {
        "jankowski": ("gap_m", "beta", "xi"),
        "linear": ("gap_m", "k_N_per_m"),
        "kelvin": ("gap_m", "k_N_per_m", "xi"),
        "hertz": ("gap_m", "beta"),
        "hertzdamp": ("gap_m", "beta", "e"),
    }
    for law in contact.CONTACT_MODELS.values():
        assert law.stiffness_units == law.parameters[1].units
        k, d = law.kernel, 2e-3
        work, _ = quad(lambda s, k=k: k.force(s, 0.0, 2.75e9, 1e3, 0.5, 2), 0.0, d)
        assert k.stored(d, 2.75e9) == pytest.approx(work, rel=1e-9)
