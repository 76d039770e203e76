"""Fixed-step methods on the general modal model (any buildings, any number of contacts).

``newmark``
    Average acceleration (gamma = 1/2, beta = 1/4) at the fixed step ``dt_s``, the contact
    forces solved implicitly by Newton's method on the penetrations in every step.
``newmark-explicit``
    The same, with the contact force lagged one step (explicit in the contact).
``central-difference``
    Explicit central differences, contact force from the backward-difference velocity.

They report maxima over their step points.  An SDOF pair with ``newmark`` or
``newmark-explicit`` runs through :mod:`pound_mc.integrators.pair` instead (same results).

The pieces of the Newmark step (:func:`newmark_matrices`, :func:`newmark_solve`,
:func:`contact_events`, ...) are public, inlined functions: the inelastic kernel
(:mod:`pound_mc.integrators.hysteretic`) builds its step from the same ones.
"""

from __future__ import annotations

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.laws import (
    episode_damping,
    episode_zeta,
    force,
    force_grad,
    newton_scalar,
    phase_of,
    stored,
)
from pound_mc.integrators.toolkit import (
    accel,
    mechanical_energy,
    powers,
    rowdot,
    run_sizes,
    solve_small,
    trapezoid,
)

#: Method codes of this module (the boundary maps names to them).
NEWMARK, NEWMARK_EXPLICIT, CENTRAL_DIFFERENCE = 1, 2, 3


@jit(inline=True)
def _newton_contacts(model, dtry, dstar, dpen, ddpen, g, c2h, beta, cd, zhd, fn, jac, rhs):
    """Contact forces at the end of a Newmark step for several contacts (Newton, 60 at most).

    Solves ``d - d* + G F(d, d_dot(d)) = 0`` on the penetrations; fills ``fn``, returns
    whether it converged.
    """
    nc = dtry.size
    conv = False
    for _it in range(60):
        for c in range(nc):
            ddt = c2h * (dtry[c] - dpen[c]) - ddpen[c]
            ph = phase_of(dtry[c], ddt)
            f, fd, fdd = force_grad(model, dtry[c], ddt, beta[c], cd[c], zhd[c], ph)
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
        if not solve_small(jac, rhs, nc):
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
        fn[c] = force(model, dtry[c], ddt, beta[c], cd[c], zhd[c], phase_of(dtry[c], ddt))
    return conv


@jit(inline=True)
def implicit_forces(model, method, dstar, dtry, dpen, ddpen, g, c2h, fc, beta, cd, zhd, fn,
                     jac, rhs):  # fmt: skip
    """Contact forces at the end of a Newmark step (lagged for ``newmark-explicit``).

    Returns whether the contact solve converged.
    """
    nc = dstar.size
    if method == NEWMARK_EXPLICIT:
        for c in range(nc):
            fn[c] = fc[c]  # lagged one step
        return True
    any_pos = False
    for c in range(nc):
        dtry[c] = dstar[c]
        if dstar[c] > 0.0:
            any_pos = True
    if not any_pos:
        for c in range(nc):
            fn[c] = 0.0
        return True
    if nc == 1:
        # scalar safeguarded Newton with the analytic slope, root in (0, d*)
        fn[0], conv = newton_scalar(model, dstar[0], dpen[0], ddpen[0], g[0, 0], c2h, fc[0],
                                    beta[0], cd[0], zhd[0])  # fmt: skip
        return conv
    return _newton_contacts(model, dtry, dstar, dpen, ddpen, g, c2h, beta, cd, zhd, fn, jac, rhs)


# -- pieces of the average-acceleration Newmark step, shared with the inelastic kernel -------


@jit(inline=True)
def newmark_matrices(omega, zeta, h, psi):
    """Modal constants of the Newmark step ``h`` [s].

    Returns the inverse effective stiffness ``1 / khat``, ``2 zeta omega`` and the contact
    flexibility ``G = sum_j psi_c,j psi_c',j / khat_j``.
    """
    n = omega.size
    nc = psi.shape[0]
    khat = np.empty(n)
    ikhat = np.empty(n)
    zw2 = np.empty(n)
    g = np.zeros((nc, nc))
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
    return ikhat, zw2, g


