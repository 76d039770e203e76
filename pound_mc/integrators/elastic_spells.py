"""Exact steps of :mod:`~pound_mc.integrators.adaptive_rk` while its equations are linear.

While every contact is open and every yielding storey is bilinear and on its elastic branch
(``z' = u'``), each storey's plastic drift ``u - z`` is constant, and so is the plastic load
``P = sum_s D_s f_s`` (``f_s = (1 - alpha_s) k_s (u_s - z_s)``): the modes are those of the
initial elastic buildings under a load linear in time over each record interval,

``q_j'' + 2 zeta_j omega_j q_j' + omega_j^2 q_j = -gamma_j a_g(t) + P_j``,

which the exact (Nigam-Jennings) step of :func:`~pound_mc.integrators.toolkit.advance` solves
without truncation error.  Such a *spell* is stepped exactly on a grid of equal steps that
divide each record interval, :data:`~pound_mc.integrators.bounds.LINEAR_STEPS_PER_PERIOD` or
more per shortest modal period (``z`` follows the drift: ``z_1 = z_0 + u_1 - u_0``).  A step
that may hold a switch is not taken: one that ends a contact's penetration or a storey's
``|z| - u_y`` above 0, or where the cubic Hermite maximum of either comes within the margin of
:func:`~pound_mc.integrators.toolkit.turning_screen` of 0 (a grazing touch, a grazing yield).
The error-controlled Runge-Kutta steps then take over from that step's start and locate the
switch as everywhere else, and hand back at the first grid point where the equations are
linear again: the screen only decides who steps, never where a switch is.

Over an exact step the floor displacements and storey drifts are continuous-time maxima (cubic
Hermite; where its maximum comes within its error bound of a peak, the maximum of the exact
solution, by safeguarded Newton on the rate), the floor accelerations maxima over the steps'
ends, as in the Runge-Kutta steps.  The energies are exact: with ``p = -gamma a_g + P``,
``int q = (int p - dv - 2 zeta omega dq) / omega^2`` (the equation of motion integrated),
``int t v = h q_1 - int q``, the input energy ``-gamma int a_g v`` follows, the plastic load's
work is ``P dq`` and the damping energy is ``int p v`` less the change of the mode's
mechanical energy (its energy balance); the hysteretic dissipation does not move.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators.bounds import LINEAR_STEPS_PER_PERIOD
from pound_mc.integrators.storey_laws import LAW_BILINEAR, YIELD_TOL
from pound_mc.integrators.toolkit import (
    advance,
    coefficients,
    hermite_max,
    matvec_spans,
    newton_in_bracket,
    turning_screen,
)

__all__ = ["SPELL_CHUNK", "spell_ready", "spell_steps", "exact_spell"]

#: Exact steps of one call of :func:`exact_spell` at most (the kernel calls it again from the
#: grid point it reached): its buffers for the peaks' candidates hold this many steps, whatever
#: the steps per record interval (a stiff building's, hundreds).
SPELL_CHUNK = 16
#: The time of an interior maximum is found to this share of the step: the maximum's value
#: is off by about the square of it times ``(omega h)^2``, far below round-off.
_MAX_TIME_TOL = 1e-10
#: The exact steps' share of the default sub-steps (``16 / substeps``, at most 1): the
#: accuracy check's run (twice the sub-steps) screens its spells on steps half as long.
_SUBSTEPS_DEFAULT = 16.0


@jit(inline=True)
def spell_ready(phase, branch, hlaw):
    """Whether the equations are linear: every contact open, every storey bilinear, elastic."""
    for c in range(phase.size):
        if phase[c] != 0:
            return False
    for s in range(branch.size):
        if branch[s] != 0 or hlaw[s] != LAW_BILINEAR:
            return False
    return True


@jit
def spell_steps(omega, zeta, dt_rec, substeps):
    """Exact steps per record interval, their length [s] and coefficients (modes x 2 x 4).

    At most ``1 / LINEAR_STEPS_PER_PERIOD`` of the shortest modal period (scaled by
    ``16 / substeps`` where that is below 1), equal steps that divide the interval.
    """
    wmax = 0.0
    for j in range(omega.size):
        wmax = max(wmax, omega[j])
    h = dt_rec
    if wmax > 0.0:
        share = min(1.0, _SUBSTEPS_DEFAULT / max(substeps, 1))
        h = min(dt_rec, 2.0 * math.pi / wmax / LINEAR_STEPS_PER_PERIOD * share)
    m_lin = max(1, int(math.ceil(dt_rec / h - 1e-9)))
    h = dt_rec / m_lin
    coef = np.empty((omega.size, 2, 4))
    for j in range(omega.size):
        coef[j] = coefficients(omega[j], zeta[j], h)
    return m_lin, h, coef


@jit
def _exact_row(y, n, pl, agb, slope, tau, rows, r, sign, omega, zeta, gamma):
    """``sign rows[r] q`` and its first two rates at ``tau`` into an exact step from ``y``."""
    x = 0.0
    xd = 0.0
    xdd = 0.0
    ag = agb + slope * tau
    for j in range(n):
        w = rows[r, j]
        if w == 0.0:
            continue  # e.g. the other building's modes
        p1 = -gamma[j] * ag + pl[j]
        qm, vm = advance(y[j], y[n + j], -gamma[j] * agb + pl[j], p1, omega[j], zeta[j], tau)
        x += w * qm
        xd += w * vm
        xdd += w * (p1 - 2.0 * zeta[j] * omega[j] * vm - omega[j] * omega[j] * qm)
    return sign * x, sign * xd, sign * xdd


@jit
def _exact_max(y, n, pl, agb, slope, hh, guess, rows, r, sign, omega, zeta, gamma):
    """Interior maximum of ``sign rows[r] q`` over an exact step whose rate turns + to -."""
    lo = 0.0
    hi = hh
    t = guess if 0.0 < guess < hh else 0.5 * hh
    for _ in range(60):
        x, xd, xdd = _exact_row(y, n, pl, agb, slope, t, rows, r, sign, omega, zeta, gamma)
        t, lo, hi, done = newton_in_bracket(t, x, xd, xdd, 1, lo, hi, _MAX_TIME_TOL)
        if done:
            break
    x, _, _ = _exact_row(y, n, pl, agb, slope, t, rows, r, sign, omega, zeta, gamma)
    return x


@jit(inline=True)
def _step_peak(peak, x0, xd0, x1, xd1, hh, herm_tol, cand, ctg, nca, k, code):
    """``peak`` raised to ``|x|`` at an exact step's end; its interior maxima as candidates.

    Where the rate turns and the cubic Hermite maximum comes within ``herm_tol`` of ``peak``,
    the step ``k``, the row ``code`` and the sign go into ``cand`` (the Hermite time into
    ``ctg``) for :func:`_refine_peaks`.  Returns the peak and the count of candidates.
    """
    m = abs(x1)
    if m > peak:
        peak = m
    if (xd0 > 0.0) != (xd1 > 0.0):
        for sg in (1, -1):
            hm, tg = hermite_max(sg * x0, sg * xd0, sg * x1, sg * xd1, hh)
            if hm > peak - herm_tol * abs(hm):
                cand[nca, 0] = k
                cand[nca, 1] = code
                cand[nca, 2] = sg
                ctg[nca] = tg
                nca += 1
    return peak, nca


@jit
def _refine_peaks(cand, ctg, nca, ybuf, k0, m_lin, h_lin, dt_rec, n, pl, ag0, slope, phi, dmat,
                  omega, zeta, gamma, peaks, peak_u):  # fmt: skip
    """The candidates' maxima on the exact solution (:func:`_step_peak`), into the peaks.

    Kept out of the steps' loop: the call there, even where never taken, made the whole 3+5
    pair's run a fifth slower (the code the compiler made of the loop around it).
    """
    nf = peaks.size
    for i in range(nca):
        k = cand[i, 0]
        code = cand[i, 1]
        s = k * h_lin
        hh = (dt_rec if k == m_lin - 1 else (k + 1) * h_lin) - s
        y = ybuf[k - k0]
        rows = phi if code < nf else dmat
        r = code if code < nf else code - nf
        xm = _exact_max(y, n, pl, ag0 + slope * s, slope, hh, ctg[i], rows, r,
                        float(cand[i, 2]), omega, zeta, gamma)  # fmt: skip
        if code < nf:
            peaks[r] = max(peaks[r], xm)
        else:
            peak_u[r] = max(peak_u[r], xm)


@jit(inline=True)
def _energies(y, y1, n, pl, agb, slope, hh, omega, zeta, gamma, en):
    """Input energy, damping energy and the plastic load's work of an exact step, into ``en``.

    ``en``: the kernel's energies per unit modal mass (input, damping, contact, plastic load,
    hysteretic) [J/kg].
    """
    de_in = 0.0
    de_d = 0.0
    dw_p = 0.0
    for j in range(n):
        w2 = omega[j] * omega[j]
        dq = y1[j] - y[j]
        dv = y1[n + j] - y[n + j]
        ip = -gamma[j] * (agb * hh + 0.5 * slope * hh * hh) + pl[j] * hh  # int p
        iq = (ip - dv - 2.0 * zeta[j] * omega[j] * dq) / w2  # int q
        iagv = agb * dq + slope * (hh * y1[j] - iq)  # int a_g v
        ipv = -gamma[j] * iagv + pl[j] * dq  # int p v
        de_mech = 0.5 * (dv * (y1[n + j] + y[n + j]) + w2 * dq * (y1[j] + y[j]))
        de_in -= gamma[j] * iagv
        de_d += ipv - de_mech
        dw_p += pl[j] * dq
    en[0] += de_in
    en[1] += de_d
    en[3] += dw_p


@jit(inline=True)
def _may_switch(y, y1, n, gap, pw0, pv0, pw1, pv1, u0, du0, u1, du1, hrow, huy, hh):
    """Whether an exact step may hold a contact onset or a yield (module docstring).

    ``pw, pv``: every contact's penetration (plus its gap) and rate, ``u, du``: every storey's
    drift and rate, at the step's start (0) and end (1); ``hrow``: the yielding storeys' rows.
    Writes the yielding storeys' ``z`` at the step's end into ``y1`` (``z`` follows the drift).
    """
    for c in range(gap.size):
        d1 = pw1[c] - gap[c]
        if d1 > 0.0:
            return True
        look, _ = turning_screen(pw0[c] - gap[c], pv0[c], d1, pv1[c], hh)
        if look:
            return True
    for s in range(huy.size):
        r = hrow[s]
        z0 = y[2 * n + s]
        z1 = z0 + (u1[r] - u0[r])
        y1[2 * n + s] = z1
        lim = huy[s] * (1.0 + YIELD_TOL)
        for sg in (1.0, -1.0):
            e0 = sg * z0 - lim
            e1 = sg * z1 - lim
            if e0 > 0.0 or e1 > 0.0:
                return True
            look, _ = turning_screen(e0, sg * du0[r], e1, sg * du1[r], hh)
            if look:
                return True
    return False


@jit
def exact_spell(
    y, y1, q, v, q1, v1, a1, n, coef, k0, m_lin, h_lin, dt_rec, ag0, slope, pl, omega, zeta, gamma,
    phi, phi_t, flo, fhi, psi_t, clo, chi, gap, pw0, pw1, pv0, pv1, hd_, hlo, hhi, hk, hal, huy,
    hrow, dmat, dlo, dhi, xf0, xfd0, u0, du0, ub, dub, peaks, peak_u, peak_acc, xb, xdb, herm_tol,
    ybuf, cand, ctg, en,
):  # fmt: skip
    """Exact steps from grid point ``k0`` of a record interval, up to one that may switch.

    The interval (``dt_rec`` [s], ground acceleration ``ag0 + slope t``) has ``m_lin`` steps
    of ``h_lin`` (coefficients ``coef``, :func:`spell_steps`); :data:`SPELL_CHUNK` of them at
    most are taken.  ``y, y1``: the state ``(q, v,
    z)`` and scratch for a step's end (``q, v, q1, v1``: their views); scratch: ``a1``, ``pl``
    (the plastic load) one value per mode, ``pw0, pw1, pv0, pv1`` per contact, ``ub, dub`` per
    storey, ``ybuf, cand, ctg`` for the peaks' candidates (``SPELL_CHUNK`` states, twice that
    times floors and storeys candidates: :func:`_step_peak`).  Moves the floors' and storeys'
    values at a step's start (``xf0, xfd0, u0, du0``) on and raises the peaks as the
    Runge-Kutta steps do; adds the energies into ``en`` (:func:`_energies`).  Returns the
    local time reached [s] (``dt_rec``: the interval's end), its grid point, whether the next
    step may switch (the Runge-Kutta steps take over there), the largest floor peak and the
    largest floor speed at the steps' ends (the error norm's scales).
    """
    for j in range(n):
        pl[j] = 0.0
    for s in range(huy.size):
        u = 0.0
        for j in range(hlo[s], hhi[s]):
            u += hd_[s, j] * y[j]
        fs = (1.0 - hal[s]) * hk[s] * (u - y[2 * n + s])
        if fs != 0.0:
            for j in range(hlo[s], hhi[s]):
                pl[j] += hd_[s, j] * fs
    s = k0 * h_lin
    xmax = 0.0
    vmax = 0.0
    nca = 0
    matvec_spans(psi_t, q, pw0, clo, chi)
    matvec_spans(psi_t, v, pv0, clo, chi)
    k = k0
    k_end = min(m_lin, k0 + SPELL_CHUNK)
    blocked = False
    while k < k_end:
        s1 = dt_rec if k == m_lin - 1 else (k + 1) * h_lin
        hh = s1 - s
        agb = ag0 + slope * s
        age = ag0 + slope * s1
        for j in range(n):
            cf = coef[j]
            p0 = -gamma[j] * agb + pl[j]
            p1 = -gamma[j] * age + pl[j]
            q1[j] = cf[0, 0] * q[j] + cf[0, 1] * v[j] + cf[0, 2] * p0 + cf[0, 3] * p1
            v1[j] = cf[1, 0] * q[j] + cf[1, 1] * v[j] + cf[1, 2] * p0 + cf[1, 3] * p1
            a1[j] = p1 - 2.0 * zeta[j] * omega[j] * v1[j] - omega[j] * omega[j] * q1[j]
        matvec_spans(psi_t, q1, pw1, clo, chi)
        matvec_spans(psi_t, v1, pv1, clo, chi)
        for r in range(u0.size):
            u1 = 0.0
            du1 = 0.0
            for j in range(dlo[r], dhi[r]):
                u1 += dmat[r, j] * q1[j]
                du1 += dmat[r, j] * v1[j]
            ub[r] = u1
            dub[r] = du1
        if _may_switch(y, y1, n, gap, pw0, pv0, pw1, pv1, u0, du0, ub, dub, hrow, huy, hh):
            blocked = True
            break
        _energies(y, y1, n, pl, agb, slope, hh, omega, zeta, gamma, en)
        for j in range(2 * n):
            ybuf[k - k0, j] = y[j]
        matvec_spans(phi_t, q1, xb, flo, fhi)
        matvec_spans(phi_t, v1, xdb, flo, fhi)
        for f in range(xb.size):
            peaks[f], nca = _step_peak(peaks[f], xf0[f], xfd0[f], xb[f], xdb[f], hh, herm_tol,
                                       cand, ctg, nca, k, f)  # fmt: skip
            xf0[f] = xb[f]
            xfd0[f] = xdb[f]
            vmax = max(vmax, abs(xdb[f]))
        for r in range(u0.size):
            peak_u[r], nca = _step_peak(peak_u[r], u0[r], du0[r], ub[r], dub[r], hh, herm_tol,
                                        cand, ctg, nca, k, xb.size + r)  # fmt: skip
            u0[r] = ub[r]
            du0[r] = dub[r]
        for c in range(gap.size):
            pw0[c] = pw1[c]
            pv0[c] = pv1[c]
        matvec_spans(phi_t, a1, xb, flo, fhi)
        for f in range(xb.size):
            peak_acc[f] = max(peak_acc[f], abs(xb[f] + age))
        for i in range(y.size):
            y[i] = y1[i]
        s = s1
        k += 1
    if nca > 0:
        _refine_peaks(cand, ctg, nca, ybuf, k0, m_lin, h_lin, dt_rec, n, pl, ag0, slope, phi, dmat,
                      omega, zeta, gamma, peaks, peak_u)  # fmt: skip
    for f in range(peaks.size):
        xmax = max(xmax, peaks[f])
    return s, k, blocked, xmax, vmax
