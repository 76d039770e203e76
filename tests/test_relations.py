import math

import numpy as np
import pytest
from reference_impact import hertzdamp_impact, jankowski_impact

from pound_mc.errors import InputError
from pound_mc.physics import relations

# relations and the single impacts behind them: also run with NUMBA_DISABLE_JIT=1
pytestmark = pytest.mark.nojit


@pytest.mark.parametrize("e", [0.1, 0.3, 0.5, 0.65, 0.8, 0.9, 0.99, 1.0])
def test_jankowski2008_is_eq_2_9_to_machine_precision(e):
    # Jankowski (2008) eq. (2.9): xi = sqrt(5) (1 - e^2) / (2 pi e), written out here.
    expected = math.sqrt(5.0) * (1.0 - e * e) / (2.0 * math.pi * e)
    assert relations.xi_from_e(e, "jankowski2008") == pytest.approx(expected, rel=1e-15, abs=1e-16)


def test_jankowski2006_closed_form():
    # Jankowski (2006) EESD 35: xi = 9 sqrt5 (1-e^2) / (2 e (e (9 pi - 16) + 16)); at e = 0.5
    # by hand: 9*2.2360680*0.75 / (2*0.5*(0.5*12.2743339+16)) = 15.093459/22.137167 = 0.6818153
    assert relations.xi_jankowski2006(0.5) == pytest.approx(0.6818153, rel=1e-6)


def test_kelvin_closed_form():
    # Anagnostopoulos (1992): xi = -ln e / sqrt(pi^2 + ln^2 e); e = exp(-pi) gives 1/sqrt(2).
    assert relations.xi_kelvin(math.exp(-math.pi)) == pytest.approx(1 / math.sqrt(2), rel=1e-14)


@pytest.mark.parametrize("e", [*np.linspace(0.1, 0.99, 8).round(4), 0.27])
def test_exact_relation_rebounds_with_target(e):
    # Independent check: Radau in physical units (tests/reference_impact.py), not the table.
    # e = 0.27 is the worst spot found by an independent check (error 4.0e-7, at a join in
    # the table's xi grid).
    achieved, _, _ = jankowski_impact(1.5, 0.7, 5.0e9, relations.xi_exact(e))
    assert abs(achieved - e) < 1e-4


@pytest.mark.parametrize(
    ("target", "published"),
    # DESIGN.md section 2: eq. 2.9 aimed at 0.3/0.5/0.65/0.8 gives ~0.377/0.558/0.685/0.813
    [(0.3, 0.377), (0.5, 0.558), (0.65, 0.685), (0.8, 0.813)],
)
def test_jankowski2008_really_produces(target, published):
    xi = relations.xi_jankowski2008(target)
    independent, _, _ = jankowski_impact(2.0, 1.2, 8.0e9, xi)
    assert relations.effective_restitution(target, "jankowski2008") == pytest.approx(
        independent, abs=1e-4
    )
    assert independent == pytest.approx(published, abs=6e-4)


def test_table_matches_high_accuracy_integration():
    # The shipped table is what the generator computes: spot-check three rows afresh.
    table = relations.exact_table()
    for i in (5, 150, 390):
        xi, e = table.loc[i, ["xi", "e"]]
        assert relations.single_impact_restitution(xi) == pytest.approx(e, abs=1e-11)


@pytest.mark.parametrize("relation", ["ye2009", "muthukumar2006"])
@pytest.mark.parametrize("e", [0.12, 0.37, 0.65, 0.905])
def test_hertzdamp_rebound(relation, e):
    # Independent check: Radau in physical units (tests/reference_impact.py), the law written
    # out there, zeta = 8 (1 - e) / (5 e v0) (Ye et al. 2009) or 3 (1 - e^2) / (4 v0)
    # (Muthukumar & DesRoches 2006); the rebound depends on e alone (two velocities agree)
    zeta = {"ye2009": 8 * (1 - e) / (5 * e), "muthukumar2006": 3 * (1 - e * e) / 4}[relation]
    for m_eff, v0, beta in ((1.5, 0.7, 5.0e9), (5.0e5, 0.2, 2.75e9)):
        independent = hertzdamp_impact(m_eff, v0, beta, zeta / v0)
        assert relations.hertzdamp_restitution(e, relation) == pytest.approx(independent,
                                                                             abs=1e-6)  # fmt: skip
    # off the table's grid, the interpolation stays within 1e-8 of a direct integration
    direct = relations.single_impact_restitution_hertzdamp(e, relation)
    assert relations.hertzdamp_restitution(e, relation) == pytest.approx(direct, abs=1e-8)