@jit(inline=True)
def newmark_arrays(n, nc, nf):
    """Work arrays of a Newmark run: modal, per contact (zeroed) and per floor (zeroed).

    ``a``, ``qn``, ``vn``, ``an``, ``qs`` (modal: accelerations, end of step, predictor);
    ``fc``, ``fn`` (contact forces at the start and end of a step), ``zhd`` (episode damping),
    ``dpen``, ``ddpen`` (penetrations and rates), ``was_in``, ``pending`` (flags), ``jac``,
    ``rhs``, ``dstar``, ``dtry`` (the contact solve's); ``peaks`` (floor displacements).
    """
    return (np.empty(n), np.empty(n), np.empty(n), np.empty(n), np.empty(n),
            np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nc),
            np.zeros(nc, dtype=np.bool_), np.zeros(nc, dtype=np.bool_), np.zeros((nc, nc)),
            np.zeros(nc), np.zeros(nc), np.zeros(nc), np.zeros(nf))  # fmt: skip


@jit(inline=True)
def initial_state(model, psi, q, v, gap, beta, cd, zhd, dpen, ddpen, fc, was_in, ag0, omega,
                  zeta, gamma, a):  # fmt: skip
    """The initial state's penetrations, rates, forces, contact flags and accelerations.

    Fills ``dpen, ddpen, fc, was_in`` and ``a``; returns the input, damping and contact powers
    [W] at the start (ground acceleration ``ag0``).
    """
    for c in range(gap.size):
        dpen[c] = rowdot(psi, c, q) - gap[c]
        ddpen[c] = rowdot(psi, c, v)
        fc[c] = force(model, dpen[c], ddpen[c], beta[c], cd[c], zhd[c],
                      phase_of(dpen[c], ddpen[c]))  # fmt: skip
        was_in[c] = dpen[c] > 0.0
    accel(q, v, ag0, omega, zeta, gamma, psi, fc, a)
    pin, pd = powers(v, ag0, omega, zeta, gamma)
    return pin, pd, contact_power(fc, ddpen)


@jit(inline=True)
def newmark_solve(settings, q, v, a, ag1, gamma, zw2, ikhat, h, load, psi, gap, g, dpen, ddpen,
                  fc, beta, cd, zhd, qs, dstar, dtry, fn, jac, rhs, qn, xi, meff, was_in,
                  ep):  # fmt: skip
    """Modal coordinates ``qn`` at the end of a Newmark step ``h``, the contact forces ``fn``.

    The predictor without contact (with the modal ``load`` added unless it is empty), then the
    contact forces (:func:`implicit_forces`) and their correction.  With restitution set per
    impact (``settings.rest_v``), an episode that starts in the step takes its damping from
    the rate before it (``ep``: the episode table).  Returns whether the contact solve
    converged.  (At most 30 arguments: numba inlines no function with more.)
    """
    model = settings.model
    c2h = 2.0 / h
    c4h = 4.0 / h
    c4h2 = 4.0 / (h * h)
    loaded = load.size > 0
    n = q.size
    for j in range(n):
        phat = -gamma[j] * ag1 + (c4h2 * q[j] + c4h * v[j] + a[j])
        phat += zw2[j] * (c2h * q[j] + v[j])
        if loaded:
            phat += load[j]
        qs[j] = phat * ikhat[j]
    per_impact = settings.rest_v.size > 0
    for c in range(gap.size):
        dstar[c] = rowdot(psi, c, qs) - gap[c]
        if per_impact and dstar[c] > 0.0 and not was_in[c]:
            cd[c], zhd[c], ep[c, outputs.EP_E] = episode_damping(settings, model,
                                                                 settings.relation, xi[c],
                                                                 ddpen[c], beta[c], meff[c],
                                                                 cd[c], zhd[c])  # fmt: skip
    conv = implicit_forces(model, settings.method, dstar, dtry, dpen, ddpen, g, c2h, fc, beta,
                           cd, zhd, fn, jac, rhs)  # fmt: skip
    for j in range(n):
        corr = 0.0
        for c in range(gap.size):
            corr += fn[c] * psi[c, j]
        qn[j] = qs[j] - corr * ikhat[j]
    return conv


@jit(inline=True)
def impact_start(settings, xi, beta, meff, cd, zhd):
    """Episode table, impact-velocity log and peak-force ``e`` of a run (``impact_log``).

    With restitution set per impact (Table 2 at the onset velocity; ``xi`` holds its
    quantile), the damping before the first onset (a step into contact runs with the damping
    it starts with) is the range's at the lowest measured velocity.
    """
    if settings.rest_v.size > 0:
        for c in range(xi.size):
            cd[c], zhd[c], _ = episode_damping(settings, settings.model, settings.relation,
                                               xi[c], settings.rest_v[0], beta[c], meff[c],
                                               cd[c], zhd[c])  # fmt: skip
    return outputs.impact_log(xi.size)


