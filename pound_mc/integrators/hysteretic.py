"""``newmark`` with yielding storeys: bilinear buildings on the general modal model.

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
step is implicit in the storey forces as in the contact.  A step in which no storey yields
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
from pound_mc.integrators.fixed import NEWMARK_EXPLICIT, _implicit_forces
from pound_mc.integrators.laws import episode_zeta, force, phase_of, stored
from pound_mc.integrators.outputs import (
    C_IMPACTS,
    C_IMPULSE,
    C_MAX_PENETRATION,
    C_PEAK_FORCE,
    DIVERGENCE_LIMIT_M,
    HYSTERETIC_ENERGY,
    IMPACT_MIN_PENETRATION_M,
    PEAK_DRIFT_LEFT,
    PEAK_DUCTILITY_LEFT,
    PEAK_FLOOR_ACCEL_LEFT,
    PEAK_FLOOR_ACCEL_RIGHT,
    RESIDUAL_DRIFT_LEFT,
    STATUS,
    STATUS_NOT_CONVERGED,
    STATUS_OK,
    STATUS_UNSTABLE,
    finish,
    reset_contacts,
)
from pound_mc.integrators.toolkit import (
    accel,
    mechanical_energy,
    powers,
    rowdot,
    run_sizes,
    trapezoid,
)

#: Columns of the storey table a run takes (one row per storey of both buildings).
S_K, S_YIELD, S_ALPHA, S_HEIGHT, S_SIDE = range(5)
N_STOREY_COLUMNS = 5
#: The plastic drifts' fixed point is reached when they change by less than this fraction of
#: the yield drift.
PLASTIC_TOLERANCE = 1e-12
#: Most fixed-point iterations of the plastic load in one step.
MAX_PLASTIC_ITERATIONS = 50


@jit(inline=True)
def return_map(drift, store, up_n, up):
    """Plastic drifts ``up`` at the end of a step from the drifts and those at its start.

    Returns the largest change from the previous ``up`` relative to the yield drift (the fixed
    point's residual).
    """
    change = 0.0
    for s in range(drift.size):
        uy = store[s, S_YIELD]
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
def _nanmax(a, b):
    """The larger of ``a`` and ``b``, ``b`` where ``a`` is NaN."""
    return a if a >= b else b


@jit
def storey_outputs(out, store, peak_u, drift, peak_acc, side_f, e_h):
    """Fill the inelastic output slots: ductility, drift ratios, floor accelerations, energy.

    Ductility is NaN for a building that cannot yield, drift ratios for one without heights;
    every slot is NaN for a run that is not ok.
    """
    if out[STATUS] != STATUS_OK:
        for k in range(PEAK_DUCTILITY_LEFT, PEAK_FLOOR_ACCEL_RIGHT + 1):
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
        out[PEAK_DUCTILITY_LEFT + b] = duct
        out[PEAK_DRIFT_LEFT + b] = pdr
        out[RESIDUAL_DRIFT_LEFT + b] = rdr
        out[PEAK_FLOOR_ACCEL_LEFT + b] = acc
    out[HYSTERETIC_ENERGY] = e_h


@jit
def newmark_hysteretic(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, dmat, store,
):  # fmt: skip
    """``newmark`` / ``newmark-explicit`` with bilinear storeys (module docstring).

    ``dmat``: drift rows of the storeys in modal coordinates (storeys x modes); ``store``: the
    storey table (columns ``S_*``: stiffness [N/m], yield drift [m] (inf: elastic), post-yield
    ratio, height [m] (NaN: none), building 0 left / 1 right).  Longer than 150 lines because it
    is the Newmark loop of :func:`~pound_mc.integrators.fixed.fixed` (same arithmetic, so that
    storeys that never yield give its results bitwise) with the plastic fixed point inside.
    """
    model = settings.model
    relation = settings.relation
    method = settings.method
    n, nc, nf, npts, m_sub, h, cd = run_sizes(ag, dt_rec, phi, gap, meff, beta, xi, settings, q)
    ns = store.shape[0]
    n_steps = (npts - 1) * m_sub
    a = np.empty(n)
    qn = np.empty(n)
    vn = np.empty(n)
    an = np.empty(n)
    qs = np.empty(n)
    khat = np.empty(n)
    fc = np.zeros(nc)
    fn = np.zeros(nc)
    zhd = np.zeros(nc)
    dpen = np.zeros(nc)
    ddpen = np.zeros(nc)
    was_in = np.zeros(nc, dtype=np.bool_)
    pending = np.zeros(nc, dtype=np.bool_)
    g = np.zeros((nc, nc))
    jac = np.zeros((nc, nc))
    rhs = np.zeros(nc)
    dstar = np.zeros(nc)
    dtry = np.zeros(nc)
    peaks = np.zeros(nf)
    up_n = np.zeros(ns)
    up = np.zeros(ns)
    drift = np.empty(ns)
    peak_u = np.zeros(ns)
    pl = np.zeros(n)
    peak_acc = np.zeros(nf)
    e0 = mechanical_energy(q, v, omega)
    reset_contacts(cout)
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
    for c in range(nc):
        dpen[c] = rowdot(psi, c, q) - gap[c]
        ddpen[c] = rowdot(psi, c, v)
        fc[c] = force(model, dpen[c], ddpen[c], beta[c], cd[c], zhd[c],
                      phase_of(dpen[c], ddpen[c]))  # fmt: skip
        was_in[c] = dpen[c] > 0.0
    accel(q, v, ag[0], omega, zeta, gamma, psi, fc, a)
    e_in = 0.0
    e_d = 0.0
    w_c = 0.0
    w_p = 0.0  # work of the plastic load
    e_h = 0.0  # hysteretic dissipation
    peak_f = 0.0
    peak_t = 0.0
    status = STATUS_OK
    pin_prev, pd_prev = powers(v, ag[0], omega, zeta, gamma)
    pc_prev = 0.0
    for c in range(nc):
        pc_prev += fc[c] * ddpen[c]
    pp_prev = 0.0
    steps = 0
    inv_m = 1.0 / m_sub
    i = 0
    k = -1
    for step in range(n_steps):
        k += 1
        if k == m_sub:
            k = 0
            i += 1
        t1 = (step + 1) * h
        ag1 = ag[i] + (ag[i + 1] - ag[i]) * ((k + 1) * inv_m)
        steps += 1
        for s in range(ns):
            up[s] = up_n[s]
        for _it in range(MAX_PLASTIC_ITERATIONS + 1):
            plastic_load(dmat, store, up, pl)
            for j in range(n):
                phat = -gamma[j] * ag1 + (c4h2 * q[j] + c4h * v[j] + a[j])
                phat += zw2[j] * (c2h * q[j] + v[j])
                phat += pl[j]
                qs[j] = phat * ikhat[j]
            for c in range(nc):
                dstar[c] = rowdot(psi, c, qs) - gap[c]
            conv = _implicit_forces(model, method, dstar, dtry, dpen, ddpen, g, c2h, fc, beta,
                                    cd, zhd, fn, jac, rhs)  # fmt: skip
            for j in range(n):
                corr = 0.0
                for c in range(nc):
                    corr += fn[c] * psi[c, j]
                qn[j] = qs[j] - corr * ikhat[j]
            for s in range(ns):
                drift[s] = rowdot(dmat, s, qn)
            if return_map(drift, store, up_n, up) <= PLASTIC_TOLERANCE:
                break
            if _it == MAX_PLASTIC_ITERATIONS:
                status = STATUS_NOT_CONVERGED
        if not conv:
            status = STATUS_NOT_CONVERGED
        for j in range(n):
            dq = qn[j] - q[j]
            vn[j] = c2h * dq - v[j]
            an[j] = c4h2 * dq - c4h * v[j] - a[j]
        for s in range(ns):
            z = drift[s] - up[s]
            e_h += (1.0 - store[s, S_ALPHA]) * store[s, S_K] * z * (up[s] - up_n[s])
            up_n[s] = up[s]
            if abs(drift[s]) > peak_u[s]:
                peak_u[s] = abs(drift[s])
        for f in range(nf):
            xa = abs(rowdot(phi, f, an) + ag1)
            if xa > peak_acc[f]:
                peak_acc[f] = xa
        for c in range(nc):
            d1 = rowdot(psi, c, qn) - gap[c]
            dd1 = rowdot(psi, c, vn)
            if d1 > 0.0 and not was_in[c]:
                pending[c] = True
                zhd[c] = episode_zeta(model, relation, xi[c], dd1, zhd[c])
            if pending[c] and d1 > IMPACT_MIN_PENETRATION_M:
                cout[c, C_IMPACTS] += 1.0
                pending[c] = False
            was_in[c] = d1 > 0.0
            dpen[c] = d1
            ddpen[c] = dd1
            if method == NEWMARK_EXPLICIT:
                fn[c] = force(model, d1, dd1, beta[c], cd[c], zhd[c], phase_of(d1, dd1))
            if d1 > cout[c, C_MAX_PENETRATION]:
                cout[c, C_MAX_PENETRATION] = d1
        pin1, pd1 = powers(vn, ag1, omega, zeta, gamma)
        pc1 = 0.0
        for c in range(nc):
            pc1 += fn[c] * ddpen[c]
        pp1 = 0.0
        for j in range(n):
            pp1 += pl[j] * vn[j]
        e_in, e_d, w_c = trapezoid(h, e_in, e_d, w_c, pin_prev, pd_prev, pc_prev,
                                   pin1, pd1, pc1)  # fmt: skip
        w_p += 0.5 * h * (pp_prev + pp1)
        for c in range(nc):
            cout[c, C_IMPULSE] += 0.5 * h * (fc[c] + fn[c])
            if fn[c] > cout[c, C_PEAK_FORCE]:
                cout[c, C_PEAK_FORCE] = fn[c]
            if fn[c] > peak_f:
                peak_f = fn[c]
                peak_t = t1
        pin_prev, pd_prev, pc_prev, pp_prev = pin1, pd1, pc1, pp1
        for j in range(n):
            q[j] = qn[j]
            v[j] = vn[j]
            a[j] = an[j]
        for c in range(nc):
            fc[c] = fn[c]
        bad = False
        for f in range(nf):
            x = abs(rowdot(phi, f, q))
            if not x < DIVERGENCE_LIMIT_M:
                bad = True
            elif x > peaks[f]:
                peaks[f] = x
        if bad:
            status = STATUS_UNSTABLE
            break
    stored_energy = 0.0
    phase = np.zeros(nc, dtype=np.int64)
    for c in range(nc):
        if dpen[c] > 0.0:
            stored_energy += stored(model, dpen[c], beta[c])
            phase[c] = 1
    # the plastic load's work enters the balance as a negative damping work
    finish(out, cout, peaks, side, phase, q, v, omega, e0, e_in, e_d - w_p, w_c, stored_energy,
           peak_f, peak_t, steps, status)  # fmt: skip
    storey_outputs(out, store, peak_u, drift, peak_acc, side, e_h)
