"""The scenes of ``pound-mc bench``'s cost-against-modes table."""

from pathlib import Path

import numpy as np

from pound_mc.numerics.bench import shear_pair
from pound_mc.scene import load_scene

SCENES = Path(__file__).resolve().parents[1] / "studies" / "scenes"


def test_shear_pair_3_5_is_the_shipped_scene():
    # the generator of the 10+10 and 20+20 pairs reproduces studies/scenes/shear_3_5.toml
    shipped = load_scene(SCENES / "shear_3_5.toml").kernel_arrays()
    made = shear_pair(3, 5).kernel_arrays()
    assert shipped.keys() == made.keys()
    for name in shipped:
        np.testing.assert_array_equal(made[name], shipped[name], err_msg=name)


def test_shear_pair_sizes():
    # 10 + 10 storeys: 20 modes, a contact at each of the 10 common floors (3 m storeys)
    sc = shear_pair(10, 10)
    arrays = sc.kernel_arrays()
    assert arrays["omega"].size == 20
    assert len(sc.contacts) == 10
    # storey stiffness falls linearly up the building, 1.2e9 -> 0.8e9 N/m on the left
    k = sc.left.storey_stiffness_N_per_m
    np.testing.assert_allclose(k[[0, -1]], [1.2e9, 0.8e9])
    np.testing.assert_allclose(np.diff(k), -0.4e9 / 9)