@jit(inline=True)
def newmark_rates(q, v, a, qn, h, vn, an):
    """Velocities ``vn`` and accelerations ``an`` at the end of a Newmark step ``h`` [s]."""
    c2h = 2.0 / h
    c4h = 4.0 / h
    c4h2 = 4.0 / (h * h)
    for j in range(q.size):
        dq = qn[j] - q[j]
        vn[j] = c2h * dq - v[j]
        an[j] = c4h2 * dq - c4h * v[j] - a[j]


@jit(inline=True)
def contact_events(model, relation, method, psi, qe, ve, gap, xi, beta, cd, zhd, was_in, pending,
                   dpen, ddpen, fn, cout, settings, meff, ep, logs, nlog):  # fmt: skip
    """Contact bookkeeping at the end of a step (coordinates ``qe``, velocities ``ve``).

    Opens an episode where a contact closes (its damping set: per impact from the rate at the
    last step point before contact where ``settings.rest_v`` is set), counts it as an impact
    once it is deep enough (its onset velocity logged), keeps the penetrations, the lagged
    force of ``newmark-explicit`` and the deepest penetration.  Returns the count of the
    impact-velocity log ``logs[0]`` (``outputs.log_impact_in``).
    """
    per_impact = settings.rest_v.size > 0
    for c in range(gap.size):
        d1 = rowdot(psi, c, qe) - gap[c]
        dd1 = rowdot(psi, c, ve)
        if d1 > 0.0 and not was_in[c]:
            pending[c] = True  # an episode: an impact once it is deep enough
            ep[c, outputs.EP_V0] = dd1
            if per_impact:
                # the prior-impact velocity: the rate at the last step point before contact
                ep[c, outputs.EP_V0] = ddpen[c]
                cd[c], zhd[c], ep[c, outputs.EP_E] = episode_damping(settings, model, relation,
                                                                     xi[c], ddpen[c], beta[c],
                                                                     meff[c], cd[c],
                                                                     zhd[c])  # fmt: skip
            else:
                zhd[c] = episode_zeta(model, relation, xi[c], dd1, zhd[c])
        if pending[c] and d1 > outputs.IMPACT_MIN_PENETRATION_M:
            cout[c, outputs.C_IMPACTS] += 1.0
            pending[c] = False
            nlog = outputs.log_impact_in(logs, nlog, ep[c, outputs.EP_V0])
            cout[c, outputs.C_MAX_IMPACT_VELOCITY] = max(cout[c, outputs.C_MAX_IMPACT_VELOCITY],
                                                         ep[c, outputs.EP_V0])  # fmt: skip
        was_in[c] = d1 > 0.0
        dpen[c] = d1
        ddpen[c] = dd1
        if method == NEWMARK_EXPLICIT:
            # the force the next (lagged) step uses, from this state
            fn[c] = force(model, d1, dd1, beta[c], cd[c], zhd[c], phase_of(d1, dd1))
        if d1 > cout[c, outputs.C_MAX_PENETRATION]:
            cout[c, outputs.C_MAX_PENETRATION] = d1
    return nlog


@jit(inline=True)
def contact_power(fn, ddpen):
    """Power of the contact forces ``sum_c F_c d_dot_c`` [W]."""
    pc = 0.0
    for c in range(fn.size):
        pc += fn[c] * ddpen[c]
    return pc


@jit(inline=True)
def impulses(h, fc, fn, t1, cout, peak_f, peak_t, ep, peak_e):
    """Add a step's impulses (trapezoidal) and peak forces; returns the peak and its time.

    ``peak_e[0]`` takes the restitution of the episode of the peak force (``ep``).
    """
    for c in range(fn.size):
        cout[c, outputs.C_IMPULSE] += 0.5 * h * (fc[c] + fn[c])
        if fn[c] > cout[c, outputs.C_PEAK_FORCE]:
            cout[c, outputs.C_PEAK_FORCE] = fn[c]
        if fn[c] > peak_f:
            peak_f = fn[c]
            peak_t = t1
            peak_e[0] = ep[c, outputs.EP_E]
    return peak_f, peak_t


@jit(inline=True)
def advance(q, v, a, qn, vn, an, fc, fn):
    """The end of the step becomes its start."""
    for j in range(q.size):
        q[j] = qn[j]
        v[j] = vn[j]
        a[j] = an[j]
    for c in range(fc.size):
        fc[c] = fn[c]


