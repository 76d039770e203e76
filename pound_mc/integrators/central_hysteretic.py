"""``central-difference`` with yielding storeys: bilinear and Bouc-Wen buildings.

The storeys enter the modal equations of the initial elastic building as the plastic load of
:mod:`pound_mc.integrators.hysteretic` (``sum_s D_s (1 - alpha_s) k_s u_p,s``).  The scheme
is explicit: every force of step ``n`` is known from the state at ``n``, so the plastic drifts
at ``n`` come from the drifts at ``n`` by one return map from those at ``n - 1`` (bilinear) or
by the Bouc-Wen law integrated along the drift increment (:func:`~pound_mc.integrators.
hysteretic.bouc_wen`), with no fixed point; the step itself is the elastic kernel's
(:func:`~pound_mc.integrators.fixed.central_step`, the plastic load added), so that storeys
that never yield give its results bitwise.  The same stability limit holds (``h < 2 / omega``
of the highest mode, and the contact's); the plastic branches only soften the storeys.

Energy: the plastic load's work (trapezoidal over the central velocities, as the input and
damping work) enters the balance as a negative damping work; the hysteretic dissipation is
summed per step as in the ``newmark`` kernel.
"""

from __future__ import annotations

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.fixed import (
    central_shift,
    central_step,
    contact_events,
    diverged,
    final_contacts,
    impact_start,
    initial_state,
    keep_sample,
    newmark_arrays,
)
from pound_mc.integrators.hysteretic import (
    plastic_load,
    return_map,
    settle_storeys,
    storey_outputs,
)
from pound_mc.integrators.toolkit import mechanical_energy, rowdot, run_sizes

__all__ = ["central_hysteretic"]


@jit(inline=True)
def _storeys_at(dmat, store, q, drift, drift_o, up, up_o, peak_u, e_h):
    """The storeys at step ``n``: drifts, plastic drifts from ``n - 1``, peaks, dissipation.

    ``drift_o, up_o``: drifts and plastic drifts at ``n - 1`` (then shifted to ``n``).
    Returns the hysteretic dissipation so far [J].
    """
    for s in range(drift.size):
        drift[s] = rowdot(dmat, s, q)
    return_map(drift, store, up_o, up, drift_o)
    return settle_storeys(store, drift, drift_o, up, up_o, peak_u, e_h)


@jit
def central_hysteretic(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """``central-difference`` with bilinear or Bouc-Wen storeys (module docstring).

    Arguments and outputs as :func:`~pound_mc.integrators.hysteretic.newmark_hysteretic`.
    """
    model = settings.model
    relation = settings.relation
    method = settings.method
    n, nc, nf, npts, m_sub, h, cd = run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q)
    ns = store.shape[0]
    n_steps = (npts - 1) * m_sub
    keep = hx.shape[0] > 0
    (a, qn, vn, an, qs, fc, fn, zhd, dpen, ddpen, was_in, pending, jac, rhs, dstar, dtry,
     peaks) = newmark_arrays(n, nc, nf)  # fmt: skip
    qprev = np.empty(n)
    fprev = np.zeros(nc)
    up_o = np.zeros(ns)  # plastic drifts at n - 1
    up = np.zeros(ns)  # and at n
    drift = np.empty(ns)
    drift_o = np.empty(ns)
    for s in range(ns):
        drift_o[s] = rowdot(dmat, s, q)
    peak_u = np.zeros(ns)
    pl = np.zeros(n)
    peak_acc = np.zeros(nf)
    e0 = mechanical_energy(q, v, omega)
    outputs.reset_contacts(cout)
    ep, vlog, peak_e = impact_start(settings, xi, beta, meff, cd, zhd)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    pin_prev, pd_prev, pc_prev = initial_state(model, psi, q, v, gap, beta, cd, zhd, dpen,
                                               ddpen, fc, was_in, ag[0], omega, zeta, gamma,
                                               a)  # fmt: skip
    for j in range(n):
        qprev[j] = q[j] - h * v[j] + 0.5 * h * h * a[j]
    e_in = e_d = w_c = 0.0  # input, damping and contact work
    w_p = pp_prev = 0.0  # work of the plastic load, its power at n - 1
    e_h = 0.0  # hysteretic dissipation
    peak_f = peak_t = 0.0
    status = outputs.STATUS_OK
    steps = 0
    inv_m = 1.0 / m_sub
    inv_h2 = 1.0 / (h * h)
    for step in range(n_steps):
        i, k = divmod(step, m_sub)  # record interval, sub-step in it
        if keep and k == 0:
            keep_sample(i, phi, q, dpen, fc, hx, hd, hf)
        t1 = (step + 1) * h
        ag_n = ag[i] + (ag[i + 1] - ag[i]) * (k * inv_m)
        steps += 1
        e_h = _storeys_at(dmat, store, q, drift, drift_o, up, up_o, peak_u, e_h)
        plastic_load(dmat, store, up, pl)
        (e_in, e_d, w_c, pin_prev, pd_prev, pc_prev, peak_f,
         peak_t) = central_step(model, psi, gap, beta, cd, zhd, dpen, fc, fprev, q, qprev, qn, v,
                                gamma, zeta, omega, ag_n, pl, h, t1, step, cout, ep, peak_e, e_in,
                                e_d, w_c, pin_prev, pd_prev, pc_prev, peak_f, peak_t)  # fmt: skip
        pp1 = 0.0
        for j in range(n):
            pp1 += pl[j] * v[j]
        if step > 0:
            w_p += 0.5 * h * (pp_prev + pp1)
        pp_prev = pp1
        for f in range(nf):  # the floors' absolute accelerations at n
            acc = ag_n
            for j in range(n):
                acc += phi[f, j] * (qn[j] - 2.0 * q[j] + qprev[j]) * inv_h2
            if abs(acc) > peak_acc[f]:
                peak_acc[f] = abs(acc)
        central_shift(q, qprev, qn, vn, fn, fc, h)
        nlog = contact_events(model, relation, method, psi, q, vn, gap, xi, beta, cd, zhd,
                              was_in, pending, dpen, ddpen, fn, cout, settings, meff, ep, logs,
                              nlog)  # fmt: skip
        for c in range(nc):
            fc[c] = fn[c]
        if diverged(phi, q, peaks):
            status = outputs.STATUS_UNSTABLE
            break
    if keep and status != outputs.STATUS_UNSTABLE:
        keep_sample(npts - 1, phi, q, dpen, fc, hx, hd, hf)
    # the energies and the storeys were summed up to the last step n with its central velocity
    for j in range(n):
        q[j] = qprev[j]
    for c in range(nc):
        dpen[c] = rowdot(psi, c, q) - gap[c]
    stored_energy, phase = final_contacts(model, dpen, beta)
    # the plastic load's work enters the balance as a negative damping work
    outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d - w_p, w_c,
                   stored_energy, peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
    storey_outputs(out, store, peak_u, drift, peak_acc, side, e_h, sout)