def test_hertzdamp_rebound_arrays_and_bounds():
    e = np.array([np.nan, 0.003, 0.65, 1.0])  # NaN kept; below the table: integrated
    out = relations.hertzdamp_restitution(e, "ye2009")
    assert np.isnan(out[0]) and out[3] == pytest.approx(1.0, abs=1e-12)
    assert out[1] == pytest.approx(relations.single_impact_restitution_hertzdamp(0.003), rel=1e-12)
    with pytest.raises(InputError, match="relation"):
        relations.hertzdamp_restitution(0.5, "jankowski2008")


def test_exact_roundtrip_and_monotone():
    e = np.linspace(0.05, 1.0, 200)
    xi = relations.xi_exact(e)
    assert np.all(np.diff(xi) < 0)
    assert np.allclose(relations.restitution_of_xi(xi), e, atol=1e-8)


@pytest.mark.parametrize("bad", [0.0, -0.2, 1.01, float("nan")])
def test_bad_restitution(bad):
    with pytest.raises(InputError, match=r"\(0, 1\]"):
        relations.xi_from_e(bad)


def test_unknown_relation_lists_choices():
    with pytest.raises(InputError, match="exact.*jankowski2006"):
        relations.xi_from_e(0.5, "nope")


def test_hertzdamp_zeta_closed_forms():
    # Muthukumar & DesRoches (2006): 3(1-e^2)/(4 v0); Ye et al. (2009): 8(1-e)/(5 e v0).
    assert relations.hertzdamp_zeta(0.6, 0.5, "muthukumar2006") == pytest.approx(0.96)
    assert relations.hertzdamp_zeta(0.6, 0.5, "ye2009") == pytest.approx(8 * 0.4 / (5 * 0.6 * 0.5))


def test_a_restitution_beyond_the_table_is_refused_in_a_scene():
    """``contact.xi`` stops at 71.17 (the end of the exact table, e = 0.00785), but ``e = 0.001``
    ran with xi = 356 from Jankowski (2008) eq. 2.9.  Reference: eq. 2.9,
    xi = sqrt(5) (1 - e^2) / (2 pi e), at e = 0.001."""
    from pound_mc.scene import scene_from_dict

    def eq_2_9(e):
        return math.sqrt(5) * (1 - e * e) / (2 * math.pi * e)

    scene = {
        "record": {"source": "builtin:elcentro", "duration_s": 4.0},
        "left": {"model": "sdof", "period_s": 0.5, "mass_kg": 1e6},
        "right": {"model": "sdof", "period_s": 1.0, "mass_kg": 1e6},
        "contact": {"model": "jankowski", "gap_m": 0.01, "e": 0.001},
    }
    with pytest.raises(InputError) as info:
        scene_from_dict(scene, file="s.toml")
    assert str(info.value).startswith("s.toml: contact.e: e = 0.001 gives xi = ")
    assert f"xi = {eq_2_9(0.001):.4g} under jankowski2008" in str(info.value)
    low = relations.lowest_e("jankowski2008")
    assert eq_2_9(low) == pytest.approx(relations.largest_xi(), rel=1e-9)
    scene["contact"]["e"] = 1.01 * low
    assert scene_from_dict(scene).xi == pytest.approx(eq_2_9(1.01 * low), rel=1e-12)


def test_the_exact_relations_refusal_names_contact_e():
    """``relation = "exact"`` below its table (e = 0.00785) named the key ``e``, not in the file."""
    from pound_mc.scene import scene_from_dict

    scene = {
        "record": {"source": "builtin:elcentro", "duration_s": 4.0},
        "left": {"model": "sdof", "period_s": 0.5, "mass_kg": 1e6},
        "right": {"model": "sdof", "period_s": 1.0, "mass_kg": 1e6},
        "contact": {"model": "jankowski", "gap_m": 0.01, "e": 0.004, "relation": "exact"},
    }
    with pytest.raises(InputError) as info:
        scene_from_dict(scene, file="s.toml")
    assert str(info.value).startswith("s.toml: contact.e: relation 'exact' is tabulated for e >= ")
