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

While every contact is open and every yielding storey is bilinear and elastic, the equations
are those of the initial elastic modes under a constant plastic load: such a spell is stepped
exactly (:mod:`~pound_mc.integrators.elastic_spells`; no truncation error, a sixth of a
Runge-Kutta step's cost), in equal steps of a share of the shortest period, up to a step that
may hold a contact onset or a yield, from which the Runge-Kutta steps take over and locate it.
Everywhere else, steps (Dormand & Prince 1980, the 5(4) pair with its first-same-as-last
stage, as SciPy's ``RK45``: :mod:`~pound_mc.integrators.dormand_prince`) are chosen by the
embedded error estimate: the error of every floor's displacement
and velocity is held under :func:`tolerance` of the response's scale (the largest floor
displacement so far, or the static displacement of the record's peak in the most flexible
mode), every yielding storey's ``z`` under it times its yield drift, and every closed contact's
penetration under it times the episode's deepest penetration, so that short contacts and
near-yield storeys take the steps they need and quiet stretches long ones.  Every step ends on
the record's samples (the ground acceleration has kinks there), and on the spells' grid
while the equations are linear; ``dt_s`` is only the first step's length, since the error
estimate bounds every step.  Every switch is located inside
the step that holds it, on the cubic Hermite
interpolant of the quantity and its rate, and the step is taken again up to it: contact onset
(grazing ones included), approach -> restitution, separation and restitution -> approach, and
each storey's branch (yield, unloading).  Inside every step the right-hand side is smooth.

Peak force, penetration, floor displacements and storey drifts are continuous-time maxima
(cubic Hermite on each step); floor accelerations are maxima over the steps' ends.  The
energies (input, damping, contact work, the plastic load's work and the hysteretic
dissipation) are integrated with the state, at its order (in a spell, exactly).  The run's
``steps`` count the exact steps and the accepted Runge-Kutta steps.
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
    _hermite_tolerance,
    _locate_switch,
    _open_contact,
    _store_history,
)
from pound_mc.integrators.dormand_prince import N_RATES, dp_step, error_norm, rates
from pound_mc.integrators.elastic_spells import (
    SPELL_CHUNK,
    exact_spell,
    spell_ready,
    spell_steps,
)
from pound_mc.integrators.hysteretic import S_ALPHA, S_BW, S_K, S_YIELD, storey_outputs
from pound_mc.integrators.laws import stored
from pound_mc.integrators.storey_laws import (
    LAW_BILINEAR,
    LAW_BOUC_WEN,
    settled_branch,
    storey_event,
    storey_switch,
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

#: Relative tolerance of the embedded error at the default 16 ``substeps``; it scales as
#: ``(16 / substeps)^2``, so that the accuracy check's run (twice the sub-steps) is held to a
#: quarter of it.
RTOL_DEFAULT = 1e-9
_SUBSTEPS_DEFAULT = 16.0
#: Step growth after an accepted step is at most this factor, and a rejected step shrinks by
#: at least ``_SHRINK_MIN``; safety factor of the step-size rule ``h (1 / err)^(1/5)``.
_GROW_MAX, _SHRINK_MIN, _SAFETY = 5.0, 0.2, 0.9
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


@jit(inline=True)
def _storey_rates(y, kk, row, n, hd_, hlo, hhi, s):
    """Drift rate and its rate of yielding storey ``s`` at a state and its rates ``kk[row]``."""
    du = 0.0
    dda = 0.0
    for j in range(hlo[s], hhi[s]):
        du += hd_[s, j] * y[n + j]
        dda += hd_[s, j] * kk[row, n + j]
    return du, dda


@jit(llvm_inline=True)
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


@jit(llvm_inline=True)
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
        rates(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
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
        rates(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi,
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
    """The yielding storeys' drift rows and constants, their laws (``storey_laws``) and rows."""
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
    hrow = np.empty(hn, dtype=np.int64)
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
            hrow[r] = s
            r += 1
    return hd_, hk, hal, huy, hbw, hlaw, hrow


@jit(inline=True)
def _scales(ag, omega, xf0, xfd0):
    """Scales of the error norm at the start, and the largest ``omega``.

    The static displacement and velocity of the record's peak in the most flexible mode, or
    the initial state's floor displacements and velocities where larger (a still ground);
    raised to the response's own peaks as they come.
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
    for f in range(xf0.size):
        xscale = max(xscale, abs(xf0[f]))
        vscale = max(vscale, abs(xfd0[f]))
    return xscale, vscale, wmax


@jit(llvm_inline=True)
def _accept(y, y1, kk, ek, fk, de, en, yq, yv, y1q, y1v, a0v, a1v, fk0, fk6, cimp, psi, gap,
            beta, cd, zhd, phase, model, cout, pending, hs, t, ag1, peak_f, peak_t, ep, logs,
            nlog, peak_e, phi_t, flo, fhi, xf0, xfd0, peaks, xb, xdb, dmat, dlo, dhi, u0, du0,
            peak_u, peak_acc, dscale, xscale, vscale):  # fmt: skip
    """An accepted step's outputs and scales; the step's end becomes the next one's start.

    Adds the energy increments ``de`` into ``en`` (input, damping, contact, plastic load,
    hysteretic); returns the peak force, its time, the impact log's count and the error
    norm's scales.
    """
    for r in range(N_RATES):
        en[r] += de[r]
    peak_f, peak_t, nlog = _contact_peaks(
        yq, yv, y1q, y1v, a0v, a1v, psi, gap, beta, cd, zhd, phase, model, fk0, fk6, cimp,
        cout, pending, hs, t, peak_f, peak_t, ep, logs, nlog, peak_e,
    )  # fmt: skip
    track_floors(phi_t, flo, fhi, xf0, xfd0, y1q, y1v, hs, peaks, xb, xdb)
    _storey_peaks(dmat, dlo, dhi, y1q, y1v, hs, u0, du0, peak_u)
    _floor_accels(phi_t, flo, fhi, a1v, ag1, peak_acc, xb)
    for f in range(peaks.size):
        xscale = max(xscale, peaks[f])
        vscale = max(vscale, abs(xfd0[f]))
    for c in range(gap.size):
        if phase[c] != 0:
            dscale[c] = max(dscale[c], rowdot(psi, c, y1q) - gap[c])
    for j in range(y.size):
        y[j] = y1[j]
        kk[0, j] = kk[6, j]
    for r in range(N_RATES):
        ek[0, r] = ek[6, r]
    for c in range(gap.size):
        fk[0, c] = fk[6, c]
    return peak_f, peak_t, nlog, xscale, vscale


@jit(inline=True)
def _switch(c_ev, s_ev, kind, y, n, yv, psi, xi, beta, meff, zhd, phase, pending, model,
            relation, substeps, dt_rec, settings, cd, ep, dscale, hlaw, branch, huy,
            h_next):  # fmt: skip
    """Apply a located switch at the step's end (a contact's phase, a storey's branch).

    Returns the next step's length, bounded at an onset by the contact's duration.
    """
    if c_ev >= 0:
        if kind == _ONSET:
            hc = _open_contact(c_ev, yv, psi, xi, beta, meff, zhd, phase, pending, model,
                               relation, substeps, dt_rec, settings, cd, ep)  # fmt: skip
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


@jit(inline=True)
def _start(q, v, n, hd_, huy, phi, dmat, y, xf0, xfd0, u0, du0, dscale):
    """The initial state ``y`` and the floors', storeys' and contacts' values at the start."""
    for j in range(n):
        y[j] = q[j]
        y[n + j] = v[j]
    for s in range(huy.size):
        # no plastic drift at the start (z = u, within the yield drift)
        y[2 * n + s] = min(max(rowdot(hd_, s, q), -huy[s]), huy[s])
    for f in range(xf0.size):
        xf0[f] = rowdot(phi, f, q)
        xfd0[f] = rowdot(phi, f, v)
    for s in range(u0.size):
        u0[s] = rowdot(dmat, s, q)
        du0[s] = rowdot(dmat, s, v)
    for c in range(dscale.size):
        dscale[c] = 1e-12


@jit
def _finish(q, v, y, n, store_h, npts, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf,
            dmat, out, cout, peaks, side, omega, e0, en, peak_f, peak_t, steps, status, logs,
            nlog, peak_e, store, peak_u, peak_acc, sout):  # fmt: skip
    """The end state into ``q, v``, the last history sample and every output of the run."""
    for j in range(n):
        q[j] = y[j]
        v[j] = y[n + j]
    if store_h and status == outputs.STATUS_OK:
        _store_history(npts - 1, q, v, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf)
    stored_energy = 0.0
    for c in range(gap.size):
        if phase[c] != 0:
            stored_energy += stored(model, rowdot(psi, c, q) - gap[c], beta[c])
    drift = np.empty(dmat.shape[0])
    for s in range(drift.size):
        drift[s] = rowdot(dmat, s, q)
    # the plastic load's work enters the balance as a negative damping work
    outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, en[0], en[1] - en[3], en[2],
                   stored_energy, peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
    storey_outputs(out, store, peak_u, drift, peak_acc, side, en[4], sout)


@jit(entry=True)
def adaptive_rk(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """Run one simulation with error-controlled ``adaptive`` steps (module docstring).

    Arguments as :func:`~pound_mc.integrators.hysteretic.newmark_hysteretic`: ``dmat`` the
    storeys' drift rows in modal coordinates, ``store`` the storey table, ``sout`` the storeys'
    peak and final drifts.  One loop (within the 200-line limit) keeps its scalar state
    (energies, clocks, step size) in locals across accepted, rejected and cut steps.  The loop
    works on views without an owner (:func:`~pound_mc.integrators.toolkit.borrow`, kept alive
    by ``owned``), as :func:`~pound_mc.integrators.adaptive.adaptive` does.
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
    hd_, hk, hal, huy, hbw, hlaw, hrow = _yielding(store, dmat, n)
    hn = hk.size
    m = 2 * n + hn
    m_lin, h_lin, coef = spell_steps(omega, zeta, dt_rec, substeps)
    phi_t = np.ascontiguousarray(phi.T)
    psi_t = np.ascontiguousarray(psi.T)
    hlo, hhi = row_spans(hd_)
    dlo, dhi = row_spans(dmat)
    flo, fhi = row_spans(phi_t)
    clo, chi = row_spans(psi_t)
    branch = np.zeros(hn, dtype=np.int64)
    phase = np.zeros(nc, dtype=np.int64)
    pending = np.zeros(nc, dtype=np.bool_)
    ep, vlog, peak_e = outputs.impact_log(nc)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    # scratch, a row each: the state, its stage and end; the energies and their increments;
    # per contact, per floor, per storey and per mode
    sm = np.zeros((3, m))
    kk = np.zeros((7, m))
    ek = np.zeros((7, N_RATES))
    fk = np.zeros((7, nc))
    se = np.zeros((2, N_RATES))
    sc = np.zeros((8, nc))
    sf = np.zeros((6, nf))
    ss = np.zeros((5, ns))
    sn = np.zeros((3, n))
    ybuf = np.empty((SPELL_CHUNK, 2 * n))
    cand = np.empty((2 * SPELL_CHUNK * (nf + ns), 3), dtype=np.int64)
    ctg = np.empty(2 * SPELL_CHUNK * (nf + ns))
    owned = (hd_, hk, hal, huy, hbw, hlaw, hrow, coef, phi_t, psi_t, hlo, hhi, dlo, dhi, flo, fhi,
             clo, chi, branch, phase, pending, ep, peak_e, sm, kk, ek, fk, se, sc, sf, ss, sn, ybuf,
             cand, ctg, cd)  # fmt: skip
    hd_, hk, hal, huy, hbw = borrow(hd_), borrow(hk), borrow(hal), borrow(huy), borrow(hbw)
    hlaw, hrow, coef, phi_t = borrow(hlaw), borrow(hrow), borrow(coef), borrow(phi_t)
    psi_t, hlo, hhi, dlo, dhi = borrow(psi_t), borrow(hlo), borrow(hhi), borrow(dlo), borrow(dhi)
    flo, fhi, clo, chi = borrow(flo), borrow(fhi), borrow(clo), borrow(chi)
    branch, phase, pending, ep = borrow(branch), borrow(phase), borrow(pending), borrow(ep)
    peak_e, sm, kk, ek, fk = borrow(peak_e), borrow(sm), borrow(kk), borrow(ek), borrow(fk)
    se, sc, sf, ss, sn = borrow(se), borrow(sc), borrow(sf), borrow(ss), borrow(sn)
    ybuf, cand, ctg, cd = borrow(ybuf), borrow(cand), borrow(ctg), borrow(cd)
    ag, omega, zeta, gamma = borrow(ag), borrow(omega), borrow(zeta), borrow(gamma)
    phi, psi, gap, dmat = borrow(phi), borrow(psi), borrow(gap), borrow(dmat)
    # views of the scratch (without an owner, as the arrays they view)
    y, ys, y1 = sm[0], sm[1], sm[2]
    de, en = se[0], se[1]  # en: input, damping, contact, plastic load, hysteretic [J/kg]
    cimp, zhd, pw0, pw1 = sc[0], sc[1], sc[2], sc[3]
    pv0, pv1, rate, dscale = sc[4], sc[5], sc[6], sc[7]
    peaks, xf0, xfd0, xb, xdb, peak_acc = sf[0], sf[1], sf[2], sf[3], sf[4], sf[5]
    u0, du0, ub, dub, peak_u = ss[0], ss[1], ss[2], ss[3], ss[4]
    err_q, err_v, pl = sn[0], sn[1], sn[2]
    # and of the state and of the rates at a step's two ends
    yq, yv, y1q, y1v = y[:n], y[n : 2 * n], y1[:n], y1[n : 2 * n]
    a0v, a1v, fk0, fk6 = kk[0, n : 2 * n], kk[6, n : 2 * n], fk[0], fk[6]
    _start(q, v, n, hd_, huy, phi, dmat, y, xf0, xfd0, u0, du0, dscale)
    herm_tol = _hermite_tolerance(omega, h_lin)
    xscale, vscale, wmax = _scales(ag, omega, xf0, xfd0)
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
        k_grid = 0  # s is the spells' grid point k_grid (-1: off the grid)
        s_block = -1.0  # a spell that stopped here: the Runge-Kutta steps go on from here
        while s < dt_rec * (1.0 - 1e-12):
            linear = spell_ready(phase, branch, hlaw)
            if linear and k_grid >= 0 and s > s_block:
                k0 = k_grid
                s, k_grid, blocked, xmax, vmax = exact_spell(
                    y, y1, yq, yv, y1q, y1v, err_q, n, coef, k_grid, m_lin, h_lin, dt_rec, ag0,
                    slope, pl, omega, zeta, gamma, phi, phi_t, flo, fhi, psi_t, clo, chi, gap,
                    pw0, pw1, pv0, pv1, hd_, hlo, hhi, hk, hal, huy, hrow, dmat, dlo, dhi, xf0,
                    xfd0, u0, du0, ub, dub, peaks, peak_u, peak_acc, xb, xdb, herm_tol, ybuf, cand,
                    ctg, en,
                )  # fmt: skip
                steps += k_grid - k0
                xscale = max(xscale, xmax)
                vscale = max(vscale, vmax)
                if not _finite(y):
                    status = outputs.STATUS_UNSTABLE
                    break
                if blocked:  # the Runge-Kutta steps take over: the rates at the state
                    rates(y, ag0 + slope * s, n, omega, zeta, gamma, psi, gap, beta, cd, zhd,
                          phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate,
                          kk, ek, fk, 0)  # fmt: skip
                    h_try = min(h_try, h_lin)
                    s_block = s
                continue
            tries += 1
            if tries > budget:
                status = outputs.STATUS_NOT_CONVERGED
                break
            # while the equations are linear, the step ends on the spells' next grid point
            g = m_lin
            if linear:
                g = min(int(math.floor(s / h_lin + 1e-9)) + 1, m_lin)
            s_end = dt_rec if g == m_lin else g * h_lin
            room = s_end - s
            hs = h_try
            if hs >= room or room - hs < 1e-3 * hs:
                hs = room
            dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta, cd,
                    zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, ys,
                    y1, de, cimp)  # fmt: skip
            err = error_norm(kk, hs, n, phi_t, flo, fhi, psi, phase, hn, xscale, vscale, huy,
                             dscale, rtol, err_q, err_v, xb, xdb)  # fmt: skip
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
                dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta,
                        cd, zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch,
                        rate, ys, y1, de, cimp)  # fmt: skip
            steps += 1
            peak_f, peak_t, nlog, xscale, vscale = _accept(
                y, y1, kk, ek, fk, de, en, yq, yv, y1q, y1v, a0v, a1v, fk0, fk6, cimp, psi, gap,
                beta, cd, zhd, phase, model, cout, pending, hs, i * dt_rec + s,
                ag0 + slope * (s + hs), peak_f, peak_t, ep, logs, nlog, peak_e, phi_t, flo, fhi,
                xf0, xfd0, peaks, xb, xdb, dmat, dlo, dhi, u0, du0, peak_u, peak_acc, dscale,
                xscale, vscale,
            )  # fmt: skip
            s += hs
            k_grid = -1
            if hs == room:  # not cut by a switch: on the grid point (or the interval's end)
                s = s_end
                k_grid = g
            fresh = switch and t_ev <= hs
            if fresh:
                h_next = _switch(c_ev, s_ev, kind, y, n, yv, psi, xi, beta, meff, zhd, phase,
                                 pending, model, relation, substeps, dt_rec, settings, cd, ep,
                                 dscale, hlaw, branch, huy, h_next)  # fmt: skip
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
    _finish(q, v, y, n, store_h, npts, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf,
            dmat, out, cout, peaks, side, omega, e0, en, peak_f, peak_t, steps, status, logs,
            nlog, peak_e, store, peak_u, peak_acc, sout)  # fmt: skip
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
