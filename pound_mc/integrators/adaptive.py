"""The ``adaptive`` method: exact linear steps between contacts, located events, RK4 in contact.

Exact (Nigam-Jennings) steps of the linear modes between contacts, on the record's samples
split into steps no longer than ``dt_s``; contact onset located by root finding on the exact
solution (a cubic Hermite bound screens every step for a grazing approach); during contact,
classical Runge-Kutta sub-steps sized from the contact-duration estimate of the law
(``substeps`` per duration), with every switch of the force law (onset, approach ->
restitution, separation) located inside its sub-step and the step cut there.  Peak force,
peak displacements and penetration are continuous-time maxima (cubic Hermite interpolation
within each step).

The kernel :func:`adaptive` is a loop over the record's intervals that alternates two kinds of
step, each made of the ``inline="always"`` helpers below (numba inlines them at its IR level:
the compiled loop is the same as one long function, the source is not).  The loop works on
views of its arrays that own nothing (:func:`~pound_mc.integrators.toolkit.borrow`): numba
counts the references of every array an inlined helper with loops receives, with an atomic
operation each, which took a quarter of a 10+10 shear pair's run.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.bounds import (
    LOCAL_DAMPING_SHARE,
    LOCAL_PERIOD_SHARE,
    MODAL_STEPS_PER_PERIOD,
    contact_bound,
    shortest_period_steps,
)
from pound_mc.integrators.laws import (
    contact_forces,
    duration,
    episode_damping,
    episode_zeta,
    force,
    stored,
    substep_peaks,
)
from pound_mc.integrators.toolkit import (
    accel,
    advance,
    borrow,
    coefficients,
    end_values,
    exact_delta,
    exact_root,
    grid_step,
    hermite_max,
    hermite_root,
    matvec_spans,
    mechanical_energy,
    powers,
    refresh,
    row_spans,
    rowdot,
    run_sizes,
    track_floors,
    turning_screen,
)

# event kinds located inside a contact sub-step
_ONSET, _TO_RESTITUTION, _SEPARATION, _TO_APPROACH = 1, 2, 3, 4


@jit
def rk4(
    q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, gap, beta, cd, zhd, phase, model,
    qn, vn, wk, fc, cimp, fc0, rate,
):  # fmt: skip
    """One classical Runge-Kutta step of length ``hs`` from local time ``s``.

    Writes the new state into ``qn, vn``, the contact impulses of the step into ``cimp`` and
    the forces at the start into ``fc0`` (the accelerations at the start are ``wk[4]``);
    returns the increments of input energy, damping energy and contact work.  ``rate``:
    scratch of one value per contact.
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
        contact_forces(wk[8], wk[9], psi, gap, beta, cd, zhd, phase, model, fc, rate)
        accel(wk[8], wk[9], ag, omega, zeta, gamma, psi, fc, wk[4 + stage])
        if stage == 0:
            for c in range(nc):
                fc0[c] = fc[c]
        for j in range(n):
            wk[stage, j] = wk[9, j]
        pin, pd = powers(wk[9], ag, omega, zeta, gamma)
        pc = 0.0
        for c in range(nc):
            if fc[c] != 0.0:
                pc += fc[c] * rate[c]  # a closed contact: its rate at this stage
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


# --------------------------------------------------------------------------- linear steps


@jit(inline=True)
def _exact_step(q, v, q1, v1, coef, regular, p0s, p1s, omega, zeta, gamma, hh):
    """Exact step of every mode over ``hh`` (the precomputed coefficients on a regular step)."""
    for j in range(q.size):
        if regular:
            cf = coef[j]
            p0 = -gamma[j] * p0s
            p1 = -gamma[j] * p1s
            q1[j] = cf[0, 0] * q[j] + cf[0, 1] * v[j] + cf[0, 2] * p0 + cf[0, 3] * p1
            v1[j] = cf[1, 0] * q[j] + cf[1, 1] * v[j] + cf[1, 2] * p0 + cf[1, 3] * p1
        else:
            q1[j], v1[j] = advance(q[j], v[j], -gamma[j] * p0s, -gamma[j] * p1s, omega[j],
                                   zeta[j], hh)  # fmt: skip