@jit(inline=True)
def diverged(phi, q, peaks):
    """Update the floors' peak displacements; True where one passes the divergence limit."""
    bad = False
    for f in range(peaks.size):
        x = abs(rowdot(phi, f, q))
        if not x < outputs.DIVERGENCE_LIMIT_M:  # also true for NaN
            bad = True
        elif x > peaks[f]:
            peaks[f] = x
    return bad


@jit(inline=True)
def final_contacts(model, dpen, beta):
    """Energy stored in the contacts still closed at the end, and their phase flags."""
    stored_energy = 0.0
    phase = np.zeros(dpen.size, dtype=np.int64)
    for c in range(dpen.size):
        if dpen[c] > 0.0:
            stored_energy += stored(model, dpen[c], beta[c])
            phase[c] = 1
    return stored_energy, phase


@jit(inline=True)
def keep_sample(i, phi, q, dpen, fc, hx, hd, hf):
    """Floor displacements, penetrations and contact forces at record sample ``i``."""
    for f in range(hx.shape[1]):
        hx[i, f] = rowdot(phi, f, q)
    for c in range(hd.shape[1]):
        hd[i, c] = dpen[c]
        hf[i, c] = fc[c]


@jit(llvm_inline=True)
def central_step(
    model, psi, gap, beta, cd, zhd, dpen, fc, fprev, q, qprev, qn, v, gamma, zeta, omega, ag_n,
    pl, h, t1, step, cout, ep, peak_e, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev, peak_f, peak_t,
):  # fmt: skip
    """One central-difference step: ``qn`` (q at n+1) from ``q`` (n) and ``qprev`` (n-1).

    The contact forces at n from the backward-difference velocity, the modal load ``pl`` at n
    (the inelastic kernel's plastic load; none where empty); ``v`` takes the central velocity
    at n, with which the energies are summed (trapezoidal between n-1 and n) and the contacts'
    impulses, peaks and the peak force (at ``t1 - h``) kept.  Returns the energies, the powers
    at n and the peak force and its time.
    """
    nc = gap.size
    for c in range(nc):
        dprev = rowdot(psi, c, qprev) - gap[c]
        vb = (dpen[c] - dprev) / h
        fc[c] = force(model, dpen[c], vb, beta[c], cd[c], zhd[c], phase_of(dpen[c], vb))
    for j in range(q.size):
        p = -gamma[j] * ag_n
        for c in range(nc):
            p -= fc[c] * psi[c, j]
        if pl.size > 0:
            p += pl[j]
        zw = zeta[j] * omega[j] * h
        qn[j] = (h * h * p + (2.0 - omega[j] * omega[j] * h * h) * q[j]
                 - (1.0 - zw) * qprev[j]) / (1.0 + zw)  # fmt: skip
    for j in range(q.size):
        v[j] = (qn[j] - qprev[j]) / (2.0 * h)
    pin1, pd1 = powers(v, ag_n, omega, zeta, gamma)
    pc1 = 0.0
    for c in range(nc):
        pc1 += fc[c] * rowdot(psi, c, v)
    if step > 0:
        e_in, e_d, w_c = trapezoid(h, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev,
                                   pin1, pd1, pc1)  # fmt: skip
        for c in range(nc):
            cout[c, outputs.C_IMPULSE] += 0.5 * h * (fprev[c] + fc[c])
    for c in range(nc):
        fprev[c] = fc[c]
        if fc[c] > cout[c, outputs.C_PEAK_FORCE]:
            cout[c, outputs.C_PEAK_FORCE] = fc[c]
        if fc[c] > peak_f:
            peak_f = fc[c]
            peak_t = t1 - h
            peak_e[0] = ep[c, outputs.EP_E]
    return e_in, e_d, w_c, pin1, pd1, pc1, peak_f, peak_t


@jit(inline=True)
def central_shift(q, qprev, qn, vn, fn, fc, h):
    """Shift a central-difference step: n becomes n-1, n+1 becomes n (``vn``: backward)."""
    for j in range(q.size):
        qprev[j] = q[j]
        q[j] = qn[j]
    for j in range(q.size):
        vn[j] = (q[j] - qprev[j]) / h
    for c in range(fc.size):
        fn[c] = fc[c]


