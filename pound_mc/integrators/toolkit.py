"""Shared toolkit of the compiled integrators: exact linear steps, cubic Hermite screens.

* :func:`advance` / :func:`coefficients`: the exact (Nigam-Jennings) step of one linear mode
  under a load linear in time (Nigam & Jennings 1969; Chopra, Table 5.2.1);
* :func:`hermite_max` / :func:`hermite_root`: the cubic Hermite interpolant of a quantity and
  its rate over a step, its interior maximum and its first root (event screens);
* :func:`exact_delta` / :func:`exact_root`: a penetration (or any row of modal weights) on the
  exact linear solution inside a step, and its root by safeguarded Newton;
* :func:`step_size`, the modal accelerations and powers, and the energy sums that the methods
  share; :func:`solve_small` for the Newton systems of several contacts.
"""

from __future__ import annotations

import math

import numpy as np
from numba import types
from numba.extending import intrinsic, overload
from numba.np.arrayobj import make_array, populate_array

from pound_mc._jit import jit

#: Most integration steps one simulation may take (record length / dt_s); beyond it the run is
#: flagged not converged instead of running for hours.
MAX_STEPS = 2.0e9
#: The Taylor series of :func:`advance` (``w h < 0.05``) stops once the next term is below this
#: share of the state's scale, ``(w h)^k / k!`` (under round-off: further terms leave the sum as
#: it is).
SERIES_TOL = 1e-17


@jit(inline=True)
def step_size(dt_rec, dt_s):
    """Steps per record interval and their length [s].

    The step is the longest one no longer than ``dt_s`` that divides the record's interval.
    """
    m_sub = max(1, int(math.ceil(dt_rec / dt_s - 1e-9)))
    return m_sub, dt_rec / m_sub


@jit(inline=True)
def grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope):
    """The linear step from local time ``s`` to grid point ``k_grid + 1`` of a record interval.

    The interval (``dt_rec`` [s], ground acceleration ``ag0 + slope t``) is split in ``m_sub``
    steps of ``h``; the last grid point is the interval's end itself, not ``m_sub h``.
    Returns its end [s], its length [s], the ground accelerations at both ends [m/s^2] and
    whether it is a whole step of ``h`` (whose precomputed coefficients apply).
    """
    s_next = dt_rec if k_grid + 1 == m_sub else (k_grid + 1) * h
    hh = s_next - s
    return s_next, hh, ag0 + slope * s, ag0 + slope * s_next, abs(hh - h) <= 1e-12 * h


@jit(inline=True)
def run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q):
    """Sizes, step and damping constants every kernel starts a run with.

    Returns ``(n, nc, nf, npts, m_sub, h, cd)``: modes, contacts, floors, record samples,
    steps per record interval and their length [s] (:func:`step_size`), and the damping
    constants ``c0 = 2 xi sqrt(beta m_eff)`` of the force laws per contact.
    """
    m_sub, h = step_size(dt_rec, settings.dt_s)
    cd = 2.0 * xi * np.sqrt(beta * meff)
    return q.size, gap.size, phi.shape[0], ag.size, m_sub, h, cd


@jit(inline=True)
def trapezoid(h, e_in, e_d, w_c, pin0, pd0, pc0, pin1, pd1, pc1):
    """Energy input, damping and contact work [J] after one trapezoidal step of ``h`` [s].

    ``pin``, ``pd``, ``pc``: input, damping and contact powers [W] at the step's two ends.
    """
    return (
        e_in + 0.5 * h * (pin0 + pin1),
        e_d + 0.5 * h * (pd0 + pd1),
        w_c + 0.5 * h * (pc0 + pc1),
    )