@jit(inline=True)
def _penetrations(q, v, psi_t, clo, chi, gap, d, dd):
    """Every contact's penetration and its rate at state ``q, v`` into ``d, dd``.

    Over the transposed contact rows and their spans
    (:func:`~pound_mc.integrators.toolkit.matvec_spans`: the same numbers as ``rowdot``).
    """
    matvec_spans(psi_t, q, d, clo, chi)
    matvec_spans(psi_t, v, dd, clo, chi)
    for c in range(gap.size):
        d[c] -= gap[c]


@jit(inline=True)
def _screen_onsets(q, v, q1, v1, p0s, slope, s, hh, dc0, ddc0, dc1, ddc1, omega, zeta, gamma,
                   psi, psi_t, clo, chi, gap):  # fmt: skip
    """First contact onset inside a linear step: ``(contact, time)``, ``(-1, inf)`` for none.

    A contact whose penetration ends the step positive crosses zero inside it; one that turns
    back inside the step is checked where the cubic Hermite bound says its maximum may reach
    zero, on the exact solution.  Fills ``dc1, ddc1`` with the penetrations at the step's end.
    """
    tau_on = np.inf
    c_on = -1
    _penetrations(q1, v1, psi_t, clo, chi, gap, dc1, ddc1)
    for c in range(gap.size):
        d0 = dc0[c]
        dd0 = ddc0[c]
        d1 = dc1[c]
        dd1 = ddc1[c]
        crossing = d1 > 0.0
        t_hi = hh
        look, tg = turning_screen(d0, dd0, d1, dd1, hh) if not crossing else (False, 0.0)
        if look:
            # exact maximum of delta in the step: root of delta_dot
            tm = exact_root(q, v, p0s, slope, s, tg, 0.0, hh, 1, c, omega, zeta, gamma, psi,
                            gap)  # fmt: skip
            dm, _, _ = exact_delta(q, v, p0s, slope, s, tm, c, omega, zeta, gamma, psi, gap)
            if dm > 0.0:
                crossing = True
                t_hi = tm
                d1 = dm
                dd1 = 0.0
        if crossing and d0 <= 0.0:
            # locate delta = 0 on the exact solution (safeguarded Newton)
            tg = hermite_root(d0, dd0, d1, dd1, t_hi)
            hi = exact_root(q, v, p0s, slope, s, tg, 0.0, t_hi, 0, c, omega, zeta, gamma, psi,
                            gap)  # fmt: skip
            if hi < tau_on:
                tau_on = hi
                c_on = c
        elif d0 > 0.0:
            hi = _resumed(d0, dd0, dc1[c], ddc1[c], hh)
            if hi < tau_on:
                tau_on = hi
                c_on = c
    return c_on, tau_on


@jit(inline=True)
def _resumed(d0, dd0, d1, dd1, hh):
    """Where an open contact that starts a step penetrating closes again (inf: it does not).

    It penetrates since a separation located within the root's error: where it grows at the
    start, the contact resumes there (0); where it turns and grows again inside the step, near
    its minimum (the root of a cubic through its rates at the ends; the penetration there is
    of the root's error, no force to speak of).  Without this the buildings would pass
    through each other without force until the penetration next crossed zero (extreme drill:
    a shear pair at zero gap, peak force 15 % low, four impacts of six).
    """
    if dd0 > 0.0:
        return 0.0
    if d1 > 0.0 and dd1 > 0.0:
        return hermite_root(dd0, 0.0, dd1, 0.0, hh)
    return np.inf


@jit(inline=True)
def _linear_energies(hh, p0s, p1s, slope, en0, en1):
    """Input and damping energy of a linear step, corrected trapezoidal rule (O(h^5) a step)."""
    # en: 0 sum gamma v, 1 sum gamma a, 2 damping power, 3 its rate
    pin0 = -p0s * en0[0]
    pin1 = -p1s * en1[0]
    dpin0 = -(slope * en0[0] + p0s * en0[1])
    dpin1 = -(slope * en1[0] + p1s * en1[1])
    de_in = 0.5 * hh * (pin0 + pin1) + hh * hh / 12.0 * (dpin0 - dpin1)
    de_d = 0.5 * hh * (en0[2] + en1[2]) + hh * hh / 12.0 * (en0[3] - en1[3])
    return de_in, de_d


