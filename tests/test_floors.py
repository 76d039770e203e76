"""Floors of each contact and each floor's own modes, as the adaptive kernel finds them."""

from pathlib import Path

import numpy as np

from pound_mc.integrators.floors import contact_floors, floor_blocks
from pound_mc.scene import load_scene

SHEAR_3_5 = Path(__file__).resolve().parents[1] / "studies" / "scenes" / "shear_3_5.toml"


def test_blocks_and_contact_floors_of_the_3_5_shear_pair():
    # studies/scenes/shear_3_5.toml: a 3-storey and a 5-storey building with 3 m storeys meet
    # at their three common floors; floors 0-2 are the left building's (modes 0-2), floors
    # 3-7 the right one's (modes 3-7), so contact c joins floor c and floor 3 + c
    arrays = load_scene(SHEAR_3_5).modal_arrays()
    lo, hi = floor_blocks(arrays["phi"])
    np.testing.assert_array_equal(lo, [0, 0, 0, 3, 3, 3, 3, 3])
    np.testing.assert_array_equal(hi, [3, 3, 3, 8, 8, 8, 8, 8])
    left, right = contact_floors(arrays["phi"], arrays["psi"], lo, hi)
    np.testing.assert_array_equal(left, [0, 1, 2])
    np.testing.assert_array_equal(right, [3, 4, 5])


def test_weights_that_are_no_floor_difference_are_left_to_the_dot_product():
    # psi = phi[0] + phi[1] is not phi[left] - phi[right]: no floors (-1)
    phi = np.array([[2.0, 0.0], [0.0, 3.0]])
    psi = np.array([[2.0, -3.0], [2.0, 3.0]])
    lo, hi = floor_blocks(phi)
    left, right = contact_floors(phi, psi, lo, hi)
    np.testing.assert_array_equal(left, [0, -1])
    np.testing.assert_array_equal(right, [1, -1])
