"""The reference's structural matrices, built here from the buildings' plain data.

A building is read by its fields only (``model``, ``storey_mass_kg``,
``storey_stiffness_N_per_m``, ``damping_ratio``, ``elevation_m``, ``hysteresis``,
``yield_disp_m``, ``post_yield_ratio``, ``bw_exponent``); its methods (its matrices, its modes)
are what the kernels run on and are not used.  Shear building (Chopra, Dynamics of Structures,
ch. 9): lumped floor masses, storey springs, so the stiffness matrix is tridiagonal.
Classical damping with the same ratio ``zeta`` in every mode (Chopra ch. 11):
``C = M Phi diag(2 zeta omega) Phi^T M``, the modes ``Phi`` (``Phi^T M Phi = I``) and
frequencies ``omega`` from :func:`scipy.linalg.eigh` of ``(K, M)``.  A wall stays with the
ground: infinite mass, no spring, no damping, no modes.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["building_matrices", "storey_heights", "column_mass"]


def _stiffness(k: np.ndarray) -> np.ndarray:
    """Shear-building stiffness [N/m]: storey ``i`` joins floor ``i - 1`` (the ground) to ``i``."""
    n = k.size
    mat = np.zeros((n, n))
    for i in range(n):
        mat[i, i] += k[i]
        if i > 0:  # the storey below floor i also pulls floor i - 1
            mat[i - 1, i - 1] += k[i]
            mat[i - 1, i] -= k[i]
            mat[i, i - 1] -= k[i]
    return mat


def building_matrices(building) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mass [kg], stiffness [N/m], damping [N s/m] matrices and circular frequencies [rad/s].

    A wall: ``[[inf]]``, ``[[0]]``, ``[[0]]`` and no frequency.
    """
    if building.model == "wall":
        return np.array([[np.inf]]), np.zeros((1, 1)), np.zeros((1, 1)), np.zeros(0)
    masses = np.asarray(building.storey_mass_kg, dtype=float)
    m = np.diag(masses)
    k = _stiffness(np.asarray(building.storey_stiffness_N_per_m, dtype=float))
    w2, phi = scipy.linalg.eigh(k, m)  # generalised problem, Phi^T M Phi = I
    omega = np.sqrt(w2)
    zeta = float(building.damping_ratio)
    c = m @ phi @ np.diag(2.0 * zeta * omega) @ phi.T @ m
    return m, k, c, omega


def storey_heights(building) -> np.ndarray:
    """Storey heights [m], bottom to top, from the floors' elevations (NaN without them)."""
    n = np.asarray(building.storey_mass_kg).size
    if building.elevation_m is None:
        return np.full(n, np.nan)
    return np.diff(np.r_[0.0, np.asarray(building.elevation_m, dtype=float)])


def column_mass(at, masses) -> float:
    """Mass [kg] a column point ``sum_k w_k x_k`` opposes to an impulse: ``1 / sum w_k^2 / m_k``.

    ``at`` the ``(floor, weight)`` pairs (floor -1: the ground, which does not move).
    """
    return 1.0 / sum(w * w / masses[f] for f, w in at if f >= 0)