@jit(inline=True)
def _linear_floor_peaks(q, v, q1, v1, p0s, slope, s, hh, phi, phi_t, flo, fhi, nphi, zf, xf0,
                        xfd0, peaks, herm_tol, omega, zeta, gamma, xb, xdb):  # fmt: skip
    """Continuous-time peak |x| of every floor over a linear step; ``xf0, xfd0`` move on.

    ``xb, xdb``: scratch of one value per floor.
    """
    matvec_spans(phi_t, q1, xb, flo, fhi)
    matvec_spans(phi_t, v1, xdb, flo, fhi)
    for f in range(phi.shape[0]):
        x1 = xb[f]
        xd1 = xdb[f]
        m = abs(x1)
        if m > peaks[f]:
            peaks[f] = m
        if (xfd0[f] > 0.0) != (xd1 > 0.0):
            # an extremum inside the step: where the cubic Hermite bound says it may be a new
            # peak, find it on the exact solution
            for sg in range(2):
                mat = phi if sg == 0 else nphi
                sign = 1.0 if sg == 0 else -1.0
                hm, tg = hermite_max(sign * xf0[f], sign * xfd0[f], sign * x1, sign * xd1, hh)
                if hm > peaks[f] - herm_tol * abs(hm):
                    tm = exact_root(q, v, p0s, slope, s, tg, 0.0, hh, 1, f, omega, zeta, gamma,
                                    mat, zf)  # fmt: skip
                    xm, _, _ = exact_delta(q, v, p0s, slope, s, tm, f, omega, zeta, gamma, mat,
                                           zf)  # fmt: skip
                    if xm > peaks[f]:
                        peaks[f] = xm
        xf0[f] = x1
        xfd0[f] = xd1


@jit(inline=True)
def _shift(q, v, q1, v1, dc0, ddc0, dc1, ddc1, en0, en1):
    """The step's end becomes the next step's start."""
    for c in range(dc0.size):
        dc0[c] = dc1[c]
        ddc0[c] = ddc1[c]
    for k in range(4):
        en0[k] = en1[k]
    for j in range(q.size):
        q[j] = q1[j]
        v[j] = v1[j]


# --------------------------------------------------------------------------- contact steps


@jit(inline=True)
def _substep_length(q, v, psi, gap, phase, hc, t, t_onset, room, model, beta, cd, zhd, loc_k,
                    loc_c):  # fmt: skip
    """Length of the next contact sub-step; ``room`` is what is left of the record interval.

    Sub-steps are graded geometrically away from onset and towards separation, where the force
    law is not smooth (delta^0.25, delta^0.5 terms), and bounded by every closed contact's
    local period and damping time (:func:`~pound_mc.integrators.bounds.contact_bound`;
    ``loc_k``, ``loc_c`` per contact).
    """
    hs = min(hc, max(1.0 * (t - t_onset), hc * 1e-3))
    for c in range(gap.size):
        if phase[c] == 0:
            continue
        ddc = rowdot(psi, c, v)
        dc = rowdot(psi, c, q) - gap[c]
        if phase[c] == 2 and ddc < 0.0:
            hs = min(hs, max(-0.5 * dc / ddc, hc * 0.25))
        hs, _ = contact_bound(hs, dc, ddc, model, beta[c], cd[c], zhd[c], phase[c], loc_k[c],
                              loc_c[c], -1.0, -1.0)  # fmt: skip
    if hs >= room or room - hs < 1e-9 * hc:
        hs = room
    return hs


@jit(inline=True)
def _locate_switch(q, v, q1, v1, a0, a1, psi, psi_t, clo, chi, gap, phase, hs, pw0, pw1):
    """First switch of a force law inside a sub-step: ``(time, contact, kind)``.

    Kinds: onset, approach -> restitution, separation, restitution -> approach; located on
    the cubic Hermite interpolant of the penetration (or its rate).  ``(inf, -1, 0)``: none.
    ``pw0, pw1``: scratch of one value per contact.
    """
    matvec_spans(psi_t, q, pw0, clo, chi)  # every contact's penetration (plus gap) at both ends
    matvec_spans(psi_t, q1, pw1, clo, chi)
    t_ev = np.inf
    c_ev = -1
    kind = 0
    for c in range(gap.size):
        # the rates only where the contact's phase needs them (most contacts are open)
        te = np.inf
        kd = 0
        if phase[c] == 0:
            d0 = pw0[c] - gap[c]
            d1 = pw1[c] - gap[c]
            if d1 > 0.0 and d0 <= 0.0:
                te = hermite_root(d0, rowdot(psi, c, v), d1, rowdot(psi, c, v1), hs)
                kd = _ONSET
            elif d0 > 0.0:
                te = _resumed(d0, rowdot(psi, c, v), d1, rowdot(psi, c, v1), hs)
                kd = _ONSET
        elif phase[c] == 1:
            dd0 = rowdot(psi, c, v)
            dd1 = rowdot(psi, c, v1)
            if dd1 <= 0.0 and dd0 > 0.0:
                te = hermite_root(dd0, rowdot(psi, c, a0), dd1, rowdot(psi, c, a1), hs)
                kd = _TO_RESTITUTION
        else:
            d0 = pw0[c] - gap[c]
            d1 = pw1[c] - gap[c]
            dd0 = rowdot(psi, c, v)
            dd1 = rowdot(psi, c, v1)
            if d1 <= 0.0 and d0 > 0.0:
                te = hermite_root(d0, dd0, d1, dd1, hs)
                kd = _SEPARATION
            if dd1 > 0.0 and dd0 <= 0.0:
                t2 = hermite_root(dd0, rowdot(psi, c, a0), dd1, rowdot(psi, c, a1), hs)
                if t2 < te:
                    te = t2
                    kd = _TO_APPROACH
        if te < t_ev:
            t_ev = te
            c_ev = c
            kind = kd
    return t_ev, c_ev, kind


