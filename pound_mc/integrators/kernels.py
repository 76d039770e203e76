"""Compiled time integrators for two buildings that pound (numba kernels).

Both buildings are integrated in their modal coordinates (:mod:`pound_mc.physics.structures`): for
each mode ``q'' + 2 zeta omega q' + omega^2 q = -gamma a_g(t) - sum_c F_c psi_c`` with
``psi_c = phi[left floor of c] - phi[right floor of c]``, so that the penetration of contact
``c`` is ``delta_c = psi_c . q - gap_c`` and its force pushes the floors apart.  The ground
acceleration is the record's samples linearly interpolated (``../shared/DESIGN.md`` section 2).

Methods (names pinned by DESIGN.md section 4):

``adaptive`` (default)
    Exact (Nigam-Jennings) steps of the linear modes between contacts, on the record's samples
    split into steps no longer than ``dt_s``; contact onset located by root finding on the
    exact solution (a cubic Hermite bound screens every step for a grazing approach); during
    contact, classical Runge-Kutta sub-steps sized from the Hertz contact-duration estimate
    ``t_c = 3.218 (m_eff/beta)^0.4 v0^-0.2`` (``substeps`` per ``t_c``), with every switch of the
    force law (onset, approach -> restitution, separation) located inside its sub-step and
    the step cut there.  Peak force, peak displacements and penetration are continuous-time
    maxima (cubic Hermite interpolation within each step).
``newmark``
    Average acceleration (gamma = 1/2, beta = 1/4) at the fixed step ``dt_s``, the contact
    forces solved implicitly by Newton's method on the penetrations in every step.
``newmark-explicit``
    The same, with the contact force lagged one step (explicit in the contact).
``central-difference``
    Explicit central differences, contact force from the backward-difference velocity.

Every run returns the outputs of :data:`OUTPUTS` and a status: 0 ok, 1 unstable (non-finite or
diverging state, or an energy balance broken either way by more than
:data:`UNSTABLE_ENERGY_FRACTION` of the energy put in), 2 not converged (Newton).
Fixed-step methods report maxima over their step points.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from pound_mc._jit import jit

__all__ = [
    "METHODS",
    "OUTPUTS",
    "CONTACT_OUTPUTS",
    "UNSTABLE_ENERGY_FRACTION",
    "run_kernel",
    "simulate_sdof_pairs",
    "simulate_scene_batch",
    "exact_step_coefficients",
]

#: Integration methods by name -> kernel code.
METHODS = {"adaptive": 0, "newmark": 1, "newmark-explicit": 2, "central-difference": 3}

#: Per-simulation outputs, in the order of the kernel's output vector.
OUTPUTS = (
    "peak_force",
    "impacts",
    "max_penetration",
    "peak_disp_left",
    "peak_disp_right",
    "impulse",
    "dissipated_energy",
    "energy_residual",
    "status",
    "input_energy",
    "steps",
    "peak_force_time",
)
_N_OUT = len(OUTPUTS)
#: Per-contact outputs (columns of the kernel's contact matrix).
CONTACT_OUTPUTS = ("peak_force", "impacts", "max_penetration", "impulse")

#: A run whose energy balance is broken by more than this fraction of the energy put in
#: (energy created by the integrator) is flagged unstable.
UNSTABLE_ENERGY_FRACTION = 0.5
#: A displacement beyond this [m] is a diverging run.
DIVERGENCE_LIMIT_M = 1.0e3
#: Most integration steps one simulation may take (record length / dt_s); beyond it the run is
#: flagged not converged instead of running for hours.
MAX_STEPS = 2.0e9

_INF = np.inf

# --------------------------------------------------------------------------- contact laws


@jit(inline=True)
def _force(model, d, dd, beta, c0, meff, zhd, phase):
    """Contact force [N] of a law by its code, in a phase (0 open, 1 approach, 2 restitution).

    ``c0 = 2 xi sqrt(beta m_eff)`` is the damping constant of the Jankowski and Kelvin laws
    (precomputed per contact: seed eq. (1.1) reads ``c = c0 delta^0.25`` for Jankowski's).
    ``d`` is clipped at 0 so located switches never see a negative root.
    """
    if phase == 0:
        return 0.0
    if d < 0.0:
        d = 0.0
    if model == 0:  # jankowski, seed eq. (1.1)
        sd = math.sqrt(d)
        f = beta * d * sd
        if phase == 1:
            f += c0 * math.sqrt(sd) * dd
        return f
    if model == 1:  # linear spring
        return beta * d
    if model == 2:  # kelvin-voigt
        return beta * d + c0 * dd
    if model == 3:  # hertz
        return beta * d * math.sqrt(d)
    # hertzdamp
    f = beta * d * math.sqrt(d) * (1.0 + zhd * dd)
    return f if f > 0.0 else 0.0


@jit
def _force_rate(model, d, dd, ddd, beta, c0, meff, zhd, phase):
    """Time derivative of :func:`_force` along the motion [N/s]."""
    if phase == 0 or d <= 0.0:
        return 0.0
    sd = math.sqrt(d)
    if model == 0:
        r = 1.5 * beta * sd * dd
        if phase == 1:
            q = math.sqrt(sd)  # d^0.25
            r += c0 * (0.25 * dd * dd / (q * q * q) + q * ddd)
        return r
    if model == 1:
        return beta * dd
    if model == 2:
        return beta * dd + c0 * ddd
    if model == 3:
        return 1.5 * beta * sd * dd
    f = beta * d * sd * (1.0 + zhd * dd)
    if f <= 0.0:
        return 0.0
    return 1.5 * beta * sd * dd * (1.0 + zhd * dd) + beta * d * sd * zhd * ddd


@jit(inline=True)
def _stored(model, d, beta):
    """Elastic energy stored in a contact at penetration ``d`` [J]."""
    if d <= 0.0:
        return 0.0
    if model == 1 or model == 2:
        return 0.5 * beta * d * d
    return 0.4 * beta * d * d * math.sqrt(d)


@jit
def _duration(model, v0, beta, meff):
    """Estimated contact duration [s] for the sub-step size."""
    if model == 1 or model == 2:
        return math.pi * math.sqrt(meff / beta)
    if v0 < 1e-12:
        v0 = 1e-12
    return 3.218 * (meff / beta) ** 0.4 * v0**-0.2


@jit(inline=True)
def _step_size(dt_rec, dt_s):
    """Steps per record interval and their length [s].

    The step is the longest one no longer than ``dt_s`` that divides the record's interval.
    """
    m_sub = max(1, int(math.ceil(dt_rec / dt_s - 1e-9)))
    return m_sub, dt_rec / m_sub


# --------------------------------------------------------------------------- exact linear step


@jit
def _advance(q, v, p0, p1, w, z, h):
    """Exact state after ``h`` of ``q'' + 2 z w q' + w^2 q = p`` with ``p`` linear p0 -> p1.

    Closed form (Nigam & Jennings 1969; Chopra, Table 5.2.1) for ``w h >= 0.05``, else a
    Taylor series of the exact solution (the closed form cancels digits for short steps).
    """
    if h == 0.0:
        return q, v
    if w * h < 0.05:
        slope = (p1 - p0) / h
        d0 = q
        d1 = v
        qs = q + v * h
        vs = v
        tv = 1.0
        for k in range(24):
            pk = p0 if k == 0 else (slope if k == 1 else 0.0)
            d2 = pk - 2.0 * z * w * d1 - w * w * d0  # d_{k+2}
            tv = tv * h / (k + 1)  # h^(k+1) / (k+1)!
            vs += d2 * tv
            qs += d2 * tv * h / (k + 2)
            d0 = d1
            d1 = d2
        return qs, vs
    k = w * w
    sq = math.sqrt(1.0 - z * z)
    wd = w * sq
    e = math.exp(-z * w * h)
    s = math.sin(wd * h)
    c = math.cos(wd * h)
    a = e * (z / sq * s + c)
    b = e * (s / wd)
    cc = (
        2.0 * z / (w * h)
        + e * (((1.0 - 2.0 * z * z) / (wd * h) - z / sq) * s - (1.0 + 2.0 * z / (w * h)) * c)
    ) / k
    dd = (
        1.0 - 2.0 * z / (w * h) + e * ((2.0 * z * z - 1.0) / (wd * h) * s + 2.0 * z / (w * h) * c)
    ) / k
    ap = -e * (w / sq * s)
    bp = e * (c - z / sq * s)
    cp = (-1.0 / h + e * ((w / sq + z / (h * sq)) * s + c / h)) / k
    dp = (1.0 - e * (z / sq * s + c)) / (k * h)
    return a * q + b * v + cc * p0 + dd * p1, ap * q + bp * v + cp * p0 + dp * p1


def exact_step_coefficients(omega: float, zeta: float, h: float) -> np.ndarray:
    """Coefficients ``[[A, B, C, D], [A', B', C', D']]`` of the exact linear step.

    ``q1 = A q0 + B v0 + C p0 + D p1`` and ``v1 = A' q0 + B' v0 + C' p0 + D' p1`` for a unit
    mass with circular frequency ``omega`` [rad/s], damping ratio ``zeta`` [-], load ``p``
    linear over the step ``h`` [s] (Nigam & Jennings 1969).
    """
    return _coefficients(float(omega), float(zeta), float(h))


@jit
def _coefficients(w, z, h):
    out = np.empty((2, 4))
    for col in range(4):
        q0 = 1.0 if col == 0 else 0.0
        v0 = 1.0 if col == 1 else 0.0
        p0 = 1.0 if col == 2 else 0.0
        p1 = 1.0 if col == 3 else 0.0
        q1, v1 = _advance(q0, v0, p0, p1, w, z, h)
        out[0, col] = q1
        out[1, col] = v1
    return out


# --------------------------------------------------------------------------- cubic Hermite


@jit
def _hermite_max(y0, yp0, y1, yp1, h):
    """Largest interior local maximum of the cubic Hermite interpolant on ``[0, h]``.

    Returns ``(value, tau)``; ``(-inf, 0)`` when the cubic has no interior maximum.
    """
    b = h * yp0
    c = 3.0 * (y1 - y0) - h * (2.0 * yp0 + yp1)
    d = 2.0 * (y0 - y1) + h * (yp0 + yp1)
    best = -_INF
    tbest = 0.0
    # y'(s) = b + 2 c s + 3 d s^2
    if abs(d) < 1e-300:
        if c < 0.0:
            s = -b / (2.0 * c)
            if 0.0 < s < 1.0:
                best = y0 + b * s + c * s * s
                tbest = s * h
        return best, tbest
    disc = c * c - 3.0 * d * b
    if disc < 0.0:
        return best, tbest
    r = math.sqrt(disc)
    for sgn in (-1.0, 1.0):
        s = (-c + sgn * r) / (3.0 * d)
        if 0.0 < s < 1.0 and 2.0 * c + 6.0 * d * s < 0.0:
            val = y0 + s * (b + s * (c + s * d))
            if val > best:
                best = val
                tbest = s * h
    return best, tbest


@jit
def _hermite_root(y0, yp0, y1, yp1, h):
    """First root in ``(0, h]`` of the cubic Hermite interpolant.

    ``y0`` and ``y1`` have opposite signs (or ``y1 == 0``); bisection safeguarded Newton.
    """
    b = h * yp0
    c = 3.0 * (y1 - y0) - h * (2.0 * yp0 + yp1)
    d = 2.0 * (y0 - y1) + h * (yp0 + yp1)
    lo = 0.0
    hi = 1.0
    flo = y0
    s = 0.5
    # a sign change inside may come earlier than the one the endpoints bracket: scan first
    n_scan = 8
    prev = y0
    for k in range(1, n_scan + 1):
        sk = k / n_scan
        val = y0 + sk * (b + sk * (c + sk * d))
        if (val >= 0.0) != (prev >= 0.0) or val == 0.0:
            lo = (k - 1) / n_scan
            hi = sk
            flo = prev
            break
        prev = val
    s = 0.5 * (lo + hi)
    for _ in range(60):
        f = y0 + s * (b + s * (c + s * d))
        if (f >= 0.0) == (flo >= 0.0):
            lo = s
        else:
            hi = s
        fp = b + s * (2.0 * c + 3.0 * d * s)
        s_new = s - f / fp if fp != 0.0 else 0.5 * (lo + hi)
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        if abs(s_new - s) < 1e-15:
            s = s_new
            break
        s = s_new
    return s * h


# --------------------------------------------------------------------------- helpers


@jit(inline=True)
def _rowdot(mat, r, x):
    acc = 0.0
    for j in range(x.size):
        acc += mat[r, j] * x[j]
    return acc


@jit(inline=True)
def _accel(q, v, ag, omega, zeta, gamma, psi, fc, a):
    """Modal accelerations into ``a`` for ground acceleration ``ag`` and contact forces."""
    n = q.size
    for j in range(n):
        a[j] = -2.0 * zeta[j] * omega[j] * v[j] - omega[j] * omega[j] * q[j] - gamma[j] * ag
    for c in range(fc.size):
        if fc[c] != 0.0:
            for j in range(n):
                a[j] -= fc[c] * psi[c, j]


@jit(inline=True)
def _powers(v, ag, omega, zeta, gamma):
    """Input power -a_g sum gamma v and structural damping power sum 2 zeta omega v^2."""
    pin = 0.0
    pd = 0.0
    for j in range(v.size):
        pin -= ag * gamma[j] * v[j]
        pd += 2.0 * zeta[j] * omega[j] * v[j] * v[j]
    return pin, pd


@jit
def _track_floors(phi, side, q0, v0, q1, v1, h, peaks):
    """Update the continuous-time peak |x| of every floor over a step (Hermite)."""
    nf = phi.shape[0]
    for f in range(nf):
        x0 = _rowdot(phi, f, q0)
        x1 = _rowdot(phi, f, q1)
        m = abs(x1)
        if m > peaks[f]:
            peaks[f] = m
        xd0 = _rowdot(phi, f, v0)
        xd1 = _rowdot(phi, f, v1)
        if (xd0 > 0.0) != (xd1 > 0.0):
            hm, _ = _hermite_max(x0, xd0, x1, xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm
            hm, _ = _hermite_max(-x0, -xd0, -x1, -xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm


@jit
def _mechanical_energy(q, v, omega):
    e = 0.0
    for j in range(q.size):
        e += 0.5 * (v[j] * v[j] + omega[j] * omega[j] * q[j] * q[j])
    return e


@jit(inline=True)
def _end_values(q, v, ag, omega, zeta, gamma, en):
    """Sums for the energy integrals at one state without contact force."""
    sgv = 0.0
    sga = 0.0
    pd = 0.0
    dpd = 0.0
    for j in range(q.size):
        a = -2.0 * zeta[j] * omega[j] * v[j] - omega[j] * omega[j] * q[j] - gamma[j] * ag
        sgv += gamma[j] * v[j]
        sga += gamma[j] * a
        pd += 2.0 * zeta[j] * omega[j] * v[j] * v[j]
        dpd += 4.0 * zeta[j] * omega[j] * v[j] * a
    en[0] = sgv
    en[1] = sga
    en[2] = pd
    en[3] = dpd


@jit
def _refresh(q, v, ag, omega, zeta, gamma, phi, psi, gap, dc, ddc, xf, xfd, en):
    """Values at the current state that linear steps carry from one step to the next."""
    for c in range(gap.size):
        dc[c] = _rowdot(psi, c, q) - gap[c]
        ddc[c] = _rowdot(psi, c, v)
    for f in range(phi.shape[0]):
        xf[f] = _rowdot(phi, f, q)
        xfd[f] = _rowdot(phi, f, v)
    _end_values(q, v, ag, omega, zeta, gamma, en)


@jit
def _exact_delta(q, v, p0s, slope, s, tau, c, omega, zeta, gamma, psi, gap):
    """Penetration of contact ``c``, its rate and acceleration at ``tau`` into a linear step.

    Any row of modal weights works: ``psi = phi, gap = 0`` gives a floor's displacement.
    """
    d = -gap[c]
    dd = 0.0
    ddd = 0.0
    ag = p0s + slope * tau
    for j in range(q.size):
        if psi[c, j] == 0.0:
            continue  # e.g. the other building's modes for a floor
        qm, vm = _advance(q[j], v[j], -gamma[j] * p0s, -gamma[j] * ag, omega[j], zeta[j], tau)
        am = -2.0 * zeta[j] * omega[j] * vm - omega[j] * omega[j] * qm - gamma[j] * ag
        d += psi[c, j] * qm
        dd += psi[c, j] * vm
        ddd += psi[c, j] * am
    return d, dd, ddd


@jit
def _exact_root(q, v, p0s, slope, s, guess, lo, hi, which, c, omega, zeta, gamma, psi, gap):
    """Root in ``[lo, hi]`` on the exact linear solution.

    Of delta (``which = 0``, from below) or delta_dot (``which = 1``, from above);
    Newton from ``guess``, kept in the bracket.
    """
    t = guess
    if not (lo < t < hi):
        t = 0.5 * (lo + hi)
    for _ in range(60):
        d, dd, ddd = _exact_delta(q, v, p0s, slope, s, t, c, omega, zeta, gamma, psi, gap)
        g = d if which == 0 else -dd
        gp = dd if which == 0 else -ddd
        if g > 0.0:
            hi = t
        else:
            lo = t
        t_new = t - g / gp if gp != 0.0 else 0.5 * (lo + hi)
        if not (lo < t_new < hi):
            t_new = 0.5 * (lo + hi)
        if abs(t_new - t) <= 1e-15 * (hi + 1e-300) or hi - lo <= 1e-15 * hi:
            t = t_new
            break
        t = t_new
    return t


# --------------------------------------------------------------------------- adaptive


@jit(inline=True)
def _contact_forces(q, v, psi, gap, meff, beta, cd, zhd, phase, model, fc):
    for c in range(fc.size):
        d = _rowdot(psi, c, q) - gap[c]
        dd = _rowdot(psi, c, v)
        fc[c] = _force(model, d, dd, beta[c], cd[c], meff[c], zhd[c], phase[c])


@jit
def _rk4(
    q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, gap, meff, beta, cd, zhd, phase, model,
    qn, vn, wk, fc, cimp, fc0,
):  # fmt: skip
    """One classical Runge-Kutta step of length ``hs`` from local time ``s``.

    Writes the new state into ``qn, vn``, the contact impulses of the step into ``cimp`` and
    the forces at the start into ``fc0`` (the accelerations at the start are ``wk[4]``);
    returns the increments of input energy, damping energy and contact work.
    """
    n = q.size
    nc = fc.size
    # wk rows: 0..3 dq stages, 4..7 dv stages, 8 q stage, 9 v stage
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    for c in range(nc):
        cimp[c] = 0.0
    for stage in range(4):
        if stage == 0:
            tau = 0.0
            for j in range(n):
                wk[8, j] = q[j]
                wk[9, j] = v[j]
        else:
            tau = hs if stage == 3 else 0.5 * hs
            fac = hs if stage == 3 else 0.5 * hs
            for j in range(n):
                wk[8, j] = q[j] + fac * wk[stage - 1, j]
                wk[9, j] = v[j] + fac * wk[4 + stage - 1, j]
        ag = ag0 + slope * (s + tau)
        _contact_forces(wk[8], wk[9], psi, gap, meff, beta, cd, zhd, phase, model, fc)
        _accel(wk[8], wk[9], ag, omega, zeta, gamma, psi, fc, wk[4 + stage])
        if stage == 0:
            for c in range(nc):
                fc0[c] = fc[c]
        for j in range(n):
            wk[stage, j] = wk[9, j]
        pin, pd = _powers(wk[9], ag, omega, zeta, gamma)
        pc = 0.0
        for c in range(nc):
            pc += fc[c] * _rowdot(psi, c, wk[9])
        wgt = (1.0 if stage == 0 or stage == 3 else 2.0) * hs / 6.0
        e_in += wgt * pin
        e_d += wgt * pd
        w_c += wgt * pc
        for c in range(nc):
            cimp[c] += wgt * fc[c]
    for j in range(n):
        qn[j] = q[j] + hs / 6.0 * (wk[0, j] + 2.0 * wk[1, j] + 2.0 * wk[2, j] + wk[3, j])
        vn[j] = v[j] + hs / 6.0 * (wk[4, j] + 2.0 * wk[5, j] + 2.0 * wk[6, j] + wk[7, j])
    return e_in, e_d, w_c


@jit
def _adaptive(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model, dt_s,
    substeps, q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    # pre: shared linear response before the first contact (see _sdof_batch).  Empty: plain
    # run.  pre[0] = 1: run linearly to the first contact onset and leave in pre the state at
    # the start of that record interval; pre[0] = 2: resume from such a state.  Layout:
    # [mode, interval, e_in, e_d, steps, e0, q (n), v (n), peaks (nf)].
    n = q.size
    nc = gap.size
    nf = phi.shape[0]
    npts = ag.size
    m_sub, h = _step_size(dt_rec, dt_s)
    cd = 2.0 * xi * np.sqrt(beta * meff)  # damping constants c0 of the force laws
    coef = np.empty((n, 2, 4))
    for j in range(n):
        coef[j] = _coefficients(omega[j], zeta[j], h)
    q1 = np.empty(n)
    v1 = np.empty(n)
    a0 = np.empty(n)
    a1 = np.empty(n)
    wk = np.empty((10, n))
    fc = np.zeros(nc)
    fc0 = np.zeros(nc)
    cimp = np.zeros(nc)
    phase = np.zeros(nc, dtype=np.int64)
    zhd = np.zeros(nc)
    peaks = np.zeros(nf)
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    e0 = _mechanical_energy(q, v, omega)
    peak_f = 0.0
    peak_t = 0.0
    steps = 0
    hc = h
    fresh = False
    dc0 = np.empty(nc)
    ddc0 = np.empty(nc)
    dc1 = np.empty(nc)
    ddc1 = np.empty(nc)
    xf0 = np.empty(nf)
    xfd0 = np.empty(nf)
    en0 = np.empty(4)
    en1 = np.empty(4)
    nphi = -phi
    zf = np.zeros(nf)
    # error bound of the cubic Hermite maximum in a linear step, (omega h)^4 / 384 of the
    # amplitude, with a safety factor of 4: a candidate below the peak by more is no new peak
    wmax = 0.0
    for j in range(n):
        wmax = max(wmax, omega[j])
    herm_tol = 4.0 * (wmax * h) ** 4 / 384.0
    t_onset = 0.0
    # steps allowed: 200 per linear step of the record, plus room for many contacts
    budget = 200 * (npts - 1) * m_sub + 1_000_000
    in_contact = False
    status = 0
    store = hx.shape[0] > 0
    for c in range(nc):
        cout[c, 0] = 0.0
        cout[c, 1] = 0.0
        cout[c, 2] = -_INF
        cout[c, 3] = 0.0
    mode = int(pre[0]) if pre.size > 0 else 0
    i_first = 0
    if mode == 2:
        i_first = int(pre[1])
        e_in = pre[2]
        e_d = pre[3]
        steps = int(pre[4])
        e0 = pre[5]
        for j in range(n):
            q[j] = pre[6 + j]
            v[j] = pre[6 + n + j]
        for f in range(nf):
            peaks[f] = pre[6 + 2 * n + f]
    for i in range(i_first, npts - 1):
        if mode == 1:
            _snapshot(pre, i, e_in, e_d, steps, e0, q, v, peaks)
        if store:
            for f in range(nf):
                hx[i, f] = _rowdot(phi, f, q)
            for c in range(nc):
                hd[i, c] = _rowdot(psi, c, q) - gap[c]
                hf[i, c] = _force(model, hd[i, c], _rowdot(psi, c, v), beta[c], cd[c], meff[c],
                                  zhd[c], phase[c])  # fmt: skip
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) / dt_rec
        s = 0.0
        k_grid = 0  # index of the next grid point within the interval
        while s < dt_rec * (1.0 - 1e-12):
            steps += 1
            if steps > budget:
                # absurd parameters (say beta = 1e300 makes contact sub-steps of 1e-119 s):
                # give up instead of running for ever, and say so
                status = 2
                break
            if not in_contact:
                # ---------------- exact linear step to the next grid point
                s_next = (k_grid + 1) * h
                if k_grid + 1 == m_sub:
                    s_next = dt_rec
                hh = s_next - s
                regular = abs(hh - h) <= 1e-12 * h
                p0s = ag0 + slope * s
                p1s = ag0 + slope * s_next
                for j in range(n):
                    if regular:
                        cf = coef[j]
                        p0 = -gamma[j] * p0s
                        p1 = -gamma[j] * p1s
                        q1[j] = cf[0, 0] * q[j] + cf[0, 1] * v[j] + cf[0, 2] * p0 + cf[0, 3] * p1
                        v1[j] = cf[1, 0] * q[j] + cf[1, 1] * v[j] + cf[1, 2] * p0 + cf[1, 3] * p1
                    else:
                        q1[j], v1[j] = _advance(q[j], v[j], -gamma[j] * p0s, -gamma[j] * p1s,
                                                omega[j], zeta[j], hh)  # fmt: skip
                # onset screening
                tau_on = _INF
                c_on = -1
                if not fresh:
                    _refresh(q, v, p0s, omega, zeta, gamma, phi, psi, gap, dc0, ddc0, xf0, xfd0,
                             en0)  # fmt: skip
                    fresh = True
                for c in range(nc):
                    d0 = dc0[c]
                    dd0 = ddc0[c]
                    d1 = _rowdot(psi, c, q1) - gap[c]
                    dd1 = _rowdot(psi, c, v1)
                    dc1[c] = d1
                    ddc1[c] = dd1
                    crossing = d1 > 0.0
                    t_hi = hh
                    if not crossing and dd0 > 0.0 and dd1 < 0.0:
                        hm, _ = _hermite_max(d0, dd0, d1, dd1, hh)
                        margin = 0.05 * (abs(dd0) + abs(dd1)) * hh
                        if hm > -margin:
                            # exact maximum of delta in the step: root of delta_dot
                            _, tg = _hermite_max(d0, dd0, d1, dd1, hh)
                            tm = _exact_root(q, v, p0s, slope, s, tg, 0.0, hh, 1, c, omega,
                                             zeta, gamma, psi, gap)  # fmt: skip
                            dm, _, _ = _exact_delta(q, v, p0s, slope, s, tm, c, omega, zeta,
                                                    gamma, psi, gap)  # fmt: skip
                            if dm > 0.0:
                                crossing = True
                                t_hi = tm
                                d1 = dm
                                dd1 = 0.0
                    if crossing and d0 <= 0.0:
                        # locate delta = 0 on the exact solution (safeguarded Newton)
                        tg = _hermite_root(d0, dd0, d1, dd1, t_hi)
                        hi = _exact_root(q, v, p0s, slope, s, tg, 0.0, t_hi, 0, c, omega, zeta,
                                         gamma, psi, gap)  # fmt: skip
                        if hi < tau_on:
                            tau_on = hi
                            c_on = c
                if c_on >= 0 and mode == 1:
                    return
                if c_on >= 0:
                    hh = tau_on
                    p1s = ag0 + slope * (s + hh)
                    for j in range(n):
                        q1[j], v1[j] = _advance(q[j], v[j], -gamma[j] * p0s, -gamma[j] * p1s,
                                                omega[j], zeta[j], hh)  # fmt: skip
                # energies by the corrected trapezoidal rule (exact to O(h^5) per step)
                if c_on >= 0:
                    for c in range(nc):
                        dc1[c] = _rowdot(psi, c, q1) - gap[c]
                        ddc1[c] = _rowdot(psi, c, v1)
                _end_values(q1, v1, p1s, omega, zeta, gamma, en1)
                # en: 0 sum gamma v, 1 sum gamma a, 2 damping power, 3 its rate
                pin0 = -p0s * en0[0]
                pin1 = -p1s * en1[0]
                dpin0 = -(slope * en0[0] + p0s * en0[1])
                dpin1 = -(slope * en1[0] + p1s * en1[1])
                e_in += 0.5 * hh * (pin0 + pin1) + hh * hh / 12.0 * (dpin0 - dpin1)
                e_d += 0.5 * hh * (en0[2] + en1[2]) + hh * hh / 12.0 * (en0[3] - en1[3])
                for f in range(nf):
                    x1 = _rowdot(phi, f, q1)
                    xd1 = _rowdot(phi, f, v1)
                    m = abs(x1)
                    if m > peaks[f]:
                        peaks[f] = m
                    if (xfd0[f] > 0.0) != (xd1 > 0.0):
                        # an extremum inside the step: where the cubic Hermite bound says it
                        # may be a new peak, find it on the exact solution
                        for sg in range(2):
                            mat = phi if sg == 0 else nphi
                            sign = 1.0 if sg == 0 else -1.0
                            hm, tg = _hermite_max(sign * xf0[f], sign * xfd0[f], sign * x1,
                                                  sign * xd1, hh)  # fmt: skip
                            if hm > peaks[f] - herm_tol * abs(hm):
                                tm = _exact_root(q, v, p0s, slope, s, tg, 0.0, hh, 1, f, omega,
                                                 zeta, gamma, mat, zf)  # fmt: skip
                                xm, _, _ = _exact_delta(q, v, p0s, slope, s, tm, f, omega, zeta,
                                                        gamma, mat, zf)  # fmt: skip
                                if xm > peaks[f]:
                                    peaks[f] = xm
                    xf0[f] = x1
                    xfd0[f] = xd1
                for c in range(nc):
                    dc0[c] = dc1[c]
                    ddc0[c] = ddc1[c]
                for k in range(4):
                    en0[k] = en1[k]
                for j in range(n):
                    q[j] = q1[j]
                    v[j] = v1[j]
                s += hh
                if c_on >= 0:
                    v0c = _rowdot(psi, c_on, v)
                    phase[c_on] = 1
                    cout[c_on, 1] += 1.0
                    if model == 4:
                        # Ye et al. (2009): zeta = 8 (1 - e) / (5 e v0), xi holds e
                        zhd[c_on] = 8.0 * (1.0 - xi[c_on]) / (5.0 * xi[c_on] * max(v0c, 1e-12))
                    hc = min(h, _duration(model, v0c, beta[c_on], meff[c_on]) / substeps)
                    t_onset = i * dt_rec + s
                    in_contact = True
                else:
                    k_grid += 1
            else:
                # ---------------- contact sub-step (RK4) with located switches
                fresh = False
                # sub-steps graded geometrically away from onset and towards separation,
                # where the force law is not smooth (delta^0.25, delta^0.5 terms)
                hs = min(hc, max(1.0 * (i * dt_rec + s - t_onset), hc * 1e-3))
                for c in range(nc):
                    if phase[c] == 2:
                        ddc = _rowdot(psi, c, v)
                        if ddc < 0.0:
                            dc = _rowdot(psi, c, q) - gap[c]
                            hs = min(hs, max(-0.5 * dc / ddc, hc * 0.25))
                if hs >= dt_rec - s or dt_rec - s - hs < 1e-9 * hc:
                    hs = dt_rec - s
                de_in, de_d, dw_c = _rk4(q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, gap,
                                         meff, beta, cd, zhd, phase, model, q1, v1, wk, fc,
                                         cimp, fc0)  # fmt: skip
                # switches: g at both ends with its rate
                for j in range(n):
                    a0[j] = wk[4, j]
                _contact_forces(q1, v1, psi, gap, meff, beta, cd, zhd, phase, model, fc)
                _accel(q1, v1, ag0 + slope * (s + hs), omega, zeta, gamma, psi, fc, a1)
                t_ev = _INF
                c_ev = -1
                kind = 0
                for c in range(nc):
                    d0 = _rowdot(psi, c, q) - gap[c]
                    d1 = _rowdot(psi, c, q1) - gap[c]
                    dd0 = _rowdot(psi, c, v)
                    dd1 = _rowdot(psi, c, v1)
                    ddd0 = _rowdot(psi, c, a0)
                    ddd1 = _rowdot(psi, c, a1)
                    te = _INF
                    kd = 0
                    if phase[c] == 0:
                        if d1 > 0.0 and d0 <= 0.0:
                            te = _hermite_root(d0, dd0, d1, dd1, hs)
                            kd = 1  # onset
                    elif phase[c] == 1:
                        if dd1 <= 0.0 and dd0 > 0.0:
                            te = _hermite_root(dd0, ddd0, dd1, ddd1, hs)
                            kd = 2  # approach -> restitution
                    else:
                        if d1 <= 0.0 and d0 > 0.0:
                            te = _hermite_root(d0, dd0, d1, dd1, hs)
                            kd = 3  # separation
                        if dd1 > 0.0 and dd0 <= 0.0:
                            t2 = _hermite_root(dd0, ddd0, dd1, ddd1, hs)
                            if t2 < te:
                                te = t2
                                kd = 4  # restitution -> approach
                    if te < t_ev:
                        t_ev = te
                        c_ev = c
                        kind = kd
                if c_ev >= 0 and t_ev < hs:
                    hs = t_ev
                    de_in, de_d, dw_c = _rk4(q, v, s, hs, ag0, slope, omega, zeta, gamma, psi,
                                             gap, meff, beta, cd, zhd, phase, model, q1, v1, wk,
                                             fc, cimp, fc0)  # fmt: skip
                    _contact_forces(q1, v1, psi, gap, meff, beta, cd, zhd, phase, model, fc)
                    _accel(q1, v1, ag0 + slope * (s + hs), omega, zeta, gamma, psi, fc, a1)
                e_in += de_in
                e_d += de_d
                w_c += dw_c
                # peak force per contact (Hermite on F with its rate), penetration
                for c in range(nc):
                    cout[c, 3] += cimp[c]
                    if phase[c] == 0:
                        continue
                    d0 = _rowdot(psi, c, q) - gap[c]
                    d1 = _rowdot(psi, c, q1) - gap[c]
                    dd0 = _rowdot(psi, c, v)
                    dd1 = _rowdot(psi, c, v1)
                    f0 = fc0[c]
                    f1 = fc[c]  # forces at the end of the (possibly cut) sub-step
                    fm = f1
                    tm = hs
                    # an interior maximum exceeds the step's end values by far less than 10 %
                    # (sub-steps are a fraction of the contact duration): interpolate only
                    # where it could raise this contact's peak
                    if max(f0, f1) >= 0.9 * cout[c, 0] and d0 > 0.25 * d1:
                        r0 = _force_rate(model, d0, dd0, _rowdot(psi, c, a0), beta[c], cd[c],
                                         meff[c], zhd[c], phase[c])  # fmt: skip
                        r1 = _force_rate(model, d1, dd1, _rowdot(psi, c, a1), beta[c], cd[c],
                                         meff[c], zhd[c], phase[c])  # fmt: skip
                        if r0 > 0.0 and r1 < 0.0:
                            hm, th = _hermite_max(f0, r0, f1, r1, hs)
                            if hm > fm:
                                fm = hm
                                tm = th
                    if f0 > fm:
                        fm = f0
                        tm = 0.0
                    if fm > cout[c, 0]:
                        cout[c, 0] = fm
                    if fm > peak_f:
                        peak_f = fm
                        peak_t = i * dt_rec + s + tm
                    dm = max(d0, d1)
                    if dd0 > 0.0 and dd1 < 0.0:
                        hm, _ = _hermite_max(d0, dd0, d1, dd1, hs)
                        if hm > dm:
                            dm = hm
                    if dm > cout[c, 2]:
                        cout[c, 2] = dm
                _track_floors(phi, side, q, v, q1, v1, hs, peaks)
                for j in range(n):
                    q[j] = q1[j]
                    v[j] = v1[j]
                s += hs
                if c_ev >= 0 and hs == t_ev:
                    if kind == 1:
                        phase[c_ev] = 1
                        cout[c_ev, 1] += 1.0
                        v0c = _rowdot(psi, c_ev, v)
                        if model == 4:
                            zhd[c_ev] = 8.0 * (1.0 - xi[c_ev]) / (5.0 * xi[c_ev] * max(v0c, 1e-12))
                        hc = min(hc, _duration(model, v0c, beta[c_ev], meff[c_ev]) / substeps)
                        t_onset = i * dt_rec + s
                    elif kind == 2:
                        phase[c_ev] = 2
                    elif kind == 3:
                        phase[c_ev] = 0
                    else:
                        phase[c_ev] = 1
                    if kind == 3:
                        any_on = False
                        for c in range(nc):
                            if phase[c] != 0:
                                any_on = True
                        if not any_on:
                            in_contact = False
                            hc = h
                            # continue with exact steps from here to the next grid point
                            k_grid = int(math.floor(s / h + 1e-9))
                            if k_grid >= m_sub:
                                k_grid = m_sub - 1
                if in_contact:
                    k_grid = int(math.floor(s / h + 1e-9))
                    if k_grid >= m_sub:
                        k_grid = m_sub - 1
            # divergence / non-finite guard
            bad = False
            for j in range(n):
                if not (math.isfinite(q[j]) and math.isfinite(v[j])):
                    bad = True
            if bad:
                status = 1
                break
        if status != 0:
            break
    if mode == 1:
        # no contact in the whole record: the end state is shared
        _snapshot(pre, npts - 1, e_in, e_d, steps, e0, q, v, peaks)
        return
    if store and status == 0:
        i = npts - 1
        for f in range(nf):
            hx[i, f] = _rowdot(phi, f, q)
        for c in range(nc):
            hd[i, c] = _rowdot(psi, c, q) - gap[c]
            hf[i, c] = _force(model, hd[i, c], _rowdot(psi, c, v), beta[c], cd[c], meff[c], zhd[c],
                              phase[c])  # fmt: skip
    stored = 0.0
    for c in range(nc):
        if phase[c] != 0:
            stored += _stored(model, _rowdot(psi, c, q) - gap[c], beta[c])
    _finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored, peak_f,
            peak_t, steps, status)  # fmt: skip


@jit
def _snapshot(pre, i, e_in, e_d, steps, e0, q, v, peaks):
    n = q.size
    pre[1] = i
    pre[2] = e_in
    pre[3] = e_d
    pre[4] = steps
    pre[5] = e0
    for j in range(n):
        pre[6 + j] = q[j]
        pre[6 + n + j] = v[j]
    for f in range(peaks.size):
        pre[6 + 2 * n + f] = peaks[f]


@jit
def _finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored, peak_f,
            peak_t, steps, status):  # fmt: skip
    nc = cout.shape[0]
    e_mech = _mechanical_energy(q, v, omega)
    scale = abs(e_in) + e0
    if scale <= 0.0:
        scale = 1e-300
    residual = (e0 + e_in - e_mech - e_d - w_c) / scale
    pl = 0.0
    pr = 0.0
    for f in range(peaks.size):
        if side[f] == 0:
            pl = max(pl, peaks[f])
        else:
            pr = max(pr, peaks[f])
        if peaks[f] > DIVERGENCE_LIMIT_M:
            status = 1
    if status == 0 and not math.isfinite(residual):
        status = 1
    if status == 0 and abs(residual) > UNSTABLE_ENERGY_FRACTION:
        status = 1
    impacts = 0.0
    maxpen = -_INF
    impulse = 0.0
    for c in range(nc):
        impacts += cout[c, 1]
        maxpen = max(maxpen, cout[c, 2])
        impulse += cout[c, 3]
    out[0] = peak_f
    out[1] = impacts
    out[2] = maxpen if impacts > 0 else 0.0
    out[3] = pl
    out[4] = pr
    out[5] = impulse
    out[6] = w_c - stored
    out[7] = residual
    out[8] = status
    out[9] = e_in
    out[10] = steps
    out[11] = peak_t
    if status != 0:
        # unstable or not converged: no plain numbers that could be taken for results
        for k in (0, 2, 3, 4, 5, 6, 7):
            out[k] = np.nan
        for c in range(nc):
            for k in (0, 2, 3):
                cout[c, k] = np.nan
    else:
        for c in range(nc):
            if cout[c, 1] == 0.0:
                cout[c, 2] = 0.0


@jit(inline=True)
def _force_grad(model, d, dd, beta, c0, meff, zhd, phase):
    """Force [N] and its partial derivatives by penetration [N/m] and by its rate [N s/m]."""
    if phase == 0 or d <= 0.0:
        return 0.0, 0.0, 0.0
    sd = math.sqrt(d)
    if model == 0:
        f = beta * d * sd
        fd = 1.5 * beta * sd
        fdd = 0.0
        if phase == 1:
            q = math.sqrt(sd)  # d^0.25
            f += c0 * q * dd
            fd += 0.25 * c0 * dd / (q * q * q)
            fdd = c0 * q
        return f, fd, fdd
    if model == 1:
        return beta * d, beta, 0.0
    if model == 2:
        return beta * d + c0 * dd, beta, c0
    if model == 3:
        return beta * d * sd, 1.5 * beta * sd, 0.0
    f = beta * d * sd * (1.0 + zhd * dd)
    if f <= 0.0:
        return 0.0, 0.0, 0.0
    return f, 1.5 * beta * sd * (1.0 + zhd * dd), beta * d * sd * zhd


@jit
def _newton_scalar(model, dstar, dn, ddn, g, c2h, fprev, beta, c0, meff, zhd):
    """Contact force of one contact at the end of a Newmark step.

    Solves ``d - d* + g F(d, c2h (d - dn) - ddn) = 0`` for ``d`` in ``(0, d*)`` (the residual is
    ``-d*`` at 0 and ``g F > 0`` at ``d*``); Newton from ``d* - g F_prev`` (the force of the
    previous step), kept in the bracket by bisection.  Returns ``(F, converged)``.
    """
    lo = 0.0
    hi = dstar
    d = dstar - g * fprev
    if not (lo < d < hi):
        d = 0.5 * (lo + hi)
    f = 0.0
    for _ in range(100):
        ddt = c2h * (d - dn) - ddn
        f, fd, fdd = _force_grad(model, d, ddt, beta, c0, meff, zhd, _phase_of(d, ddt))
        r = d - dstar + g * f
        if abs(r) <= 1e-14 * dstar:
            return f, True
        if r > 0.0:
            hi = d
        else:
            lo = d
        slope = 1.0 + g * (fd + fdd * c2h)
        d_new = d - r / slope
        if not (lo < d_new < hi):
            d_new = 0.5 * (lo + hi)
        if abs(d_new - d) <= 1e-14 * dstar or hi - lo <= 1e-14 * dstar:
            ddt = c2h * (d_new - dn) - ddn
            f = _force(model, d_new, ddt, beta, c0, meff, zhd, _phase_of(d_new, ddt))
            return f, True
        d = d_new
    return f, False


# --------------------------------------------------------------------------- fixed step


@jit
def _solve_small(a, b, nc):
    """Solve ``a x = b`` in place (Gauss elimination with partial pivoting); returns ok."""
    for k in range(nc):
        p = k
        for r in range(k + 1, nc):
            if abs(a[r, k]) > abs(a[p, k]):
                p = r
        if a[p, k] == 0.0:
            return False
        if p != k:
            for col in range(nc):
                tmp = a[k, col]
                a[k, col] = a[p, col]
                a[p, col] = tmp
            tmp = b[k]
            b[k] = b[p]
            b[p] = tmp
        for r in range(k + 1, nc):
            f = a[r, k] / a[k, k]
            for col in range(k, nc):
                a[r, col] -= f * a[k, col]
            b[r] -= f * b[k]
    for k in range(nc - 1, -1, -1):
        acc = b[k]
        for col in range(k + 1, nc):
            acc -= a[k, col] * b[col]
        b[k] = acc / a[k, k]
    return True


@jit(inline=True)
def _phase_of(d, dd):
    if d <= 0.0:
        return 0
    return 1 if dd > 0.0 else 2


@jit
def _fixed(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model, method, dt_s,
    q, v, out, cout, hx, hd, hf,
):  # fmt: skip
    n = q.size
    nc = gap.size
    nf = phi.shape[0]
    npts = ag.size
    m_sub, h = _step_size(dt_rec, dt_s)
    cd = 2.0 * xi * np.sqrt(beta * meff)  # damping constants c0 of the force laws
    n_steps = (npts - 1) * m_sub
    store = hx.shape[0] > 0
    a = np.empty(n)
    qn = np.empty(n)
    vn = np.empty(n)
    an = np.empty(n)
    qs = np.empty(n)
    qprev = np.empty(n)
    khat = np.empty(n)
    fc = np.zeros(nc)
    fn = np.zeros(nc)
    fprev = np.zeros(nc)
    zhd = np.zeros(nc)
    dpen = np.zeros(nc)
    ddpen = np.zeros(nc)
    was_in = np.zeros(nc, dtype=np.bool_)
    g = np.zeros((nc, nc))
    jac = np.zeros((nc, nc))
    rhs = np.zeros(nc)
    dstar = np.zeros(nc)
    dtry = np.zeros(nc)
    peaks = np.zeros(nf)
    e0 = _mechanical_energy(q, v, omega)
    for c in range(nc):
        cout[c, 0] = 0.0
        cout[c, 1] = 0.0
        cout[c, 2] = -_INF
        cout[c, 3] = 0.0
    c2h = 2.0 / h
    c4h = 4.0 / h
    c4h2 = 4.0 / (h * h)
    ikhat = np.empty(n)
    zw2 = np.empty(n)
    for j in range(n):
        khat[j] = omega[j] * omega[j] + 4.0 * zeta[j] * omega[j] / h + 4.0 / (h * h)
        ikhat[j] = 1.0 / khat[j]
        zw2[j] = 2.0 * zeta[j] * omega[j]
    for c1 in range(nc):
        for c2 in range(nc):
            acc = 0.0
            for j in range(n):
                acc += psi[c1, j] * psi[c2, j] / khat[j]
            g[c1, c2] = acc
    # initial contact state and accelerations
    for c in range(nc):
        dpen[c] = _rowdot(psi, c, q) - gap[c]
        ddpen[c] = _rowdot(psi, c, v)
        fc[c] = _force(model, dpen[c], ddpen[c], beta[c], cd[c], meff[c], zhd[c],
                       _phase_of(dpen[c], ddpen[c]))  # fmt: skip
        was_in[c] = dpen[c] > 0.0
    _accel(q, v, ag[0], omega, zeta, gamma, psi, fc, a)
    if method == 3:
        for j in range(n):
            qprev[j] = q[j] - h * v[j] + 0.5 * h * h * a[j]
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    peak_f = 0.0
    peak_t = 0.0
    status = 0
    pin_prev, pd_prev = _powers(v, ag[0], omega, zeta, gamma)
    pc_prev = 0.0
    for c in range(nc):
        pc_prev += fc[c] * ddpen[c]
    steps = 0
    inv_m = 1.0 / m_sub
    i = 0
    k = -1
    for step in range(n_steps):
        k += 1
        if k == m_sub:
            k = 0
            i += 1
        if store and k == 0:
            for f in range(nf):
                hx[i, f] = _rowdot(phi, f, q)
            for c in range(nc):
                hd[i, c] = dpen[c]
                hf[i, c] = fc[c]
        t1 = (step + 1) * h
        ag1 = ag[i] + (ag[i + 1] - ag[i]) * ((k + 1) * inv_m)
        steps += 1
        if method == 3:
            # central difference: q_{n+1} from q_n, q_{n-1}; force at n from backward velocity
            ag_n = ag[i] + (ag[i + 1] - ag[i]) * (k * inv_m)
            for c in range(nc):
                dprev = _rowdot(psi, c, qprev) - gap[c]
                vb = (dpen[c] - dprev) / h
                fc[c] = _force(model, dpen[c], vb, beta[c], cd[c], meff[c], zhd[c],
                               _phase_of(dpen[c], vb))  # fmt: skip
            for j in range(n):
                p = -gamma[j] * ag_n
                for c in range(nc):
                    p -= fc[c] * psi[c, j]
                zw = zeta[j] * omega[j] * h
                qn[j] = (h * h * p + (2.0 - omega[j] * omega[j] * h * h) * q[j]
                         - (1.0 - zw) * qprev[j]) / (1.0 + zw)  # fmt: skip
            # velocity at n (central), then shift; the state reported is at n+1 with a
            # backward-difference velocity consistent with the scheme
            for j in range(n):
                v[j] = (qn[j] - qprev[j]) / (2.0 * h)
            # energies at step n with the central velocity, trapezoidal between n-1 and n
            pin1, pd1 = _powers(v, ag_n, omega, zeta, gamma)
            pc1 = 0.0
            for c in range(nc):
                pc1 += fc[c] * _rowdot(psi, c, v)
            if step > 0:
                e_in += 0.5 * h * (pin_prev + pin1)
                e_d += 0.5 * h * (pd_prev + pd1)
                w_c += 0.5 * h * (pc_prev + pc1)
                for c in range(nc):
                    cout[c, 3] += 0.5 * h * (fprev[c] + fc[c])
            for c in range(nc):
                fprev[c] = fc[c]
                if fc[c] > cout[c, 0]:
                    cout[c, 0] = fc[c]
                if fc[c] > peak_f:
                    peak_f = fc[c]
                    peak_t = t1 - h
            pin_prev = pin1
            pd_prev = pd1
            pc_prev = pc1
            for j in range(n):
                qprev[j] = q[j]
                q[j] = qn[j]
            for j in range(n):
                vn[j] = (q[j] - qprev[j]) / h
            for c in range(nc):
                fn[c] = fc[c]
        else:
            # Newmark average acceleration, modal predictor without contact at n+1
            for j in range(n):
                phat = -gamma[j] * ag1 + (c4h2 * q[j] + c4h * v[j] + a[j])
                phat += zw2[j] * (c2h * q[j] + v[j])
                qs[j] = phat * ikhat[j]
            for c in range(nc):
                dstar[c] = _rowdot(psi, c, qs) - gap[c]
            if method == 2:
                for c in range(nc):
                    fn[c] = fc[c]  # lagged one step
            else:
                # Newton on the penetrations: d - d* + G F(d, d_dot(d)) = 0
                any_pos = False
                for c in range(nc):
                    dtry[c] = dstar[c]
                    if dstar[c] > 0.0:
                        any_pos = True
                if not any_pos:
                    for c in range(nc):
                        fn[c] = 0.0
                elif nc == 1:
                    # scalar safeguarded Newton with the analytic slope, root in (0, d*)
                    fn[0], conv = _newton_scalar(
                        model, dstar[0], dpen[0], ddpen[0], g[0, 0], c2h, fc[0], beta[0], cd[0],
                        meff[0], zhd[0],
                    )  # fmt: skip
                    if not conv:
                        status = 2
                else:
                    conv = False
                    for _it in range(60):
                        for c in range(nc):
                            ddt = c2h * (dtry[c] - dpen[c]) - ddpen[c]
                            ph = _phase_of(dtry[c], ddt)
                            f, fd, fdd = _force_grad(model, dtry[c], ddt, beta[c], cd[c], meff[c],
                                                     zhd[c], ph)  # fmt: skip
                            fn[c] = f
                            rhs[c] = fd + fdd * c2h  # slope along the Newmark velocity
                        for c1 in range(nc):
                            for c2 in range(nc):
                                jac[c1, c2] = g[c1, c2] * rhs[c2] + (1.0 if c1 == c2 else 0.0)
                        for c1 in range(nc):
                            r = dtry[c1] - dstar[c1]
                            for c2 in range(nc):
                                r += g[c1, c2] * fn[c2]
                            rhs[c1] = -r
                        if not _solve_small(jac, rhs, nc):
                            break
                        step_max = 0.0
                        scale = 0.0
                        for c in range(nc):
                            step_max = max(step_max, abs(rhs[c]))
                            dtry[c] += rhs[c]
                            scale = max(scale, abs(dtry[c]), abs(dstar[c]))
                        if step_max <= 1e-12 * scale + 1e-15:
                            conv = True
                            break
                    for c in range(nc):
                        ddt = c2h * (dtry[c] - dpen[c]) - ddpen[c]
                        fn[c] = _force(model, dtry[c], ddt, beta[c], cd[c], meff[c], zhd[c],
                                       _phase_of(dtry[c], ddt))  # fmt: skip
                    if not conv:
                        status = 2
            for j in range(n):
                corr = 0.0
                for c in range(nc):
                    corr += fn[c] * psi[c, j]
                qn[j] = qs[j] - corr * ikhat[j]
                dq = qn[j] - q[j]
                vn[j] = c2h * dq - v[j]
                an[j] = c4h2 * dq - c4h * v[j] - a[j]
        # contact bookkeeping at n+1
        for c in range(nc):
            d1 = _rowdot(psi, c, qn if method != 3 else q) - gap[c]
            dd1 = _rowdot(psi, c, vn)
            if d1 > 0.0 and not was_in[c]:
                cout[c, 1] += 1.0
                if model == 4:
                    zhd[c] = 8.0 * (1.0 - xi[c]) / (5.0 * xi[c] * max(dd1, 1e-12))
            was_in[c] = d1 > 0.0
            dpen[c] = d1
            ddpen[c] = dd1
            if method == 2:
                # the force the next (lagged) step uses, from this state
                fn[c] = _force(model, d1, dd1, beta[c], cd[c], meff[c], zhd[c], _phase_of(d1, dd1))
            if d1 > cout[c, 2]:
                cout[c, 2] = d1
        if method != 3:
            # energies (trapezoidal); contact work with the force acting over the step
            pin1, pd1 = _powers(vn, ag1, omega, zeta, gamma)
            pc1 = 0.0
            for c in range(nc):
                pc1 += fn[c] * ddpen[c]
            e_in += 0.5 * h * (pin_prev + pin1)
            e_d += 0.5 * h * (pd_prev + pd1)
            w_c += 0.5 * h * (pc_prev + pc1)
            for c in range(nc):
                cout[c, 3] += 0.5 * h * (fc[c] + fn[c])
                if fn[c] > cout[c, 0]:
                    cout[c, 0] = fn[c]
                if fn[c] > peak_f:
                    peak_f = fn[c]
                    peak_t = t1
            pin_prev = pin1
            pd_prev = pd1
            pc_prev = pc1
        if method != 3:
            for j in range(n):
                q[j] = qn[j]
                v[j] = vn[j]
                a[j] = an[j]
        for c in range(nc):
            fc[c] = fn[c]
        bad = False
        for f in range(nf):
            x = abs(_rowdot(phi, f, q))
            if not x < DIVERGENCE_LIMIT_M:  # also true for NaN
                bad = True
            elif x > peaks[f]:
                peaks[f] = x
        if bad:
            status = 1
            break
    if store and status != 1:
        i = npts - 1
        for f in range(nf):
            hx[i, f] = _rowdot(phi, f, q)
        for c in range(nc):
            hd[i, c] = dpen[c]
            hf[i, c] = fc[c]
    stored = 0.0
    phase = np.zeros(nc, dtype=np.int64)
    if method == 3:
        # energies were integrated up to the last step n with its central velocity
        for j in range(n):
            q[j] = qprev[j]
        for c in range(nc):
            dpen[c] = _rowdot(psi, c, q) - gap[c]
    for c in range(nc):
        if dpen[c] > 0.0:
            stored += _stored(model, dpen[c], beta[c])
            phase[c] = 1
    _finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored, peak_f,
            peak_t, steps, status)  # fmt: skip


# --------------------------------------------------------------------------- entry points


@jit
def _newmark_pair(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model, method, dt_s,
    q, v, out, cout,
):  # fmt: skip
    """:func:`_fixed` for ``newmark`` / ``newmark-explicit`` on an SDOF pair, state in scalars.

    Same scheme, same arithmetic order for the state, same outputs; an SDOF pair needs no
    arrays in its step, which makes it about three times as fast (the tests hold it to the general
    kernel).
    """
    npts = ag.size
    m_sub, h = _step_size(dt_rec, dt_s)
    inv_m = 1.0 / m_sub
    c2h = 2.0 / h
    c4h = 4.0 / h
    c4h2 = 4.0 / (h * h)
    w0, w1 = omega[0], omega[1]
    zw0, zw1 = 2.0 * zeta[0] * omega[0], 2.0 * zeta[1] * omega[1]
    g0, g1 = gamma[0], gamma[1]
    ps0, ps1 = psi[0, 0], psi[0, 1]
    f0, f1 = phi[0, 0], phi[1, 1]
    kh0 = w0 * w0 + 4.0 * zeta[0] * w0 / h + c4h2
    kh1 = w1 * w1 + 4.0 * zeta[1] * w1 / h + c4h2
    ik0, ik1 = 1.0 / kh0, 1.0 / kh1
    gg = ps0 * ps0 * ik0 + ps1 * ps1 * ik1
    b = beta[0]
    cd = 2.0 * xi[0] * math.sqrt(beta[0] * meff[0])
    me = meff[0]
    gp = gap[0]
    q0, q1 = q[0], q[1]
    v0, v1 = v[0], v[1]
    e0 = 0.5 * (v0 * v0 + w0 * w0 * q0 * q0 + v1 * v1 + w1 * w1 * q1 * q1)
    zhd = 0.0
    dpen = ps0 * q0 + ps1 * q1 - gp
    ddpen = ps0 * v0 + ps1 * v1
    fc = _force(model, dpen, ddpen, b, cd, me, zhd, _phase_of(dpen, ddpen))
    was_in = dpen > 0.0
    a0 = -zw0 * v0 - w0 * w0 * q0 - g0 * ag[0] - fc * ps0
    a1 = -zw1 * v1 - w1 * w1 * q1 - g1 * ag[0] - fc * ps1
    pin_prev = -ag[0] * (g0 * v0 + g1 * v1)
    pd_prev = zw0 * v0 * v0 + zw1 * v1 * v1
    pc_prev = fc * ddpen
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    impulse = 0.0
    impacts = 0.0
    maxpen = -_INF
    peak_f = 0.0
    peak_t = 0.0
    pk0 = 0.0
    pk1 = 0.0
    status = 0
    steps = 0
    for i in range(npts - 1):
        dag = (ag[i + 1] - ag[i]) * inv_m
        for k in range(m_sub):
            ag1 = ag[i] + dag * (k + 1)
            steps += 1
            qs0 = (-g0 * ag1 + (c4h2 * q0 + c4h * v0 + a0) + zw0 * (c2h * q0 + v0)) * ik0
            qs1 = (-g1 * ag1 + (c4h2 * q1 + c4h * v1 + a1) + zw1 * (c2h * q1 + v1)) * ik1
            dstar = ps0 * qs0 + ps1 * qs1 - gp
            if method == 2:
                fn = fc  # lagged one step
            elif dstar > 0.0:
                fn, conv = _newton_scalar(model, dstar, dpen, ddpen, gg, c2h, fc, b, cd, me, zhd)
                if not conv:
                    status = 2
            else:
                fn = 0.0
            n0 = qs0 - fn * ps0 * ik0
            n1 = qs1 - fn * ps1 * ik1
            dq0 = n0 - q0
            dq1 = n1 - q1
            nv0 = c2h * dq0 - v0
            nv1 = c2h * dq1 - v1
            a0 = c4h2 * dq0 - c4h * v0 - a0
            a1 = c4h2 * dq1 - c4h * v1 - a1
            q0, q1, v0, v1 = n0, n1, nv0, nv1
            d1 = ps0 * q0 + ps1 * q1 - gp
            dd1 = ps0 * v0 + ps1 * v1
            if d1 > 0.0 and not was_in:
                impacts += 1.0
                if model == 4:
                    zhd = 8.0 * (1.0 - xi[0]) / (5.0 * xi[0] * max(dd1, 1e-12))
            was_in = d1 > 0.0
            dpen = d1
            ddpen = dd1
            if method == 2:
                fn = _force(model, d1, dd1, b, cd, me, zhd, _phase_of(d1, dd1))
            if d1 > maxpen:
                maxpen = d1
            pin1 = -ag1 * (g0 * v0 + g1 * v1)
            pd1 = zw0 * v0 * v0 + zw1 * v1 * v1
            pc1 = fn * dd1
            e_in += 0.5 * h * (pin_prev + pin1)
            e_d += 0.5 * h * (pd_prev + pd1)
            w_c += 0.5 * h * (pc_prev + pc1)
            impulse += 0.5 * h * (fc + fn)
            if fn > peak_f:
                peak_f = fn
                peak_t = (i * m_sub + k + 1) * h
            pin_prev = pin1
            pd_prev = pd1
            pc_prev = pc1
            fc = fn
            x0 = abs(f0 * q0)
            x1 = abs(f1 * q1)
            if x0 > pk0:
                pk0 = x0
            if x1 > pk1:
                pk1 = x1
            if not (x0 < DIVERGENCE_LIMIT_M and x1 < DIVERGENCE_LIMIT_M):
                status = 1
                break
        if status == 1:
            break
    q[0], q[1], v[0], v[1] = q0, q1, v0, v1
    cout[0, 0] = peak_f
    cout[0, 1] = impacts
    cout[0, 2] = maxpen
    cout[0, 3] = impulse
    peaks = np.empty(2)
    peaks[0] = pk0
    peaks[1] = pk1
    phase = np.zeros(1, dtype=np.int64)
    stored = 0.0
    if dpen > 0.0:
        stored = _stored(model, dpen, b)
        phase[0] = 1
    _finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored, peak_f,
            peak_t, steps, status)  # fmt: skip


@jit
def _run(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model, method, dt_s,
    substeps, q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    if not (dt_s > 0.0) or (ag.size - 1) * dt_rec / dt_s > MAX_STEPS:
        # a step so small that the run could not end: flagged as not converged
        for k in range(out.size):
            out[k] = np.nan
        out[1] = 0.0
        out[8] = 2.0
        out[10] = 0.0
        for c in range(cout.shape[0]):
            for k in range(cout.shape[1]):
                cout[c, k] = np.nan
        return
    if method == 0:
        _adaptive(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model,
                  dt_s, substeps, q, v, out, cout, hx, hd, hf, pre)  # fmt: skip
    elif (
        (method == 1 or method == 2) and omega.size == 2 and gap.size == 1
        and phi.shape[0] == 2 and phi[0, 1] == 0.0 and phi[1, 0] == 0.0 and hx.shape[0] == 0
    ):  # fmt: skip
        _newmark_pair(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                      model, method, dt_s, q, v, out, cout)  # fmt: skip
    else:
        _fixed(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, model,
               method, dt_s, q, v, out, cout, hx, hd, hf)  # fmt: skip


def run_kernel(
    ag,
    dt_rec,
    omega,
    zeta,
    gamma,
    phi,
    side,
    psi,
    gap,
    meff,
    beta,
    xi,
    *,
    model: int = 0,
    method: int = 0,
    dt_s: float = 0.001,
    substeps: int = 16,
    q0=None,
    v0=None,
    history: bool = False,
):
    """Run one simulation on prepared modal arrays.

    :func:`pound_mc.scene.simulate` is the scene-level entry point.
    Returns ``(out, contact_out, history_or_None)``.
    """
    n = omega.size
    nc = gap.size
    nf = phi.shape[0]
    q = np.zeros(n) if q0 is None else np.array(q0, dtype=float)
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float)
    out = np.empty(_N_OUT)
    cout = np.empty((nc, len(CONTACT_OUTPUTS)))
    nh = ag.size if history else 0
    hx = np.zeros((nh, nf))
    hd = np.zeros((nh, nc))
    hf = np.zeros((nh, nc))
    f8 = np.float64
    _run(
        np.ascontiguousarray(ag, dtype=f8), f8(dt_rec),
        np.ascontiguousarray(omega, dtype=f8), np.ascontiguousarray(zeta, dtype=f8),
        np.ascontiguousarray(gamma, dtype=f8), np.ascontiguousarray(phi, dtype=f8),
        np.ascontiguousarray(side, dtype=np.int64), np.ascontiguousarray(psi, dtype=f8),
        np.ascontiguousarray(gap, dtype=f8), np.ascontiguousarray(meff, dtype=f8),
        np.ascontiguousarray(beta, dtype=f8), np.ascontiguousarray(xi, dtype=f8),
        int(model), int(method), f8(dt_s), f8(substeps), q, v, out, cout, hx, hd, hf,
        np.zeros(0),
    )  # fmt: skip
    hist = (hx, hd, hf) if history else None
    return out, cout, hist


@jit(inline=True)
def _sdof_arrays(k, tl, zl, ml, tr, zr, mr, gap, beta, xi):
    """Modal arrays of SDOF pair ``k`` (mass-normalised: q = sqrt(m) x)."""
    omega = np.empty(2)
    zeta = np.empty(2)
    gamma = np.empty(2)
    phi = np.zeros((2, 2))
    side = np.zeros(2, dtype=np.int64)
    side[1] = 1
    psi = np.empty((1, 2))
    omega[0] = 2.0 * math.pi / tl[k]
    omega[1] = 2.0 * math.pi / tr[k]
    zeta[0] = zl[k]
    zeta[1] = zr[k]
    gamma[0] = math.sqrt(ml[k])
    gamma[1] = math.sqrt(mr[k])
    phi[0, 0] = 1.0 / gamma[0]
    phi[1, 1] = 1.0 / gamma[1]
    psi[0, 0] = phi[0, 0]
    psi[0, 1] = -phi[1, 1]
    g = np.full(1, gap[k])
    me = np.full(1, ml[k] * mr[k] / (ml[k] + mr[k]))
    be = np.full(1, beta[k])
    x = np.full(1, xi[k])
    return omega, zeta, gamma, phi, side, psi, g, me, be, x


@jit(parallel=True)
def _sdof_batch(
    ag, dt_rec, tl, zl, ml, tr, zr, mr, gap, beta, xi, dt_s, model, method, substeps, out,
    first, group, shared,
):  # fmt: skip
    # 1. adaptive: the linear response up to the first contact of each group of simulations
    #    that differ only in contact parameters, once per group (``first`` = a member of it)
    ngroup = first.size
    empty = np.zeros((0, 2))
    empty1 = np.zeros((0, 1))
    if method == 0:
        for gi in numba.prange(ngroup):
            k = first[gi]
            omega, zeta, gamma, phi, side, psi, g, me, be, x = _sdof_arrays(
                k, tl, zl, ml, tr, zr, mr, gap, beta, xi
            )
            shared[gi, 0] = 1.0
            _run(ag, dt_rec, omega, zeta, gamma, phi, side, psi, g, me, be, x, model, method,
                 dt_s[k], substeps, np.zeros(2), np.zeros(2), np.empty(_N_OUT),
                 np.empty((1, 4)), empty, empty1, empty1, shared[gi])  # fmt: skip
            shared[gi, 0] = 2.0
    # 2. every simulation, resumed from its group's shared state
    nsim = tl.size
    for k in numba.prange(nsim):
        omega, zeta, gamma, phi, side, psi, g, me, be, x = _sdof_arrays(
            k, tl, zl, ml, tr, zr, mr, gap, beta, xi
        )
        pre = shared[group[k]] if method == 0 else np.zeros(0)
        _run(ag, dt_rec, omega, zeta, gamma, phi, side, psi, g, me, be, x, model, method,
             dt_s[k], substeps, np.zeros(2), np.zeros(2), out[k], np.empty((1, 4)), empty,
             empty1, empty1, pre.copy())  # fmt: skip


def simulate_sdof_pairs(
    acc,
    dt_rec,
    *,
    left_period_s,
    left_damping_ratio,
    left_mass_kg,
    right_period_s,
    right_damping_ratio,
    right_mass_kg,
    gap_m,
    beta,
    xi,
    dt_s,
    method: str = "adaptive",
    contact_model: str = "jankowski",
    substeps: int = 16,
) -> dict[str, np.ndarray]:
    """Run many SDOF-pair simulations on one record in parallel threads.

    Every argument after ``dt_rec`` is an array with one value per simulation (or a scalar).
    Returns ``{output name: array}`` for every name in :data:`OUTPUTS`; each simulation writes
    only its own slot, so results do not depend on the number of threads.
    """
    from pound_mc.physics.contact import CONTACT_MODELS

    arrays = [
        left_period_s, left_damping_ratio, left_mass_kg, right_period_s, right_damping_ratio,
        right_mass_kg, gap_m, beta, xi, dt_s,
    ]  # fmt: skip
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in arrays])
    arrays = [np.ascontiguousarray(a.ravel()) for a in arrays]
    nsim = arrays[0].size
    out = np.empty((nsim, _N_OUT))
    # simulations that differ only in contact parameters share their linear response up to
    # the first contact (periods, damping ratios, masses, gap and step define a group)
    linear = np.stack([arrays[k] for k in (0, 1, 2, 3, 4, 5, 6, 9)], axis=1)
    _, first, group = np.unique(linear, axis=0, return_index=True, return_inverse=True)
    shared = np.zeros((first.size, 6 + 2 * 2 + 2))
    _sdof_batch(
        np.ascontiguousarray(acc, dtype=np.float64), float(dt_rec), *arrays[:9],
        arrays[9], CONTACT_MODELS[contact_model]["code"], METHODS[method], float(substeps), out,
        first.astype(np.int64), group.ravel().astype(np.int64), shared,
    )  # fmt: skip
    result = {name: out[:, k] for k, name in enumerate(OUTPUTS)}
    result["impacts"] = result["impacts"].astype(np.int32)
    result["status"] = result["status"].astype(np.int8)
    result["steps"] = result["steps"].astype(np.int64)
    return result


@jit(parallel=True)
def _scene_batch(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap, beta, xi, dt_s, model, method,
    substeps, out, cout,
):  # fmt: skip
    nsim = beta.size
    n = omega.size
    nf = phi.shape[0]
    nc = psi.shape[0]
    for k in numba.prange(nsim):
        empty = np.zeros((0, nf))
        empty1 = np.zeros((0, nc))
        _run(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap[k].copy(), meff,
             np.full(nc, beta[k]), np.full(nc, xi[k]), model, method, dt_s[k], substeps,
             np.zeros(n), np.zeros(n), out[k], cout[k], empty, empty1, empty1,
             np.zeros(0))  # fmt: skip


def simulate_scene_batch(
    acc,
    dt_rec,
    arrays: dict,
    *,
    gap_m,
    beta,
    xi,
    dt_s,
    method: str = "adaptive",
    contact_model: str = "jankowski",
    substeps: int = 16,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Run many simulations of one pair of buildings (any model) on one record, in threads.

    Parameters
    ----------
    acc, dt_rec
        Ground acceleration [m/s^2] and its sampling interval [s].
    arrays : dict
        :meth:`pound_mc.scene.Scene.modal_arrays` of the pair (shared by every simulation).
    gap_m : array_like
        Gaps [m], shape ``(nsim,)`` (every contact) or ``(nsim, n_contacts)``.
    beta, xi, dt_s : array_like
        Per simulation: impact stiffness [N/m^1.5, or N/m for linear laws], damping ratio (the
        restitution ``e`` for ``hertzdamp``) and step bound [s].

    Returns
    -------
    outputs : dict
        ``{name: (nsim,)}`` for every name in :data:`OUTPUTS`.
    contacts : dict
        ``{name: (nsim, n_contacts)}`` for every name in :data:`CONTACT_OUTPUTS`.
    """
    from pound_mc.physics.contact import CONTACT_MODELS

    nc = arrays["psi"].shape[0]
    beta, xi, dt_s = np.broadcast_arrays(
        *[np.asarray(a, dtype=np.float64) for a in (beta, xi, dt_s)]
    )
    beta, xi, dt_s = (np.ascontiguousarray(a.ravel()) for a in (beta, xi, dt_s))
    nsim = beta.size
    gap = np.asarray(gap_m, dtype=np.float64)
    gap = np.ascontiguousarray(
        np.broadcast_to(gap.reshape(gap.shape[0] if gap.ndim else 1, -1), (nsim, nc))
    )
    out = np.empty((nsim, _N_OUT))
    cout = np.empty((nsim, nc, len(CONTACT_OUTPUTS)))
    f8 = np.float64
    _scene_batch(
        np.ascontiguousarray(acc, dtype=f8),
        f8(dt_rec),
        *(np.ascontiguousarray(arrays[k], dtype=f8) for k in ("omega", "zeta", "gamma", "phi")),
        np.ascontiguousarray(arrays["side"], dtype=np.int64),
        np.ascontiguousarray(arrays["psi"], dtype=f8),
        np.ascontiguousarray(arrays["meff"], dtype=f8),
        gap,
        beta,
        xi,
        dt_s,
        CONTACT_MODELS[contact_model]["code"],
        METHODS[method],
        f8(substeps),
        out,
        cout,
    )  # fmt: skip
    result = {name: out[:, k] for k, name in enumerate(OUTPUTS)}
    result["impacts"] = result["impacts"].astype(np.int32)
    result["status"] = result["status"].astype(np.int8)
    result["steps"] = result["steps"].astype(np.int64)
    contacts = {name: cout[:, :, k] for k, name in enumerate(CONTACT_OUTPUTS)}
    contacts["impacts"] = contacts["impacts"].astype(np.int32)
    return result, contacts
