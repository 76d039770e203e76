"""The Dormand-Prince 5(4) step of :mod:`~pound_mc.integrators.adaptive_rk` and its error.

The tableau (Dormand & Prince 1980, the pair with its first-same-as-last stage, as SciPy's
``RK45``), the right-hand side of the yielding buildings' equations (:func:`rates`: modes,
contacts, yielding storeys and the energy rates), one step (:func:`dp_step`) and the
embedded error estimate relative to the tolerance (:func:`error_norm`).  Each stage's sum is
written out with the tableau's numbers (:func:`_stage`), so that the compiler vectorises it
over the state; the numbers are those of the sum over the tableau's rows.
"""

from __future__ import annotations

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators.laws import force
from pound_mc.integrators.storey_laws import z_rate
from pound_mc.integrators.toolkit import matvec_spans, rowdot

__all__ = ["N_RATES", "rates", "dp_step", "error_norm"]

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
#: Energy rates integrated with the state: input, damping, contact, plastic load, hysteretic.
N_RATES = 5


@jit(llvm_inline=True)
def rates(y, ag, n, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model, hd_, hlo, hhi, hk,
          hal, huy, hbw, hlaw, branch, rate, kk, ek, fk, st):  # fmt: skip
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


# the tableau's entries as numbers, for the stages' sums below
_A10 = _A[1, 0]
_A20, _A21 = _A[2, 0], _A[2, 1]
_A30, _A31, _A32 = _A[3, 0], _A[3, 1], _A[3, 2]
_A40, _A41, _A42, _A43 = _A[4, 0], _A[4, 1], _A[4, 2], _A[4, 3]
_A50, _A51, _A52, _A53, _A54 = _A[5, 0], _A[5, 1], _A[5, 2], _A[5, 3], _A[5, 4]
_A60, _A62, _A63, _A64, _A65 = _A[6, 0], _A[6, 2], _A[6, 3], _A[6, 4], _A[6, 5]
_E0, _E2, _E3, _E4, _E5, _E6 = _E[0], _E[2], _E[3], _E[4], _E[5], _E[6]


@jit(inline=True)
def _stage(y, kk, ys, hs, st):
    """The state of stage ``st``, ``y + hs sum_r A[st, r] kk[r]``, into ``ys``.

    Each stage's sum written out with the tableau's numbers (zeros left out), summed in the
    order of ``r``: a loop over the state that the compiler vectorises, the numbers those of
    the sum over the tableau's row.
    """
    m = y.size
    if st == 1:
        for i in range(m):
            ys[i] = y[i] + hs * (_A10 * kk[0, i])
    elif st == 2:
        for i in range(m):
            ys[i] = y[i] + hs * (_A20 * kk[0, i] + _A21 * kk[1, i])
    elif st == 3:
        for i in range(m):
            ys[i] = y[i] + hs * (_A30 * kk[0, i] + _A31 * kk[1, i] + _A32 * kk[2, i])
    elif st == 4:
        for i in range(m):
            ys[i] = y[i] + hs * (_A40 * kk[0, i] + _A41 * kk[1, i] + _A42 * kk[2, i]
                                 + _A43 * kk[3, i])  # fmt: skip
    elif st == 5:
        for i in range(m):
            ys[i] = y[i] + hs * (_A50 * kk[0, i] + _A51 * kk[1, i] + _A52 * kk[2, i]
                                 + _A53 * kk[3, i] + _A54 * kk[4, i])  # fmt: skip
    else:
        for i in range(m):
            ys[i] = y[i] + hs * (_A60 * kk[0, i] + _A62 * kk[2, i] + _A63 * kk[3, i]
                                 + _A64 * kk[4, i] + _A65 * kk[5, i])  # fmt: skip


@jit(inline=True)
def _embedded(kk, i):
    """``sum_st E[st] kk[st, i]``: the embedded error's rate of state variable ``i``."""
    return (_E0 * kk[0, i] + _E2 * kk[2, i] + _E3 * kk[3, i] + _E4 * kk[4, i] + _E5 * kk[5, i]
            + _E6 * kk[6, i])  # fmt: skip


@jit(llvm_inline=True)
def dp_step(y, kk, ek, fk, hs, ag0, slope, s, n, omega, zeta, gamma, psi, gap, beta, cd, zhd,
             phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, ys, y1, de,
             cimp):  # fmt: skip
    """One Dormand-Prince step of ``hs`` from ``y`` (``kk[0]``, ``ek[0]``, ``fk[0]``: its rates).

    Fills the stages ``kk[1:]`` (``kk[6]`` the rates at the end), the new state ``y1``, the
    energy increments ``de`` and the contact impulses ``cimp``.
    """
    for st in range(1, 7):
        _stage(y, kk, ys, hs, st)
        rates(ys, ag0 + slope * (s + _C[st] * hs), n, omega, zeta, gamma, psi, gap, beta, cd,
              zhd, phase, model, hd_, hlo, hhi, hk, hal, huy, hbw, hlaw, branch, rate, kk, ek,
              fk, st)  # fmt: skip
    for i in range(y.size):
        y1[i] = ys[i]  # stage 7 is evaluated at the fifth-order solution (first same as last)
    for r in range(N_RATES):
        acc = 0.0
        for st in range(6):
            acc += _B[st] * ek[st, r]
        de[r] = hs * acc
    for c in range(cimp.size):
        acc = 0.0
        for st in range(6):
            acc += _B[st] * fk[st, c]
        cimp[c] = hs * acc


@jit(llvm_inline=True)
def error_norm(kk, hs, n, phi_t, flo, fhi, psi, phase, hn, xscale, vscale, huy, dscale, rtol, err_q,
           err_v, xb, xdb):  # fmt: skip
    """Embedded error of a step relative to the tolerance (<= 1: accepted)."""
    for j in range(n):
        err_q[j] = hs * _embedded(kk, j)
        err_v[j] = hs * _embedded(kk, n + j)
    matvec_spans(phi_t, err_q, xb, flo, fhi)
    matvec_spans(phi_t, err_v, xdb, flo, fhi)
    worst = 0.0
    for f in range(xb.size):
        worst = max(worst, abs(xb[f]) / (rtol * xscale), abs(xdb[f]) / (rtol * vscale))
    for s in range(hn):
        worst = max(worst, abs(hs * _embedded(kk, 2 * n + s)) / (rtol * huy[s]))
    for c in range(phase.size):
        if phase[c] != 0:
            worst = max(worst, abs(rowdot(psi, c, err_q)) / (rtol * dscale[c]))
    return worst
