"""``adaptive`` for a bilinear SDOF pair: exact steps per branch between located yield events.

A bilinear SDOF (kinematic hardening, ``../shared/DESIGN.md`` section 9) is piecewise linear.
Building ``j`` (mode ``j``, floor ``x = f q``, storey stiffness ``k``, yield drift ``u_y``,
post-yield ratio ``alpha``) moves on one of two branches:

* elastic, plastic drift ``u_p`` constant:
  ``q'' + 2 z w q' + w^2 q = -g a_g + f (1 - alpha) k u_p``;
* yielding in direction ``s = +-1`` (``|x - u_p| = u_y``, drift growing in magnitude):
  ``q'' + 2 z w q' + alpha w^2 q = -g a_g - f (1 - alpha) k s u_y``: circular frequency
  ``sqrt(alpha) w``, the same damping constant (ratio ``z / sqrt(alpha)``), a constant load.

A constant load is a static shift of the coordinate (``q = q_s + P / W^2``), so on either
branch the shifted coordinate obeys the elastic mode's equation with that branch's frequency,
and everything of :mod:`pound_mc.integrators.adaptive_pair` applies to it unchanged: the exact
(Nigam-Jennings) step (coefficients for the regular step precomputed per branch), the exact
solution inside a step for located events, the contact phase's Runge-Kutta sub-steps (a shifted
gap).  Events besides contact onset: elastic -> yielding where ``s (x - u_p)`` reaches ``u_y``
(located on the exact solution like a contact onset), yielding -> elastic where the velocity
turns (the root of the rate); inside contact sub-steps both are located on the sub-step's cubic
Hermite interpolant and the sub-step is taken again up to them.

Energy: the plastic drifts enter the elastic modal equations as a load; its work (exact per
step: constant on the elastic branch, linear in ``q`` on the yielding one) enters the balance
as in :mod:`pound_mc.integrators.hysteretic`, and the hysteretic dissipation
``(1 - alpha) k s u_y dx`` is summed exactly.  Outputs as the inelastic ``newmark`` kernel
(:func:`~pound_mc.integrators.hysteretic.storey_outputs`); floor accelerations at the steps'
and sub-steps' ends.  The yielding branch must be an underdamped oscillator
(``alpha > z^2``, :func:`branch_supported`); histories at the record's samples as the pair
kernel's, no shared response before contact.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.adaptive import _alive
from pound_mc.integrators.adaptive_pair import _store_pair
from pound_mc.integrators.adaptive_pair_contact import (
    RAMP_GROWTH,
    RAMP_GROWTH_POT,
    RAMP_START,
    RAMP_START_POT,
    TAIL,
    TAIL_MIN,
    TAIL_MIN_POT,
    TAIL_POT,
    _rk4_pair,
    _rk4_pot,
    _roots,
    _stage,
    _track_floor,
)
from pound_mc.integrators.adaptive_pair_linear import (
    ONSET_TOL,
    _exact_max,
    _exact_root_pair,
    _mode_step,
)
from pound_mc.integrators.bounds import (
    LOCAL_DAMPING_SHARE,
    LOCAL_PERIOD_SHARE,
    contact_bound,
    shortest_period_steps,
)
from pound_mc.integrators.hysteretic import S_ALPHA, S_BW, S_K, S_YIELD, storey_outputs
from pound_mc.integrators.laws import LAW_CODES, duration, episode_zeta, stored, substep_peaks
from pound_mc.integrators.toolkit import (
    advance,
    borrow,
    coefficients,
    grid_step,
    hermite_max,
    hermite_root,
    step_size,
)

__all__ = ["adaptive_bilinear", "branch_supported", "bilinear_pair_steps"]

_INF = math.inf
_TWELFTH = 1.0 / 12.0
_JANKOWSKI = LAW_CODES["jankowski"]
#: A yield event needs the drift beyond the yield drift by this fraction of it [-]: a branch
#: that has just unloaded at ``|z| = u_y`` does not yield again on round-off.
YIELD_TOL = 1e-13


def branch_supported(post_yield_ratio: float, damping_ratio: float) -> bool:
    """Whether ``adaptive`` runs a bilinear SDOF: its yielding branch is underdamped.

    The branch has frequency ``sqrt(alpha) w`` and damping ratio ``z / sqrt(alpha)``; the
    exact step is written for damping ratios below 1, so ``alpha > z^2`` (``alpha = 0``,
    no stiffness after yield, runs with ``newmark``).
    """
    return post_yield_ratio > damping_ratio * damping_ratio


def bilinear_pair_steps(store, zeta) -> bool:
    """Whether this kernel's exact branch steps run a yielding SDOF pair.

    ``store``: the storey table (row ``j``: building ``j``), ``zeta``: the damping ratios.
    Bouc-Wen storeys are not piecewise linear, and a yielding branch at ``alpha <= z^2`` is not
    an underdamped oscillator (:func:`branch_supported`): both run with the error-controlled
    steps of :mod:`pound_mc.integrators.adaptive_rk` instead.
    """
    store = np.asarray(store, dtype=float)
    if np.any(store[:, S_BW] > 0.0):
        return False
    return all(
        not math.isfinite(store[j, S_YIELD]) or branch_supported(store[j, S_ALPHA], zeta[j])
        for j in range(2)
    )


@jit
def _crossing(y0, yd0, y1, yd1, hh, q0, q1, v0, v1, p0s, slope, w0, z0, g0, w1, z1, g1, c0, c1,
              off):  # fmt: skip
    """First time in ``(0, hh]`` where ``y = c0 q0 + c1 q1 - off`` crosses 0 upwards, or inf.

    On the exact solution of the step from the state ``(q, v)`` (shifted coordinates): a sign
    change of the end values, or an interior maximum above 0 (screened on the cubic Hermite
    interpolant and found on the exact solution), located by safeguarded Newton, as a contact
    onset in :func:`~pound_mc.integrators.adaptive_pair.adaptive_pair`.
    """
    if y0 > 0.0:
        return _INF
    crossing = y1 > 0.0
    t_hi = hh
    if not crossing and yd0 > 0.0 and yd1 < 0.0:
        hm, tg = hermite_max(y0, yd0, y1, yd1, hh)
        if hm > -0.05 * (abs(yd0) + abs(yd1)) * hh:
            dm, tm = _exact_max(q0, q1, v0, v1, p0s, slope, tg, hh, w0, z0, g0, w1, z1, g1, c0,
                                c1, off)  # fmt: skip
            if dm > 0.0:
                crossing = True
                t_hi = tm
                y1 = dm
                yd1 = 0.0
    if not crossing:
        return _INF
    tg = hermite_root(y0, yd0, y1, yd1, t_hi)
    return _exact_root_pair(q0, q1, v0, v1, p0s, slope, tg, 0.0, t_hi, 0, w0, z0, g0, w1, z1, g1,
                            c0, c1, off, ONSET_TOL)  # fmt: skip


@jit(inline=True)
def _branch(j, br, up, ww, zw2, ff, kk, uy, al, ps):
    """Frequency, damping ratio and shift of building ``j``'s coordinate on its branch.

    Returns ``(W, Z, shift, weight of the shift in the penetration)``.
    """
    if br[j] == 0:
        w = math.sqrt(ww[j])
        sh = ff[j] * (1.0 - al[j]) * kk[j] * up[j] / ww[j]
    else:
        w = math.sqrt(al[j] * ww[j])
        sh = -ff[j] * (1.0 - al[j]) * kk[j] * br[j] * uy[j] / (al[j] * ww[j])
    return w, 0.5 * zw2[j] / w, sh, ps[j] * sh


@jit
def adaptive_bilinear(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, store, sout,
):  # fmt: skip
    """``adaptive`` for an SDOF pair with bilinear buildings (module docstring).

    Arguments as :func:`~pound_mc.integrators.adaptive_pair.adaptive_pair` (no ``pre``;
    ``hx, hd, hf``: histories at the record's samples, empty arrays for none) and the storey
    table ``store`` of
    :func:`~pound_mc.integrators.hysteretic.newmark_hysteretic` (row ``j``: building ``j``;
    yield drift inf: elastic).  The linear steps and the contact sub-steps share the branch
    state and its events in one loop; each step's work is in the helpers below.
    """
    model, relation, substeps, npts = settings.model, settings.relation, settings.substeps, ag.size
    # linear steps and contact sub-steps bounded by the shorter period (bounds), as in the pair
    h_lin, h_rk = shortest_period_steps(omega, settings.dt_s)
    m_sub, h = step_size(dt_rec, h_lin)
    _m_rk, h_rk = step_size(dt_rec, h_rk)
    inv_dt = 1.0 / dt_rec
    ww = omega * omega
    zw2 = 2.0 * zeta * omega
    g = gamma.copy()
    ff = np.array([phi[0, 0], phi[1, 1]])
    ps = np.array([psi[0, 0], psi[0, 1]])
    kk = store[:, S_K].copy()
    uy = store[:, S_YIELD].copy()
    al = store[:, S_ALPHA].copy()
    gp, b, me, xi0 = gap[0], beta[0], meff[0], xi[0]
    cd = 2.0 * xi0 * math.sqrt(b * me)
    loc_k = LOCAL_PERIOD_SHARE * math.sqrt(me) / substeps
    loc_c = LOCAL_DAMPING_SHARE * me / substeps
    cf = _branch_coefficients(omega, zeta, uy, al, h)
    br = np.zeros(2, dtype=np.int64)  # 0 elastic, +-1 yielding in that direction
    up = np.zeros(2)  # plastic drift [m]
    w_b = np.empty(2)
    z_b = np.empty(2)
    sh = np.zeros(2)
    qs = np.empty(2)
    nq = np.empty(2)
    nv = np.empty(2)
    a_end = np.empty(2)
    peaks = np.zeros(2)
    peak_acc = np.zeros(2)
    e0 = 0.5 * (v[0] * v[0] + ww[0] * q[0] * q[0] + v[1] * v[1] + ww[1] * q[1] * q[1])
    for j in range(2):
        peak_acc[j] = abs(ag[0])
    phase = 0
    zhd = e_in = e_d = w_c = w_p = e_h = 0.0
    peak_f = peak_t = impacts = impulse = 0.0
    pending = False
    # onset velocity of every impact, in a list never reassigned (outputs.log_impact_in)
    logs = [outputs.impact_log(1)[1]]
    nlog = 0
    v_ep = math.nan
    maxpen = -_INF
    steps = 0
    hc = h_rk
    herm_tol = 4.0 * (max(omega[0], omega[1]) * h) ** 4 / 384.0
    t_onset = 0.0
    budget = 200 * (npts - 1) * m_sub + 1_000_000
    in_contact = False
    pot = model == _JANKOWSKI
    kpot = 0.8 * cd
    ramp_0, ramp_k, tail, tail_min = (
        (RAMP_START_POT, RAMP_GROWTH_POT, TAIL_POT, TAIL_MIN_POT)
        if pot
        else (RAMP_START, RAMP_GROWTH, TAIL, TAIL_MIN)
    )
    status = outputs.STATUS_OK
    changed = True  # the branches changed: their frequencies and shifts are due
    fsal = False
    fc_end = 0.0
    gpe = gp
    store_h = hx.shape[0] > 0
    # the loop works on views without an owner (toolkit.borrow) as adaptive's does: its helpers
    # receive them at every step; the arrays stay owned by ``owned`` (_alive)
    owned = (ww, zw2, g, ff, ps, kk, uy, al, cf, br, up, w_b, z_b, sh, qs, nq, nv, a_end, peaks,
             peak_acc)  # fmt: skip
    ww, zw2, g, ff, ps, kk = borrow(ww), borrow(zw2), borrow(g), borrow(ff), borrow(ps), borrow(kk)
    uy, al, cf, br, up = borrow(uy), borrow(al), borrow(cf), borrow(br), borrow(up)
    w_b, z_b, sh, qs, nq = borrow(w_b), borrow(z_b), borrow(sh), borrow(qs), borrow(nq)
    nv, a_end, peaks, peak_acc = borrow(nv), borrow(a_end), borrow(peaks), borrow(peak_acc)
    q, v = borrow(q), borrow(v)
    for i in range(npts - 1):
        if store_h:
            _store_pair(i, q[0], q[1], v[0], v[1], ff[0], ff[1], ps[0], ps[1], gp, b, cd, zhd,
                        phase, model, hx, hd, hf)  # fmt: skip
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) * inv_dt
        s = 0.0
        k_grid = 0
        fsal = False  # a new interval: new load, the next sub-step starts afresh
        while s < dt_rec * (1.0 - 1e-12):
            steps += 1
            if steps > budget:
                status = outputs.STATUS_NOT_CONVERGED
                break
            if changed:
                gpe, cfa, cfb = _branch_steps(br, up, ww, zw2, ff, kk, uy, al, ps, cf, gp, w_b, z_b,
                                              sh)  # fmt: skip
                changed = False
            for j in range(2):
                qs[j] = q[j] - sh[j]
            kind = 0  # 1 onset, 2 / 3 a branch switch of building 0 / 1
            if not in_contact:
                # ---------------- exact linear step to the next grid point (or an event)
                hh, p0s, p1s, kind = _branch_step(k_grid, s, ag0, slope, m_sub, h, dt_rec, q, v, qs,
                                                  nq, nv, g, w_b, z_b, cfa, cfb, ps, gpe, ff, sh,
                                                  br, up, uy)  # fmt: skip
                e_in, e_d = _step_tallies(hh, slope, p0s, p1s, q, v, qs, nq, nv, a_end, g, w_b, z_b,
                                          zw2, ff, sh, peaks, herm_tol, e_in, e_d)  # fmt: skip
                s_end = s + hh
                if kind == 0:
                    k_grid += 1
                fsal = False
            else:
                # ---------------- contact sub-step (RK4) with located switches
                hs = _substep_length(i * dt_rec + s - t_onset, dt_rec - s, qs, v, ps, gpe, phase,
                                     hc, model, b, cd, zhd, loc_k, loc_c, ramp_0, ramp_k, tail,
                                     tail_min)  # fmt: skip
                hh, fc0, fc1, kind, ac0, ac1, de = _contact_substep(
                    qs, v, nq, nv, a_end, s, hs, ag0, slope, w_b, zw2, g, ps, gpe, b, cd, zhd,
                    phase, model, pot, kpot, br, up, ff, sh, uy, fsal, fc_end,
                )  # fmt: skip
                fc_end = fc1
                # the force and accelerations at the end start the next sub-step (first same
                # as last) unless something switched there
                fsal = kind == 0
                e_in += de[0]
                e_d += de[1]
                w_c += de[2]
                impulse += de[3]
                d0 = ps[0] * qs[0] + ps[1] * qs[1] - gpe
                d1 = ps[0] * nq[0] + ps[1] * nq[1] - gpe
                dd0 = ps[0] * v[0] + ps[1] * v[1]
                dd1 = ps[0] * nv[0] + ps[1] * nv[1]
                if phase != 0:
                    # peak force (Hermite on F with its rate) and penetration
                    ddd0 = ps[0] * ac0 + ps[1] * ac1
                    ddd1 = ps[0] * a_end[0] + ps[1] * a_end[1]
                    fm, tm, dm = substep_peaks(model, fc0, fc1, d0, d1, dd0, dd1, ddd0, ddd1, hh,
                                               peak_f, b, cd, zhd, phase)  # fmt: skip
                    if fm > peak_f:
                        peak_f = fm
                        peak_t = i * dt_rec + s + tm
                    maxpen = max(maxpen, dm)
                    if pending and dm > outputs.IMPACT_MIN_PENETRATION_M:
                        impacts += 1.0
                        pending = False
                        nlog = outputs.log_impact_in(logs, nlog, v_ep)
                for j in range(2):
                    peaks[j] = _track_floor(ff[j] * q[j], ff[j] * v[j], ff[j] * (nq[j] + sh[j]),
                                            ff[j] * nv[j], hh, peaks[j])  # fmt: skip
                s_end = s + hh
                phase, pending, v_ep, zhd, hc, t_onset, in_contact = _contact_switch(
                    kind, phase, pending, v_ep, zhd, hc, h_rk, t_onset, in_contact, dd1, i, dt_rec,
                    s_end, model, relation, xi0, b, me, substeps,
                )  # fmt: skip
                if kind >= 4:
                    kind = 0
                k_grid = min(int(math.floor(s_end / h + 1e-9)), m_sub - 1)
            # ---------------- common end of a step: work of the plastic load, hysteresis
            w_p, e_h = _plastic_work(q, v, qs, nq, nv, a_end, ff, al, kk, br, up, uy, sh, peak_acc,
                                     ag0, slope, s_end, w_p, e_h)  # fmt: skip
            s = s_end
            if kind == 1:
                phase = 1
                pending = True
                v0c = ps[0] * v[0] + ps[1] * v[1]
                v_ep = v0c
                zhd = episode_zeta(model, relation, xi0, v0c, zhd)
                hc = min(h_rk, duration(model, v0c, b, me) / substeps)
                t_onset = i * dt_rec + s
                in_contact = True
            elif kind >= 2:
                j = kind - 2
                if br[j] == 0:
                    br[j] = 1 if ff[j] * q[j] - up[j] > 0.0 else -1
                else:
                    up[j] = ff[j] * q[j] - br[j] * uy[j]
                    br[j] = 0
                changed = True
            if not math.isfinite(q[0] + q[1] + v[0] + v[1]):
                status = outputs.STATUS_UNSTABLE
                break
        if status != 0:
            break
    if store_h and status == outputs.STATUS_OK:
        _store_pair(npts - 1, q[0], q[1], v[0], v[1], ff[0], ff[1], ps[0], ps[1], gp, b, cd, zhd,
                    phase, model, hx, hd, hf)  # fmt: skip
    _finish_bilinear(out, cout, q, v, omega, side, store, sout, peaks, peak_acc, ff, ps, gp, b,
                     model, phase, e0, e_in, e_d, w_p, w_c, e_h, peak_f, peak_t, impacts, maxpen,
                     impulse, logs[0], nlog, steps, status)  # fmt: skip
    _alive(owned)


@jit(inline=True)
def _branch_coefficients(omega, zeta, uy, al, h):
    """Exact-step coefficients of the regular step ``h`` [s] per building and branch.

    ``cf[j, 0]``: building ``j`` elastic, ``cf[j, 1]``: yielding (where it may yield, ``uy``
    finite); the two rows of ``toolkit.coefficients`` each.
    """
    cf = np.zeros((2, 2, 2, 4))
    for j in range(2):
        cf[j, 0] = coefficients(omega[j], zeta[j], h)
        if math.isfinite(uy[j]):
            wy = math.sqrt(al[j]) * omega[j]
            cf[j, 1] = coefficients(wy, zeta[j] * omega[j] / wy, h)
    return cf


@jit(inline=True)
def _branch_steps(br, up, ww, zw2, ff, kk, uy, al, ps, cf, gp, w_b, z_b, sh):
    """Both buildings' frequencies, damping ratios and shifts on their branches, in place.

    Into ``w_b, z_b, sh`` (:func:`_branch`); returns the gap of the shifted coordinates and the
    regular step's coefficients of each building's branch (the two rows of ``cf[j, branch]``
    in one tuple, as :func:`~pound_mc.integrators.adaptive_pair_linear._mode_step` takes them).
    """
    gpe = gp
    for j in range(2):
        w_b[j], z_b[j], sh[j], dg = _branch(j, br, up, ww, zw2, ff, kk, uy, al, ps)
        gpe -= dg
    c = cf[0, 0 if br[0] == 0 else 1]
    cfa = (c[0, 0], c[0, 1], c[0, 2], c[0, 3], c[1, 0], c[1, 1], c[1, 2], c[1, 3])
    c = cf[1, 0 if br[1] == 0 else 1]
    cfb = (c[0, 0], c[0, 1], c[0, 2], c[0, 3], c[1, 0], c[1, 1], c[1, 2], c[1, 3])
    return gpe, cfa, cfb


@jit(inline=True)
def _branch_step(k_grid, s, ag0, slope, m_sub, h, dt_rec, q, v, qs, nq, nv, g, w_b, z_b, cfa, cfb,
                 ps, gpe, ff, sh, br, up, uy):  # fmt: skip
    """The exact linear step to the next grid point, or to the first event inside it.

    From local time ``s`` [s] of the record interval (next grid point ``k_grid``) and the state
    ``q, v`` (``qs``: shifted), each building on its branch (``w_b, z_b``; the regular step's
    coefficients ``cfa, cfb``).  Events: a contact onset, an elastic branch reaching its yield
    drift and a yielding branch's velocity turning (unloading), each located on the exact
    solution.  Writes the end state into ``nq, nv`` (shifted); returns the step's length [s],
    the ground accelerations at its ends and the event at its end (0 none, 1 onset, ``2 + j``
    a branch switch of building ``j``).
    """
    kind = 0
    s_next, hh, p0s, p1s, whole_step = grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope)
    if whole_step:
        nq[0], nv[0] = _mode_step(qs[0], v[0], p0s, p1s, g[0], cfa)
        nq[1], nv[1] = _mode_step(qs[1], v[1], p0s, p1s, g[1], cfb)
    else:
        for j in range(2):
            nq[j], nv[j] = advance(qs[j], v[j], -g[j] * p0s, -g[j] * p1s, w_b[j],
                                   z_b[j], hh)  # fmt: skip
    w0, z0, w1, z1 = w_b[0], z_b[0], w_b[1], z_b[1]
    g0, g1 = g[0], g[1]
    # contact onset
    t_ev = _INF
    dd0 = ps[0] * v[0] + ps[1] * v[1]
    d1 = ps[0] * nq[0] + ps[1] * nq[1] - gpe
    dd1 = ps[0] * nv[0] + ps[1] * nv[1]
    if d1 > 0.0 or (dd0 > 0.0 and dd1 < 0.0):
        t_ev = _crossing(ps[0] * qs[0] + ps[1] * qs[1] - gpe, dd0, d1, dd1, hh, qs[0],
                         qs[1], v[0], v[1], p0s, slope, w0, z0, g0, w1, z1, g1,
                         ps[0], ps[1], gpe)  # fmt: skip
        if t_ev < _INF:
            kind = 1
    # yield (elastic branch) and unloading (yielding branch) of each building
    for j in range(2):
        cj0 = ff[j] if j == 0 else 0.0
        cj1 = ff[j] if j == 1 else 0.0
        x0 = ff[j] * q[j]
        xd0 = ff[j] * v[j]
        x1 = ff[j] * (nq[j] + sh[j])
        xd1 = ff[j] * nv[j]
        if br[j] == 0:
            if not math.isfinite(uy[j]):
                continue
            lim = uy[j] * (1.0 + YIELD_TOL)
            for sgn in (1.0, -1.0):
                # sgn (x - u_p) - u_y on the shifted coordinate
                y1 = sgn * (x1 - up[j]) - lim
                if y1 <= 0.0 and not (sgn * xd0 > 0.0 and sgn * xd1 < 0.0):
                    continue
                off = lim + sgn * (up[j] - ff[j] * sh[j])
                t = _crossing(
                    sgn * (x0 - up[j]) - lim, sgn * xd0, y1, sgn * xd1, hh, qs[0],
                    qs[1], v[0], v[1], p0s, slope, w0, z0, g0, w1, z1, g1,
                    sgn * cj0, sgn * cj1, off,
                )  # fmt: skip
                if t < t_ev:
                    t_ev = t
                    kind = 2 + j
        elif br[j] * xd1 <= 0.0 < br[j] * xd0:
            # the velocity turns: root of the rate of s x (a maximum)
            sgn = float(br[j])
            wj = w_b[j]
            zj = z_b[j]
            xa0 = ff[j] * (-2.0 * zj * wj * v[j] - wj * wj * qs[j] - g[j] * p0s)
            xa1 = ff[j] * (-2.0 * zj * wj * nv[j] - wj * wj * nq[j] - g[j] * p1s)
            tg = hermite_root(sgn * xd0, sgn * xa0, sgn * xd1, sgn * xa1, hh)
            t = _exact_root_pair(qs[0], qs[1], v[0], v[1], p0s, slope, tg, 0.0, hh,
                                 1, w0, z0, g0, w1, z1, g1, sgn * cj0, sgn * cj1,
                                 0.0, ONSET_TOL)  # fmt: skip
            if t < t_ev:
                t_ev = t
                kind = 2 + j
    if kind != 0:
        hh = t_ev
        p1s = ag0 + slope * (s + hh)
        for j in range(2):
            nq[j], nv[j] = advance(qs[j], v[j], -g[j] * p0s, -g[j] * p1s, w_b[j],
                                   z_b[j], hh)  # fmt: skip
    return hh, p0s, p1s, kind


@jit(inline=True)
def _step_tallies(hh, slope, p0s, p1s, q, v, qs, nq, nv, a_end, g, w_b, z_b, zw2, ff, sh, peaks,
                  herm_tol, e_in, e_d):  # fmt: skip
    """Energies and floor peaks over an exact linear step of length ``hh`` [s].

    Writes the modal accelerations at its end into ``a_end`` and the floor peaks into
    ``peaks``; returns the input and damping energies.
    """
    w0, z0, w1, z1 = w_b[0], z_b[0], w_b[1], z_b[1]
    g0, g1 = g[0], g[1]
    # energies by the corrected trapezoidal rule (exact to O(h^5) per step)
    hh12 = hh * hh * _TWELFTH
    for j in range(2):
        wj2 = w_b[j] * w_b[j]
        a0 = -zw2[j] * v[j] - wj2 * qs[j] - g[j] * p0s
        a1 = -zw2[j] * nv[j] - wj2 * nq[j] - g[j] * p1s
        a_end[j] = a1
        pin0 = -p0s * g[j] * v[j]
        pin1 = -p1s * g[j] * nv[j]
        dpin0 = -g[j] * (slope * v[j] + p0s * a0)
        dpin1 = -g[j] * (slope * nv[j] + p1s * a1)
        e_in += 0.5 * hh * (pin0 + pin1) + hh12 * (dpin0 - dpin1)
        pd0 = zw2[j] * v[j] * v[j]
        pd1 = zw2[j] * nv[j] * nv[j]
        e_d += 0.5 * hh * (pd0 + pd1) + hh12 * 2.0 * zw2[j] * (v[j] * a0 - nv[j] * a1)
        # peak floor displacement: an extremum inside the step on the exact solution
        xa = ff[j] * q[j]
        xda = ff[j] * v[j]
        xb = ff[j] * (nq[j] + sh[j])
        xdb = ff[j] * nv[j]
        pk = max(peaks[j], abs(xb))
        if (xda > 0.0) != (xdb > 0.0):
            sgn = 1.0 if xda > 0.0 else -1.0
            hm, tg = hermite_max(sgn * xa, sgn * xda, sgn * xb, sgn * xdb, hh)
            if hm > pk - herm_tol * abs(hm):
                c0 = sgn * ff[j] if j == 0 else 0.0
                c1 = sgn * ff[j] if j == 1 else 0.0
                xm, _ = _exact_max(qs[0], qs[1], v[0], v[1], p0s, slope, tg, hh,
                                   w0, z0, g0, w1, z1, g1, c0, c1,
                                   -sgn * ff[j] * sh[j])  # fmt: skip
                if xm > pk:
                    pk = xm
        peaks[j] = pk
    return e_in, e_d


@jit(inline=True)
def _substep_length(since, room, qs, v, ps, gpe, phase, hc, model, b, cd, zhd, loc_k, loc_c,
                    ramp_0, ramp_k, tail, tail_min):  # fmt: skip
    """A contact sub-step's length [s], graded and bounded as the SDOF pair's.

    ``since``: the time since the episode's onset [s], ``room``: the time left in the record
    interval [s]; ``hc``: the episode's sub-step [s]; the contact's local period and damping
    time bound it (:func:`~pound_mc.integrators.bounds.contact_bound`, no screen).
    """
    hs = min(hc, max(ramp_k * since, hc * ramp_0))
    if phase == 2:
        ddc = ps[0] * v[0] + ps[1] * v[1]
        if ddc < 0.0:
            dc = ps[0] * qs[0] + ps[1] * qs[1] - gpe
            hs = min(hs, max(-tail * dc / ddc, hc * tail_min))
    if phase != 0:  # the contact's local period and damping time (bounds)
        hs, _ = contact_bound(hs, ps[0] * qs[0] + ps[1] * qs[1] - gpe,
                              ps[0] * v[0] + ps[1] * v[1], model, b, cd, zhd, phase,
                              loc_k, loc_c, -1.0, -1.0)  # fmt: skip
    if hs >= room or room - hs < 1e-9 * hc:
        hs = room
    return hs


@jit(inline=True)
def _contact_switch(kind, phase, pending, v_ep, zhd, hc, h_rk, t_onset, in_contact, dd1, i, dt_rec,
                    s_end, model, relation, xi0, b, me, substeps):  # fmt: skip
    """The contact's phase after the switch ``kind`` at a contact sub-step's end.

    4: an onset (from phase 0: an episode starts at the penetration rate ``dd1`` [m/s] at the
    sub-step's end ``s_end`` [s] of record interval ``i``) or approach -> restitution;
    5: restitution -> approach; 6: separation (the sub-step bound back to ``h_rk`` [s]).
    Returns ``(phase, pending, v_ep, zhd, hc, t_onset, in_contact)``.
    """
    if kind == 4:  # approach -> restitution (or onset)
        if phase == 0:
            phase = 1
            pending = True
            v_ep = dd1
            zhd = episode_zeta(model, relation, xi0, dd1, zhd)
            hc = min(hc, duration(model, dd1, b, me) / substeps)
            t_onset = i * dt_rec + s_end
        else:
            phase = 2
    elif kind == 5:  # restitution -> approach
        phase = 1
    elif kind == 6:  # separation
        phase = 0
        in_contact = False
        hc = h_rk
    return phase, pending, v_ep, zhd, hc, t_onset, in_contact


@jit(inline=True)
def _plastic_work(q, v, qs, nq, nv, a_end, ff, al, kk, br, up, uy, sh, peak_acc, ag0, slope,
                  s_end, w_p, e_h):  # fmt: skip
    """The end of a step: the plastic load's work and the hysteretic dissipation over it.

    The state moves to the step's end (``nq, nv``, shifted back into ``q, v``) and the floors'
    absolute accelerations there (at local time ``s_end`` [s], ground acceleration
    ``ag0 + slope s_end``) raise ``peak_acc``; returns ``w_p, e_h`` with the step's shares added.
    """
    for j in range(2):
        dq = nq[j] - qs[j]
        pl = ff[j] * (1.0 - al[j]) * kk[j]
        if br[j] == 0:
            w_p += pl * up[j] * dq
        else:
            qa = qs[j] + sh[j]
            qb = nq[j] + sh[j]
            w_p += pl * (0.5 * ff[j] * (qa + qb) - br[j] * uy[j]) * dq
            e_h += (1.0 - al[j]) * kk[j] * br[j] * uy[j] * ff[j] * dq
        q[j] = nq[j] + sh[j]
        v[j] = nv[j]
        xa = abs(ff[j] * a_end[j] + ag0 + slope * s_end)
        if xa > peak_acc[j]:
            peak_acc[j] = xa
    return w_p, e_h


@jit
def _finish_bilinear(out, cout, q, v, omega, side, store, sout, peaks, peak_acc, ff, ps, gp, b,
                     model, phase, e0, e_in, e_d, w_p, w_c, e_h, peak_f, peak_t, impacts, maxpen,
                     impulse, vlog, nlog, steps, status):  # fmt: skip
    """The outputs of a run that ended at the state ``q, v`` (``outputs.finish``).

    With the storeys' (:func:`~pound_mc.integrators.hysteretic.storey_outputs`): the floors'
    peak drifts ``peaks`` and absolute accelerations ``peak_acc``, the hysteretic dissipation
    ``e_h``; ``vlog``: the impact velocities, ``nlog`` of them.
    """
    cout[0, outputs.C_PEAK_FORCE], cout[0, outputs.C_IMPACTS] = peak_f, impacts
    cout[0, outputs.C_MAX_PENETRATION], cout[0, outputs.C_IMPULSE] = maxpen, impulse
    cout[0, outputs.C_MAX_IMPACT_VELOCITY] = outputs.log_max(vlog, nlog)
    ph = np.full(1, phase, dtype=np.int64)
    stored_energy = 0.0
    if phase != 0:
        stored_energy = stored(model, ps[0] * q[0] + ps[1] * q[1] - gp, b)
    # the plastic load's work enters the balance as a negative damping work
    outputs.finish(out, cout, peaks, side, ph, q, v, omega, e0, e_in, e_d - w_p, w_c, stored_energy,
           peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, vlog, nlog, math.nan)  # fixed restitution: set by the batch
    drift = np.array([ff[0] * q[0], ff[1] * q[1]])
    storey_outputs(out, store, peaks, drift, peak_acc, side, e_h, sout)


@jit
def _contact_substep(qs, v, nq, nv, a_end, s, hs, ag0, slope, w_b, zw2, g, ps, gpe, b, cd, zhd,
                     phase, model, pot, kpot, br, up, ff, sh, uy, fsal, fc_prev):  # fmt: skip
    """One RK4 sub-step in shifted coordinates, cut at the first switch inside it.

    ``fsal``: ``fc_prev`` and ``a_end`` hold the force and accelerations at the start.

    Switches: of the contact law (returned kind 4: onset or approach -> restitution, 5:
    restitution -> approach, 6: separation) and of a building's branch (kind 2 + j), located
    on the sub-step's cubic Hermite interpolant.
    Writes the end state into ``nq, nv`` and its accelerations into ``a_end``; returns the
    sub-step taken, the forces at its ends, the kind of switch at its end, the accelerations
    at its start and the increments of input, damping, contact work and impulse.
    """
    de = np.empty(4)
    hh = hs
    kind = 0
    fc0 = fc_prev
    ac0 = a_end[0]
    ac1 = a_end[1]
    have = fsal
    fc1 = 0.0
    for attempt in range(2):
        ww0 = w_b[0] * w_b[0]
        ww1 = w_b[1] * w_b[1]
        if pot and phase == 1:
            (nq[0], nq[1], nv[0], nv[1], de[0], de[1], de[2], de[3], fc0, ac0, ac1, _) = _rk4_pot(
                qs[0], qs[1], v[0], v[1], s, hh, ag0, slope, -zw2[0], ww0, g[0], -zw2[1], ww1,
                g[1], zw2[0], zw2[1], ps[0], ps[1], gpe, b, cd, kpot,
                _roots(qs[0], qs[1], ps[0], ps[1], gpe),
            )  # fmt: skip
        else:
            (nq[0], nq[1], nv[0], nv[1], de[0], de[1], de[2], de[3], fc0, ac0, ac1) = _rk4_pair(
                qs[0], qs[1], v[0], v[1], s, hh, ag0, slope, -zw2[0], ww0, g[0], -zw2[1], ww1,
                g[1], zw2[0], zw2[1], ps[0], ps[1], gpe, b, cd, zhd, phase, model, have, fc0,
                ac0, ac1,
            )  # fmt: skip
        have = True  # a sub-step taken again starts where this one did
        fc1, _, a_end[0], a_end[1] = _stage(nq[0], nq[1], nv[0], nv[1], ag0 + slope * (s + hh),
                                            -zw2[0], ww0, g[0], -zw2[1], ww1, g[1], ps[0], ps[1],
                                            gpe, b, cd, zhd, phase, model)  # fmt: skip
        if attempt == 1:
            break
        d0 = ps[0] * qs[0] + ps[1] * qs[1] - gpe
        d1 = ps[0] * nq[0] + ps[1] * nq[1] - gpe
        dd0 = ps[0] * v[0] + ps[1] * v[1]
        dd1 = ps[0] * nv[0] + ps[1] * nv[1]
        ddd0 = ps[0] * ac0 + ps[1] * ac1
        ddd1 = ps[0] * a_end[0] + ps[1] * a_end[1]
        t_ev = _INF
        if phase == 0:
            if d1 > 0.0 and d0 <= 0.0:
                t_ev = hermite_root(d0, dd0, d1, dd1, hh)
                kind = 4
        elif phase == 1:
            if dd1 <= 0.0 and dd0 > 0.0:
                t_ev = hermite_root(dd0, ddd0, dd1, ddd1, hh)
                kind = 4
        else:
            if d1 <= 0.0 and d0 > 0.0:
                t_ev = hermite_root(d0, dd0, d1, dd1, hh)
                kind = 6
            if dd1 > 0.0 and dd0 <= 0.0:
                t2 = hermite_root(dd0, ddd0, dd1, ddd1, hh)
                if t2 < t_ev:
                    t_ev = t2
                    kind = 5
        for j in range(2):
            acs = ac0 if j == 0 else ac1
            if br[j] == 0:
                if not math.isfinite(uy[j]):
                    continue
                z0 = ff[j] * (qs[j] + sh[j]) - up[j]
                z1 = ff[j] * (nq[j] + sh[j]) - up[j]
                sgn = 1.0 if z1 > 0.0 else -1.0
                lim = uy[j] * (1.0 + YIELD_TOL)
                if sgn * z1 > lim >= sgn * z0:
                    t = hermite_root(sgn * z0 - lim, sgn * ff[j] * v[j], sgn * z1 - lim,
                                     sgn * ff[j] * nv[j], hh)  # fmt: skip
                    if t < t_ev:
                        t_ev = t
                        kind = 2 + j
            elif br[j] * nv[j] * ff[j] <= 0.0 < br[j] * v[j] * ff[j]:
                sgn = br[j] * ff[j]
                t = hermite_root(sgn * v[j], sgn * acs, sgn * nv[j], sgn * a_end[j], hh)
                if t < t_ev:
                    t_ev = t
                    kind = 2 + j
        if t_ev == _INF:
            kind = 0
            break
        if t_ev >= hh:
            break
        hh = t_ev
    if pot and phase == 2:  # the elastic force alone: its work is exact (adaptive_pair)
        de[2] = stored(model, ps[0] * nq[0] + ps[1] * nq[1] - gpe, b) - stored(
            model, ps[0] * qs[0] + ps[1] * qs[1] - gpe, b
        )
    return hh, fc0, fc1, kind, ac0, ac1, de
