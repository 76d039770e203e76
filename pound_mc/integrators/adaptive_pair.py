"""The ``adaptive`` method for an SDOF pair (two modes, one contact) with scalar state.

:func:`adaptive_pair` is :func:`pound_mc.integrators.adaptive.adaptive` specialised to two
single-storey buildings that meet at one contact: the modal state is four scalars, the step
coefficients are scalars computed once, and no array is touched in the hot loop.  Same
algorithm (exact Nigam-Jennings steps between contacts, contact onset located on the exact
solution, Runge-Kutta sub-steps during contact with every switch of the force law located),
same outputs, the same status and energy logic and the same ``pre`` protocol (the shared
linear response before the first contact, see :mod:`pound_mc.integrators.outputs`) and the
same histories.  ``tests/test_adaptive_pair.py``
holds it to the general kernel.

The kernel's loop alternates the two phases' steps, each in its own module:
:mod:`~pound_mc.integrators.adaptive_pair_linear` (exact steps between contacts, and runs of
quiet whole steps) and :mod:`~pound_mc.integrators.adaptive_pair_contact` (RK4 sub-steps in
contact, the start of an episode).  Their helpers are compiled on their own and inlined by
LLVM (``llvm_inline``, :func:`pound_mc._jit.jit`), so the compiled loop is one function, its
scalar state in registers; the arrays (record, histories, shared response, impact log) are
touched in the kernel only.

Notation: mode ``j`` (0 left, 1 right) has circular frequency ``w_j`` [rad/s], damping ratio
``z_j``, participation ``g_j = sqrt(m_j)`` [kg^0.5] (mass-normalised, ``q_j = sqrt(m_j) x_j``);
the penetration is ``delta = ps0 q0 + ps1 q1 - gap`` and floor ``j`` moves ``x_j = f_j q_j``.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import laws
from pound_mc.integrators.adaptive_pair_contact import (
    RAMP_GROWTH,
    RAMP_GROWTH_POT,
    RAMP_START,
    RAMP_START_POT,
    TAIL,
    TAIL_MIN,
    TAIL_MIN_POT,
    TAIL_POT,
    _contact_substep,
    _open_episode,
)
from pound_mc.integrators.adaptive_pair_linear import (
    _linear_step,
    _quiet_close,
    _quiet_start,
    _quiet_step,
)
from pound_mc.integrators.bounds import FINE as _FINE
from pound_mc.integrators.bounds import (
    LINEAR_STEPS_PER_PERIOD,
    LOCAL_DAMPING_SHARE,
    LOCAL_PERIOD_SHARE,
    STEPS_PER_PERIOD,
    damping_screen,
    period_screen,
)
from pound_mc.integrators.outputs import (
    C_IMPACTS,
    C_IMPULSE,
    C_MAX_IMPACT_VELOCITY,
    C_MAX_PENETRATION,
    C_PEAK_FORCE,
    N_OUT,
    ONSET_CD,
    ONSET_GRID,
    ONSET_PEAK,
    ONSET_S,
    ONSET_ZHD,
    PEAK_DISP_LEFT,
    PRE_E0,
    PRE_E_D,
    PRE_E_IN,
    PRE_INTERVAL,
    PRE_MODE,
    PRE_RESUME,
    PRE_RESUME_ONSET,
    PRE_RESUME_PEAK,
    PRE_RUN_TO_CONTACT,
    PRE_STATE,
    PRE_STEPS,
    STATUS_NOT_CONVERGED,
    STATUS_OK,
    STATUS_UNSTABLE,
    finish,
    finish_impacts,
    impact_log,
    log_impact_in,
    log_max,
    peak_only,
)
from pound_mc.integrators.toolkit import coefficients, step_size

__all__ = ["adaptive_pair"]

_INF = math.inf
_JANKOWSKI = laws.LAW_CODES["jankowski"]


@jit
def adaptive_pair(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """:func:`~pound_mc.integrators.adaptive.adaptive` for an SDOF pair, state in scalars.

    Same arguments and outputs; ``phi`` is diagonal (floor ``j`` is mode ``j``), one contact.
    ``hx, hd, hf``: histories at the record's samples (empty arrays: none).  ``pre``: the shared
    linear response before the first contact (layout in :mod:`pound_mc.integrators.outputs`;
    floor peaks after the state), empty for a plain run.  Its scalar state lives in locals
    across both kinds of step, each step's work in its phase's module (module docstring).
    """
    model = settings.model
    substeps = settings.substeps
    npts = ag.size
    inv_dt = 1.0 / dt_rec
    w0, w1, z0, z1, g0, g1 = omega[0], omega[1], zeta[0], zeta[1], gamma[0], gamma[1]
    m_sub, h, m_rk, h_rk, km, cf0, cf1, herm_tol = _step_constants(dt_rec, settings.dt_s, w0, z0,
                                                                   g0, w1, z1, g1)  # fmt: skip
    ps0, ps1, f0, f1 = psi[0, 0], psi[0, 1], phi[0, 0], phi[1, 1]
    gp, b, me, xi0 = gap[0], beta[0], meff[0], xi[0]
    cd = 2.0 * xi0 * math.sqrt(b * me)  # damping constant c0 of the force laws
    # the constants of the two phases' steps (adaptive_pair_linear)
    lin = (m_sub, h, dt_rec, cf0, cf1, herm_tol)
    md = (w0, z0, g0, w1, z1, g1)
    geo = (ps0, ps1, gp, f0, f1)
    q0, q1, v0, v1 = q[0], q[1], v[0], v[1]
    e0 = 0.5 * (v0 * v0 + w0 * w0 * q0 * q0)
    e0 += 0.5 * (v1 * v1 + w1 * w1 * q1 * q1)
    mode = int(pre[PRE_MODE]) if pre.size > 0 else 0
    # the check's run: no energies; the floors' peaks from a contact onset (PRE_RESUME_ONSET)
    lean = mode == PRE_RESUME_PEAK or mode == PRE_RESUME_ONSET
    floors = not lean or mode == PRE_RESUME_ONSET
    # where the run starts: k_grid is the index of the next grid point within the interval
    (i, s, k_grid, steps, e_in, e_d, e0, q0, q1, v0, v1, pk0, pk1, peak_f, cd,
     zhd) = _resumed(pre, mode, lean, q0, q1, v0, v1, e0, cd)  # fmt: skip
    phase = 0
    w_c = peak_t = impacts = impulse = 0.0
    pending = False  # an episode not yet counted as an impact
    maxpen = -_INF
    hc = h_rk
    fresh = in_contact = fsal = False
    dc0 = ddc0 = xf0 = xf1 = xfd0 = xfd1 = fc_end = ae0 = ae1 = t_onset = 0.0
    en0 = (0.0, 0.0, 0.0, 0.0)  # the energy sums at a linear step's start (_ends)
    budget = 200 * (npts - 1) * m_rk + 1_000_000
    # whether the accuracy check's run (_FINE times every sub-step bound that depends on
    # ``substeps``) would take the same sub-steps: then its peak force is this run's, bitwise
    same_fine = True
    # _roots of the state, valid while ``rooted`` (the last sub-step was an approach's)
    roots = (0.0, 0.0, 0.0)
    rooted = False
    pot = model == _JANKOWSKI
    kpot = 0.8 * cd
    # restitution set per impact (Table 2 at the onset velocity; ``xi0`` holds its quantile)
    per_impact = settings.rest_v.size > 0
    # the impact-velocity log in a list that is never reassigned (outputs.log_impact_in)
    logs = [impact_log(1)[1]]
    nlog = 0
    v_ep = e_ep = peak_e = math.nan
    ramp = ((RAMP_START_POT, RAMP_GROWTH_POT, TAIL_POT, TAIL_MIN_POT) if pot else
            (RAMP_START, RAMP_GROWTH, TAIL, TAIL_MIN))  # fmt: skip
    loc_k = LOCAL_PERIOD_SHARE * math.sqrt(me) / substeps
    loc_c = LOCAL_DAMPING_SHARE * me / substeps
    status = STATUS_OK
    store = hx.shape[0] > 0
    # the screen of the local bounds (_contact_bound) covers their tightness at _FINE, which
    # only ``same_fine`` needs: a lean run (the check's own run) reports none, and its screen
    # covers the bounds themselves, the larger share (every bound is slack there, bit for bit)
    share = 1.0 if lean else _FINE
    bounds = (loc_k, loc_c, period_screen(model, b, loc_k, share))
    kc4 = damping_screen(model, b, cd, loc_c, share)
    # past the outputs and their ``same`` slot: where the check's run may start (the state at
    # the last onset before which the check's run is this one, PRE_RESUME_ONSET)
    onsets = out.size > N_OUT + 1
    while i < npts - 1:
        if fresh and not in_contact:
            # ---------------- runs of whole grid steps where nothing happens inside them
            # (_quiet_step; the general step below takes the others, from the grid point this
            # loop stops at).  A loop of its own keeps its state in registers (B1: the linear
            # phases 2.5 times faster than as a branch of the interval loop)
            run = _quiet_start()
            while i < npts - 1:
                if k_grid == 0:  # a new record interval
                    if mode == PRE_RUN_TO_CONTACT:
                        e_in, e_d, en0, run = _quiet_close(run, e_in, e_d, en0, q0, q1, v0, v1,
                                                           km, h)  # fmt: skip
                        _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
                    if store:
                        _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase,
                                    model, hx, hd, hf)  # fmt: skip
                    ag0 = ag[i]
                    slope = (ag[i + 1] - ag[i]) * inv_dt
                (quiet, hh, q0, q1, v0, v1, dc0, ddc0, xf0, xfd0, xf1, xfd1, pk0, pk1,
                 run) = _quiet_step(k_grid, s, ag0, slope, q0, q1, v0, v1, dc0, ddc0, xf0, xfd0,
                                    xf1, xfd1, pk0, pk1, en0, run, lean, floors, lin, md,
                                    geo,
                                    km)  # fmt: skip
                if not quiet:
                    break  # the general step below takes this grid step
                steps += 1
                if not math.isfinite(q0 + q1 + v0 + v1):
                    status = STATUS_UNSTABLE
                    break
                s += hh  # as the general step: the next grid step starts here
                k_grid += 1
                if k_grid == m_sub:
                    s = 0.0
                    k_grid = 0
                    i += 1
            if not lean:
                e_in, e_d, en0, run = _quiet_close(run, e_in, e_d, en0, q0, q1, v0, v1, km, h)
            if status != 0 or i >= npts - 1:
                break
        else:
            if mode == PRE_RUN_TO_CONTACT:
                _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
            if store:
                _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase,
                            model, hx, hd, hf)  # fmt: skip
        ag0 = ag[i]
        slope = (ag[i + 1] - ag[i]) * inv_dt
        fsal = False  # a new interval: new load, the next sub-step starts afresh
        while s < dt_rec * (1.0 - 1e-12):
            steps += 1
            if steps > budget:
                status = STATUS_NOT_CONVERGED
                break
            if not in_contact:
                # ---------------- exact linear step to the next grid point (or an onset)
                (opened, hh, nq0, nq1, nv0, nv1, dc0, ddc0, xf0, xfd0, xf1, xfd1, en0, e_in, e_d,
                 pk0, pk1) = _linear_step(k_grid, s, ag0, slope, q0, q1, v0, v1, fresh, dc0, ddc0,
                                          xf0, xfd0, xf1, xfd1, en0, e_in, e_d, pk0, pk1, lean,
                                          floors, lin, md, geo, km)  # fmt: skip
                fresh = True
                if opened and mode == PRE_RUN_TO_CONTACT:
                    return
                if opened and onsets and same_fine:  # the check's run is this one up to here
                    _snapshot_onset(out[N_OUT + 1 :], i, s, k_grid, steps - 1, q0, q1, v0, v1,
                                    peak_f, cd, zhd, pk0, pk1)  # fmt: skip
                q0, q1, v0, v1 = nq0, nq1, nv0, nv1
                s += hh
                if opened:
                    phase = 1
                    pending = True
                    v_ep = ps0 * v0 + ps1 * v1
                    cd, zhd, e_ep, kpot, kc4, hc, same_fine = _open_episode(
                        settings, per_impact, v_ep, b, me, xi0, cd, zhd, e_ep, kpot, kc4, loc_c,
                        share, h_rk, same_fine,
                    )  # fmt: skip
                    t_onset = i * dt_rec + s
                    in_contact = True
                    fsal = False
                    rooted = False
                else:
                    k_grid += 1
            else:
                # ---------------- contact sub-step (RK4) with located switches
                fresh = False
                (q0, q1, v0, v1, s, k_grid, phase, hc, in_contact, opened, same_fine, fsal, fc_end,
                 ae0, ae1, roots, rooted, e_in, e_d, w_c, impulse, peak_f, peak_t, peak_e, maxpen,
                 impacts, pending, counted, pk0, pk1) = _contact_substep(
                    i * dt_rec + s, dt_rec - s, s, ag0, slope, q0, q1, v0, v1, phase, hc, h_rk,
                    t_onset, zhd, cd, kpot, kc4, same_fine, fsal, fc_end, ae0, ae1, roots, rooted,
                    e_in, e_d, w_c, impulse, peak_f, peak_t, peak_e, e_ep, maxpen, impacts,
                    pending, pk0, pk1, floors, pot, model, b, km, geo, ramp, bounds, h, m_sub,
                )  # fmt: skip
                if counted:  # the episode is an impact
                    nlog = log_impact_in(logs, nlog, v_ep)
                if opened:  # an onset at the step's end: a new episode
                    phase = 1
                    pending = True
                    v_ep = ps0 * v0 + ps1 * v1
                    cd, zhd, e_ep, kpot, kc4, hc, same_fine = _open_episode(
                        settings, per_impact, v_ep, b, me, xi0, cd, zhd, e_ep, kpot, kc4, loc_c,
                        share, hc, same_fine,
                    )  # fmt: skip
                    t_onset = i * dt_rec + s
            # divergence / non-finite guard
            if not math.isfinite(q0 + q1 + v0 + v1):  # inf or nan in any of them
                status = STATUS_UNSTABLE
                break
        if status != 0:
            break
        i += 1
        s = 0.0
        k_grid = 0
    if mode == PRE_RUN_TO_CONTACT:
        # no contact in the whole record: the end state is shared
        _snapshot_pair(pre, npts - 1, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1)
        return
    if lean:
        _finish_lean(out, cout, peak_f, status, floors, side, pk0, pk1)
        return
    if store and status == STATUS_OK:
        _store_pair(npts - 1, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase,
                    model, hx, hd, hf)  # fmt: skip
    q[0], q[1], v[0], v[1] = q0, q1, v0, v1
    _finish_pair(out, cout, q, v, omega, side, model, phase, ps0 * q0 + ps1 * q1 - gp, b,
                 pk0, pk1, e0, e_in, e_d, w_c, peak_f, peak_t, peak_e, impacts, maxpen, impulse,
                 logs[0], nlog, steps, status, same_fine)  # fmt: skip


@jit(llvm_inline=True)
def _step_constants(dt_rec, dt_s, w0, z0, g0, w1, z1, g1):
    """The steps of a run and their constants, from the modes and the step bound ``dt_s`` [s].

    Returns the linear steps per record interval and their length ``h`` [s]
    (:data:`~pound_mc.integrators.bounds.LINEAR_STEPS_PER_PERIOD` of the shorter period), the
    same for the longest contact sub-step ``h_rk`` (a step of the record interval split
    evenly as ``h`` is), ``km`` (:func:`~pound_mc.integrators.adaptive_pair_linear._ends`),
    the exact-step coefficients of each mode for a step ``h`` (the two rows of
    ``toolkit.coefficients`` in one tuple) and the tolerance of a floor peak's Hermite screen.
    """
    wmax = max(w0, w1)
    m_sub, h = step_size(dt_rec, min(dt_s, 2.0 * math.pi / (LINEAR_STEPS_PER_PERIOD * wmax)))
    # the longest contact sub-step, a step of the record interval split evenly as h is
    m_rk, h_rk = step_size(dt_rec, min(dt_s, 2.0 * math.pi / (STEPS_PER_PERIOD * wmax)))
    k0, k1 = -2.0 * z0 * w0, -2.0 * z1 * w1
    ww0, ww1 = w0 * w0, w1 * w1
    zw2_0, zw2_1 = 2.0 * z0 * w0, 2.0 * z1 * w1
    zw4_0, zw4_1 = 4.0 * z0 * w0, 4.0 * z1 * w1
    km = (k0, ww0, g0, k1, ww1, g1, zw2_0, zw2_1, zw4_0, zw4_1)
    cf = coefficients(w0, z0, h)
    cf0 = (cf[0, 0], cf[0, 1], cf[0, 2], cf[0, 3], cf[1, 0], cf[1, 1], cf[1, 2], cf[1, 3])
    cf = coefficients(w1, z1, h)
    cf1 = (cf[0, 0], cf[0, 1], cf[0, 2], cf[0, 3], cf[1, 0], cf[1, 1], cf[1, 2], cf[1, 3])
    # error bound of the cubic Hermite maximum in a linear step, (omega h)^4 / 384 of the
    # amplitude, with a safety factor of 4: a candidate below the peak by more is no new peak
    herm_tol = 4.0 * (wmax * h) ** 4 / 384.0
    return m_sub, h, m_rk, h_rk, km, cf0, cf1, herm_tol


@jit(llvm_inline=True)
def _resumed(pre, mode, lean, q0, q1, v0, v1, e0, cd):
    """Where a run starts: the record's start, or the shared response ``pre`` it resumes from.

    ``q0, q1, v0, v1``, ``e0``: the initial state and its energy; ``cd``: the law's damping
    constant.  Returns ``(i, s, k_grid, steps, e_in, e_d, e0, q0, q1, v0, v1, pk0, pk1, peak_f,
    cd, zhd)``: the record interval, local time [s] and grid point, the steps so far, the
    energies, the state, the floor peaks, the peak force and the damping of the episode
    (:func:`_snapshot_pair` and, within an interval, :func:`_snapshot_onset`).
    """
    i = 0
    s = 0.0
    k_grid = 0
    steps = 0
    e_in = e_d = pk0 = pk1 = peak_f = zhd = 0.0
    if mode == PRE_RESUME or lean:
        i = int(pre[PRE_INTERVAL])
        e_in = pre[PRE_E_IN]
        e_d = pre[PRE_E_D]
        steps = int(pre[PRE_STEPS])
        e0 = pre[PRE_E0]
        q0, q1, v0, v1 = pre[PRE_STATE], pre[PRE_STATE + 1], pre[PRE_STATE + 2], pre[PRE_STATE + 3]
        pk0, pk1 = pre[PRE_STATE + 4], pre[PRE_STATE + 5]
    if mode == PRE_RESUME_ONSET:  # within the interval, at the start of a linear step
        s, k_grid, peak_f = pre[ONSET_S], int(pre[ONSET_GRID]), pre[ONSET_PEAK]
        cd, zhd = pre[ONSET_CD], pre[ONSET_ZHD]
    return i, s, k_grid, steps, e_in, e_d, e0, q0, q1, v0, v1, pk0, pk1, peak_f, cd, zhd


@jit
def _finish_pair(out, cout, q, v, omega, side, model, phase, d, b, pk0, pk1, e0, e_in, e_d, w_c,
                 peak_f, peak_t, peak_e, impacts, maxpen, impulse, vlog, nlog, steps, status,
                 same_fine):  # fmt: skip
    """The outputs of a run that ended at the state ``q, v`` (:func:`outputs.finish`).

    ``phase`` and ``d``: the contact's phase and penetration [m] at the end (its stored
    energy); ``pk0, pk1``: the floor peaks [m]; ``vlog``: the impact velocities, ``nlog`` of
    them; ``same_fine``: whether the accuracy check's run would take this run's sub-steps,
    written to the slot past the outputs where ``out`` has one.
    """
    cout[0, C_PEAK_FORCE] = peak_f
    cout[0, C_IMPACTS] = impacts
    cout[0, C_MAX_PENETRATION] = maxpen
    cout[0, C_IMPULSE] = impulse
    cout[0, C_MAX_IMPACT_VELOCITY] = log_max(vlog, nlog)
    peaks = np.empty(2)
    peaks[0] = pk0
    peaks[1] = pk1
    ph = np.zeros(1, dtype=np.int64)
    ph[0] = phase
    stored_energy = 0.0
    if phase != 0:
        stored_energy = laws.stored(model, d, b)
    finish(out, cout, peaks, side, ph, q, v, omega, e0, e_in, e_d, w_c, stored_energy, peak_f,
           peak_t, steps, status)  # fmt: skip
    finish_impacts(out, cout, vlog, nlog, peak_e)
    if out.size > N_OUT:  # a slot past the outputs: does the accuracy check's run differ?
        out[N_OUT] = 1.0 if same_fine else 0.0


@jit(inline=True)
def _snapshot_pair(pre, i, e_in, e_d, steps, e0, q0, q1, v0, v1, pk0, pk1):
    """:func:`~pound_mc.integrators.outputs.snapshot` of the scalar state."""
    pre[PRE_INTERVAL] = i
    pre[PRE_E_IN] = e_in
    pre[PRE_E_D] = e_d
    pre[PRE_STEPS] = steps
    pre[PRE_E0] = e0
    pre[PRE_STATE] = q0
    pre[PRE_STATE + 1] = q1
    pre[PRE_STATE + 2] = v0
    pre[PRE_STATE + 3] = v1
    pre[PRE_STATE + 4] = pk0
    pre[PRE_STATE + 5] = pk1


@jit(inline=True)
def _finish_lean(out, cout, peak_f, status, floors, side, pk0, pk1):
    """The outputs of the accuracy check's run: the peak force and, from an onset, the floors'."""
    peak_only(out, cout, peak_f, status)
    if floors and status == STATUS_OK:
        out[PEAK_DISP_LEFT + side[0]] = pk0
        out[PEAK_DISP_LEFT + side[1]] = pk1


@jit(inline=True)
def _snapshot_onset(pre, i, s, k_grid, steps, q0, q1, v0, v1, peak_f, cd, zhd, pk0, pk1):
    """A ``PRE_RESUME_ONSET`` start: a linear step's start (state, peak force, floors' peaks)."""
    _snapshot_pair(pre, i, 0.0, 0.0, steps, 0.0, q0, q1, v0, v1, pk0, pk1)
    pre[ONSET_S] = s
    pre[ONSET_GRID] = k_grid
    pre[ONSET_PEAK] = peak_f
    pre[ONSET_CD] = cd
    pre[ONSET_ZHD] = zhd


@jit(inline=True)
def _store_pair(i, q0, q1, v0, v1, f0, f1, ps0, ps1, gp, b, cd, zhd, phase, model, hx, hd, hf):
    """Floor displacements, penetration and force at record sample ``i``."""
    hx[i, 0] = f0 * q0
    hx[i, 1] = f1 * q1
    d = ps0 * q0 + ps1 * q1 - gp
    hd[i, 0] = d
    hf[i, 0] = laws.force(model, d, ps0 * v0 + ps1 * v1, b, cd, zhd, phase)
