"""``newmark`` with yielding storeys: bilinear and Bouc-Wen buildings on the general modal model.

A bilinear storey ``s`` (kinematic hardening, ``../shared/DESIGN.md`` section 9) resists its
drift ``u_s`` with ``alpha k u + (1 - alpha) k z``, ``z = u - u_p`` elastic-perfectly-plastic
(``|z| <= u_y``).  Written as the elastic force ``k u`` less ``(1 - alpha) k u_p``, the plastic
drifts ``u_p`` enter the modal equations of the *initial elastic* building as a load,

``q'' + 2 zeta omega q' + omega^2 q = -gamma a_g - sum_c F_c psi_c + sum_s D_s f_s``,
``f_s = (1 - alpha_s) k_s u_p,s``,

with ``D_s`` the storey's drift row in modal coordinates (``u = D q``).  Each step is the
average-acceleration Newmark step of :func:`pound_mc.integrators.fixed.fixed` (contact solved
implicitly) with the plastic drifts at the end of the step found by return mapping
(``z_trial = u - u_p,n``; beyond ``u_y`` the excess flows plastically); the plastic load is
iterated to a fixed point (contraction ``(1 - alpha) k h^2 / 4 m``, a few 1e-4 at 1 ms), so the
step is implicit in the storey forces as in the contact.  A Bouc-Wen storey has the same
force with ``z`` smooth; its ``z`` at the end of a step is integrated along the step's drift
increment (the drift taken linear in the step; :func:`bouc_wen`) inside the same fixed point,
so ``u_p = u - z`` enters the same plastic load.  A step in which no storey yields
adds a zero load: with yield drifts never reached the results are bitwise those of the
elastic kernel.

Energy: the work of the plastic load less the storeys' recoverable energy is the hysteretic
dissipation; it is summed exactly per step (``(1 - alpha) k z du_p``) and the balance closes
with it.
"""

from __future__ import annotations

import math

import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators import outputs
from pound_mc.integrators.fixed import (
    advance,
    contact_events,
    contact_power,
    diverged,
    final_contacts,
    impact_start,
    impulses,
    initial_state,
    keep_sample,
    newmark_arrays,
    newmark_matrices,
    newmark_rates,
    newmark_solve,
)
from pound_mc.integrators.toolkit import (
    mechanical_energy,
    powers,
    rowdot,
    run_sizes,
    trapezoid,
)

#: Columns of the storey table a run takes (one row per storey of both buildings).
S_K, S_YIELD, S_ALPHA, S_HEIGHT, S_SIDE, S_BW = range(6)
N_STOREY_COLUMNS = 6
#: RK4 sub-steps of the Bouc-Wen law per ``u_y / n`` of drift increment (at least one):
#: relative error about 1e-8 for an increment of ``u_y / 2`` (n = 2), far less at 1 ms steps.
BW_SUBSTEPS_PER_SCALE = 16.0
#: The plastic drifts' fixed point is reached when they change by less than this fraction of
#: the yield drift.
PLASTIC_TOLERANCE = 1e-12
#: Most fixed-point iterations of the plastic load in one step.
MAX_PLASTIC_ITERATIONS = 50


@jit
def bouc_wen(z, du, uy, n):
    """Bouc-Wen ``z`` [m] after a drift increment ``du`` [m] from ``z`` (linear drift path).

    ``dz/du = 1 - |z / u_y|^n (0.5 sign(du z) + 0.5)``: elastic (``dz = du``) while the drift
    moves ``z`` towards 0, then ``dw/d|du| = 1 - (w / u_y)^n`` in ``w = sign(du) z >= 0``,
    integrated by classical RK4 in sub-steps of at most ``u_y / (16 n)``
    (:data:`BW_SUBSTEPS_PER_SCALE`; one sub-step at the increments of a 1 ms step).
    """
    if du == 0.0:
        return z
    sgn = 1.0 if du > 0.0 else -1.0
    rest = abs(du)
    w = sgn * z
    if w < 0.0:  # unloading towards z = 0: elastic
        if rest <= -w:
            return z + du
        rest += w
        w = 0.0
    m = int(math.ceil(rest * n * BW_SUBSTEPS_PER_SCALE / uy))
    m = max(m, 1)
    hh = rest / m
    for _ in range(m):
        k1 = 1.0 - (w / uy) ** n
        k2 = 1.0 - (abs(w + 0.5 * hh * k1) / uy) ** n
        k3 = 1.0 - (abs(w + 0.5 * hh * k2) / uy) ** n
        k4 = 1.0 - (abs(w + hh * k3) / uy) ** n
        w += hh * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
    return sgn * w


@jit(inline=True)
def return_map(drift, store, up_n, up, drift_n):
    """Plastic drifts ``up`` at the end of a step from the drifts and those at its start.

    Bilinear storeys by return mapping, Bouc-Wen storeys (``S_BW > 0``) by
    :func:`bouc_wen` over the drift increment from ``drift_n``.  Returns the largest change
    from the previous ``up`` relative to the yield drift (the fixed point's residual).
    """
    change = 0.0
    for s in range(drift.size):
        uy = store[s, S_YIELD]
        if store[s, S_BW] > 0.0:
            z = bouc_wen(drift_n[s] - up_n[s], drift[s] - drift_n[s], uy, store[s, S_BW])
            new = drift[s] - z
        else:
            z = drift[s] - up_n[s]
            new = up_n[s]
            if z > uy:
                new = drift[s] - uy
            elif z < -uy:
                new = drift[s] + uy
        change = max(change, abs(new - up[s]) / uy)
        up[s] = new
    return change


