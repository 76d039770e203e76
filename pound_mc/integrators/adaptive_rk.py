"""``adaptive`` for every building: error-controlled Runge-Kutta steps with located events.

The kernel of yielding buildings of any structure (SDOF or shear buildings, walls, rows,
floor-to-floor and slab-on-column contacts), any storey law of
:mod:`~pound_mc.integrators.storey_laws` (bilinear at any post-yield ratio from 0, Bouc-Wen)
and any contact law and restitution.  The state is that of
:mod:`pound_mc.integrators.hysteretic`: the modes of the *initial elastic* buildings, loaded
by the yielding storeys' plastic drifts,

``q'' + 2 zeta omega q' + omega^2 q = -gamma a_g - sum_c F_c psi_c + sum_s D_s f_s``,
``f_s = (1 - alpha_s) k_s (u_s - z_s)``,

with ``u = D q`` the storey drifts and ``z`` the hysteretic drift of each yielding storey,
carried as a state variable (``z' = g(z, u') u'``, :mod:`~pound_mc.integrators.storey_laws`).

Steps (Dormand & Prince 1980, the 5(4) pair with its first-same-as-last stage, as SciPy's
``RK45``) are chosen by the embedded error estimate: the error of every floor's displacement
and velocity is held under :func:`tolerance` of the response's scale (the largest floor
displacement so far, or the static displacement of the record's peak in the most flexible
mode), every yielding storey's ``z`` under it times its yield drift, and every closed contact's
penetration under it times the episode's deepest penetration, so that short contacts and
near-yield storeys take the steps they need and quiet spells long ones.  Every step ends on
the record's samples (the ground acceleration has kinks there); ``dt_s`` is only the first
step's length, since the error estimate bounds every step.  Every switch is located inside
the step that holds it, on the cubic Hermite
interpolant of the quantity and its rate, and the step is taken again up to it: contact onset
(grazing ones included), approach -> restitution, separation and restitution -> approach, and
each storey's branch (yield, unloading).  Inside every step the right-hand side is smooth.

Peak force, penetration, floor displacements and storey drifts are continuous-time maxima
(cubic Hermite on each step); floor accelerations are maxima over the steps' ends.  The
energies (input, damping, contact work, the plastic load's work and the hysteretic
dissipation) are integrated with the state, at its order.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.adaptive import (
    _ONSET,
    _SEPARATION,
    _TO_RESTITUTION,
    _contact_peaks,
    _locate_switch,
    _open_contact,
    _store_history,
    _stored_energy,
)
from pound_mc.integrators.hysteretic import S_ALPHA, S_BW, S_K, S_YIELD, storey_outputs
from pound_mc.integrators.laws import force
from pound_mc.integrators.storey_laws import (
    LAW_BILINEAR,
    LAW_BOUC_WEN,
    settled_branch,
    storey_event,
    storey_switch,
    z_rate,
)
from pound_mc.integrators.toolkit import (
    borrow,
    hermite_max,
    hermite_root,
    matvec_spans,
    mechanical_energy,
    row_spans,
    rowdot,
    track_floors,
)

__all__ = ["adaptive_rk", "tolerance", "RTOL_DEFAULT"]

# Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett & Wanner, Table 5.2)
_C = np.array([0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0])
_A = np.array([
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
])  # fmt: skip
#: Fifth-order weights (the last row of ``_A``: first same as last).
_B = np.array([35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0,
               11.0 / 84.0, 0.0])  # fmt: skip
#: Fifth- less fourth-order weights: the embedded error estimate.
_E = np.array([71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0,
               22.0 / 525.0, -1.0 / 40.0])  # fmt: skip
#: Relative tolerance of the embedded error at the default 16 ``substeps``; it scales as
#: ``(16 / substeps)^2``, so that the accuracy check's run (twice the sub-steps) is held to a
#: quarter of it.
RTOL_DEFAULT = 1e-9
_SUBSTEPS_DEFAULT = 16.0
#: Step growth after an accepted step is at most this factor, and a rejected step shrinks by
#: at least ``_SHRINK_MIN``; safety factor of the step-size rule ``h (1 / err)^(1/5)``.
_GROW_MAX, _SHRINK_MIN, _SAFETY = 5.0, 0.2, 0.9
#: Energy rates integrated with the state: input, damping, contact, plastic load, hysteretic.
_N_RATES = 5
#: A drift rate below this share of ``u_y omega_max`` (a penetration rate below it of the
#: response's velocity scale) is a located turn's round-off: the branch (the phase) there
#: follows the rate's rate (:func:`~pound_mc.integrators.storey_laws.settled_branch`,
#: :func:`_settle`).
DU_TOL = 1e-9
#: Rejected steps allowed per record interval before the run is not converged.
_MAX_REJECTS = 10_000


@jit(inline=True)
def tolerance(substeps):
    """Relative tolerance of the embedded error estimate for ``substeps`` (module docstring)."""
    r = _SUBSTEPS_DEFAULT / max(substeps, 1)
    return RTOL_DEFAULT * r * r


@jit
def _deriv(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
           hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, st):  # fmt: skip
    """Right-hand side at state ``y = (q, v, z)`` and ground acceleration ``ag``: row ``st``.

    Writes the rates into ``kk[st]``, the energy rates (input, damping, contact, plastic load,
    hysteretic) into ``ek[st]`` and the contact forces into ``fk[st]``; indices, not views,
    so that no array is reference-counted per call.  ``hlo, hhi``: the modes each yielding
    storey's drift row spans (its building's).
    """
    pin = 0.0
    pd = 0.0
    for j in range(n):
        vj = y[n + j]
        kk[st, j] = vj
        zw = 2.0 * zeta[j] * omega[j]
        kk[st, n + j] = -zw * vj - omega[j] * omega[j] * y[j] - gamma[j] * ag
        pin -= ag * gamma[j] * vj
        pd += zw * vj * vj
    pc = 0.0
    for c in range(gap.size):
        if phase[c] == 0:
            fk[st, c] = 0.0
            continue
        d = -gap[c]
        dd = 0.0
        for j in range(n):
            d += psi[c, j] * y[j]
            dd += psi[c, j] * y[n + j]
        rate[c] = dd
        f = force(model, d, dd, beta[c], cd[c], zhd[c], phase[c])
        fk[st, c] = f
        if f != 0.0:
            pc += f * dd
            for j in range(n):
                kk[st, n + j] -= f * psi[c, j]
    pp = 0.0
    peh = 0.0
    for s in range(hk.size):
        u = 0.0
        du = 0.0
        for j in range(hlo[s], hhi[s]):
            u += hd_[s, j] * y[j]
            du += hd_[s, j] * y[n + j]
        z = y[2 * n + s]
        kp = (1.0 - hal[s]) * hk[s]
        fs = kp * (u - z)
        if fs != 0.0:
            for j in range(hlo[s], hhi[s]):
                kk[st, n + j] += hd_[s, j] * fs
        zd = z_rate(hlaw[s], branch[s], z, du, huy[s], hbw[s])
        kk[st, 2 * n + s] = zd
        pp += fs * du  # the plastic load's power sum_j P_j v_j, storey by storey
        peh += kp * z * (du - zd)
    ek[st, 0] = pin
    ek[st, 1] = pd
    ek[st, 2] = pc
    ek[st, 3] = pp
    ek[st, 4] = peh


@jit
def _dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta, cd, zhd,
             phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, ys, y1, de,
             cimp):  # fmt: skip
    """One Dormand-Prince step of ``hs`` from ``y`` (``kk[0]``, ``ek[0]``, ``fk[0]``: its rates).

    Fills the stages ``kk[1:]`` (``kk[6]`` the rates at the end), the new state ``y1``, the
    energy increments ``de`` and the contact impulses ``cimp``.
    """
    m = y.size
    for st in range(1, 7):
        for i in range(m):
            acc = 0.0
            for r in range(st):
                acc += _A[st, r] * kk[r, i]
            ys[i] = y[i] + hs * acc
        _deriv(ys, ag0 + slope * (s + _C[st] * hs), n, omega, zeta, gamma, psi, gap, beta, cd,
               zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, kk, ek,
               fk, st)  # fmt: skip
    for i in range(m):
        y1[i] = ys[i]  # stage 7 is evaluated at the fifth-order solution (first same as last)
    for r in range(_N_RATES):
        acc = 0.0
        for st in range(6):
            acc += _B[st] * ek[st, r]
        de[r] = hs * acc
    for c in range(cimp.size):
        acc = 0.0
        for st in range(6):
            acc += _B[st] * fk[st, c]
        cimp[c] = hs * acc


@jit
def _error(kk, hs, n, phi_t, flo, fhi, psi, phase, hn, xscale, vscale, huy, dscale, rtol, err_q,
           err_v, xb, xdb):  # fmt: skip
    """Embedded error of a step relative to the tolerance (<= 1: accepted)."""
    for j in range(n):
        eq = 0.0
        ev = 0.0
        for st in range(7):
            eq += _E[st] * kk[st, j]
            ev += _E[st] * kk[st, n + j]
        err_q[j] = hs * eq
        err_v[j] = hs * ev
    matvec_spans(phi_t, err_q, xb, flo, fhi)
    matvec_spans(phi_t, err_v, xdb, flo, fhi)
    worst = 0.0
    for f in range(xb.size):
        worst = max(worst, abs(xb[f]) / (rtol * xscale), abs(xdb[f]) / (rtol * vscale))
    for s in range(hn):
        ez = 0.0
        for st in range(7):
            ez += _E[st] * kk[st, 2 * n + s]
        worst = max(worst, abs(hs * ez) / (rtol * huy[s]))
    for c in range(phase.size):
        if phase[c] != 0:
            worst = max(worst, abs(rowdot(psi, c, err_q)) / (rtol * dscale[c]))
    return worst


@jit(inline=True)
def _storey_rates(y, kk, row, n, hd_, hlo, hhi, s):
    """Drift rate and its rate of yielding storey ``s`` at a state and its rates ``kk[row]``."""
    du = 0.0
    dda = 0.0
    for j in range(hlo[s], hhi[s]):
        du += hd_[s, j] * y[n + j]
        dda += hd_[s, j] * kk[row, n + j]
    return du, dda


@jit
def _first_event(y, y1, q, v, q1, v1, a0, a1, kk, hs, n, psi, psi_t, clo, chi, gap, phase, hd_,
                 hlo, hhi, huy, hlaw, branch, pw0, pw1):  # fmt: skip
    """Earliest switch in a step: ``(time, contact, storey, kind)``; ``(inf, -1, -1, 0)``: none.

    Contacts by :func:`~pound_mc.integrators.adaptive._locate_switch`, plus a grazing onset
    (the penetration rises above 0 and falls back inside the step); storeys by
    :func:`~pound_mc.integrators.storey_laws.storey_event`.  ``q, v, q1, v1, a0, a1``: views
    of the states ``y``, ``y1`` and of the rates ``kk[0]``, ``kk[6]`` at the step's ends.
    """
    t_ev, c_ev, kind = _locate_switch(q, v, q1, v1, a0, a1, psi, psi_t, clo, chi, gap, phase, hs,
                                      pw0, pw1)  # fmt: skip
    for c in range(gap.size):
        if phase[c] != 0:
            continue
        d0 = pw0[c] - gap[c]
        d1 = pw1[c] - gap[c]
        if d0 <= 0.0 and d1 <= 0.0:
            dd0 = rowdot(psi, c, v)
            dd1 = rowdot(psi, c, v1)
            if dd0 > 0.0 and dd1 < 0.0:
                hm, tm = hermite_max(d0, dd0, d1, dd1, hs)
                if hm > 0.0:
                    te = hermite_root(d0, dd0, hm, 0.0, tm)
                    if te < t_ev:
                        t_ev, c_ev, kind = te, c, _ONSET
    s_ev = -1
    for s in range(huy.size):
        du0, dda0 = _storey_rates(y, kk, 0, n, hd_, hlo, hhi, s)
        du1, dda1 = _storey_rates(y1, kk, 6, n, hd_, hlo, hhi, s)
        te = storey_event(hlaw[s], branch[s], y[2 * n + s], y1[2 * n + s], du0, du1, dda0, dda1,
                          huy[s], hs)  # fmt: skip
        if te < t_ev:
            t_ev = te
            s_ev = s
            c_ev = -1
            kind = 0
    return t_ev, c_ev, s_ev, kind


@jit
def _settle(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
            hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, wmax, vscale, fresh):  # fmt: skip
    """Settle every contact phase and storey branch at a step's end; the rates in row 0.

    A located switch leaves the quantity that turned (a penetration rate, a drift rate) within
    round-off of 0: there its rate decides (:data:`DU_TOL`), so that a switch is never undone
    at once (a contact resting at zero gap would otherwise flip between approach and
    restitution for ever).  Contacts: in approach with a falling penetration, restitution; in
    restitution with a rising one, approach; in restitution at or below zero penetration and
    falling, open.  Storeys: :func:`~pound_mc.integrators.storey_laws.settled_branch`.  Also
    catches a turn that a step's end values hid from the event screen.  ``kk[0]`` (and
    ``ek[0]``, ``fk[0]``) hold the rates at ``y`` for the phases as they were; evaluated again
    where one changed, or where ``fresh`` (an event changed them).
    """
    changed = fresh
    if fresh:
        _deriv(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
               hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, 0)  # fmt: skip
    for _ in range(3):
        moved = False
        tol = DU_TOL * vscale
        for c in range(phase.size):
            if phase[c] == 0:
                continue
            d = -gap[c]
            dd = 0.0
            ddd = 0.0
            for j in range(n):
                d += psi[c, j] * y[j]
                dd += psi[c, j] * y[n + j]
                ddd += psi[c, j] * kk[0, n + j]
            way = dd if abs(dd) > tol else ddd
            new = phase[c]
            if phase[c] == 1 and way < 0.0:
                new = 2
            elif phase[c] == 2 and way > 0.0 and d > 0.0:
                new = 1
            if new == 2 and way <= 0.0 and d <= 0.0:
                new = 0
            if new != phase[c]:
                phase[c] = new
                moved = True
        for s in range(huy.size):
            du, dda = _storey_rates(y, kk, 0, n, hd_, hlo, hhi, s)
            b = settled_branch(hlaw[s], branch[s], y[2 * n + s], du, dda, huy[s],
                               DU_TOL * huy[s] * wmax)  # fmt: skip
            if b != branch[s]:
                if hlaw[s] == LAW_BILINEAR and b != 0:
                    y[2 * n + s] = b * huy[s]  # yielding: z on the yield surface
                branch[s] = b
                moved = True
        if not moved:
            return changed
        changed = True
        _deriv(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
               hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, 0)  # fmt: skip
    return changed


@jit(inline=True)
def _storey_peaks(dmat, dlo, dhi, q1, v1, hs, u0, du0, peak_u):
    """Continuous-time peak |drift| of every storey over a step (cubic Hermite); moves on.

    ``dlo, dhi``: the modes each storey's drift row spans.
    """
    for s in range(u0.size):
        u1 = 0.0
        du1 = 0.0
        for j in range(dlo[s], dhi[s]):
            u1 += dmat[s, j] * q1[j]
            du1 += dmat[s, j] * v1[j]
        m = abs(u1)
        if m > peak_u[s]:
            peak_u[s] = m
        if (du0[s] > 0.0) != (du1 > 0.0):
            hm, _ = hermite_max(u0[s], du0[s], u1, du1, hs)
            if hm > peak_u[s]:
                peak_u[s] = hm
            hm, _ = hermite_max(-u0[s], -du0[s], -u1, -du1, hs)
            if hm > peak_u[s]:
                peak_u[s] = hm
        u0[s] = u1
        du0[s] = du1


@jit(inline=True)
def _floor_accels(phi_t, flo, fhi, a1, ag1, peak_acc, xb):
    """Peak absolute floor accelerations at a step's end [m/s^2] (``xb``: scratch per floor)."""
    matvec_spans(phi_t, a1, xb, flo, fhi)
    for f in range(xb.size):
        xa = abs(xb[f] + ag1)
        if xa > peak_acc[f]:
            peak_acc[f] = xa


