"""The contact phase of the SDOF pair's ``adaptive`` kernel: RK4 sub-steps, located switches.

The pieces :func:`~pound_mc.integrators.adaptive_pair.adaptive_pair` takes its contact
sub-steps with: the force and modal accelerations at a state, the classical Runge-Kutta step
(and its form for Jankowski's approach phase, in ``u = v + psi D(delta)``), the sub-step of a
new episode and the floor peaks over a sub-step; and the sub-step itself,
:func:`_contact_substep` (its length, the step cut at the first switch of the force law inside
it, the energies and peaks, the switch), and :func:`_open_episode`, the start of an episode at
an onset.  Notation as in :mod:`~pound_mc.integrators.adaptive_pair` and
:mod:`~pound_mc.integrators.adaptive_pair_linear` (``km``, ``geo``).
"""

from __future__ import annotations

import math

from pound_mc._jit import jit
from pound_mc.integrators import laws
from pound_mc.integrators.bounds import FINE as _FINE
from pound_mc.integrators.bounds import contact_bound, damping_screen
from pound_mc.integrators.outputs import IMPACT_MIN_PENETRATION_M
from pound_mc.integrators.toolkit import hermite_max, hermite_root

__all__ = [
    "RAMP_GROWTH",
    "RAMP_GROWTH_POT",
    "RAMP_START",
    "RAMP_START_POT",
    "TAIL",
    "TAIL_MIN",
    "TAIL_MIN_POT",
    "TAIL_POT",
]

_INF = math.inf
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


@jit(inline=True)
def _episode_substep(hc, dur, same_fine):
    """The contact sub-step [s] of a new episode and whether the check's run still takes it.

    ``hc`` bounded by ``dur`` (the estimated duration over ``substeps``); the accuracy check's
    run is bounded by ``_FINE dur`` (``same_fine``: it took this run's sub-steps so far).
    """
    return min(hc, dur), same_fine and hc <= _FINE * dur


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


@jit(llvm_inline=True)
def _substep_length(since, room, q0, q1, v0, v1, phase, hc, model, b, cd, zhd, kc4, geo, ramp,
                    bounds):  # fmt: skip
    """A contact sub-step's length [s] and whether a local bound was tight at the check's share.

    ``since``: the time since the episode's onset [s], ``room``: the time left in the record
    interval [s]; ``hc``: the episode's sub-step [s]; ``ramp``: ``(ramp_0, ramp_k, tail,
    tail_min)`` (:data:`RAMP_START` ...), ``bounds``: ``(loc_k, loc_c, kp4)`` and ``kc4`` the
    local bounds and their screens (:func:`~pound_mc.integrators.bounds.contact_bound`).
    """
    ps0, ps1, gp, _, _ = geo
    ramp_0, ramp_k, tail, tail_min = ramp
    loc_k, loc_c, kp4 = bounds
    # sub-steps graded geometrically away from onset and towards separation,
    # where the force law is not smooth (delta^0.25, delta^0.5 terms)
    hs = min(hc, max(ramp_k * since, hc * ramp_0))
    if phase == 2:
        ddc = ps0 * v0 + ps1 * v1
        if ddc < 0.0:
            dc = ps0 * q0 + ps1 * q1 - gp
            hs = min(hs, max(-tail * dc / ddc, hc * tail_min))
    # at the penetration the step may reach (its rate), not only at its start
    dc = ps0 * q0 + ps1 * q1 - gp
    hs, tight = contact_bound(hs, dc, ps0 * v0 + ps1 * v1, model, b, cd, zhd, phase,
                              loc_k, loc_c, kp4, kc4)  # fmt: skip
    if hs >= room or room - hs < 1e-9 * hc:
        hs = room
    return hs, tight