@jit
def fixed(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf,
):  # fmt: skip
    """Run one simulation with a fixed-step method (module docstring).

    ``xi`` holds the damping ratio per contact (the restitution ``e`` for Hertz-damp laws).
    The three schemes share the per-step bookkeeping (contacts, energies, maxima, divergence)
    in one loop whose scalar state stays in locals.
    """
    model = settings.model
    relation = settings.relation
    method = settings.method
    n, nc, nf, npts, m_sub, h, cd = run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q)
    n_steps = (npts - 1) * m_sub
    store = hx.shape[0] > 0
    (a, qn, vn, an, qs, fc, fn, zhd, dpen, ddpen, was_in, pending, jac, rhs, dstar, dtry,
     peaks) = newmark_arrays(n, nc, nf)  # fmt: skip
    qprev = np.empty(n)
    fprev = np.zeros(nc)
    ep, vlog, peak_e = impact_start(settings, xi, beta, meff, cd, zhd)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    no_load = np.zeros(0)
    e0 = mechanical_energy(q, v, omega)
    outputs.reset_contacts(cout)
    ikhat, zw2, g = newmark_matrices(omega, zeta, h, psi)
    # initial contact state and accelerations
    pin_prev, pd_prev, pc_prev = initial_state(model, psi, q, v, gap, beta, cd, zhd, dpen,
                                               ddpen, fc, was_in, ag[0], omega, zeta, gamma,
                                               a)  # fmt: skip
    if method == CENTRAL_DIFFERENCE:
        for j in range(n):
            qprev[j] = q[j] - h * v[j] + 0.5 * h * h * a[j]
    e_in = e_d = w_c = 0.0  # input, damping and contact work
    peak_f = peak_t = 0.0
    status = outputs.STATUS_OK
    steps = 0
    inv_m = 1.0 / m_sub
    for step in range(n_steps):
        i, k = divmod(step, m_sub)  # record interval, sub-step in it
        if store and k == 0:
            keep_sample(i, phi, q, dpen, fc, hx, hd, hf)
        t1 = (step + 1) * h
        ag1 = ag[i] + (ag[i + 1] - ag[i]) * ((k + 1) * inv_m)
        steps += 1
        if method == CENTRAL_DIFFERENCE:
            ag_n = ag[i] + (ag[i + 1] - ag[i]) * (k * inv_m)
            (e_in, e_d, w_c, pin_prev, pd_prev, pc_prev, peak_f,
             peak_t) = central_step(model, psi, gap, beta, cd, zhd, dpen, fc, fprev, q, qprev, qn,
                                    v, gamma, zeta, omega, ag_n, no_load, h, t1, step, cout, ep,
                                    peak_e, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev, peak_f,
                                    peak_t)  # fmt: skip
            central_shift(q, qprev, qn, vn, fn, fc, h)
        else:
            # Newmark average acceleration, modal predictor without contact at n+1
            if not newmark_solve(settings, q, v, a, ag1, gamma, zw2, ikhat, h, no_load, psi,
                                 gap, g, dpen, ddpen, fc, beta, cd, zhd, qs, dstar, dtry, fn,
                                 jac, rhs, qn, xi, meff, was_in, ep):  # fmt: skip
                status = outputs.STATUS_NOT_CONVERGED
            newmark_rates(q, v, a, qn, h, vn, an)
        # contact bookkeeping at n+1
        nlog = contact_events(model, relation, method, psi,
                                    qn if method != CENTRAL_DIFFERENCE else q, vn, gap, xi, beta,
                                    cd, zhd, was_in, pending, dpen, ddpen, fn, cout, settings,
                                    meff, ep, logs, nlog)  # fmt: skip
        if method != CENTRAL_DIFFERENCE:
            # energies (trapezoidal); contact work with the force acting over the step
            pin1, pd1 = powers(vn, ag1, omega, zeta, gamma)
            pc1 = contact_power(fn, ddpen)
            e_in, e_d, w_c = trapezoid(h, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev,
                                       pin1, pd1, pc1)  # fmt: skip
            peak_f, peak_t = impulses(h, fc, fn, t1, cout, peak_f, peak_t, ep, peak_e)
            pin_prev, pd_prev, pc_prev = pin1, pd1, pc1
            advance(q, v, a, qn, vn, an, fc, fn)
        else:
            for c in range(nc):
                fc[c] = fn[c]
        if diverged(phi, q, peaks):
            status = outputs.STATUS_UNSTABLE
            break
    if store and status != outputs.STATUS_UNSTABLE:
        keep_sample(npts - 1, phi, q, dpen, fc, hx, hd, hf)
    if method == CENTRAL_DIFFERENCE:
        # energies were integrated up to the last step n with its central velocity
        for j in range(n):
            q[j] = qprev[j]
        for c in range(nc):
            dpen[c] = rowdot(psi, c, q) - gap[c]
    stored_energy, phase = final_contacts(model, dpen, beta)
    outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d, w_c, stored_energy,
                   peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