@jit(inline=True)
def _cut_substep(
    q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, psi_t, clo, chi, gap, beta, cd, zhd, phase,
    model, q1, v1, a0, a1, wk, fc, fc0, cimp, rate, pw0, pw1,
):  # fmt: skip
    """The RK4 sub-step of ``hs`` [s] from local time ``s``, cut at the first switch inside it.

    The sub-step (:func:`rk4`, its end state into ``q1, v1``, the accelerations at its ends
    into ``a0, a1``), and again to the first switch of a force law inside it
    (:func:`_locate_switch`) from the same start.  Returns the sub-step taken, the increments
    of input energy, damping energy and contact work, and the switch ``(time, contact, kind)``.
    """
    de_in, de_d, dw_c = rk4(q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, gap, beta, cd, zhd,
                            phase, model, q1, v1, wk, fc, cimp, fc0, rate)  # fmt: skip
    for j in range(q.size):
        a0[j] = wk[4, j]
    contact_forces(q1, v1, psi, gap, beta, cd, zhd, phase, model, fc, rate)
    accel(q1, v1, ag0 + slope * (s + hs), omega, zeta, gamma, psi, fc, a1)
    t_ev, c_ev, kind = _locate_switch(q, v, q1, v1, a0, a1, psi, psi_t, clo, chi, gap,
                                      phase, hs, pw0, pw1)  # fmt: skip
    if c_ev >= 0 and t_ev < hs:
        hs = t_ev
        de_in, de_d, dw_c = rk4(q, v, s, hs, ag0, slope, omega, zeta, gamma, psi,
                                gap, beta, cd, zhd, phase, model, q1, v1, wk, fc,
                                cimp, fc0, rate)  # fmt: skip
        contact_forces(q1, v1, psi, gap, beta, cd, zhd, phase, model, fc, rate)
        accel(q1, v1, ag0 + slope * (s + hs), omega, zeta, gamma, psi, fc, a1)
    return hs, de_in, de_d, dw_c, t_ev, c_ev, kind


@jit(inline=True)
def _contact_peaks(q, v, q1, v1, a0, a1, psi, gap, beta, cd, zhd, phase, model, fc0, fc, cimp,
                   cout, pending, hs, t, peak_f, peak_t, ep, logs, nlog, peak_e):  # fmt: skip
    """Peak force per contact (Hermite on F with its rate), penetration and impulse.

    Returns the run's peak force and its time, raised where this sub-step holds a new one, and
    the count of the impact-velocity log ``logs[0]`` (``outputs.log_impact_in``; ``ep``,
    ``peak_e``: see ``outputs.impact_log``).
    """
    for c in range(gap.size):
        cout[c, outputs.C_IMPULSE] += cimp[c]
        if phase[c] == 0:
            continue
        d0 = rowdot(psi, c, q) - gap[c]
        d1 = rowdot(psi, c, q1) - gap[c]
        dd0 = rowdot(psi, c, v)
        dd1 = rowdot(psi, c, v1)
        f0 = fc0[c]
        f1 = fc[c]  # forces at the end of the (possibly cut) sub-step
        fm, tm, dm = substep_peaks(
            model, f0, f1, d0, d1, dd0, dd1, rowdot(psi, c, a0), rowdot(psi, c, a1), hs,
            cout[c, outputs.C_PEAK_FORCE], beta[c], cd[c], zhd[c], phase[c],
        )  # fmt: skip
        if fm > cout[c, outputs.C_PEAK_FORCE]:
            cout[c, outputs.C_PEAK_FORCE] = fm
        if fm > peak_f:
            peak_f = fm
            peak_t = t + tm
            peak_e[0] = ep[c, outputs.EP_E]
        if dm > cout[c, outputs.C_MAX_PENETRATION]:
            cout[c, outputs.C_MAX_PENETRATION] = dm
        if pending[c] and dm > outputs.IMPACT_MIN_PENETRATION_M:
            cout[c, outputs.C_IMPACTS] += 1.0  # the episode is an impact
            pending[c] = False
            nlog = outputs.log_impact_in(logs, nlog, ep[c, outputs.EP_V0])
            cout[c, outputs.C_MAX_IMPACT_VELOCITY] = max(
                cout[c, outputs.C_MAX_IMPACT_VELOCITY], ep[c, outputs.EP_V0]
            )
    return peak_f, peak_t, nlog