@jit(inline=True)
def _yielding(store, dmat, n):
    """The yielding storeys' drift rows and constants, and their laws (``storey_laws``)."""
    ns = store.shape[0]
    hn = 0
    for s in range(ns):
        if math.isfinite(store[s, S_YIELD]) and math.isfinite(store[s, S_K]):
            hn += 1
    hd_ = np.empty((hn, n))
    hk = np.empty(hn)
    hal = np.empty(hn)
    huy = np.empty(hn)
    hbw = np.empty(hn)
    hlaw = np.empty(hn, dtype=np.int64)
    r = 0
    for s in range(ns):
        if math.isfinite(store[s, S_YIELD]) and math.isfinite(store[s, S_K]):
            for j in range(n):
                hd_[r, j] = dmat[s, j]
            hk[r] = store[s, S_K]
            hal[r] = store[s, S_ALPHA]
            huy[r] = store[s, S_YIELD]
            hbw[r] = store[s, S_BW]
            hlaw[r] = LAW_BOUC_WEN if store[s, S_BW] > 0.0 else LAW_BILINEAR
            r += 1
    return hd_, hk, hal, huy, hbw, hlaw


@jit(inline=True)
def _initial_state(q, v, hd_, huy, m):
    """The state ``y = [q, v, z]`` (``m`` values) at the start: no plastic drift.

    ``z = u``, the yielding storeys' drifts (rows ``hd_`` in modal coordinates), within their
    yield drifts ``huy``.
    """
    n = q.size
    y = np.empty(m)
    for j in range(n):
        y[j] = q[j]
        y[n + j] = v[j]
    for s in range(huy.size):
        # no plastic drift at the start (z = u, within the yield drift)
        y[2 * n + s] = min(max(rowdot(hd_, s, q), -huy[s]), huy[s])
    return y


