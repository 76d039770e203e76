"""Step bounds of the ``adaptive`` kernels, by what each integrates: written once, shared.

Every kernel that steps a contact bounds its steps by the buildings it carries (the shortest
period among their modes, :data:`LINEAR_STEPS_PER_PERIOD` and :data:`STEPS_PER_PERIOD`) and
by the contact's own time scale at the penetration it is at (its local period and damping
time, :func:`contact_bound`).  The SDOF pair (:mod:`~pound_mc.integrators.adaptive_pair`),
the bilinear pair (:mod:`~pound_mc.integrators.adaptive_bilinear`) and the general modal
kernel (:mod:`~pound_mc.integrators.adaptive`) take them from here; the error-controlled
kernel (:mod:`~pound_mc.integrators.adaptive_rk`) needs none for its Runge-Kutta steps (its
error estimate bounds every one), and bounds its exact steps of the linear spells by
:data:`LINEAR_STEPS_PER_PERIOD` (:mod:`~pound_mc.integrators.elastic_spells`).
"""

from __future__ import annotations

import math

from pound_mc._jit import jit
from pound_mc.integrators import laws
from pound_mc.integrators.accuracy import ADAPTIVE_SUBSTEPS_FACTOR

__all__ = [
    "LINEAR_STEPS_PER_PERIOD",
    "STEPS_PER_PERIOD",
    "MODAL_STEPS_PER_PERIOD",
    "LOCAL_PERIOD_SHARE",
    "LOCAL_DAMPING_SHARE",
    "contact_bound",
    "damping_screen",
    "period_screen",
    "shortest_period_steps",
    "FINE",
]

_INF = math.inf
_JANKOWSKI = laws.LAW_CODES["jankowski"]