@jit(inline=True)
def _open_contact(c, v, psi, xi, beta, meff, zhd, phase, pending, model, relation, substeps, hc,
                  settings, cd, ep):  # fmt: skip
    """Contact ``c`` starts an episode: its phase, episode damping and sub-step bound.

    With restitution set per impact (``settings.rest_v`` not empty, ``xi`` its quantile) the
    episode's damping follows from Table 2 at the onset velocity, into ``cd`` and ``zhd``;
    ``ep`` keeps the onset velocity and restitution of the episode.

    The episode counts as an impact once its penetration exceeds ``IMPACT_MIN_PENETRATION_M``
    (:func:`_contact_peaks`).
    """
    v0c = rowdot(psi, c, v)
    phase[c] = 1
    pending[c] = True
    ep[c, outputs.EP_V0] = v0c
    if settings.rest_v.size > 0:
        cd[c], zhd[c], ep[c, outputs.EP_E] = episode_damping(settings, model, relation, xi[c], v0c,
                                                     beta[c], meff[c], cd[c], zhd[c])  # fmt: skip
    else:
        zhd[c] = episode_zeta(model, relation, xi[c], v0c, zhd[c])
    return min(hc, duration(model, v0c, beta[c], meff[c]) / substeps)


@jit(inline=True)
def _switch(kind, c, v, psi, xi, beta, meff, zhd, phase, pending, model, relation, substeps, hc,
            h_rk, settings, cd, ep):  # fmt: skip
    """Contact ``c``'s phase after a switch of ``kind`` at the end of a sub-step.

    An onset starts an episode (:func:`_open_contact`); after a separation that leaves every
    contact open, exact steps go on from there to the next grid point.  ``hc``: the contact
    sub-step [s], ``h_rk`` its value once every contact is open.  Returns the sub-step and
    whether the run is still in its contact phase.
    """
    in_contact = True
    if kind == _ONSET:
        hc = _open_contact(c, v, psi, xi, beta, meff, zhd, phase, pending, model, relation,
                           substeps, hc, settings, cd, ep)  # fmt: skip
    elif kind == _TO_RESTITUTION:
        phase[c] = 2
    elif kind == _SEPARATION:
        phase[c] = 0
        if _all_open(phase):
            # continue with exact steps from here to the next grid point
            in_contact = False
            hc = h_rk
    else:
        phase[c] = 1
    return hc, in_contact


@jit(inline=True)
def _grid_index(s, h, m_sub):
    """Index of the next grid point of the record interval after local time ``s``."""
    k_grid = int(math.floor(s / h + 1e-9))
    if k_grid >= m_sub:
        k_grid = m_sub - 1
    return k_grid


@jit(inline=True)
def _store_history(i, q, v, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf):
    """Floor displacements, penetrations and forces at record sample ``i``."""
    for f in range(phi.shape[0]):
        hx[i, f] = rowdot(phi, f, q)
    for c in range(gap.size):
        hd[i, c] = rowdot(psi, c, q) - gap[c]
        hf[i, c] = force(model, hd[i, c], rowdot(psi, c, v), beta[c], cd[c], zhd[c], phase[c])


@jit(inline=True)
def _all_open(phase):
    """Whether no contact is closed."""
    for c in range(phase.size):
        if phase[c] != 0:
            return False
    return True