@jit(inline=True)
def plastic_load(dmat, store, up, pl):
    """Modal load of the plastic drifts ``sum_s D_s (1 - alpha_s) k_s u_p,s`` into ``pl``."""
    for j in range(pl.size):
        pl[j] = 0.0
    for s in range(up.size):
        if up[s] != 0.0:
            fs = (1.0 - store[s, S_ALPHA]) * store[s, S_K] * up[s]
            for j in range(pl.size):
                pl[j] += dmat[s, j] * fs


@jit(inline=True)
def settle_storeys(store, drift, drift_n, up, up_n, peak_u, e_h):
    """A step's end for the storeys: dissipation, peaks, and the end taken as the next start.

    ``drift, up``: the drifts and plastic drifts at the step's end, ``drift_n, up_n`` at its
    start (set to the end here); ``peak_u``: each storey's peak |drift|.  Returns the
    hysteretic dissipation so far [J] (``(1 - alpha) k z du_p`` a step; Bouc-Wen: ``z`` by the
    trapezoid, as it varies over the step).
    """
    for s in range(drift.size):
        z = drift[s] - up[s]
        if store[s, S_BW] > 0.0:  # z varies over the step: trapezoid in the plastic drift
            z = 0.5 * (z + drift_n[s] - up_n[s])
        if up[s] != up_n[s]:  # a wall's storey (k infinite) never yields: no inf * 0
            e_h += (1.0 - store[s, S_ALPHA]) * store[s, S_K] * z * (up[s] - up_n[s])
        up_n[s] = up[s]
        drift_n[s] = drift[s]
        if abs(drift[s]) > peak_u[s]:
            peak_u[s] = abs(drift[s])
    return e_h


@jit(inline=True)
def _nanmax(a, b):
    """The larger of ``a`` and ``b``, ``b`` where ``a`` is NaN."""
    return a if a >= b else b


@jit
def storey_outputs(out, store, peak_u, drift, peak_acc, side_f, e_h, sout):
    """Fill the inelastic output slots: ductility, drift ratios, floor accelerations, energy.

    Ductility is NaN for a building that cannot yield, drift ratios for one without heights;
    every slot is NaN for a run that is not ok.  ``sout`` (storeys x 2, or no rows) takes each
    storey's peak |drift| and its drift at the end of the run [m].
    """
    ok = out[outputs.STATUS] == outputs.STATUS_OK
    for s in range(sout.shape[0]):
        sout[s, 0] = peak_u[s] if ok else np.nan
        sout[s, 1] = drift[s] if ok else np.nan
    if not ok:
        for k in range(outputs.PEAK_DUCTILITY_LEFT, outputs.PEAK_FLOOR_ACCEL_RIGHT + 1):
            out[k] = np.nan
        return
    for b in range(2):
        duct = np.nan
        pdr = np.nan
        rdr = np.nan
        for s in range(drift.size):
            if int(store[s, S_SIDE]) != b:
                continue
            uy = store[s, S_YIELD]
            hs = store[s, S_HEIGHT]
            if math.isfinite(uy):
                duct = _nanmax(duct, peak_u[s] / uy)
            pdr = _nanmax(pdr, peak_u[s] / hs)
            rdr = _nanmax(rdr, abs(drift[s]) / hs)
        acc = 0.0
        for f in range(side_f.size):
            if side_f[f] == b and peak_acc[f] > acc:
                acc = peak_acc[f]
        out[outputs.PEAK_DUCTILITY_LEFT + b] = duct
        out[outputs.PEAK_DRIFT_LEFT + b] = pdr
        out[outputs.RESIDUAL_DRIFT_LEFT + b] = rdr
        out[outputs.PEAK_FLOOR_ACCEL_LEFT + b] = acc
    out[outputs.HYSTERETIC_ENERGY] = e_h