@jit(llvm_inline=True)
def _contact_substep(
    t, room, s, ag0, slope, q0, q1, v0, v1, phase, hc, h_rk, t_onset, zhd, cd, kpot, kc4,
    same_fine, fsal, fc_end, ae0, ae1, roots, rooted, e_in, e_d, w_c, impulse, peak_f, peak_t,
    peak_e, e_ep, maxpen, impacts, pending, pk0, pk1, floors, pot, model, b, km, geo, ramp,
    bounds, h, m_sub,
):  # fmt: skip
    """One contact sub-step (RK4) from local time ``s`` [s], cut at the first switch in it.

    The sub-step (:func:`_substep_length`), and again to the first switch of the force law
    inside it (located by Hermite interpolation in the step), from the same start; then its
    energies, impulse, peak force, penetration and floor peaks, and the switch at its end.
    ``t``: the time [s] at its start, ``room``: the time left in the record interval [s];
    ``phase``: the contact's (0 open, 1 approach, 2 restitution); ``hc``: the episode's
    sub-step [s] (``h_rk`` once the contact opens); ``fsal``: ``fc_end, ae0, ae1`` hold the
    force [N] and modal accelerations at the start; ``rooted``: ``roots`` holds its
    :func:`_roots`; ``pot``: Jankowski's law (its approach phase by :func:`_rk4_pot`).
    Returns the state, time and grid point at the end, the phase, the sub-step bound, whether
    the contact is still in its contact phase and whether an onset at the end opens an episode
    (:func:`_open_episode`, done by the kernel), the rest of the arguments updated, and whether
    the episode became an impact (the kernel logs its onset velocity).
    """
    k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, _, _ = km
    ps0, ps1, gp, f0, f1 = geo
    hs, tight = _substep_length(t - t_onset, room, q0, q1, v0, v1, phase, hc, model, b, cd, zhd,
                                kc4, geo, ramp, bounds)  # fmt: skip
    same_fine = same_fine and not tight
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
    counted = False
    # peak force (Hermite on F with its rate), penetration
    if phase != 0:
        fm, tm, dm = laws.substep_peaks(model, fc0, fc1, d0, d1, dd0, dd1, ddd0, ddd1,
                                        hs, peak_f, b, cd, zhd, phase)  # fmt: skip
        if fm > peak_f:
            peak_f = fm
            peak_t = t + tm
            peak_e = e_ep
        if dm > maxpen:
            maxpen = dm
        if pending and dm > IMPACT_MIN_PENETRATION_M:
            impacts += 1.0  # the episode is an impact
            pending = False
            counted = True
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
    in_contact = True
    opened = False
    if event and hs == t_ev:
        if kind == 1:
            opened = True
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
    return (q0, q1, v0, v1, s, k_grid, phase, hc, in_contact, opened, same_fine, fsal, fc_end,
            ae0, ae1, roots, rooted, e_in, e_d, w_c, impulse, peak_f, peak_t, peak_e, maxpen,
            impacts, pending, counted, pk0, pk1)  # fmt: skip


@jit(llvm_inline=True)
def _open_episode(settings, per_impact, v0c, b, me, xi0, cd, zhd, e_ep, kpot, kc4, loc_c, share,
                  hc, same_fine):  # fmt: skip
    """The damping and the sub-step of a contact episode opening at velocity ``v0c`` [m/s].

    With restitution set per impact (``per_impact``, ``xi0`` its quantile), the damping
    constant ``cd`` and the episode's restitution ``e_ep`` from Table 2 at ``v0c``
    (:func:`~pound_mc.integrators.laws.episode_damping`), with ``kpot = 0.8 cd`` and the
    damping bound's screen ``kc4``; else the law's damping ``zhd`` for the episode.  ``hc``:
    the sub-step before [s], bounded by the episode's duration over ``substeps``
    (:func:`_episode_substep`, ``share``: that of the screen).  Returns
    ``(cd, zhd, e_ep, kpot, kc4, hc, same_fine)``.
    """
    model, relation, substeps = settings.model, settings.relation, settings.substeps
    if per_impact:
        cd, zhd, e_ep = laws.episode_damping(settings, model, relation, xi0, v0c, b,
                                             me, cd, zhd)  # fmt: skip
        kpot = 0.8 * cd
        kc4 = damping_screen(model, b, cd, loc_c, share)
    else:
        zhd = laws.episode_zeta(model, relation, xi0, v0c, zhd)
    hc, same_fine = _episode_substep(hc, laws.duration(model, v0c, b, me) / substeps, same_fine)
    return cd, zhd, e_ep, kpot, kc4, hc, same_fine