@jit(inline=True)
def _error_scales(ag, omega, xf0, xfd0):
    """Scales of the error norm at the start, and the highest circular frequency [rad/s].

    The static displacement and velocity of the record's peak ``ag`` in the most flexible
    mode, raised to the response's own peaks as they come (here: the initial state's floor
    displacements ``xf0`` and velocities ``xfd0``).  Returns ``(xscale, vscale, wmax)``.
    """
    agmax = 0.0
    for i in range(ag.size):
        agmax = max(agmax, abs(ag[i]))
    wmin = np.inf
    wmax = 0.0
    for j in range(omega.size):
        wmin = min(wmin, omega[j])
        wmax = max(wmax, omega[j])
    xscale = max(agmax / (wmin * wmin), 1e-12)
    vscale = max(agmax / wmin, 1e-12)
    for f in range(xf0.size):  # an initial state sets the scale where the ground is still
        xscale = max(xscale, abs(xf0[f]))
        vscale = max(vscale, abs(xfd0[f]))
    return xscale, vscale, wmax


@jit(inline=True)
def _accept(y, y1, y1q, kk, ek, fk, peaks, xfd0, psi, gap, phase, dscale, xscale, vscale):
    """An accepted step: its end (``y1``, the last stage's rates) starts the next step.

    The error scales rise to the response's peaks: the floors' (``peaks``, velocities
    ``xfd0``) and each closed contact's penetration (``dscale``, in place); returns the new
    ``(xscale, vscale)``.
    """
    for f in range(peaks.size):
        xscale = max(xscale, peaks[f])
        vscale = max(vscale, abs(xfd0[f]))
    for c in range(gap.size):
        if phase[c] != 0:
            dscale[c] = max(dscale[c], rowdot(psi, c, y1q) - gap[c])
    for j in range(y.size):
        y[j] = y1[j]
        kk[0, j] = kk[6, j]
    for r in range(_N_RATES):
        ek[0, r] = ek[6, r]
    for c in range(gap.size):
        fk[0, c] = fk[6, c]
    return xscale, vscale