@jit(inline=True)
def _finite(q, v):
    """Whether the state is finite."""
    ok = True
    for j in range(q.size):
        if not (math.isfinite(q[j]) and math.isfinite(v[j])):
            ok = False
    return ok


@jit(inline=True)
def _hermite_tolerance(omega, h):
    """Error bound of the cubic Hermite maximum in a linear step, relative to the amplitude.

    ``(omega h)^4 / 384`` with a safety factor of 4: a candidate below the peak by more is no
    new peak.
    """
    wmax = 0.0
    for j in range(omega.size):
        wmax = max(wmax, omega[j])
    return 4.0 * (wmax * h) ** 4 / 384.0


@jit(inline=True)
def _resume(pre, q, v, peaks):
    """The start of a run from the shared response ``pre`` (:func:`outputs.snapshot`).

    Writes the state into ``q, v`` and the floor peaks into ``peaks``; returns the record
    interval, the input and damping energies, the steps so far and the initial energy.
    """
    n = q.size
    for j in range(n):
        q[j] = pre[outputs.PRE_STATE + j]
        v[j] = pre[outputs.PRE_STATE + n + j]
    for f in range(peaks.size):
        peaks[f] = pre[outputs.PRE_STATE + 2 * n + f]
    return (int(pre[outputs.PRE_INTERVAL]), pre[outputs.PRE_E_IN], pre[outputs.PRE_E_D],
            int(pre[outputs.PRE_STEPS]), pre[outputs.PRE_E0])  # fmt: skip


@jit(inline=True)
def _stored_energy(q, psi, gap, beta, phase, model):
    """Energy [J] stored in the closed contacts at the state ``q``."""
    stored_energy = 0.0
    for c in range(gap.size):
        if phase[c] != 0:
            stored_energy += stored(model, rowdot(psi, c, q) - gap[c], beta[c])
    return stored_energy


# --------------------------------------------------------------------------- the kernel


