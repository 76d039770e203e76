"""Independent tight-tolerance reference solution of a scene (SciPy, pure Python).

Used to check the compiled kernels of :mod:`pound_mc.integrators`; it shares none of their
code and none of the physics they take from :mod:`pound_mc.physics`: it reads the scene's plain
data (buildings' masses, stiffnesses, damping ratios and storey laws; the contacts' floors; the
contact law's name and parameters) and writes out the rest itself
(:mod:`~pound_mc.integrators.reference.frame`: matrices, modes from :func:`scipy.linalg.eigh`
and damping; :mod:`~pound_mc.integrators.reference.impact`: force laws, xi-e relations,
single-impact restitution, the seed's Table 2).  ``tests/test_architecture.py`` holds it to
that: these modules import nothing from the package but each other.

The buildings are integrated in *physical* floor coordinates (not modes),

``M x'' + C x' + K x = -M 1 a_g(t) + f_c(x, x')``,

with the shear-building mass and stiffness matrices and classical (modal) damping of the
same ratio in every mode, ``C = M Phi diag(2 zeta omega) Phi^T M``.
At a contact between left floor ``i`` and right floor ``j`` the penetration is
``delta = x_i - x_j - gap`` and the force ``F >= 0`` acts as ``-F`` on the left floor and ``+F`` on
the right floor (``../shared/DESIGN.md`` section 2).  The force laws are:

``jankowski`` (seed eq. 1.1)
    approach (``delta_dot > 0``): ``F = beta delta^1.5 + c delta_dot`` with
    ``c = 2 xi sqrt(beta sqrt(delta) m_eff)``; restitution: ``F = beta delta^1.5``.
``hertz``
    ``F = beta delta^1.5``.
``linear`` / ``kelvin``
    ``F = k delta`` / ``F = k delta + 2 xi sqrt(k m_eff) delta_dot``.
``hertzdamp``
    ``F = max(0, beta delta^1.5 (1 + zeta delta_dot))`` with ``zeta`` from ``e`` and ``v0``,
    the approach velocity of the episode, by the scene's relation (default Ye et al. 2009,
    ``zeta = 8 (1 - e) / (5 e v0)``).

A scene that gives ``e`` (not ``xi``) has its ``xi`` computed here by the scene's relation
(seed eq. 2.9 by default; ``exact`` by root finding on a single impact integrated here).

The ground acceleration is the record's samples linearly interpolated, so the right-hand side
has kinks at the samples: the solution is integrated sample interval by sample interval, each a
smooth problem, with SciPy's ``DOP853`` at ``rtol = 1e-11``.  Every contact carries an explicit
phase (open, approach, restitution); the switches are terminal events (open -> approach when
``delta`` crosses 0 upwards, approach -> restitution when ``delta_dot`` crosses 0 downwards,
restitution -> open when ``delta`` crosses 0 downwards, restitution -> approach when
``delta_dot`` crosses 0 upwards) and the integration restarts after each with the new phases,
so the right-hand side is smooth inside every segment.  Peak force and peak displacements are
continuous-time maxima: the dense output of every segment is sampled finely and the best sample
refined with :func:`scipy.optimize.minimize_scalar`.

With ``restitution = "velocity"`` each impact's ``e`` is the seed's Table 2 (transcribed in
:data:`~pound_mc.integrators.reference.impact.TABLE_2`) at the relative velocity at the onset
event, and its damping (``xi`` by the relation, or ``zeta``) is fixed for that episode.

This is slow (seconds for a 30 s SDOF-pair record) and meant for tests and checks only.
"""

from pound_mc.integrators.reference.solver import reference_solution

__all__ = ["reference_solution"]
