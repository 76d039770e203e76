import pytest

from pound_mc.errors import InputError
from pound_mc.physics import materials

# Jankowski (2008) Table 2, typed here from the paper: (material, velocity, e_min, e_max).
TABLE2 = [
    ("steel", 0.2, 0.6415, 0.7438), ("steel", 0.5, 0.5264, 0.7142),
    ("steel", 1.0, 0.5140, 0.6239), ("steel", 1.5, 0.4967, 0.5652),
    ("steel", 2.0, 0.4863, 0.5057),
    ("concrete", 0.2, 0.7230, 0.7840), ("concrete", 0.5, 0.6580, 0.6859),
    ("concrete", 1.0, 0.5858, 0.5981), ("concrete", 1.5, 0.5378, 0.5658),
    ("concrete", 2.0, 0.4419, 0.5659), ("concrete", 3.0, 0.4311, 0.5001),
    ("concrete", 4.0, 0.4278, 0.4826),
    ("timber", 0.2, 0.6567, 0.6934), ("timber", 0.5, 0.5852, 0.6356),
    ("timber", 1.0, 0.5334, 0.5797), ("timber", 1.5, 0.4851, 0.5354),
    ("timber", 2.0, 0.4281, 0.5347), ("timber", 3.0, 0.4076, 0.4708),
    ("timber", 4.0, 0.4002, 0.4428),
    ("ceramics", 0.2, 0.7575, 0.7996), ("ceramics", 0.5, 0.6870, 0.7681),
    ("ceramics", 1.0, 0.6270, 0.6697), ("ceramics", 1.5, 0.5770, 0.6456),
    ("ceramics", 2.0, 0.5115, 0.5642), ("ceramics", 3.0, 0.4737, 0.5208),
    ("ceramics", 4.0, 0.4330, 0.4921),
]  # fmt: skip

# Table 3: (material, mass_min, mass_max, beta_min, beta_max, beta_mean) [kg, N/m^1.5]
TABLE3 = [
    ("steel", 0.053, 0.054, 1.1e10, 1.5e10, 1.30e10),
    ("steel", 0.538, 0.541, 2.4e10, 4.4e10, 3.55e10),
    ("steel", 2.013, 2.013, 3.8e10, 6.6e10, 5.44e10),
    ("concrete", 1.329, 1.350, 3.9e9, 10.0e9, 7.90e9),
    ("concrete", 1.763, 1.835, 4.7e9, 11.2e9, 8.13e9),
    ("concrete", 2.531, 2.636, 6.4e9, 13.0e9, 10.45e9),
    ("timber", 0.065, 0.066, 0.7e8, 1.8e8, 1.38e8),
    ("timber", 0.109, 0.112, 0.9e8, 2.8e8, 2.16e8),
    ("timber", 0.493, 0.497, 1.0e8, 5.2e8, 2.97e8),
    ("ceramics", 0.243, 0.247, 1.1e9, 2.3e9, 1.80e9),
    ("ceramics", 0.372, 0.377, 2.2e9, 4.0e9, 3.13e9),
    ("ceramics", 0.538, 0.572, 2.8e9, 5.8e9, 4.57e9),
]

# Table 1: (material, grade, diameter mm, mass_min, mass_max, balls tested)
TABLE1 = [
    ("steel", "18G2A", 21, 0.053, 0.054, 2), ("steel", "18G2A", 50, 0.538, 0.541, 2),
    ("steel", "18G2A", 83, 2.013, 2.013, 2),
    ("concrete", "C30/37", 103, 1.329, 1.350, 5), ("concrete", "C30/37", 114, 1.763, 1.835, 5),
    ("concrete", "C30/37", 128, 2.531, 2.636, 5),
    ("timber", "pinewood", 55, 0.065, 0.066, 2), ("timber", "pinewood", 71, 0.109, 0.112, 2),
    ("timber", "pinewood", 118, 0.493, 0.497, 2),
    ("ceramics", "25", 58, 0.243, 0.247, 2), ("ceramics", "25", 69, 0.372, 0.377, 2),
    ("ceramics", "25", 80, 0.538, 0.572, 2),
]  # fmt: skip


def test_table1_exact():
    rows = [tuple(r) for r in materials.table(1).itertuples(index=False)]
    assert rows == TABLE1


def test_table2_exact():
    rows = [tuple(r) for r in materials.table(2).itertuples(index=False)]
    assert rows == TABLE2


def test_table3_exact():
    rows = [tuple(r) for r in materials.table(3).itertuples(index=False)]
    assert rows == TABLE3


def test_restitution_range_at_table_velocity_and_between():
    assert materials.restitution_range("timber", 1.5) == (0.4851, 0.5354)
    lo, hi = materials.restitution_range("concrete", 0.75)  # halfway between 0.5 and 1.0
    assert lo == pytest.approx((0.6580 + 0.5858) / 2, rel=1e-12)
    assert hi == pytest.approx((0.6859 + 0.5981) / 2, rel=1e-12)


def test_restitution_outside_policy():
    # Steel was not tested above 2 m/s: clamp holds the 2 m/s range, raise refuses.
    assert materials.restitution_range("steel", 3.0) == (0.4863, 0.5057)
    with pytest.raises(InputError, match="outside the measured range"):
        materials.restitution_range("steel", 3.0, outside="raise")


def test_stiffness_range_interpolates_between_ball_masses():
    mid1, mid2 = (1.329 + 1.350) / 2, (1.763 + 1.835) / 2
    x = 0.25 * mid1 + 0.75 * mid2
    lo, hi, mean = materials.stiffness_range("concrete", x)
    assert lo == pytest.approx(0.25 * 3.9e9 + 0.75 * 4.7e9, rel=1e-12)
    assert mean == pytest.approx(0.25 * 7.90e9 + 0.75 * 8.13e9, rel=1e-12)
    # a building storey (1e6 kg) gets the heaviest ball's range under the clamp policy
    assert materials.stiffness_range("concrete", 1e6) == (6.4e9, 13.0e9, 10.45e9)


def test_material_ranges():
    assert materials.material_ranges("concrete") == {"e": (0.4278, 0.7840), "beta": (3.9e9, 13.0e9)}


def test_unknown_material():
    with pytest.raises(InputError, match="steel"):
        materials.restitution_range("glass", 1.0)
