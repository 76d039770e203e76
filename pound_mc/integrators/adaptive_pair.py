"""The ``adaptive`` method for an SDOF pair (two modes, one contact) with scalar state.

:func:`adaptive_pair` is :func:`pound_mc.integrators.adaptive.adaptive` specialised to two
single-storey buildings that meet at one contact: the modal state is four scalars, the step
coefficients are scalars computed once, and no array is touched in the hot loop.  Same
algorithm (exact Nigam-Jennings steps between contacts, contact onset located on the exact
solution, Runge-Kutta sub-steps during contact with every switch of the force law located),
same outputs, the same status and energy logic and the same ``pre`` protocol (the shared
linear response before the first contact, see :mod:`pound_mc.integrators.outputs`) and the
same histories.  ``tests/test_adaptive_pair.py``
holds it to the general kernel.

Notation: mode ``j`` (0 left, 1 right) has circular frequency ``w_j`` [rad/s], damping ratio
``z_j``, participation ``g_j = sqrt(m_j)`` [kg^0.5] (mass-normalised, ``q_j = sqrt(m_j) x_j``);
the penetration is ``delta = ps0 q0 + ps1 q1 - gap`` and floor ``j`` moves ``x_j = f_j q_j``.

Longer than 600 lines because the scalar state of the two modes is spelled out (four scalars
for every array of the general kernel) and the Jankowski approach phase has its own RK4 step.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import laws
from pound_mc.integrators.bounds import FINE as _FINE
from pound_mc.integrators.bounds import (
    LINEAR_STEPS_PER_PERIOD,
    LOCAL_DAMPING_SHARE,
    LOCAL_PERIOD_SHARE,
    STEPS_PER_PERIOD,
    contact_bound,
    damping_screen,
    period_screen,
)
from pound_mc.integrators.outputs import (
    C_IMPACTS,
    C_IMPULSE,
    C_MAX_IMPACT_VELOCITY,
    C_MAX_PENETRATION,
    C_PEAK_FORCE,
    IMPACT_MIN_PENETRATION_M,
    N_OUT,
    ONSET_CD,
    ONSET_GRID,
    ONSET_PEAK,
    ONSET_S,
    ONSET_ZHD,
    PEAK_DISP_LEFT,
    PRE_E0,
    PRE_E_D,
    PRE_E_IN,
    PRE_INTERVAL,
    PRE_MODE,
    PRE_RESUME,
    PRE_RESUME_ONSET,
    PRE_RESUME_PEAK,
    PRE_RUN_TO_CONTACT,
    PRE_STATE,
    PRE_STEPS,
    STATUS_NOT_CONVERGED,
    STATUS_OK,
    STATUS_UNSTABLE,
    finish,
    finish_impacts,
    impact_log,
    log_impact_in,
    log_max,
    peak_only,
)
from pound_mc.integrators.toolkit import (
    advance,
    coefficients,
    grid_step,
    hermite_max,
    hermite_root,
    newton_in_bracket,
    step_size,
    turning_screen,
)

__all__ = ["adaptive_pair"]

_INF = math.inf
_TWELFTH = 1.0 / 12.0
#: Contact onset located to this fraction of the step [-] (1e-12 of a 0.01 s step: the
#: penetration at the located onset is ~1e-14 v0, far below anything the contact phase resolves).
#: What holds in every case is the penetration: at a grazing onset (rate near 0) the time of a
#: root within round-off of zero may be off by more.
ONSET_TOL = 1e-12
#: An onset within this fraction of the step from the cubic Hermite guess is the root of the
#: second-order Taylor polynomial at the guess (:func:`_exact_root_pair`).
QUADRATIC_ROOT_SPAN = 1e-4
_JANKOWSKI = laws.LAW_CODES["jankowski"]
#: Sub-steps after onset grow geometrically from ``RAMP_START`` of the contact sub-step by a
#: factor ``1 + RAMP_GROWTH``; Jankowski's approach phase integrates ``u = v + psi D(delta)``
#: (below), which takes the ``delta^0.25`` singularity out of the velocities and lets the ramp
#: start later and grow faster at the same accuracy (B1: peak force +7e-6 against the SciPy
#: reference, the general kernel's ramp +2.2e-5).
RAMP_START, RAMP_GROWTH = 1e-3, 1.0
RAMP_START_POT, RAMP_GROWTH_POT = 1e-2, 2.0
#: In restitution, a sub-step spans at most ``TAIL`` of the time left to separation at the
#: current rate, and no less than ``TAIL_MIN`` of the contact sub-step (Jankowski: ``*_POT``;
#: its restitution force ``beta delta^1.5`` is smooth enough for the coarser tail, B1 unchanged
#: to 1e-6 with 38 sub-steps fewer).
TAIL, TAIL_MIN = 0.5, 0.25
TAIL_POT, TAIL_MIN_POT = 1.0, 0.5


@jit
def _exact_pen(
    q0, q1, v0, v1, p0s, slope, tau, w0, z0, g0, w1, z1, g1, c0, c1, off,
):  # fmt: skip
    """``c0 x0 + c1 x1 - off`` with its rate and acceleration ``tau`` into a linear step.

    On the exact solution (no contact force); ``c0, c1`` weight the modal coordinates
    (``psi`` for the penetration, ``+-f_j`` and 0 for a floor's displacement).
    """
    d = -off
    dd = 0.0
    ddd = 0.0
    ag = p0s + slope * tau
    for j in range(2):
        c, q, v, w, z, g = (c0, q0, v0, w0, z0, g0) if j == 0 else (c1, q1, v1, w1, z1, g1)
        if c != 0.0:
            qm, vm = advance(q, v, -g * p0s, -g * ag, w, z, tau)
            am = -2.0 * z * w * vm - w * w * qm - g * ag
            d += c * qm
            dd += c * vm
            ddd += c * am
    return d, dd, ddd


@jit
def _exact_root_pair(
    q0, q1, v0, v1, p0s, slope, guess, lo, hi, which, w0, z0, g0, w1, z1, g1, c0, c1, off, tol,
):  # fmt: skip
    """Root in ``[lo, hi]`` of :func:`_exact_pen` (``which = 0``, from below) or of its rate.

    ``which = 1``: a root of the rate from above (a maximum).  Newton from ``guess``, kept in
    the bracket, as ``toolkit.exact_root``, until a Newton step is below ``tol`` of the
    bracket's end (``exact_root``: 1e-15).
    """
    t = guess
    if not (lo < t < hi):
        t = 0.5 * (lo + hi)
    for it in range(60):
        d, dd, ddd = _exact_pen(q0, q1, v0, v1, p0s, slope, t, w0, z0, g0, w1, z1, g1, c0, c1,
                                off)  # fmt: skip
        if it == 0 and which == 0 and dd > 0.0:
            # the guess (cubic Hermite) is close: the root of the Taylor polynomial at it,
            # d + dd x + ddd x^2 / 2 (two Newton steps from x = 0; it has a real root), is the
            # root to round-off where |x| <= QUADRATIC_ROOT_SPAN of the bracket's end (the
            # cubic term, third derivative x^3 / 6, at most 1.6e-15 of the amplitude at
            # omega h = 2 pi / 30); one exact evaluation, not four
            x = -d / dd
            x -= (d + x * (dd + 0.5 * ddd * x)) / (dd + ddd * x)
            real = dd * dd >= 2.0 * d * ddd
            if real and abs(x) <= QUADRATIC_ROOT_SPAN * hi and lo <= t + x <= hi:
                return t + x
        t, lo, hi, done = newton_in_bracket(t, d, dd, ddd, which, lo, hi, tol)
        if done:
            break
    return t


@jit
def _exact_max(
    q0, q1, v0, v1, p0s, slope, guess, hh, w0, z0, g0, w1, z1, g1, c0, c1, off,
):  # fmt: skip
    """Local maximum of :func:`_exact_pen` near ``guess`` (the cubic Hermite estimate).

    One Newton step for the root of the rate from the exact value, rate and acceleration at
    ``guess``, and the value there from the second-order Taylor polynomial: the Hermite
    estimate is off by O((omega h)^3 h), so the value is off by O(third derivative dt^3),
    far below round-off of the amplitude at the steps linear phases take.
    Returns ``(value, time)``.
    """
    d, dd, ddd = _exact_pen(q0, q1, v0, v1, p0s, slope, guess, w0, z0, g0, w1, z1, g1, c0, c1,
                            off)  # fmt: skip
    if ddd >= 0.0:
        return d, guess  # not a maximum here: the value at the estimate
    dt = -dd / ddd
    t = guess + dt
    if t < 0.0 or t > hh:
        return d, guess
    return d + 0.5 * dd * dt, t


@jit(inline=True)
def _mode_step(q, v, p0s, p1s, g, cf):
    """Exact step of one mode: its new ``(q, v)`` from the step's coefficients ``cf``.

    ``cf``: the two rows of ``toolkit.coefficients`` in one tuple; the load ``-g ag`` is linear
    between the ground accelerations ``p0s`` and ``p1s`` [m/s^2].
    """
    p0 = -g * p0s
    p1 = -g * p1s
    q1 = cf[0] * q + cf[1] * v + cf[2] * p0 + cf[3] * p1
    v1 = cf[4] * q + cf[5] * v + cf[6] * p0 + cf[7] * p1
    return q1, v1


@jit(inline=True)
def _ends(q0, q1, v0, v1, ag, km):
    """Sums for the energy integrals without contact force (``toolkit.end_values``).

    ``km``: ``(k_0, ww_0, g_0, k_1, ww_1, g_1, zw2_0, zw2_1, zw4_0, zw4_1)`` with
    ``k_j = -2 z_j w_j``, ``ww_j = w_j^2``, ``zw2_j = 2 z_j w_j``, ``zw4_j = 4 z_j w_j``.
    Returns ``sum g v``, ``sum g a``, the damping power and its rate.
    """
    k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, zw4_0, zw4_1 = km
    a0 = k0 * v0 - ww0 * q0 - g0 * ag
    a1 = k1 * v1 - ww1 * q1 - g1 * ag
    sgv = g0 * v0
    sgv += g1 * v1
    sga = g0 * a0
    sga += g1 * a1
    pd = zw2_0 * v0 * v0
    pd += zw2_1 * v1 * v1
    dpd = zw4_0 * v0 * a0
    dpd += zw4_1 * v1 * a1
    return sgv, sga, pd, dpd


@jit(inline=True)
def _energy_step(hh, slope, p0s, p1s, start, q0, q1, v0, v1, km):
    """Input and damping energy of a linear step of length ``hh`` [s] (per unit modal mass).

    The corrected trapezoidal rule (exact to O(h^5) per step) on the sums of :func:`_ends` at
    the step's start (``start``) and at its end state ``q0, q1, v0, v1``; ``p0s, p1s``: ground
    accelerations.  Returns both energies and the end's sums (the next step's ``start``).
    """
    s0, s1, s2, s3 = start
    end = _ends(q0, q1, v0, v1, p1s, km)
    e0, e1, e2, e3 = end
    pin0 = -p0s * s0
    pin1 = -p1s * e0
    dpin0 = -(slope * s0 + p0s * s1)
    dpin1 = -(slope * e0 + p1s * e1)
    hh12 = hh * hh * _TWELFTH
    de_in = 0.5 * hh * (pin0 + pin1) + hh12 * (dpin0 - dpin1)
    return de_in, 0.5 * hh * (s2 + e2) + hh12 * (s3 - e3), end


@jit(inline=True)
def _quiet_start():
    """The sums of an empty run of whole linear steps (:func:`_quiet_add`).

    ``(n, s_in, s_d, pin, pd, sgv, slope, p, dpin0, dpd0, jumps)``: steps; the trapezoidal sums
    of input and damping power (times 2); the two powers, ``sum g v``, the slope and the ground
    acceleration at the run's last point; the rates of the input and damping powers at its
    first point; the jumps of the input power's rate at record samples.
    """
    return (0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@jit(inline=True)
def _quiet_add(run, hh, slope, p0s, p1s, start, nv0, nv1, km):
    """The sums of :func:`_quiet_start` after one more whole step ``hh`` [s] to ``nv0, nv1``.

    The corrected trapezoidal rule of :func:`_energy_step`, step after step, is the plain
    trapezoidal sum plus ``h^2 / 12`` times the power's rate at the run's start less its rate at
    the run's end: the rates at the points between cancel, except the input power's at record
    samples, where the ground acceleration's slope changes (its jump times ``sum g v``).  So a
    step needs the powers only, not the accelerations (``start``: the sums of :func:`_ends` at
    the run's first point, ``p0s`` its ground acceleration).
    """
    n, s_in, s_d, pin, pd, sgv, slope0, p, dpin0, dpd0, jumps = run
    if n == 0:
        pin = -p0s * start[0]
        pd = start[2]
        dpin0 = -(slope * start[0] + p0s * start[1])
        dpd0 = start[3]
    elif slope != slope0:
        jumps += (slope - slope0) * sgv
    k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, zw4_0, zw4_1 = km
    sgv = g0 * nv0
    sgv += g1 * nv1
    pin1 = -p1s * sgv
    pd1 = zw2_0 * nv0 * nv0
    pd1 += zw2_1 * nv1 * nv1
    s_in += hh * (pin + pin1)
    s_d += hh * (pd + pd1)
    return (n + 1, s_in, s_d, pin1, pd1, sgv, slope, p1s, dpin0, dpd0, jumps)


@jit(inline=True)
def _quiet_close(run, e_in, e_d, en0, q0, q1, v0, v1, km, h):
    """Energies and the next step's ``start`` sums after a run, and an empty run.

    ``q0, q1, v0, v1``: the state at the run's last point; ``h`` the whole step [s].  Without
    a step in the run, everything is returned as it was.
    """
    n, s_in, s_d, pin, pd, sgv, slope, p, dpin0, dpd0, jumps = run
    if n == 0:
        return e_in, e_d, en0, run
    end = _ends(q0, q1, v0, v1, p, km)
    dpin1 = -(slope * end[0] + p * end[1])
    h12 = h * h * _TWELFTH
    e_in += 0.5 * s_in + h12 * (dpin0 - dpin1 - jumps)
    e_d += 0.5 * s_d + h12 * (dpd0 - end[3])
    return e_in, e_d, end, _quiet_start()


@jit(inline=True, llvm_inline=True)
def _stage(q0, q1, v0, v1, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, gp, b, cd, zhd, phase,
           model):  # fmt: skip
    """Contact force [N], penetration rate [m/s] and modal accelerations at one state."""
    d = ps0 * q0 + ps1 * q1 - gp
    dd = ps0 * v0 + ps1 * v1
    if model == _JANKOWSKI and phase == 2:
        # laws.force in restitution (_jankowski_k's elastic force alone, penetration clipped
        # at 0), spelled out: compiled from the law, the force waits on the approach's
        # d^0.25 as well, which LLVM computes and then discards by a select (+1 square root's
        # latency on every stage of the sub-step chain)
        if d < 0.0:
            d = 0.0
        fc = b * d * math.sqrt(d)
    else:
        fc = laws.force(model, d, dd, b, cd, zhd, phase)
    a0, a1 = _accel(q0, q1, v0, v1, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, fc)
    return fc, dd, a0, a1


@jit(inline=True, llvm_inline=True)
def _accel(q0, q1, v0, v1, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, fc):
    """Modal accelerations at one state under contact force ``fc`` [N] (:func:`_stage`)."""
    a0 = k0 * v0 - ww0 * q0 - g0 * ag
    a1 = k1 * v1 - ww1 * q1 - g1 * ag
    if fc != 0.0:
        a0 -= fc * ps0
        a1 -= fc * ps1
    return a0, a1


@jit(inline=True, llvm_inline=True)
def _roots(q0, q1, ps0, ps1, gp):
    """Penetration ``d`` [m] at ``q`` with ``sqrt(d)`` and ``d^0.25`` (both 0 where ``d <= 0``).

    Jankowski's approach phase needs both roots at every state it evaluates; a state's are
    taken once and passed on (:func:`_rk4_pot`), the square roots' latency being most of the
    phase's time.
    """
    d = ps0 * q0 + ps1 * q1 - gp
    sd = 0.0
    qd = 0.0
    if d > 0.0:
        sd = math.sqrt(d)
        qd = math.sqrt(sd)
    return d, sd, qd


@jit(inline=True, llvm_inline=True)
def _stage_pot(q0, q1, u0, u1, roots, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, b, cd, kpot):
    """Jankowski approach phase at state ``(q, u)``: force, rate, ``v``, ``u'``, damping force.

    ``u = v + psi D(delta)`` with ``D = 0.8 c0 delta^1.25``, whose rate is the damping force
    ``c0 delta^0.25 delta_dot`` of the law (seed eq. (1.1)): ``u' = `` the accelerations without it.
    ``roots``: :func:`_roots` at ``q``.
    """
    d, sd, qd = roots
    pot = 0.0
    fel = 0.0
    cq = 0.0
    if d > 0.0:
        pot = kpot * d * qd
        fel = b * d * sd
        cq = cd * qd
    v0 = u0 - ps0 * pot
    v1 = u1 - ps1 * pot
    dd = ps0 * v0 + ps1 * v1
    fdamp = cq * dd
    au0 = k0 * v0 - ww0 * q0 - g0 * ag - fel * ps0
    au1 = k1 * v1 - ww1 * q1 - g1 * ag - fel * ps1
    return fel, fdamp, dd, v0, v1, au0, au1, pot


@jit(inline=True, llvm_inline=True)
def _potential(roots, kpot, b):
    """``D(delta) = 0.8 c0 delta^1.25`` and the stored energy ``0.4 beta delta^2.5`` (0 open).

    ``roots``: :func:`_roots` at the state.
    """
    d, sd, qd = roots
    if not d > 0.0:
        return 0.0, 0.0
    return kpot * d * qd, 0.4 * b * d * d * sd


@jit(inline=True, llvm_inline=True)
def _rk4_pot(
    q0, q1, v0, v1, s, hs, ag0, slope, k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, ps0, ps1, gp,
    b, cd, kpot, roots0,
):  # fmt: skip
    """:func:`_rk4_pair` for Jankowski's approach phase, in ``(q, u = v + psi D(delta))``.

    The damping force is the rate of ``D``: its impulse over the step is the change of ``D``
    (exact), and ``u`` sees only the elastic force, which is smooth enough for RK4 from onset.
    ``roots0``: :func:`_roots` at the start (the end's of the sub-step before, or of a first
    attempt, are these very values); the end's are returned last, after the outputs of
    :func:`_rk4_pair`.
    """
    pot0, en0 = _potential(roots0, kpot, b)
    u0 = v0 + ps0 * pot0
    u1 = v1 + ps1 * pot0
    h6 = hs / 6.0
    e_in = e_d = w_d = imp = 0.0
    sq0 = sq1 = su0 = su1 = 0.0
    kq0 = kq1 = ku0 = ku1 = 0.0
    fc_start = acc0 = acc1 = 0.0
    for stage in range(4):
        fac = 0.0 if stage == 0 else (hs if stage == 3 else 0.5 * hs)
        wgt = 1.0 if stage == 0 or stage == 3 else 2.0
        ag = ag0 + slope * (s + fac)
        wq0 = q0 + fac * kq0
        wq1 = q1 + fac * kq1
        # the first stage's state is the start's (q + 0 k: its penetration the same wherever
        # positive, and not used elsewhere)
        roots = roots0 if stage == 0 else _roots(wq0, wq1, ps0, ps1, gp)
        fel, fdamp, dd, wv0, wv1, au0, au1, pot = _stage_pot(
            wq0, wq1, u0 + fac * ku0, u1 + fac * ku1, roots, ag, k0, ww0, g0, k1, ww1, g1,
            ps0, ps1, b, cd, kpot,
        )  # fmt: skip
        fc = fel + fdamp
        if stage == 0:
            fc_start = fc
            acc0 = au0 - ps0 * fdamp
            acc1 = au1 - ps1 * fdamp
        kq0, kq1, ku0, ku1 = wv0, wv1, au0, au1
        sq0 += wgt * kq0
        sq1 += wgt * kq1
        su0 += wgt * ku0
        su1 += wgt * ku1
        e_in -= wgt * (ag * g0 * wv0 + ag * g1 * wv1)
        e_d += wgt * (zw2_0 * wv0 * wv0 + zw2_1 * wv1 * wv1)
        # the damping force's work by parts, [delta' D] - int D delta'': D (delta^1.25) is
        # smooth where the damping power (delta^0.25 delta'^2) is not
        w_d += wgt * pot * (ps0 * (au0 - ps0 * fdamp) + ps1 * (au1 - ps1 * fdamp))
        imp += wgt * fel
    nq0 = q0 + h6 * sq0
    nq1 = q1 + h6 * sq1
    roots1 = _roots(nq0, nq1, ps0, ps1, gp)
    pot1, en1 = _potential(roots1, kpot, b)
    nv0 = u0 + h6 * su0 - ps0 * pot1
    nv1 = u1 + h6 * su1 - ps1 * pot1
    # the contact's work: the elastic force's is the change of its stored energy (exact), the
    # damping force's by parts
    w_c = en1 - en0 + (ps0 * nv0 + ps1 * nv1) * pot1 - (ps0 * v0 + ps1 * v1) * pot0 - h6 * w_d
    return (nq0, nq1, nv0, nv1, h6 * e_in, h6 * e_d, w_c, h6 * imp + (pot1 - pot0), fc_start,
            acc0, acc1, roots1)  # fmt: skip


@jit(inline=True, llvm_inline=True)
def _rk4_pair(
    q0, q1, v0, v1, s, hs, ag0, slope, k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, ps0, ps1, gp,
    b, cd, zhd, phase, model, have, fcs, as0, as1,
):  # fmt: skip
    """One classical Runge-Kutta step of length ``hs`` from local time ``s``.

    ``have``: ``fcs, as0, as1`` are the force and modal accelerations at the start (the end
    of the previous sub-step, same phase and record interval), not evaluated again.
    Returns the new state, the increments of input energy, damping energy, contact work and
    impulse, the force at the start and the modal accelerations at the start.
    """
    h6 = hs / 6.0
    w_end = 1.0 * hs / 6.0
    w_mid = 2.0 * hs / 6.0
    half = 0.5 * hs
    # stage 1
    ag = ag0 + slope * s
    if have:
        fc, dd, a0, a1 = fcs, ps0 * v0 + ps1 * v1, as0, as1
    else:
        fc, dd, a0, a1 = _stage(q0, q1, v0, v1, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, gp, b,
                                cd, zhd, phase, model)  # fmt: skip
    fc_start = fc
    acc0 = a0
    acc1 = a1
    kq0, kq1, kv0, kv1 = v0, v1, a0, a1
    sq0, sq1, sv0, sv1 = kq0, kq1, kv0, kv1
    pin = -(ag * g0 * v0)
    pin -= ag * g1 * v1
    pd = zw2_0 * v0 * v0
    pd += zw2_1 * v1 * v1
    e_in = w_end * pin
    e_d = w_end * pd
    w_c = w_end * (fc * dd)
    imp = w_end * fc
    # stages 2 and 3 (half step), 4 (full step)
    for stage in range(1, 4):
        fac = hs if stage == 3 else half
        wgt = w_end if stage == 3 else w_mid
        wq0 = q0 + fac * kq0
        wq1 = q1 + fac * kq1
        wv0 = v0 + fac * kv0
        wv1 = v1 + fac * kv1
        ag = ag0 + slope * (s + fac)
        fc, dd, a0, a1 = _stage(wq0, wq1, wv0, wv1, ag, k0, ww0, g0, k1, ww1, g1, ps0, ps1, gp,
                                b, cd, zhd, phase, model)  # fmt: skip
        kq0, kq1, kv0, kv1 = wv0, wv1, a0, a1
        if stage == 3:
            sq0 += kq0
            sq1 += kq1
            sv0 += kv0
            sv1 += kv1
        else:
            sq0 += 2.0 * kq0
            sq1 += 2.0 * kq1
            sv0 += 2.0 * kv0
            sv1 += 2.0 * kv1
        pin = -(ag * g0 * wv0)
        pin -= ag * g1 * wv1
        pd = zw2_0 * wv0 * wv0
        pd += zw2_1 * wv1 * wv1
        e_in += wgt * pin
        e_d += wgt * pd
        w_c += wgt * (fc * dd)
        imp += wgt * fc
    return (q0 + h6 * sq0, q1 + h6 * sq1, v0 + h6 * sv0, v1 + h6 * sv1, e_in, e_d, w_c, imp,
            fc_start, acc0, acc1)  # fmt: skip


@jit
def adaptive_pair(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """:func:`~pound_mc.integrators.adaptive.adaptive` for an SDOF pair, state in scalars.

    Same arguments and outputs; ``phi`` is diagonal (floor ``j`` is mode ``j``), one contact.
    ``hx, hd, hf``: histories at the record's samples (empty arrays: none).  ``pre``: the shared
    linear response before the first contact (layout in :mod:`pound_mc.integrators.outputs`;
    floor peaks after the state), empty for a plain run.  Longer than 150 lines for the reason
    the general kernel is: its scalar state lives in locals across both kinds of step.
    """
    model = settings.model
    relation = settings.relation
    substeps = settings.substeps
    npts = ag.size
    inv_dt = 1.0 / dt_rec
    w0, w1, z0, z1, g0, g1 = omega[0], omega[1], zeta[0], zeta[1], gamma[0], gamma[1]
    wmax = max(w0, w1)
    m_sub, h = step_size(
        dt_rec, min(settings.dt_s, 2.0 * math.pi / (LINEAR_STEPS_PER_PERIOD * wmax))
    )
    # the longest contact sub-step, a step of the record interval split evenly as h is
    m_rk, h_rk = step_size(dt_rec, min(settings.dt_s, 2.0 * math.pi / (STEPS_PER_PERIOD * wmax)))
    k0, k1 = -2.0 * z0 * w0, -2.0 * z1 * w1
    ww0, ww1 = w0 * w0, w1 * w1
    zw2_0, zw2_1 = 2.0 * z0 * w0, 2.0 * z1 * w1
    zw4_0, zw4_1 = 4.0 * z0 * w0, 4.0 * z1 * w1
    km = (k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, zw4_0, zw4_1)
    ps0, ps1, f0, f1 = psi[0, 0], psi[0, 1], phi[0, 0], phi[1, 1]
    gp, b, me, xi0 = gap[0], beta[0], meff[0], xi[0]
    cd = 2.0 * xi0 * math.sqrt(b * me)  # damping constant c0 of the force laws
    cf = coefficients(w0, z0, h)
    cf0 = (cf[0, 0], cf[0, 1], cf[0, 2], cf[0, 3], cf[1, 0], cf[1, 1], cf[1, 2], cf[1, 3])
    cf = coefficients(w1, z1, h)
    cf1 = (cf[0, 0], cf[0, 1], cf[0, 2], cf[0, 3], cf[1, 0], cf[1, 1], cf[1, 2], cf[1, 3])
    q0, q1, v0, v1 = q[0], q[1], v[0], v[1]
    phase = 0
    zhd = pk0 = pk1 = e_in = e_d = w_c = 0.0
    e0 = 0.5 * (v0 * v0 + w0 * w0 * q0 * q0)
    e0 += 0.5 * (v1 * v1 + w1 * w1 * q1 * q1)
    peak_f = peak_t = impacts = impulse = 0.0
    pending = False  # an episode not yet counted as an impact
    maxpen = -_INF
    steps = 0
    hc = h_rk
    fresh = False
    dc0 = ddc0 = xf0 = xf1 = xfd0 = xfd1 = 0.0
    en0 = (0.0, 0.0, 0.0, 0.0)  # the energy sums at a linear step's start (_ends)
    # error bound of the cubic Hermite maximum in a linear step, (omega h)^4 / 384 of the
    # amplitude, with a safety factor of 4: a candidate below the peak by more is no new peak
    herm_tol = 4.0 * (wmax * h) ** 4 / 384.0
    t_onset = 0.0
    budget = 200 * (npts - 1) * m_rk + 1_000_000
    # whether the accuracy check's run (_FINE times every sub-step bound that depends on
    # ``substeps``) would take the same sub-steps: then its peak force is this run's, bitwise
    same_fine = True
    in_contact = False
    fsal = False
    fc_end = ae0 = ae1 = 0.0
    # _roots of the state, valid while ``rooted`` (the last sub-step was an approach's)
    roots = (0.0, 0.0, 0.0)
    rooted = False
    pot = model == _JANKOWSKI
    kpot = 0.8 * cd
    # restitution set per impact (Table 2 at the onset velocity; ``xi0`` holds its quantile)
    per_impact = settings.rest_v.size > 0
    # the impact-velocity log in a list that is never reassigned (outputs.log_impact_in)
    logs = [impact_log(1)[1]]
    nlog = 0
    v_ep = e_ep = peak_e = math.nan
    ramp_0 = RAMP_START_POT if pot else RAMP_START
    ramp_k = RAMP_GROWTH_POT if pot else RAMP_GROWTH
    tail = TAIL_POT if pot else TAIL
    tail_min = TAIL_MIN_POT if pot else TAIL_MIN
    loc_k = LOCAL_PERIOD_SHARE * math.sqrt(me) / substeps
    loc_c = LOCAL_DAMPING_SHARE * me / substeps
    status = STATUS_OK
    store = hx.shape[0] > 0
    mode = int(pre[PRE_MODE]) if pre.size > 0 else 0
    # the accuracy check's run: no energies (they do not move the state); the floors' peaks
    # only from a contact onset (PRE_RESUME_ONSET: the peak force and the floors' peaks)
    lean = mode == PRE_RESUME_PEAK or mode == PRE_RESUME_ONSET
    floors = not lean or mode == PRE_RESUME_ONSET
    # the screen of the local bounds (_contact_bound) covers their tightness at _FINE, which
    # only ``same_fine`` needs: a lean run (the check's own run) reports none, and its screen
    # covers the bounds themselves, the larger share (every bound is slack there, bit for bit)
    share = 1.0 if lean else _FINE
    kp4 = period_screen(model, b, loc_k, share)
    kc4 = damping_screen(model, b, cd, loc_c, share)
    # past the outputs and their ``same`` slot: where the check's run may start (the state at
    # the last onset before which the check's run is this one, PRE_RESUME_ONSET)
    onsets = out.size > N_OUT + 1
    i_first = 0
    s = 0.0
    k_grid = 0  # index of the next grid point within the interval
    if mode == PRE_RESUME or lean:
        i_first = int(pre[PRE_INTERVAL])
        e_in = pre[PRE_E_IN]
        e_d = pre[PRE_E_D]
        steps = int(pre[PRE_STEPS])
        e0 = pre[PRE_E0]
        q0, q1, v0, v1 = pre[PRE_STATE], pre[PRE_STATE + 1], pre[PRE_STATE + 2], pre[PRE_STATE + 3]
        pk0, pk1 = pre[PRE_STATE + 4], pre[PRE_STATE + 5]
    if mode == PRE_RESUME_ONSET:  # within the interval, at the start of a linear step
        s, k_grid, peak_f = pre[ONSET_S], int(pre[ONSET_GRID]), pre[ONSET_PEAK]
        cd, zhd = pre[ONSET_CD], pre[ONSET_ZHD]
        kpot = 0.8 * cd
        kc4 = damping_screen(model, b, cd, loc_c, share)
    i = i_first
    while i < npts - 1:
        if fresh and not in_contact:
            # ---------------- runs of whole grid steps where nothing happens inside them: no
            # onset, no turning penetration, no floor extremum; the same arithmetic as the
            # general linear step below, which takes the others (from the grid point this loop
            # stops at).  A loop of its own: its state stays in registers (B1: the linear
            # phases 2.5 times faster than as a branch of the interval loop).  Its energies are
            # the general step's corrected trapezoidal rule summed over the run (_quiet_add)
            run = _quiet_start()
            while i < npts - 1:
                if k_grid == 0:  # a new record interval
                    if mode == PRE_RUN_TO_CONTACT:
                        e_in, e_d, en0, run = _quiet_close(run, e_in, e_d, en0, q0, q1, v0, v1,
                                                           km, h)  # fmt: skip
                        _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
                    if store:
                        _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase,
                                    model, hx, hd, hf)  # fmt: skip
                    ag0 = ag[i]
                    slope = (ag[i + 1] - ag[i]) * inv_dt
                _, hh, p0s, p1s, quiet = grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope)
                if not quiet:
                    break  # not a whole step: the general step below takes it
                nq0, nv0 = _mode_step(q0, v0, p0s, p1s, g0, cf0)
                nq1, nv1 = _mode_step(q1, v1, p0s, p1s, g1, cf1)
                d1 = ps0 * nq0 + ps1 * nq1 - gp
                dd1 = ps0 * nv0 + ps1 * nv1
                xb0, xdb0, xb1, xdb1 = f0 * nq0, f0 * nv0, f1 * nq1, f1 * nv1
                # a turning penetration matters only where the bound of its cubic Hermite says
                # the general step's screen could act (margin and tolerance as there)
                quiet = d1 <= 0.0 and dc0 <= 0.0
                if quiet and ddc0 > 0.0 and dd1 < 0.0:
                    margin = 0.05 * (abs(ddc0) + abs(dd1)) * hh
                    bnd = max(dc0, d1) + _hermite_spread(dc0, ddc0, d1, dd1, hh)
                    quiet = bnd < -margin * (1.0 + 1e-9)
                if not quiet:
                    break  # the general step below takes this grid step
                steps += 1
                if not lean:
                    run = _quiet_add(run, hh, slope, p0s, p1s, en0, nv0, nv1, km)
                if floors:
                    # a floor extremum that may be a new peak: found here as the general step
                    # would (the state does not depend on it)
                    pk0 = _quiet_floor_peak(f0, 0, xf0, xfd0, xb0, xdb0, pk0, q0, q1, v0, v1,
                                            p0s, slope, hh, w0, z0, g0, w1, z1, g1,
                                            herm_tol)  # fmt: skip
                    pk1 = _quiet_floor_peak(f1, 1, xf1, xfd1, xb1, xdb1, pk1, q0, q1, v0, v1,
                                            p0s, slope, hh, w0, z0, g0, w1, z1, g1,
                                            herm_tol)  # fmt: skip
                    pk0 = max(pk0, abs(xb0))
                    pk1 = max(pk1, abs(xb1))
                    xf0, xfd0, xf1, xfd1 = xb0, xdb0, xb1, xdb1
                dc0 = d1
                ddc0 = dd1
                q0, q1, v0, v1 = nq0, nq1, nv0, nv1
                if not math.isfinite(q0 + q1 + v0 + v1):
                    status = STATUS_UNSTABLE
                    break
                s += hh  # as the general step: the next grid step starts here
                k_grid += 1
                if k_grid == m_sub:
                    s = 0.0
                    k_grid = 0
                    i += 1
            if not lean:
                e_in, e_d, en0, run = _quiet_close(run, e_in, e_d, en0, q0, q1, v0, v1, km, h)
            if status != 0 or i >= npts - 1:
                break
        else:
            if mode == PRE_RUN_TO_CONTACT:
                _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
            if store:
                _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase, model,
                            hx, hd, hf)  # fmt: skip
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) * inv_dt
        fsal = False  # a new interval: new load, the next sub-step starts afresh
        while s < dt_rec * (1.0 - 1e-12):
            steps += 1
            if steps > budget:
                status = STATUS_NOT_CONVERGED
                break
            if not in_contact:
                # ---------------- exact linear step to the next grid point
                s_next, hh, p0s, p1s, whole_step = grid_step(k_grid, m_sub, h, dt_rec, s, ag0,
                                                              slope)  # fmt: skip
                if whole_step:
                    nq0, nv0 = _mode_step(q0, v0, p0s, p1s, g0, cf0)
                    nq1, nv1 = _mode_step(q1, v1, p0s, p1s, g1, cf1)
                else:
                    nq0, nv0 = advance(q0, v0, -g0 * p0s, -g0 * p1s, w0, z0, hh)
                    nq1, nv1 = advance(q1, v1, -g1 * p0s, -g1 * p1s, w1, z1, hh)
                if not fresh:
                    dc0 = ps0 * q0 + ps1 * q1 - gp
                    ddc0 = ps0 * v0 + ps1 * v1
                    xf0 = f0 * q0
                    xf1 = f1 * q1
                    xfd0 = f0 * v0
                    xfd1 = f1 * v1
                    en0 = _ends(q0, q1, v0, v1, p0s, km)
                    fresh = True
                # onset screening
                d0 = dc0
                dd0 = ddc0
                d1 = ps0 * nq0 + ps1 * nq1 - gp
                dd1 = ps0 * nv0 + ps1 * nv1
                dc1 = d1
                ddc1 = dd1
                crossing = d1 > 0.0
                t_hi = hh
                look, tg = turning_screen(d0, dd0, d1, dd1, hh) if not crossing else (False, 0.0)
                if look:
                    # exact maximum of delta in the step: root of delta_dot
                    dm, tm = _exact_max(q0, q1, v0, v1, p0s, slope, tg, hh, w0, z0, g0, w1, z1,
                                        g1, ps0, ps1, gp)  # fmt: skip
                    if dm > 0.0:
                        crossing = True
                        t_hi = tm
                        d1 = dm
                        dd1 = 0.0
                onset = False
                if crossing and d0 <= 0.0:
                    # locate delta = 0 on the exact solution (safeguarded Newton)
                    tg = hermite_root(d0, dd0, d1, dd1, t_hi)
                    hh = _exact_root_pair(q0, q1, v0, v1, p0s, slope, tg, 0.0, t_hi, 0, w0, z0,
                                          g0, w1, z1, g1, ps0, ps1, gp, ONSET_TOL)  # fmt: skip
                    onset = True
                elif d0 > 0.0 and (dd0 > 0.0 or (d1 > 0.0 and dd1 > 0.0)):
                    # penetrating since a located separation (within the root's error) and
                    # growing now or again at the end: the contact resumes here or where delta
                    # turns (its minimum); the test above looks for a crossing that never comes
                    if dd0 > 0.0:
                        hh = 0.0
                    else:
                        hh = _exact_root_pair(q0, q1, v0, v1, p0s, slope, 0.5 * hh, 0.0, hh, 1,
                                              w0, z0, g0, w1, z1, g1, -ps0, -ps1, -gp,
                                              ONSET_TOL)  # fmt: skip
                    onset = True
                if onset:
                    if mode == PRE_RUN_TO_CONTACT:
                        return
                    if onsets and same_fine:  # the check's run is this one up to here
                        _snapshot_onset(out[N_OUT + 1 :], i, s, k_grid, steps - 1, q0, q1, v0,
                                        v1, peak_f, cd, zhd, pk0, pk1)  # fmt: skip
                    p1s = ag0 + slope * (s + hh)
                    nq0, nv0 = advance(q0, v0, -g0 * p0s, -g0 * p1s, w0, z0, hh)
                    nq1, nv1 = advance(q1, v1, -g1 * p0s, -g1 * p1s, w1, z1, hh)
                    dc1 = ps0 * nq0 + ps1 * nq1 - gp
                    ddc1 = ps0 * nv0 + ps1 * nv1
                if not lean:
                    # energies by the corrected trapezoidal rule (exact to O(h^5) per step)
                    de_in, de_d, en0 = _energy_step(hh, slope, p0s, p1s, en0, nq0, nq1, nv0, nv1,
                                                    km)  # fmt: skip
                    e_in += de_in
                    e_d += de_d
                if floors:
                    # peak floor displacements: where the cubic Hermite bound says an extremum
                    # inside the step may be a new peak, find it on the exact solution
                    pk0 = _floor_peak(f0, 0, xf0, xfd0, f0 * nq0, f0 * nv0, pk0, q0, q1, v0, v1,
                                      p0s, slope, hh, w0, z0, g0, w1, z1, g1, herm_tol)  # fmt: skip
                    pk1 = _floor_peak(f1, 1, xf1, xfd1, f1 * nq1, f1 * nv1, pk1, q0, q1, v0, v1,
                                      p0s, slope, hh, w0, z0, g0, w1, z1, g1, herm_tol)  # fmt: skip
                    xf0, xfd0, xf1, xfd1 = f0 * nq0, f0 * nv0, f1 * nq1, f1 * nv1
                dc0 = dc1
                ddc0 = ddc1
                q0, q1, v0, v1 = nq0, nq1, nv0, nv1
                s += hh
                if onset:
                    v0c = ps0 * v0 + ps1 * v1
                    phase = 1
                    pending = True
                    v_ep = v0c
                    if per_impact:
                        cd, zhd, e_ep = laws.episode_damping(settings, model, relation, xi0, v0c, b,
                                                        me, cd, zhd)  # fmt: skip
                        kpot = 0.8 * cd
                        kc4 = damping_screen(model, b, cd, loc_c, share)
                    else:
                        zhd = laws.episode_zeta(model, relation, xi0, v0c, zhd)
                    hc, same_fine = _episode_substep(
                        h_rk, laws.duration(model, v0c, b, me) / substeps, same_fine
                    )
                    t_onset = i * dt_rec + s
                    in_contact = True
                    fsal = False
                    rooted = False
                else:
                    k_grid += 1
            else:
                # ---------------- contact sub-step (RK4) with located switches
                fresh = False
                # sub-steps graded geometrically away from onset and towards separation,
                # where the force law is not smooth (delta^0.25, delta^0.5 terms)
                hs = min(hc, max(ramp_k * (i * dt_rec + s - t_onset), hc * ramp_0))
                if phase == 2:
                    ddc = ps0 * v0 + ps1 * v1
                    if ddc < 0.0:
                        dc = ps0 * q0 + ps1 * q1 - gp
                        hs = min(hs, max(-tail * dc / ddc, hc * tail_min))
                # at the penetration the step may reach (its rate), not only at its start
                dc = ps0 * q0 + ps1 * q1 - gp
                hs, tight = contact_bound(hs, dc, ps0 * v0 + ps1 * v1, model, b, cd, zhd, phase,
                                           loc_k, loc_c, kp4, kc4)  # fmt: skip
                same_fine = same_fine and not tight
                if hs >= dt_rec - s or dt_rec - s - hs < 1e-9 * hc:
                    hs = dt_rec - s
                # the sub-step, and again to the first switch of the force law inside it
                # (located by Hermite interpolation in the step), from the same start
                have, fs0, as0, as1 = fsal, fc_end, ae0, ae1
                t_ev = _INF
                kind = 0
                pot_step = pot and phase == 1
                if pot_step and not rooted:
                    roots = _roots(q0, q1, ps0, ps1, gp)
                roots1 = roots
                for attempt in range(2):
                    if pot_step:
                        (nq0, nq1, nv0, nv1, de_in, de_d, dw_c, cimp, fc0, ac0, ac1,
                         roots1) = _rk4_pot(
                            q0, q1, v0, v1, s, hs, ag0, slope, k0, ww0, g0, k1, ww1, g1, zw2_0,
                            zw2_1, ps0, ps1, gp, b, cd, kpot, roots,
                        )  # fmt: skip
                    else:
                        (nq0, nq1, nv0, nv1, de_in, de_d, dw_c, cimp, fc0, ac0, ac1) = _rk4_pair(
                            q0, q1, v0, v1, s, hs, ag0, slope, k0, ww0, g0, k1, ww1, g1, zw2_0,
                            zw2_1, ps0, ps1, gp, b, cd, zhd, phase, model, have, fs0, as0, as1,
                        )  # fmt: skip
                    ag_end = ag0 + slope * (s + hs)
                    if pot_step and roots1[0] > 0.0:
                        # laws.force (_jankowski_k, approach) from the roots _rk4_pot took at
                        # the end: beta d sqrt(d) + c0 d^0.25 dd, the same operations
                        d_e, sd_e, qd_e = roots1
                        fc1 = b * d_e * sd_e + cd * qd_e * (ps0 * nv0 + ps1 * nv1)
                        ae0, ae1 = _accel(nq0, nq1, nv0, nv1, ag_end, k0, ww0, g0, k1, ww1, g1,
                                          ps0, ps1, fc1)  # fmt: skip
                    else:
                        fc1, _, ae0, ae1 = _stage(nq0, nq1, nv0, nv1, ag_end, k0, ww0, g0, k1,
                                                  ww1, g1, ps0, ps1, gp, b, cd, zhd, phase,
                                                  model)  # fmt: skip
                    fc_end = fc1
                    d0 = ps0 * q0 + ps1 * q1 - gp
                    d1 = ps0 * nq0 + ps1 * nq1 - gp
                    dd0 = ps0 * v0 + ps1 * v1
                    dd1 = ps0 * nv0 + ps1 * nv1
                    ddd0 = ps0 * ac0 + ps1 * ac1
                    ddd1 = ps0 * ae0 + ps1 * ae1
                    if attempt == 1:
                        break
                    if phase == 0:
                        if d1 > 0.0 and d0 <= 0.0:
                            t_ev = hermite_root(d0, dd0, d1, dd1, hs)
                            kind = 1  # onset
                    elif phase == 1:
                        if dd1 <= 0.0 and dd0 > 0.0:
                            t_ev = hermite_root(dd0, ddd0, dd1, ddd1, hs)
                            kind = 2  # approach -> restitution
                    else:
                        if d1 <= 0.0 and d0 > 0.0:
                            t_ev = hermite_root(d0, dd0, d1, dd1, hs)
                            kind = 3  # separation
                        if dd1 > 0.0 and dd0 <= 0.0:
                            t2 = hermite_root(dd0, ddd0, dd1, ddd1, hs)
                            if t2 < t_ev:
                                t_ev = t2
                                kind = 4  # restitution -> approach
                    if not t_ev < hs:
                        break
                    hs = t_ev
                    have, fs0, as0, as1 = True, fc0, ac0, ac1
                event = t_ev < _INF
                if pot and phase == 2:  # the elastic force alone: its work is exact
                    dw_c = laws.stored(model, d1, b) - laws.stored(model, d0, b)
                e_in += de_in
                e_d += de_d
                w_c += dw_c
                impulse += cimp
                # peak force (Hermite on F with its rate), penetration
                if phase != 0:
                    fm, tm, dm = laws.substep_peaks(model, fc0, fc1, d0, d1, dd0, dd1, ddd0, ddd1,
                                                    hs, peak_f, b, cd, zhd, phase)  # fmt: skip
                    if fm > peak_f:
                        peak_f = fm
                        peak_t = i * dt_rec + s + tm
                        peak_e = e_ep
                    if dm > maxpen:
                        maxpen = dm
                    if pending and dm > IMPACT_MIN_PENETRATION_M:
                        impacts += 1.0  # the episode is an impact
                        pending = False
                        nlog = log_impact_in(logs, nlog, v_ep)
                if floors:
                    # peak floor displacements over the sub-step (Hermite)
                    pk0 = _track_floor(f0 * q0, f0 * v0, f0 * nq0, f0 * nv0, hs, pk0)
                    pk1 = _track_floor(f1 * q1, f1 * v1, f1 * nq1, f1 * nv1, hs, pk1)
                q0, q1, v0, v1 = nq0, nq1, nv0, nv1
                # the roots at the end start the next approach sub-step (_rk4_pot)
                roots = roots1
                rooted = pot_step
                s += hs
                # the force and accelerations at the end start the next sub-step (first same as
                # last) unless the force law switched there
                fsal = not event
                if event and hs == t_ev:
                    if kind == 1:
                        phase = 1
                        pending = True
                        v0c = ps0 * v0 + ps1 * v1
                        v_ep = v0c
                        if per_impact:
                            cd, zhd, e_ep = laws.episode_damping(settings, model, relation, xi0,
                                                                 v0c, b, me, cd, zhd)  # fmt: skip
                            kpot = 0.8 * cd
                            kc4 = damping_screen(model, b, cd, loc_c, share)
                        else:
                            zhd = laws.episode_zeta(model, relation, xi0, v0c, zhd)
                        hc, same_fine = _episode_substep(
                            hc, laws.duration(model, v0c, b, me) / substeps, same_fine
                        )
                        t_onset = i * dt_rec + s
                    elif kind == 2:
                        phase = 2
                    elif kind == 3:
                        phase = 0
                        in_contact = False
                        hc = h_rk
                    else:
                        phase = 1
                # continue with exact steps from here to the next grid point
                k_grid = int(math.floor(s / h + 1e-9))
                if k_grid >= m_sub:
                    k_grid = m_sub - 1
            # divergence / non-finite guard
            if not math.isfinite(q0 + q1 + v0 + v1):  # inf or nan in any of them
                status = STATUS_UNSTABLE
                break
        if status != 0:
            break
        i += 1
        s = 0.0
        k_grid = 0
    if mode == PRE_RUN_TO_CONTACT:
        # no contact in the whole record: the end state is shared
        _snapshot_pair(pre, npts - 1, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
        return
    if lean:
        peak_only(out, cout, peak_f, status)
        if floors and status == STATUS_OK:
            out[PEAK_DISP_LEFT + side[0]] = pk0
            out[PEAK_DISP_LEFT + side[1]] = pk1
        return
    if store and status == STATUS_OK:
        _store_pair(npts - 1, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase, model,
                    hx, hd, hf)  # fmt: skip
    q[0], q[1], v[0], v[1] = q0, q1, v0, v1
    cout[0, C_PEAK_FORCE] = peak_f
    cout[0, C_IMPACTS] = impacts
    cout[0, C_MAX_PENETRATION] = maxpen
    cout[0, C_IMPULSE] = impulse
    vlog = logs[0]
    cout[0, C_MAX_IMPACT_VELOCITY] = log_max(vlog, nlog)
    peaks = np.empty(2)
    peaks[0] = pk0
    peaks[1] = pk1
    ph = np.zeros(1, dtype=np.int64)
    ph[0] = phase
    stored_energy = 0.0
    if phase != 0:
        stored_energy = laws.stored(model, ps0 * q0 + ps1 * q1 - gp, b)
    finish(out, cout, peaks, side, ph, q, v, omega, e0, e_in, e_d, w_c, stored_energy, peak_f,
           peak_t, steps, status)  # fmt: skip
    finish_impacts(out, cout, vlog, nlog, peak_e)
    if out.size > N_OUT:  # a slot past the outputs: does the accuracy check's run differ?
        out[N_OUT] = 1.0 if same_fine else 0.0


@jit(inline=True)
def _episode_substep(hc, dur, same_fine):
    """The contact sub-step [s] of a new episode and whether the check's run still takes it.

    ``hc`` bounded by ``dur`` (the estimated duration over ``substeps``); the accuracy check's
    run is bounded by ``_FINE dur`` (``same_fine``: it took this run's sub-steps so far).
    """
    return min(hc, dur), same_fine and hc <= _FINE * dur


@jit(inline=True)
def _hermite_spread(y0, yp0, y1, yp1, h):
    """How far the cubic Hermite interpolant on ``[0, h]`` may exceed its larger end value.

    Its rate is ``yp0 (1 - s) + yp1 s + C s (1 - s)`` per ``s = t / h``, with
    ``C = 6 (y1 - y0) / h - 3 (yp0 + yp1)``, at most ``M = max|yp| + |C| / 4`` in magnitude;
    the interpolant is within ``M h / 2`` of the nearer end, in value and in magnitude.
    """
    m = max(abs(yp0), abs(yp1)) + 0.25 * abs(6.0 * (y1 - y0) / h - 3.0 * (yp0 + yp1))
    return 0.5 * m * h


@jit(inline=True)
def _floor_peak(
    ff, fl, xa, xda, xb, xdb, pk, q0, q1, v0, v1, p0s, slope, hh, w0, z0, g0, w1, z1, g1, herm_tol,
):  # fmt: skip
    """Peak ``|x|`` [m] of floor ``fl`` (``x = ff q_fl``) updated over an exact linear step.

    ``xa, xda`` and ``xb, xdb``: its displacement and velocity at the step's start and end.
    Where the velocity turns, the step holds one extremum (a maximum of ``x`` where it turns
    from + to -, else of ``-x``: the cubic Hermite has no other); where the Hermite estimate
    says it may be a new peak, it is found on the exact solution (:func:`_exact_max`).
    """
    m = abs(xb)
    if m > pk:
        pk = m
    if (xda > 0.0) != (xdb > 0.0):
        sign = 1.0 if xda > 0.0 else -1.0
        hm, tg = hermite_max(sign * xa, sign * xda, sign * xb, sign * xdb, hh)
        if hm > pk - herm_tol * abs(hm):
            c0 = sign * ff if fl == 0 else 0.0
            c1 = sign * ff if fl == 1 else 0.0
            xm, _ = _exact_max(q0, q1, v0, v1, p0s, slope, tg, hh, w0, z0, g0, w1, z1, g1, c0, c1,
                               0.0)  # fmt: skip
            if xm > pk:
                pk = xm
    return pk


@jit(inline=True)
def _quiet_floor_peak(
    ff, fl, xa, xda, xb, xdb, pk, q0, q1, v0, v1, p0s, slope, hh, w0, z0, g0, w1, z1, g1, herm_tol,
):  # fmt: skip
    """:func:`_floor_peak` in the quiet-step loop, where a turn may be a new peak.

    Only where the floor's velocity turns and the spread bound of its cubic Hermite
    (:func:`_hermite_spread`) does not rule out a new peak.  ``_floor_peak`` screens again,
    but calling it at every turn of a floor's velocity made the kernel 9 % slower (40
    benchmark-like pairs, results bitwise equal).
    """
    if (xda > 0.0) != (xdb > 0.0):
        bnd = max(abs(xa), abs(xb)) + _hermite_spread(xa, xda, xb, xdb, hh)
        if not bnd * (1.0 + herm_tol + 1e-9) < pk:
            pk = _floor_peak(ff, fl, xa, xda, xb, xdb, pk, q0, q1, v0, v1, p0s, slope, hh, w0, z0,
                             g0, w1, z1, g1, herm_tol)  # fmt: skip
    return pk


@jit(inline=True)
def _track_floor(x0, xd0, x1, xd1, h, peak):
    """Peak ``|x|`` of a floor updated over a step (cubic Hermite), as ``_track_floors``."""
    m = abs(x1)
    if m > peak:
        peak = m
    if (xd0 > 0.0) != (xd1 > 0.0):
        hm, _ = hermite_max(x0, xd0, x1, xd1, h)
        if hm > peak:
            peak = hm
        hm, _ = hermite_max(-x0, -xd0, -x1, -xd1, h)
        if hm > peak:
            peak = hm
    return peak


@jit(inline=True)
def _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1):
    """:func:`~pound_mc.integrators.outputs.snapshot` of the scalar state."""
    pre[PRE_INTERVAL] = i
    pre[PRE_E_IN] = e_in
    pre[PRE_E_D] = e_d
    pre[PRE_STEPS] = steps
    pre[PRE_E0] = e0
    pre[PRE_STATE] = q0
    pre[PRE_STATE + 1] = q1
    pre[PRE_STATE + 2] = v0
    pre[PRE_STATE + 3] = v1
    pre[PRE_STATE + 4] = pk0
    pre[PRE_STATE + 5] = pk1


@jit(inline=True)
def _snapshot_onset(pre, i, s, k_grid, steps, q0, q1, v0, v1, peak_f, cd, zhd, pk0, pk1):
    """A ``PRE_RESUME_ONSET`` start: a linear step's start (state, peak force, floors' peaks)."""
    _snapshot_pair(pre, i, 0.0, 0.0, steps, 0.0, q0, q1, v0, v1, pk0, pk1)
    pre[ONSET_S] = s
    pre[ONSET_GRID] = k_grid
    pre[ONSET_PEAK] = peak_f
    pre[ONSET_CD] = cd
    pre[ONSET_ZHD] = zhd


@jit(inline=True)
def _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase, model, hx, hd, hf):
    """Floor displacements, penetration and force at record sample ``i``."""
    hx[i, 0] = f0 * q0
    hx[i, 1] = f1 * q1
    d = ps0 * q0 + ps1 * q1 - gp
    hd[i, 0] = d
    hf[i, 0] = laws.force(model, d, ps0 * v0 + ps1 * v1, b, cd, zhd, phase)