@jit
def newmark_hysteretic(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """``newmark`` / ``newmark-explicit`` with bilinear or Bouc-Wen storeys (module docstring).

    ``hx, hd, hf``: floor displacements, penetrations and contact forces at the record's
    samples, as :func:`~pound_mc.integrators.fixed.fixed` keeps them (empty arrays: none).

    ``dmat``: drift rows of the storeys in modal coordinates (storeys x modes); ``store``: the
    storey table (columns ``S_*``: stiffness [N/m], yield drift [m] (inf: elastic), post-yield
    ratio, height [m] (NaN: none), building 0 left / 1 right, Bouc-Wen exponent (0: bilinear));
    ``sout``: the storeys' peak
    and final drifts (:func:`storey_outputs`).  The step is made of the Newmark
    pieces of :mod:`pound_mc.integrators.fixed` (same arithmetic, so that storeys that never
    yield give its results bitwise) with the plastic fixed point around them.
    """
    model = settings.model
    relation = settings.relation
    method = settings.method
    n, nc, nf, npts, m_sub, h, cd = run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q)
    ns = store.shape[0]
    n_steps = (npts - 1) * m_sub
    (a, qn, vn, an, qs, fc, fn, zhd, dpen, ddpen, was_in, pending, jac, rhs, dstar, dtry,
     peaks) = newmark_arrays(n, nc, nf)  # fmt: skip
    up_n = np.zeros(ns)
    up = np.zeros(ns)
    drift = np.empty(ns)
    drift_n = np.empty(ns)  # drifts at the start of the step (Bouc-Wen storeys)
    for s in range(ns):
        drift_n[s] = rowdot(dmat, s, q)
    peak_u = np.zeros(ns)
    pl = np.zeros(n)
    peak_acc = np.zeros(nf)
    e0 = mechanical_energy(q, v, omega)
    outputs.reset_contacts(cout)
    ikhat, zw2, g = newmark_matrices(omega, zeta, h, psi)
    ep, vlog, peak_e = impact_start(settings, xi, beta, meff, cd, zhd)
    logs = [vlog]  # never reassigned in the loop (outputs.log_impact_in)
    nlog = 0
    pin_prev, pd_prev, pc_prev = initial_state(model, psi, q, v, gap, beta, cd, zhd, dpen,
                                               ddpen, fc, was_in, ag[0], omega, zeta, gamma,
                                               a)  # fmt: skip
    e_in = e_d = w_c = 0.0  # input, damping and contact work
    w_p = 0.0  # work of the plastic load
    e_h = 0.0  # hysteretic dissipation
    peak_f = peak_t = 0.0
    status = outputs.STATUS_OK
    pp_prev = 0.0
    steps = 0
    inv_m = 1.0 / m_sub
    keep = hx.shape[0] > 0
    for step in range(n_steps):
        i, k = divmod(step, m_sub)  # record interval, sub-step in it
        if keep and k == 0:
            keep_sample(i, phi, q, dpen, fc, hx, hd, hf)
        t1 = (step + 1) * h
        ag1 = ag[i] + (ag[i + 1] - ag[i]) * ((k + 1) * inv_m)
        steps += 1
        for s in range(ns):
            up[s] = up_n[s]
        for _it in range(MAX_PLASTIC_ITERATIONS + 1):
            plastic_load(dmat, store, up, pl)
            conv = newmark_solve(settings, q, v, a, ag1, gamma, zw2, ikhat, h, pl, psi, gap, g,
                                 dpen, ddpen, fc, beta, cd, zhd, qs, dstar, dtry, fn, jac, rhs,
                                 qn, xi, meff, was_in, ep)  # fmt: skip
            for s in range(ns):
                drift[s] = rowdot(dmat, s, qn)
            if return_map(drift, store, up_n, up, drift_n) <= PLASTIC_TOLERANCE:
                break
            if _it == MAX_PLASTIC_ITERATIONS:
                status = outputs.STATUS_NOT_CONVERGED
        if not conv:
            status = outputs.STATUS_NOT_CONVERGED
        newmark_rates(q, v, a, qn, h, vn, an)
        e_h = settle_storeys(store, drift, drift_n, up, up_n, peak_u, e_h)
        for f in range(nf):
            xa = abs(rowdot(phi, f, an) + ag1)
            if xa > peak_acc[f]:
                peak_acc[f] = xa
        nlog = contact_events(model, relation, method, psi, qn, vn, gap, xi, beta, cd,
                                    zhd, was_in, pending, dpen, ddpen, fn, cout, settings, meff,
                                    ep, logs, nlog)  # fmt: skip
        pin1, pd1 = powers(vn, ag1, omega, zeta, gamma)
        pc1 = contact_power(fn, ddpen)
        pp1 = 0.0
        for j in range(n):
            pp1 += pl[j] * vn[j]
        e_in, e_d, w_c = trapezoid(h, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev,
                                   pin1, pd1, pc1)  # fmt: skip
        w_p += 0.5 * h * (pp_prev + pp1)
        peak_f, peak_t = impulses(h, fc, fn, t1, cout, peak_f, peak_t, ep, peak_e)
        pin_prev, pd_prev, pc_prev, pp_prev = pin1, pd1, pc1, pp1
        advance(q, v, a, qn, vn, an, fc, fn)
        if diverged(phi, q, peaks):
            status = outputs.STATUS_UNSTABLE
            break
    if keep and status != outputs.STATUS_UNSTABLE:
        keep_sample(npts - 1, phi, q, dpen, fc, hx, hd, hf)
    stored_energy, phase = final_contacts(model, dpen, beta)
    # the plastic load's work enters the balance as a negative damping work
    outputs.finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d - w_p, w_c,
                   stored_energy, peak_f, peak_t, steps, status)  # fmt: skip
    outputs.finish_impacts(out, cout, logs[0], nlog, peak_e[0])
    storey_outputs(out, store, peak_u, drift, peak_acc, side, e_h, sout)