#: A linear step spans at most ``1 / LINEAR_STEPS_PER_PERIOD`` of the shorter building period:
#: the steps are exact, but the onset screen and the peak search interpolate the penetration
#: between steps, which at ``omega h`` near 1 (a 0.05-s building at 0.01 s) misses and
#: misplaces impacts (extreme drill: peak forces off by up to 200 times).  At 30 (``omega h``
#: 0.21) every building of 0.3 s or more takes one step per 100-Hz sample, and the extreme
#: drill's 972 runs give the peak forces they give at 50, to the same error against the SciPy
#: reference (three digits) wherever its force is more than round-off.  The linear phases'
#: energies (corrected trapezoidal rule, error ``(omega h)^4``) are then those of the general
#: kernel at ``dt_s``: a 0.3-s building's energy residual goes from 1e-5 to 4e-5.
LINEAR_STEPS_PER_PERIOD = 30.0
#: A contact sub-step spans at most ``1 / STEPS_PER_PERIOD`` of the shorter building period:
#: unlike the linear steps, the RK4 sub-steps carry the buildings' own motion, whose error
#: grows as ``(omega h)^5`` (at 30 instead of 50, 0.3-s pairs at 8 sub-steps: peak forces off
#: by up to 2e-4 instead of 2e-5).
STEPS_PER_PERIOD = 50.0
#: The general modal kernel's contact sub-steps span at most ``1 / MODAL_STEPS_PER_PERIOD`` of
#: the shortest modal period.  Without it a 3+5 pair with 1,000 kg storeys of 1e9 N/m stepped
#: its few-ms modes at the 10 ms ``dt_s`` (twice the reference's peak force, status ok).  At
#: 20 every drill is within 3e-4 of the reference, as at 50, while the 3+5 pair of
#: ``shear_3_5.toml`` (contacts of ~0.1 s between 1e6 kg floors) takes 9 % more time than
#: unbounded (peak force 6.1e-6 from the reference; 8.5e-6 unbounded, 2.3e-6 at 50 for 52 %).
MODAL_STEPS_PER_PERIOD = 20.0
#: A contact sub-step spans at most 2/3 of ``1 / substeps`` of the contact's local period at
#: the current penetration and at the one its rate reaches in the step (secant stiffness of
#: the law, :func:`_contact_bound`): ``pi sqrt(2) / 1.5``.
#: The sub-step from the onset velocity (``duration / substeps``) fails where an episode starts
#: at a near-zero velocity (zero gap, a building resting against the other) and the contact
#: then carries load: the onset duration is long, the stiff contact is stepped at ``dt_s``
#: (extreme drill: peak forces off by up to 270 times).  For one impact the bound is looser
#: than ``duration / substeps``: the local period at the deepest penetration is 2.1 (Hertz) or
#: 2 (linear) contact durations, so the bound is 1.4 times ``duration / substeps`` or more
#: there (B1 bitwise unchanged; at half, one sub-step of a Hertz scene changes).
LOCAL_PERIOD_SHARE = math.pi * math.sqrt(2.0) / 1.5
#: A contact sub-step spans at most ``LOCAL_DAMPING_SHARE / substeps`` of the contact's
#: damping time ``m_eff / c`` (``c = dF / d delta_dot`` at the penetration the rate reaches in
#: the step, :func:`_contact_bound`): 0.5 at the default 16 sub-steps.
#: The local period alone fails where the contact is overdamped (Jankowski with ``e = 0.1``:
#: ``xi = 5.8``, the damping rate ``2 xi`` times the local frequency): RK4 then steps the
#: damping at ``c h / m_eff`` near 3.4, at its stability limit (extreme drill: peak forces off
#: by 2 %).  It binds only from ``xi`` about 0.85 (Jankowski; B1, ``xi = 0.35``, unchanged).
LOCAL_DAMPING_SHARE = 8.0
#: The accuracy check's run has ``ADAPTIVE_SUBSTEPS_FACTOR`` times the sub-steps: each bound
#: that depends on ``substeps`` is this fraction of the run's (exactly, the factor being a
#: power of two), so the run can tell whether the check's run would take its very sub-steps.
FINE = 1.0 / ADAPTIVE_SUBSTEPS_FACTOR
#: Jankowski's local bounds are powers of the penetration (``_contact_bound``): below a
#: penetration that follows from ``hs`` without a root, neither binds nor is tight at
#: ``FINE``, and their evaluation (six square roots, two divisions) is skipped.  The screen
#: passes only this far below that penetration, far beyond the bounds' rounding, so that the
#: sub-steps are those of the full evaluation bit for bit.
_SCREEN_MARGIN = 1.0 - 1e-6
#: The damping bound's rate of force is a difference, ``F(d, 1) - F(d, 0)``, whose rounding
#: grows with ``beta d^1.25 / c0``: screened only where ``beta / c0`` is below this (and the
#: penetration below 1 m), which keeps that rounding below 1e-7 of the difference.
_SCREEN_CANCEL = 1e8


@jit(inline=True)
def period_screen(model, b, loc_k, share):
    """``kp4`` of :func:`contact_bound`: ``(share loc_k)^4 / (0.4 b)^2`` (Jankowski), else -1.

    The local period bound at ``share`` (``FINE``, or 1 where its tightness at ``FINE`` is
    not needed) of Jankowski's law, ``share loc_k d / sqrt(0.4 b d^2.5)``, is at least ``hs``
    where ``d hs^4 <= (share loc_k)^4 / (0.4 b)^2``.
    """
    if model != _JANKOWSKI:
        return -1.0
    k = share * loc_k
    k *= k
    return _SCREEN_MARGIN * k * k / ((0.4 * b) * (0.4 * b))


@jit(inline=True)
def damping_screen(model, b, cd, loc_c, share):
    """``kc4`` of :func:`contact_bound`: ``(share loc_c / c0)^4`` (Jankowski), else -1.

    The approach's damping rate ``c0 d^0.25`` times ``hs`` is at most ``share loc_c`` where
    ``d hs^4 <= (share loc_c / c0)^4`` (``share`` as :func:`period_screen`); without damping
    (``c0 = 0``) it never binds.
    """
    if model != _JANKOWSKI:
        return -1.0
    if cd == 0.0:
        return _INF
    if not b <= _SCREEN_CANCEL * cd:
        return -1.0
    k = share * loc_c / cd
    k *= k
    return _SCREEN_MARGIN * k * k