@jit(inline=True)
def _switch(kind, c_ev, s_ev, y, yv, n, psi, xi, beta, meff, zhd, phase, pending, model, relation,
            substeps, dt_rec, settings, cd, ep, dscale, branch, hlaw, huy, h_next):  # fmt: skip
    """The switch at a step's end: of contact ``c_ev`` (``kind``) or of storey ``s_ev``.

    An onset starts an episode (:func:`~pound_mc.integrators.adaptive._open_contact`), whose
    penetration scale starts at its onset velocity times its sub-step and bounds the next step
    ``h_next`` [s]; a storey takes its branch after the switch and its ``z`` in ``y``.
    Returns the next step.
    """
    if c_ev >= 0:
        if kind == _ONSET:
            hc = _open_contact(c_ev, yv, psi, xi, beta, meff, zhd, phase, pending,
                               model, relation, substeps, dt_rec, settings, cd,
                               ep)  # fmt: skip
            dscale[c_ev] = max(1e-15, abs(ep[c_ev, outputs.EP_V0]) * hc)
            h_next = min(h_next, hc)
        elif kind == _TO_RESTITUTION:
            phase[c_ev] = 2
        elif kind == _SEPARATION:
            phase[c_ev] = 0
        else:
            phase[c_ev] = 1
    else:
        branch[s_ev], y[2 * n + s_ev] = storey_switch(
            hlaw[s_ev], branch[s_ev], y[2 * n + s_ev], 0.0, huy[s_ev]
        )
    return h_next