@jit
def adaptive(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """Run one simulation with the ``adaptive`` method (module docstring).

    ``xi`` holds the damping ratio per contact (the restitution ``e`` for Hertz-damp laws).
    ``pre``: shared linear response before the first contact (layout in
    :mod:`pound_mc.integrators.outputs`); empty for a plain run.  The loop keeps its scalar
    state (energies, clocks, phase flags) in locals across the two kinds of step; each step's
    work is in the helpers above.
    """
    ag, omega, zeta, gamma = borrow(ag), borrow(omega), borrow(zeta), borrow(gamma)
    phi, side = borrow(phi), borrow(side)
    psi, gap, meff, beta, xi = borrow(psi), borrow(gap), borrow(meff), borrow(beta), borrow(xi)
    q, v, out, cout, pre = borrow(q), borrow(v), borrow(out), borrow(cout), borrow(pre)
    model = settings.model
    relation = settings.relation
    substeps = settings.substeps
    n, nc, nf, npts, m_sub, h, cd = run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q)
    # contact sub-steps: at most a share of the shortest modal period (the RK4 sub-steps carry
    # every mode) and of each contact's local period and damping time (bounds)
    _h_lin, h_rk = shortest_period_steps(omega, settings.dt_s, MODAL_STEPS_PER_PERIOD)
    loc_k = LOCAL_PERIOD_SHARE * np.sqrt(meff) / substeps
    loc_c = LOCAL_DAMPING_SHARE * meff / substeps
    coef = np.empty((n, 2, 4))
    for j in range(n):
        coef[j] = coefficients(omega[j], zeta[j], h)
    q1 = np.empty(n)
    v1 = np.empty(n)
    a0 = np.empty(n)
    a1 = np.empty(n)
    wk = np.empty((10, n))
    fc = np.zeros(nc)
    fc0 = np.zeros(nc)
    cimp = np.zeros(nc)
    phase = np.zeros(nc, dtype=np.int64)
    pending = np.zeros(nc, dtype=np.bool_)  # an episode not yet counted as an impact
    zhd = np.zeros(nc)
    ep, vlog, peak_e = outputs.impact_log(nc)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    peaks = np.zeros(nf)
    dc0 = np.empty(nc)
    ddc0 = np.empty(nc)
    dc1 = np.empty(nc)
    ddc1 = np.empty(nc)
    xf0 = np.empty(nf)
    xfd0 = np.empty(nf)
    en0 = np.empty(4)
    en1 = np.empty(4)
    nphi = -phi
    # transposed for matrix-vector products whose inner loop runs over floors or contacts
    phi_t = np.ascontiguousarray(phi.T)
    psi_t = np.ascontiguousarray(psi.T)
    flo, fhi = row_spans(phi_t)  # a mode moves the floors of its own building only
    clo, chi = row_spans(psi_t)
    xb = np.empty(nf)
    xdb = np.empty(nf)
    pw0 = np.empty(nc)
    pw1 = np.empty(nc)
    rate = np.empty(nc)  # penetration rates of the closed contacts (contact_forces)
    zf = np.zeros(nf)
    # the loop works on views without an owner (toolkit.borrow): the arrays stay owned by
    # ``owned``, alive to every return below (_alive)
    owned = (coef, q1, v1, a0, a1, wk, fc, fc0, cimp, phase, pending, zhd, ep, peak_e, peaks,
             dc0, ddc0, dc1, ddc1, xf0, xfd0, en0, en1, nphi, phi_t, psi_t, flo, fhi, clo, chi,
             xb, xdb, pw0, pw1, rate, zf, cd)  # fmt: skip
    coef, q1, v1, a0, a1 = borrow(coef), borrow(q1), borrow(v1), borrow(a0), borrow(a1)
    wk, fc, fc0, cimp, zhd = borrow(wk), borrow(fc), borrow(fc0), borrow(cimp), borrow(zhd)
    phase, pending, ep, peak_e = borrow(phase), borrow(pending), borrow(ep), borrow(peak_e)
    dc0, ddc0, dc1, ddc1 = borrow(dc0), borrow(ddc0), borrow(dc1), borrow(ddc1)
    xf0, xfd0, en0, en1, nphi = borrow(xf0), borrow(xfd0), borrow(en0), borrow(en1), borrow(nphi)
    phi_t, psi_t, flo, fhi = borrow(phi_t), borrow(psi_t), borrow(flo), borrow(fhi)
    clo, chi, xb, xdb, pw0 = borrow(clo), borrow(chi), borrow(xb), borrow(xdb), borrow(pw0)
    pw1, rate, zf, cd, peaks = borrow(pw1), borrow(rate), borrow(zf), borrow(cd), borrow(peaks)
    herm_tol = _hermite_tolerance(omega, h)
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    e0 = mechanical_energy(q, v, omega)
    peak_f = 0.0
    peak_t = 0.0
    steps = 0
    hc = h_rk
    fresh = False
    t_onset = 0.0
    # steps allowed: 200 per linear step of the record, plus room for many contacts
    budget = 200 * (npts - 1) * m_sub + 1_000_000
    in_contact = False
    status = outputs.STATUS_OK
    store = hx.shape[0] > 0
    outputs.reset_contacts(cout)
    mode = int(pre[outputs.PRE_MODE]) if pre.size > 0 else 0
    # the peak force alone: no energies and no floor peaks (neither moves the state)
    lean = mode == outputs.PRE_RESUME_PEAK
    i_first = 0
    if mode == outputs.PRE_RESUME or lean:
        i_first, e_in, e_d, steps, e0 = _resume(pre, q, v, peaks)
    for i in range(i_first, npts - 1):
        if mode == outputs.PRE_RUN_TO_CONTACT:
            outputs.snapshot(pre, i, e_in, e_d, steps, e0, q, v, peaks)
        if store:
            _store_history(i, q, v, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf)
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) / dt_rec
        s = 0.0
        k_grid = 0  # index of the next grid point within the interval
        while s < dt_rec * (1.0 - 1e-12):
            steps += 1
            if steps > budget:
                # absurd parameters (say beta = 1e300 makes contact sub-steps of 1e-119 s):
                # give up instead of running for ever, and say so
                status = outputs.STATUS_NOT_CONVERGED
                break
            if not in_contact:
                # ---------------- exact linear step to the next grid point (or an onset)
                s_next, hh, p0s, p1s, regular = grid_step(k_grid, m_sub, h, dt_rec, s, ag0, slope)
                _exact_step(q, v, q1, v1, coef, regular, p0s, p1s, omega, zeta, gamma, hh)
                if not fresh:
                    refresh(q, v, p0s, omega, zeta, gamma, phi, psi, gap, dc0, ddc0, xf0, xfd0,
                            en0)  # fmt: skip
                    fresh = True
                c_on, tau_on = _screen_onsets(q, v, q1, v1, p0s, slope, s, hh, dc0, ddc0, dc1,
                                              ddc1, omega, zeta, gamma, psi, psi_t, clo,
                                              chi, gap)  # fmt: skip
                if c_on >= 0 and mode == outputs.PRE_RUN_TO_CONTACT:
                    return
                if c_on >= 0:
                    hh = tau_on
                    p1s = ag0 + slope * (s + hh)
                    _exact_step(q, v, q1, v1, coef, False, p0s, p1s, omega, zeta, gamma, hh)
                    _penetrations(q1, v1, psi_t, clo, chi, gap, dc1, ddc1)
                if not lean:
                    end_values(q1, v1, p1s, omega, zeta, gamma, en1)
                    de_in, de_d = _linear_energies(hh, p0s, p1s, slope, en0, en1)
                    e_in += de_in
                    e_d += de_d
                    _linear_floor_peaks(q, v, q1, v1, p0s, slope, s, hh, phi, phi_t, flo, fhi,
                                        nphi, zf, xf0, xfd0, peaks, herm_tol, omega, zeta, gamma,
                                        xb, xdb)  # fmt: skip
                _shift(q, v, q1, v1, dc0, ddc0, dc1, ddc1, en0, en1)
                s += hh
                if c_on >= 0:
                    hc = _open_contact(c_on, v, psi, xi, beta, meff, zhd, phase, pending, model,
                                       relation, substeps, h_rk, settings, cd, ep)  # fmt: skip
                    t_onset = i * dt_rec + s
                    in_contact = True
                else:
                    k_grid += 1
            else:
                # ---------------- contact sub-step (RK4) with located switches
                fresh = False
                hs = _substep_length(q, v, psi, gap, phase, hc, i * dt_rec + s, t_onset,
                                     dt_rec - s, model, beta, cd, zhd, loc_k,
                                     loc_c)  # fmt: skip
                hs, de_in, de_d, dw_c, t_ev, c_ev, kind = _cut_substep(
                    q, v, s, hs, ag0, slope, omega, zeta, gamma, psi, psi_t, clo, chi, gap, beta,
                    cd, zhd, phase, model, q1, v1, a0, a1, wk, fc, fc0, cimp, rate, pw0, pw1,
                )  # fmt: skip
                e_in += de_in
                e_d += de_d
                w_c += dw_c
                peak_f, peak_t, nlog = _contact_peaks(
                    q, v, q1, v1, a0, a1, psi, gap, beta, cd, zhd, phase, model, fc0, fc, cimp,
                    cout, pending, hs, i * dt_rec + s, peak_f, peak_t, ep, logs, nlog, peak_e,
                )  # fmt: skip
                # floor peaks over the sub-step; xf0, xfd0 move on to its end
                if not lean:
                    track_floors(phi_t, flo, fhi, xf0, xfd0, q1, v1, hs, peaks, xb, xdb)
                for j in range(n):
                    q[j] = q1[j]
                    v[j] = v1[j]
                s += hs
                if c_ev >= 0 and hs == t_ev:
                    hc, in_contact = _switch(kind, c_ev, v, psi, xi, beta, meff, zhd, phase,
                                             pending, model, relation, substeps, hc, h_rk,
                                             settings, cd, ep)  # fmt: skip
                    if kind == _ONSET:
                        t_onset = i * dt_rec + s
                k_grid = _grid_index(s, h, m_sub)
            # divergence / non-finite guard
            if not _finite(q, v):
                status = outputs.STATUS_UNSTABLE
                break
        if status != outputs.STATUS_OK:
            break
    if mode == outputs.PRE_RUN_TO_CONTACT:
        # no contact in the whole record: the end state is shared
        outputs.snapshot(pre, npts - 1, e_in, e_d, steps, e0, q, v, peaks)
    elif lean:
        outputs.peak_only(out, cout, peak_f, status)
    else:
        if store and status == outputs.STATUS_OK:
            _store_history(npts - 1, q, v, phi, psi, gap, beta, cd, zhd, phase, model, hx, hd, hf)
        stored_energy = _stored_energy(q, psi, gap, beta, phase, model)
        outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c,
                       stored_energy, peak_f, peak_t, steps, status)  # fmt: skip
        outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
    _alive(owned)


@jit
def _alive(owned):
    """A use of ``owned`` (the kernel's scratch arrays) that keeps them alive to here."""
    return len(owned)
