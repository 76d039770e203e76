"""The linear phase of the SDOF pair's ``adaptive`` kernel: exact steps between contacts.

The pieces :func:`~pound_mc.integrators.adaptive_pair.adaptive_pair` takes its linear steps
with: the exact (Nigam-Jennings) step of each mode, the exact solution inside a step (the
penetration or a floor's displacement with its rate and acceleration, their roots and maxima),
the energies by the corrected trapezoidal rule, the sums of a run of quiet whole steps and the
floor peaks; and the two steps themselves: :func:`_quiet_step` (a whole grid step where
nothing happens inside it) and :func:`_linear_step` (any step, to the next grid point or to a
contact onset inside it).  Notation as in :mod:`~pound_mc.integrators.adaptive_pair`; the
constants travel as tuples ``lin = (m_sub, h, dt_rec, cf0, cf1, herm_tol)`` (the grid, the
exact-step coefficients of each mode and the tolerance of a floor peak's Hermite screen),
``md = (w0, z0, g0, w1, z1, g1)``, ``geo = (ps0, ps1, gp, f0, f1)`` and ``km``
(:func:`_ends`).
"""

from __future__ import annotations

from pound_mc._jit import jit
from pound_mc.integrators.toolkit import (
    advance,
    grid_step,
    hermite_max,
    hermite_root,
    newton_in_bracket,
    turning_screen,
)

__all__ = ["ONSET_TOL", "QUADRATIC_ROOT_SPAN"]

_TWELFTH = 1.0 / 12.0
#: Contact onset located to this fraction of the step [-] (1e-12 of a 0.01 s step: the
#: penetration at the located onset is ~1e-14 v0, far below anything the contact phase resolves).
#: What holds in every case is the penetration: at a grazing onset (rate near 0) the time of a
#: root within round-off of zero may be off by more.
ONSET_TOL = 1e-12
#: An onset within this fraction of the step from the cubic Hermite guess is the root of the
#: second-order Taylor polynomial at the guess (:func:`_exact_root_pair`).
QUADRATIC_ROOT_SPAN = 1e-4


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


@jit(llvm_inline=True)
def _quiet_step(
    k_grid, s, ag0, slope, q0, q1, v0, v1, dc0, ddc0, xf0, xfd0, xf1, xfd1, pk0, pk1, en0, run,
    lean, floors, lin, md, geo, km,
):  # fmt: skip
    """One step of a quiet run: a whole grid step where nothing happens inside it.

    No onset, no turning penetration, no floor extremum: the same arithmetic as
    :func:`_linear_step`, which takes the other steps (from the grid point a run stops at).
    ``k_grid, s``: the grid point and local time [s] the step starts at in the record interval
    (ground acceleration ``ag0 + slope t``); the state, the penetration ``dc0`` and its rate
    ``ddc0``, the floors' displacements and velocities ``xf, xfd`` and their peaks ``pk`` at
    its start; ``en0``: the sums of :func:`_ends` at the run's start, ``run``: the run's sums
    (:func:`_quiet_start`); ``lean``: no energies; ``floors``: the floor peaks.  Returns whether the
    step was quiet, its length [s] and all of these at its end; where it was not, the state as
    it was (the general step takes it).
    """
    m_sub, h, dt_rec, cf0, cf1, herm_tol = lin
    w0, z0, g0, w1, z1, g1 = md
    ps0, ps1, gp, f0, f1 = geo
    _, hh, p0s, p1s, quiet = grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope)
    if not quiet:  # not a whole step: the general step takes it
        return False, hh, q0, q1, v0, v1, dc0, ddc0, xf0, xfd0, xf1, xfd1, pk0, pk1, run
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
    if not quiet:  # the general step takes this grid step
        return False, hh, q0, q1, v0, v1, dc0, ddc0, xf0, xfd0, xf1, xfd1, pk0, pk1, run
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
    return True, hh, nq0, nq1, nv0, nv1, d1, dd1, xf0, xfd0, xf1, xfd1, pk0, pk1, run


@jit(llvm_inline=True)
def _linear_step(
    k_grid, s, ag0, slope, q0, q1, v0, v1, fresh, dc0, ddc0, xf0, xfd0, xf1, xfd1, en0, e_in,
    e_d, pk0, pk1, lean, floors, lin, md, geo, km,
):  # fmt: skip
    """The exact linear step to the next grid point, or to a contact onset inside it.

    Arguments as :func:`_quiet_step`; ``en0``: the sums of :func:`_ends` at the step's start,
    ``e_in, e_d``: input and damping energy so far; ``fresh``: ``dc0, ddc0, xf, xfd`` and
    ``en0`` hold the step's start (else they are taken from the state).  An onset is where the
    penetration crosses zero on the exact solution (a maximum inside the step screened by the
    cubic Hermite bound, found on the exact solution), located by safeguarded Newton, or a
    penetration since a located separation that grows again.  Returns whether the step ends at
    an onset, its length [s], the state, the penetration and its rate at its end, and the
    floors, the energy sums, the energies and the floor peaks there (the energy sums and the
    energies as they were where ``lean``, the floors and their peaks where not ``floors``).
    """
    m_sub, h, dt_rec, cf0, cf1, herm_tol = lin
    w0, z0, g0, w1, z1, g1 = md
    ps0, ps1, gp, f0, f1 = geo
    s_next, hh, p0s, p1s, whole_step = grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope)
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
    return (onset, hh, nq0, nq1, nv0, nv1, dc1, ddc1, xf0, xfd0, xf1, xfd1, en0, e_in, e_d, pk0,
            pk1)  # fmt: skip