@jit(entry=True)
def adaptive_rk(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """Run one simulation with error-controlled ``adaptive`` steps (module docstring).

    Arguments as :func:`~pound_mc.integrators.hysteretic.newmark_hysteretic`: ``dmat`` the
    storeys' drift rows in modal coordinates, ``store`` the storey table, ``sout`` the storeys'
    peak and final drifts.  The loop keeps its scalar state (energies, clocks, step size) in
    locals across accepted, rejected and cut steps, and works on views without an owner
    (:func:`~pound_mc.integrators.toolkit.borrow`, kept alive by ``owned``), as
    :func:`~pound_mc.integrators.adaptive.adaptive` does.
    """
    model = settings.model
    relation = settings.relation
    substeps = settings.substeps
    n = q.size
    nc = gap.size
    nf = phi.shape[0]
    npts = ag.size
    ns = store.shape[0]
    cd = 2.0 * xi * np.sqrt(beta * meff)
    rtol = tolerance(substeps)
    hd_, hk, hal, huy, hbw, hlaw = _yielding(store, dmat, n)
    hlo, hhi = row_spans(hd_)
    dlo, dhi = row_spans(dmat)
    hn = hk.size
    branch = np.zeros(hn, dtype=np.int64)
    m = 2 * n + hn
    y = _initial_state(q, v, hd_, huy, m)
    kk = np.zeros((7, m))
    ek = np.zeros((7, _N_RATES))
    fk = np.zeros((7, nc))
    ys = np.empty(m)
    y1 = np.empty(m)
    de = np.empty(_N_RATES)
    cimp = np.zeros(nc)
    phase = np.zeros(nc, dtype=np.int64)
    pending = np.zeros(nc, dtype=np.bool_)
    zhd = np.zeros(nc)
    ep, vlog, peak_e = outputs.impact_log(nc)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    peaks = np.zeros(nf)
    phi_t = np.ascontiguousarray(phi.T)
    psi_t = np.ascontiguousarray(psi.T)
    flo, fhi = row_spans(phi_t)
    clo, chi = row_spans(psi_t)
    xf0 = np.empty(nf)
    xfd0 = np.empty(nf)
    for f in range(nf):
        xf0[f] = rowdot(phi, f, q)
        xfd0[f] = rowdot(phi, f, v)
    xb = np.empty(nf)
    xdb = np.empty(nf)
    pw0 = np.empty(nc)
    pw1 = np.empty(nc)
    rate = np.zeros(nc)
    err_q = np.empty(n)
    err_v = np.empty(n)
    u0 = np.empty(ns)
    du0 = np.empty(ns)
    for s in range(ns):
        u0[s] = rowdot(dmat, s, q)
        du0[s] = rowdot(dmat, s, v)
    peak_u = np.zeros(ns)
    peak_acc = np.zeros(nf)
    dscale = np.full(nc, 1e-12)
    # views of the state and of the rates at a step's two ends
    yq, yv, y1q, y1v = y[:n], y[n : 2 * n], y1[:n], y1[n : 2 * n]
    a0v, a1v = kk[0, n : 2 * n], kk[6, n : 2 * n]
    owned = (hd_, hk, hal, huy, hbw, hlaw, hlo, hhi, dlo, dhi, branch, y, kk, ek, fk, ys, y1, de,
             cimp, phase, pending, zhd, ep, peak_e, peaks, phi_t, psi_t, flo, fhi, clo, chi, xf0,
             xfd0, xb, xdb, pw0, pw1, rate, err_q, err_v, u0, du0, peak_u, peak_acc, dscale,
             cd)  # fmt: skip
    hd_, hk, hal, huy, hbw = borrow(hd_), borrow(hk), borrow(hal), borrow(huy), borrow(hbw)
    hlaw, hlo, hhi, dlo, dhi = borrow(hlaw), borrow(hlo), borrow(hhi), borrow(dlo), borrow(dhi)
    branch, y, kk, ek, fk = borrow(branch), borrow(y), borrow(kk), borrow(ek), borrow(fk)
    ys, y1, de, cimp, phase = borrow(ys), borrow(y1), borrow(de), borrow(cimp), borrow(phase)
    pending, zhd, ep, peak_e = borrow(pending), borrow(zhd), borrow(ep), borrow(peak_e)
    peaks, phi_t, psi_t, flo = borrow(peaks), borrow(phi_t), borrow(psi_t), borrow(flo)
    fhi, clo, chi, xf0, xfd0 = borrow(fhi), borrow(clo), borrow(chi), borrow(xf0), borrow(xfd0)
    xb, xdb, pw0, pw1, rate = borrow(xb), borrow(xdb), borrow(pw0), borrow(pw1), borrow(rate)
    err_q, err_v, u0, du0 = borrow(err_q), borrow(err_v), borrow(u0), borrow(du0)
    peak_u, peak_acc, dscale, cd = borrow(peak_u), borrow(peak_acc), borrow(dscale), borrow(cd)
    yq, yv, y1q, y1v = borrow(yq), borrow(yv), borrow(y1q), borrow(y1v)
    a0v, a1v = borrow(a0v), borrow(a1v)
    fk0, fk6 = borrow(fk[0]), borrow(fk[6])
    ag, omega, zeta, gamma = borrow(ag), borrow(omega), borrow(zeta), borrow(gamma)
    phi, psi, gap, dmat = borrow(phi), borrow(psi), borrow(gap), borrow(dmat)
    xscale, vscale, wmax = _error_scales(ag, omega, xf0, xfd0)
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    w_p = 0.0
    e_h = 0.0
    e0 = mechanical_energy(q, v, omega)
    _settle(y, ag[0], n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
            hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, wmax, vscale, True)  # fmt: skip
    h_try = min(settings.dt_s, dt_rec, 0.05 * 2.0 * math.pi / wmax)
    peak_f = 0.0
    peak_t = 0.0
    steps = 0
    status = outputs.STATUS_OK
    store_h = hx.shape[0] > 0
    outputs.reset_contacts(cout)
    # steps allowed (accepted, rejected and cut): absurd parameters give up instead of running
    # for ever, and say so
    budget = 200 * (npts - 1) + 2_000_000
    tries = 0
    for i in range(npts - 1):
        if store_h:
            _store_history(i, yq, yv, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf)
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) / dt_rec
        s = 0.0
        rejects = 0
        while s < dt_rec * (1.0 - 1e-12):
            tries += 1
            if tries > budget:
                status = outputs.STATUS_NOT_CONVERGED
                break
            room = dt_rec - s
            hs = h_try
            if hs >= room or room - hs < 1e-3 * hs:
                hs = room
            _dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta, cd,
                     zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, ys,
                     y1, de, cimp)  # fmt: skip
            err = _error(kk, hs, n, phi_t, flo, fhi, psi, phase, hn, xscale, vscale, huy, dscale,
                         rtol, err_q, err_v, xb, xdb)  # fmt: skip
            if not (err <= 1.0):
                rejects += 1
                if rejects > _MAX_REJECTS or not (hs > 1e-300):
                    status = outputs.STATUS_NOT_CONVERGED
                    break
                h_try = hs * (_SHRINK_MIN if not math.isfinite(err) else
                              max(_SHRINK_MIN, _SAFETY * err ** -0.2))  # fmt: skip
                continue
            h_next = hs * (_GROW_MAX if err == 0.0 else min(_GROW_MAX, _SAFETY * err**-0.2))
            t_ev, c_ev, s_ev, kind = _first_event(y, y1, yq, yv, y1q, y1v, a0v, a1v, kk, hs, n,
                                                  psi, psi_t, clo, chi, gap, phase, hd_, hlo,
                                                  hhi, huy, hlaw, branch, pw0, pw1)  # fmt: skip
            switch = c_ev >= 0 or s_ev >= 0
            if switch and t_ev < hs:
                hs = t_ev
                _dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta,
                         cd, zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch,
                         rate, ys, y1, de, cimp)  # fmt: skip
            steps += 1
            e_in += de[0]
            e_d += de[1]
            w_c += de[2]
            w_p += de[3]
            e_h += de[4]
            t = i * dt_rec + s
            peak_f, peak_t, nlog = _contact_peaks(
                yq, yv, y1q, y1v, a0v, a1v, psi, gap, beta, cd, zhd, phase, model, fk0, fk6, cimp,
                cout, pending, hs, t, peak_f, peak_t, ep, logs, nlog, peak_e,
            )  # fmt: skip
            track_floors(phi_t, flo, fhi, xf0, xfd0, y1q, y1v, hs, peaks, xb, xdb)
            _storey_peaks(dmat, dlo, dhi, y1q, y1v, hs, u0, du0, peak_u)
            _floor_accels(phi_t, flo, fhi, a1v, ag0 + slope * (s + hs), peak_acc, xb)
            xscale, vscale = _accept(y, y1, y1q, kk, ek, fk, peaks, xfd0, psi, gap, phase, dscale,
                                     xscale, vscale)  # fmt: skip
            s += hs
            fresh = False
            if switch and t_ev <= hs:
                fresh = True
                h_next = _switch(kind, c_ev, s_ev, y, yv, n, psi, xi, beta, meff, zhd, phase,
                                 pending, model, relation, substeps, dt_rec, settings, cd, ep,
                                 dscale, branch, hlaw, huy, h_next)  # fmt: skip
            # every step's end: a switch, or a turn the end values hid, settled (no Zeno)
            _settle(y, ag0 + slope * s, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase,
                    model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, wmax,
                    vscale, fresh)  # fmt: skip
            h_try = h_next
            if not _finite(y):
                status = outputs.STATUS_UNSTABLE
                break
        if status != outputs.STATUS_OK:
            break
    for j in range(n):
        q[j] = y[j]
        v[j] = y[n + j]
    if store_h and status == outputs.STATUS_OK:
        _store_history(npts - 1, q, v, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf)
    stored_energy = _stored_energy(q, psi, gap, beta, phase, model)
    drift = np.empty(ns)
    for s in range(ns):
        drift[s] = rowdot(dmat, s, q)
    outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d - w_p, w_c,
                   stored_energy, peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
    storey_outputs(out, store, peak_u, drift, peak_acc, side, e_h, sout)
    _alive(owned)


@jit
def _finite(y):
    """Whether every state variable is finite."""
    for j in range(y.size):
        if not math.isfinite(y[j]):
            return False
    return True


@jit
def _alive(owned):
    """A use of ``owned`` (the kernel's scratch arrays) that keeps them alive to here."""
    return len(owned)