@jit(inline=True, llvm_inline=True)
def contact_bound(hs, d, dd, model, b, cd, zhd, phase, loc_k, loc_c, kp4, kc4):
    """``hs`` [s] bounded by the contact's local period and damping time at penetration ``d``.

    Local period (:data:`LOCAL_PERIOD_SHARE`): that of the secant stiffness ``2 E(d) / d^2``
    (``E``: the law's stored energy), ``pi sqrt(2 m_eff) d / sqrt(E)``, at ``d`` and at the
    penetration the rate ``dd`` reaches in the step; ``loc_k`` is
    ``LOCAL_PERIOD_SHARE sqrt(m_eff) / substeps``.  Damping time
    (:data:`LOCAL_DAMPING_SHARE`): ``m_eff / c`` with ``c = dF / d delta_dot`` at the
    penetration the rate reaches (every law's force is linear in the rate: the force at unit
    rate less the force at rest; ``c`` grows with the penetration in every law, so the deepest
    point of the step bounds it); ``loc_c`` is ``LOCAL_DAMPING_SHARE m_eff / substeps``.
    Also returns whether the bounds at :data:`FINE` of these (the accuracy check's run) would
    shorten ``hs``: they are those bounds times ``FINE`` exactly, and until one shortens it
    both runs evaluate them at the same points.  ``kp4`` and ``kc4``
    (:func:`period_screen`, :func:`damping_screen`): where ``d hs^4`` at the deepest point is
    below them (and the penetration below 1 m), neither bound can bind or be tight at ``FINE``
    (screens at share 1, a lean run's: neither can bind; the tightness returned is then False,
    which that run does not use).
    """
    hs0 = hs
    tight = False
    reach = max(dd, 0.0)
    dmax = d + reach * hs
    if dmax <= 1.0:
        h4 = hs * hs
        h4 *= h4
        x = dmax * h4
        if x <= kp4 and (phase != 1 or x <= kc4):
            return hs, False
    for k in range(1 if reach == 0.0 else 2):  # without a rate both points are ``d``
        dk = d + reach * hs if k == 1 else d
        if dk > 0.0:
            e = laws.stored(model, dk, b)
            if e > 0.0:
                hl = loc_k * dk / math.sqrt(e)
                tight = tight or FINE * hl < hs0
                if hl < hs:
                    hs = hl
    dk = d + reach * hs
    if dk > 0.0:
        c = laws.force(model, dk, 1.0, b, cd, zhd, phase)
        c -= laws.force(model, dk, 0.0, b, cd, zhd, phase)
        tight = tight or c * hs0 > FINE * loc_c
        if c * hs > loc_c:
            hs = loc_c / c
    return hs, tight


@jit(inline=True)
def shortest_period_steps(omega, dt_s, per_period=STEPS_PER_PERIOD):
    """Bounds of a linear step and of a contact sub-step [s] from the modes' ``omega``.

    ``min(dt_s, T_min / LINEAR_STEPS_PER_PERIOD)`` and ``min(dt_s, T_min / per_period)``
    (:data:`STEPS_PER_PERIOD`, or :data:`MODAL_STEPS_PER_PERIOD` for the general kernel) with
    ``T_min`` the shortest modal period (``dt_s`` where there are no modes).
    """
    wmax = 0.0
    for j in range(omega.size):
        wmax = max(wmax, omega[j])
    if wmax <= 0.0:
        return dt_s, dt_s
    tmin = 2.0 * math.pi / wmax
    return min(dt_s, tmin / LINEAR_STEPS_PER_PERIOD), min(dt_s, tmin / per_period)