@jit
def advance(q, v, p0, p1, w, z, h):
    """Exact state after ``h`` of ``q'' + 2 z w q' + w^2 q = p`` with ``p`` linear p0 -> p1.

    Closed form (Nigam & Jennings 1969; Chopra, Table 5.2.1) for ``w h >= 0.05``, else a
    Taylor series of the exact solution (the closed form cancels digits for short steps) to
    :data:`SERIES_TOL`.
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
        r = 1.0  # (w h)^(k+1) / (k+1)!: the terms left, relative to the state's scale
        for k in range(24):
            pk = p0 if k == 0 else (slope if k == 1 else 0.0)
            d2 = pk - 2.0 * z * w * d1 - w * w * d0  # d_{k+2}
            tv = tv * h / (k + 1)  # h^(k+1) / (k+1)!
            vs += d2 * tv
            qs += d2 * tv * h / (k + 2)
            d0 = d1
            d1 = d2
            r = r * w * h / (k + 1)
            if k >= 1 and r < SERIES_TOL:
                break  # the rest is below round-off (w h < 0.05: 9 terms at most)
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
    return coefficients(float(omega), float(zeta), float(h))


@jit
def coefficients(w, z, h):
    """Compiled :func:`exact_step_coefficients` (``w`` [rad/s], ``z`` [-], ``h`` [s])."""
    out = np.empty((2, 4))
    for col in range(4):
        q0 = 1.0 if col == 0 else 0.0
        v0 = 1.0 if col == 1 else 0.0
        p0 = 1.0 if col == 2 else 0.0
        p1 = 1.0 if col == 3 else 0.0
        q1, v1 = advance(q0, v0, p0, p1, w, z, h)
        out[0, col] = q1
        out[1, col] = v1
    return out


@jit(llvm_inline=True)
def hermite_max(y0, yp0, y1, yp1, h):
    """Largest interior local maximum of the cubic Hermite interpolant on ``[0, h]``.

    Returns ``(value, tau)``; ``(-inf, 0)`` when the cubic has no interior maximum.
    """
    b = h * yp0
    c = 3.0 * (y1 - y0) - h * (2.0 * yp0 + yp1)
    d = 2.0 * (y0 - y1) + h * (yp0 + yp1)
    best = -np.inf
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


@jit(inline=True)
def turning_screen(d0, dd0, d1, dd1, hh):
    """Whether a penetration that turns inside a step may reach zero there.

    ``d, dd``: the penetration [m] and its rate at the step's ends.  Where the rate turns from
    + to -, the step holds one maximum; its cubic Hermite estimate, within a margin of 5 % of
    the rates times the step ``hh`` [s], decides whether the exact maximum is looked for.
    Returns ``(look, tg)``: that decision and the Hermite estimate of its time [s].
    """
    if dd0 > 0.0 and dd1 < 0.0:
        hm, tg = hermite_max(d0, dd0, d1, dd1, hh)
        margin = 0.05 * (abs(dd0) + abs(dd1)) * hh
        return hm > -margin, tg
    return False, 0.0


@jit(llvm_inline=True)
def hermite_root(y0, yp0, y1, yp1, h):
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
        if abs(s_new - s) < 1e-15:
            # converged; tested before the safeguard, which would take a converged step
            # onto the bracket's end (the bracket moved to ``s``) for a bisection
            if lo <= s_new <= hi:
                s = s_new
            break
        if not (lo < s_new < hi):
            s_new = 0.5 * (lo + hi)
        s = s_new
    return s * h


@jit(inline=True)
def rowdot(mat, r, x):
    """Dot product of row ``r`` of ``mat`` with ``x``."""
    acc = 0.0
    for j in range(x.size):
        acc += mat[r, j] * x[j]
    return acc


@jit(inline=True)
def row_spans(mat):
    """First and one past the last non-zero column of every row (unsigned: no wraparound).

    Of the transposed mode shapes: the floors of the building a mode belongs to; of the
    transposed contact rows: the contacts a mode takes part in.
    """
    nr, ncol = mat.shape
    lo = np.zeros(nr, dtype=np.uint64)
    hi = np.zeros(nr, dtype=np.uint64)
    for r in range(nr):
        for j in range(ncol):
            if mat[r, j] != 0.0:
                if hi[r] == 0:
                    lo[r] = j
                hi[r] = j + 1
    return lo, hi


@jit(inline=True)
def matvec_spans(mat_t, x, out, lo, hi):
    """``out = mat x`` from the transpose ``mat_t`` of ``mat`` and its spans (:func:`row_spans`).

    Every ``out[r]`` is summed over ``j`` in the order :func:`rowdot` sums it, and to the same
    number: the terms left out, outside the spans, are zero products, which leave a finite sum
    as it is.  The inner loop runs over ``r``, whose sums do not wait on one another.
    """
    for r in range(out.size):
        out[r] = 0.0
    for j in range(x.size):
        xj = x[j]
        for r in range(lo[j], hi[j]):
            out[r] += mat_t[j, r] * xj


@jit(inline=True)
def accel(q, v, ag, omega, zeta, gamma, psi, fc, a):
    """Modal accelerations into ``a`` for ground acceleration ``ag`` and contact forces."""
    n = q.size
    for j in range(n):
        a[j] = -2.0 * zeta[j] * omega[j] * v[j] - omega[j] * omega[j] * q[j] - gamma[j] * ag
    for c in range(fc.size):
        if fc[c] != 0.0:
            for j in range(n):
                a[j] -= fc[c] * psi[c, j]


@jit(inline=True)
def powers(v, ag, omega, zeta, gamma):
    """Input power -a_g sum gamma v and structural damping power sum 2 zeta omega v^2."""
    pin = 0.0
    pd = 0.0
    for j in range(v.size):
        pin -= ag * gamma[j] * v[j]
        pd += 2.0 * zeta[j] * omega[j] * v[j] * v[j]
    return pin, pd


@jit
def track_floors(phi_t, flo, fhi, xf, xfd, q1, v1, h, peaks, xb, xdb):
    """Update the continuous-time peak |x| of every floor over a step (Hermite).

    ``phi_t``: the transposed mode shapes, ``flo, fhi`` their spans (:func:`row_spans`);
    ``xf, xfd``: every floor's displacement and velocity at the step's start, replaced by those
    at its end (state ``q1, v1``): the next step starts where this one ends; ``xb, xdb``:
    scratch of one value per floor.
    """
    matvec_spans(phi_t, q1, xb, flo, fhi)
    matvec_spans(phi_t, v1, xdb, flo, fhi)
    for f in range(xb.size):
        x0 = xf[f]
        xd0 = xfd[f]
        x1 = xb[f]
        xd1 = xdb[f]
        xf[f] = x1
        xfd[f] = xd1
        m = abs(x1)
        if m > peaks[f]:
            peaks[f] = m
        if (xd0 > 0.0) != (xd1 > 0.0):
            hm, _ = hermite_max(x0, xd0, x1, xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm
            hm, _ = hermite_max(-x0, -xd0, -x1, -xd1, h)
            if hm > peaks[f]:
                peaks[f] = hm


@jit
def mechanical_energy(q, v, omega):
    """Kinetic plus strain energy of the modes per unit modal mass [J]."""
    e = 0.0
    for j in range(q.size):
        e += 0.5 * (v[j] * v[j] + omega[j] * omega[j] * q[j] * q[j])
    return e


@jit(inline=True)
def end_values(q, v, ag, omega, zeta, gamma, en):
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
def refresh(q, v, ag, omega, zeta, gamma, phi, psi, gap, dc, ddc, xf, xfd, en):
    """Values at the current state that linear steps carry from one step to the next."""
    for c in range(gap.size):
        dc[c] = rowdot(psi, c, q) - gap[c]
        ddc[c] = rowdot(psi, c, v)
    for f in range(phi.shape[0]):
        xf[f] = rowdot(phi, f, q)
        xfd[f] = rowdot(phi, f, v)
    end_values(q, v, ag, omega, zeta, gamma, en)


@jit
def exact_delta(q, v, p0s, slope, s, tau, c, omega, zeta, gamma, psi, gap):
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
        qm, vm = advance(q[j], v[j], -gamma[j] * p0s, -gamma[j] * ag, omega[j], zeta[j], tau)
        am = -2.0 * zeta[j] * omega[j] * vm - omega[j] * omega[j] * qm - gamma[j] * ag
        d += psi[c, j] * qm
        dd += psi[c, j] * vm
        ddd += psi[c, j] * am
    return d, dd, ddd


@jit(inline=True)
def newton_in_bracket(t, d, dd, ddd, which, lo, hi, tol):
    """One safeguarded Newton step for a root of delta (``which = 0``) or of its rate.

    The bracket ``[lo, hi]`` shrinks to the side of ``t`` that keeps the root; a step leaving
    it is replaced by bisection.  Returns ``(t, lo, hi, done)``, done when the step is below
    ``tol`` of the bracket's end or the bracket below 1e-15 of it.
    """
    g = d if which == 0 else -dd
    gp = dd if which == 0 else -ddd
    if g > 0.0:
        hi = t
    else:
        lo = t
    t_new = t - g / gp if gp != 0.0 else 0.5 * (lo + hi)
    if abs(t_new - t) <= tol * (hi + 1e-300) and lo <= t_new <= hi:
        # converged: tested before the safeguard, which would take a converged step onto
        # the bracket's end (the bracket moved to ``t``) for a bisection
        return t_new, lo, hi, True
    if not (lo < t_new < hi):
        t_new = 0.5 * (lo + hi)
    done = abs(t_new - t) <= tol * (hi + 1e-300) or hi - lo <= 1e-15 * hi
    return t_new, lo, hi, done


@jit
def exact_root(q, v, p0s, slope, s, guess, lo, hi, which, c, omega, zeta, gamma, psi, gap):
    """Root in ``[lo, hi]`` on the exact linear solution.

    Of delta (``which = 0``, from below) or delta_dot (``which = 1``, from above);
    Newton from ``guess``, kept in the bracket.
    """
    t = guess
    if not (lo < t < hi):
        t = 0.5 * (lo + hi)
    for _ in range(60):
        d, dd, ddd = exact_delta(q, v, p0s, slope, s, t, c, omega, zeta, gamma, psi, gap)
        t, lo, hi, done = newton_in_bracket(t, d, dd, ddd, which, lo, hi, 1e-15)
        if done:
            break
    return t


@jit
def solve_small(a, b, nc):
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


def borrow(arr):
    """A view of ``arr`` that does not own its memory (no reference counting on it).

    numba counts the references of every array that a helper receives, atomically, at each
    call of an inlined helper with loops; a view without an owner makes each count a test
    for null.  The owner must outlive the view: only views of a function's arguments, or of
    arrays its caller holds, are safe.  In Python (``NUMBA_DISABLE_JIT=1``) ``arr`` itself.
    """
    return arr


@intrinsic
def _ownerless(typingctx, arr):
    """Compiled :func:`borrow`: ``arr``'s data, shape and strides without its meminfo."""
    if not isinstance(arr, types.Array):
        return None

    def codegen(context, builder, sig, args):
        src = make_array(arr)(context, builder, value=args[0])
        dst = make_array(arr)(context, builder)
        populate_array(dst, data=src.data, shape=src.shape, strides=src.strides,
                       itemsize=src.itemsize, meminfo=None, parent=None)  # fmt: skip
        return dst._getvalue()

    return arr(arr), codegen


@overload(borrow)
def _borrow_compiled(arr):
    if isinstance(arr, types.Array):
        return lambda arr: _ownerless(arr)
    return None
