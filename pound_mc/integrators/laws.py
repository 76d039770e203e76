"""Kernel side of the contact laws: the declared laws dispatched by their kernel code.

Each law is declared once, in :data:`pound_mc.physics.contact.CONTACT_MODELS` (parameters,
relations, public force and the compiled functions of :class:`~pound_mc.physics.contact.KernelLaw`);
this module numbers the laws and relations for the kernels and routes a kernel's call to the
declared function.  The codes are private to :mod:`pound_mc.integrators`: everything above it
passes names.
"""

from __future__ import annotations

import math

from pound_mc._jit import jit
from pound_mc.integrators.toolkit import hermite_max, rowdot
from pound_mc.physics.contact import CONTACT_MODELS
from pound_mc.physics.relations import HERTZDAMP_RELATIONS

#: Kernel codes of the contact laws (their order in the registry).
LAW_CODES = {name: code for code, name in enumerate(CONTACT_MODELS)}
#: Kernel codes of each law's damping relations (their order in the law's declaration; laws
#: without damping run with code 0).
RELATION_CODES = {
    name: {rel: code for code, rel in enumerate(law.relations)}
    for name, law in CONTACT_MODELS.items()
}

_JANKOWSKI = LAW_CODES["jankowski"]
_LINEAR = LAW_CODES["linear"]
_KELVIN = LAW_CODES["kelvin"]
_HERTZ = LAW_CODES["hertz"]
_HERTZDAMP = LAW_CODES["hertzdamp"]
_YE2009 = RELATION_CODES["hertzdamp"]["ye2009"]
_MUTHUKUMAR2006 = RELATION_CODES["hertzdamp"]["muthukumar2006"]

_J = CONTACT_MODELS["jankowski"].kernel
_L = CONTACT_MODELS["linear"].kernel
_K = CONTACT_MODELS["kelvin"].kernel
_H = CONTACT_MODELS["hertz"].kernel
_HD = CONTACT_MODELS["hertzdamp"].kernel
# module-level names: numba freezes globals at compile time
_j_force, _l_force, _k_force, _h_force, _hd_force = (
    _J.force, _L.force, _K.force, _H.force, _HD.force
)  # fmt: skip
_j_rate, _l_rate, _k_rate, _h_rate, _hd_rate = _J.rate, _L.rate, _K.rate, _H.rate, _HD.rate
_j_grad, _l_grad, _k_grad, _h_grad, _hd_grad = _J.grad, _L.grad, _K.grad, _H.grad, _HD.grad
_j_stored, _l_stored, _k_stored, _h_stored, _hd_stored = (
    _J.stored, _L.stored, _K.stored, _H.stored, _HD.stored
)  # fmt: skip
_j_dur, _l_dur, _k_dur, _h_dur, _hd_dur = (
    _J.duration, _L.duration, _K.duration, _H.duration, _HD.duration
)  # fmt: skip
_zeta_ye2009 = jit(inline=True)(HERTZDAMP_RELATIONS["ye2009"])
_zeta_muthukumar2006 = jit(inline=True)(HERTZDAMP_RELATIONS["muthukumar2006"])


@jit(inline=True)
def force(model, d, dd, beta, c0, zeta, phase):
    """Contact force [N] of a law by its code, in a phase (0 open, 1 approach, 2 restitution).

    ``d`` is clipped at 0 so located switches never see a negative root.
    """
    if phase == 0:
        return 0.0
    if d < 0.0:
        d = 0.0
    if model == _JANKOWSKI:
        return _j_force(d, dd, beta, c0, zeta, phase)
    if model == _LINEAR:
        return _l_force(d, dd, beta, c0, zeta, phase)
    if model == _KELVIN:
        return _k_force(d, dd, beta, c0, zeta, phase)
    if model == _HERTZ:
        return _h_force(d, dd, beta, c0, zeta, phase)
    return _hd_force(d, dd, beta, c0, zeta, phase)


@jit(inline=True)
def contact_forces(q, v, psi, gap, beta, cd, zeta, phase, model, fc, rate):
    """Forces of every contact at state ``q, v`` into ``fc`` [N] (0 for open contacts).

    ``rate`` receives the penetration rate [m/s] of every closed contact.
    """
    for c in range(fc.size):
        if phase[c] == 0:
            fc[c] = 0.0  # as force() for an open contact, without its row products
            continue
        d = rowdot(psi, c, q) - gap[c]
        dd = rowdot(psi, c, v)
        rate[c] = dd
        fc[c] = force(model, d, dd, beta[c], cd[c], zeta[c], phase[c])


@jit
def force_rate(model, d, dd, ddd, beta, c0, zeta, phase):
    """Time derivative of :func:`force` along the motion [N/s]."""
    if phase == 0 or d <= 0.0:
        return 0.0
    if model == _JANKOWSKI:
        return _j_rate(d, dd, ddd, beta, c0, zeta, phase)
    if model == _LINEAR:
        return _l_rate(d, dd, ddd, beta, c0, zeta, phase)
    if model == _KELVIN:
        return _k_rate(d, dd, ddd, beta, c0, zeta, phase)
    if model == _HERTZ:
        return _h_rate(d, dd, ddd, beta, c0, zeta, phase)
    return _hd_rate(d, dd, ddd, beta, c0, zeta, phase)


@jit(inline=True, llvm_inline=True)
def substep_peaks(model, f0, f1, d0, d1, dd0, dd1, ddd0, ddd1, hs, peak, beta, c0, zeta, phase):
    """Largest force and penetration over a contact sub-step of length ``hs`` [s].

    ``f, d, dd, ddd``: force [N], penetration [m] and its first two rates at the sub-step's
    start (0) and end (1).  The force's interior maximum is that of the cubic Hermite on the
    force and its rate, looked for only where it could raise ``peak`` (an interior maximum
    exceeds the end values by far less than 10 %: sub-steps are a fraction of the contact
    duration); the penetration's that of the cubic Hermite on it and its rate.  Returns the
    largest force, its time in the sub-step [s] and the largest penetration.
    """
    fm = f1
    tm = hs
    if max(f0, f1) >= 0.9 * peak and d0 > 0.25 * d1:
        r0 = force_rate(model, d0, dd0, ddd0, beta, c0, zeta, phase)
        r1 = force_rate(model, d1, dd1, ddd1, beta, c0, zeta, phase)
        if r0 > 0.0 and r1 < 0.0:
            hm, th = hermite_max(f0, r0, f1, r1, hs)
            if hm > fm:
                fm = hm
                tm = th
    if f0 > fm:
        fm = f0
        tm = 0.0
    dm = max(d0, d1)
    if dd0 > 0.0 and dd1 < 0.0:
        hm, _ = hermite_max(d0, dd0, d1, dd1, hs)
        if hm > dm:
            dm = hm
    return fm, tm, dm


@jit(inline=True)
def force_grad(model, d, dd, beta, c0, zeta, phase):
    """Force [N] and its partial derivatives by penetration [N/m] and by its rate [N s/m]."""
    if phase == 0 or d <= 0.0:
        return 0.0, 0.0, 0.0
    if model == _JANKOWSKI:
        return _j_grad(d, dd, beta, c0, zeta, phase)
    if model == _LINEAR:
        return _l_grad(d, dd, beta, c0, zeta, phase)
    if model == _KELVIN:
        return _k_grad(d, dd, beta, c0, zeta, phase)
    if model == _HERTZ:
        return _h_grad(d, dd, beta, c0, zeta, phase)
    return _hd_grad(d, dd, beta, c0, zeta, phase)


@jit(inline=True)
def stored(model, d, beta):
    """Elastic energy stored in a contact at penetration ``d`` [J]."""
    if d <= 0.0:
        return 0.0
    if model == _JANKOWSKI:
        return _j_stored(d, beta)
    if model == _LINEAR:
        return _l_stored(d, beta)
    if model == _KELVIN:
        return _k_stored(d, beta)
    if model == _HERTZ:
        return _h_stored(d, beta)
    return _hd_stored(d, beta)


@jit
def duration(model, v0, beta, meff):
    """Estimated contact duration [s] for the sub-step size."""
    if model == _JANKOWSKI:
        return _j_dur(v0, beta, meff)
    if model == _LINEAR:
        return _l_dur(v0, beta, meff)
    if model == _KELVIN:
        return _k_dur(v0, beta, meff)
    if model == _HERTZ:
        return _h_dur(v0, beta, meff)
    return _hd_dur(v0, beta, meff)


@jit(inline=True)
def episode_zeta(model, relation, e, v0, zeta):
    """Damping constant of a contact episode that starts at velocity ``v0`` [m/s].

    Hertz-damp laws only (``e`` the restitution, ``relation`` the relation's code); other laws
    keep ``zeta`` as it is.
    """
    if model != _HERTZDAMP:
        return zeta
    v = max(v0, 1e-12)
    if relation == _MUTHUKUMAR2006:
        return _zeta_muthukumar2006(e, v)
    return _zeta_ye2009(e, v)


@jit(inline=True)
def phase_of(d, dd):
    """Phase of a contact at penetration ``d`` and rate ``dd`` (0 open, 1 approach, 2 back)."""
    if d <= 0.0:
        return 0
    return 1 if dd > 0.0 else 2


@jit
def newton_scalar(model, dstar, dn, ddn, g, c2h, fprev, beta, c0, zeta):
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
        f, fd, fdd = force_grad(model, d, ddt, beta, c0, zeta, phase_of(d, ddt))
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
            f = force(model, d_new, ddt, beta, c0, zeta, phase_of(d_new, ddt))
            return f, True
        d = d_new
    return f, False


@jit(inline=True)
def impact_restitution(settings, quantile, v0):
    """Restitution [-] of an impact at prior-impact velocity ``v0`` [m/s], set per impact.

    ``settings.rest_v``: the table's velocities [m/s], ``rest_lo`` / ``rest_hi``: its range of
    ``e`` at them; linear in velocity between rows, outside them held (``settings.outside``
    0) or continued linearly and kept within ``[rest_floor, 1]`` (1); ``e`` at ``quantile``
    of the range.
    """
    rv = settings.rest_v
    lo = settings.rest_lo
    hi = settings.rest_hi
    n = rv.size
    if v0 <= rv[0]:
        k = 0
    elif v0 >= rv[n - 1]:
        k = n - 2
    else:
        k = 0
        while v0 > rv[k + 1]:
            k += 1
    t = (v0 - rv[k]) / (rv[k + 1] - rv[k])
    if settings.outside == 0:
        t = min(max(t, 0.0), 1.0)
    e_lo = lo[k] + t * (lo[k + 1] - lo[k])
    e_hi = hi[k] + t * (hi[k + 1] - hi[k])
    if settings.outside != 0:
        e_lo = min(max(e_lo, settings.rest_floor), 1.0)
        e_hi = min(max(e_hi, settings.rest_floor), 1.0)
    return e_lo + quantile * (e_hi - e_lo)


@jit(inline=True)
def impact_xi(settings, e):
    """Damping ratio [-] for restitution ``e`` by the run's relation (its table, linear)."""
    tab = settings.xi_tab
    x = (e - settings.xi_e0) / settings.xi_de
    if x <= 0.0:
        return tab[0]
    k = int(x)
    if k >= tab.size - 1:
        return tab[tab.size - 1]
    t = x - k
    return tab[k] + t * (tab[k + 1] - tab[k])


@jit(inline=True)
def episode_damping(settings, model, relation, quantile, v0, beta, meff, cd, zhd):
    """Damping of an episode whose restitution is set per impact at its onset velocity ``v0``.

    Returns ``(c0, zeta, e)``: the damping constant of the law [N s/m per its law], the
    Hertz-damp constant [s/m] and the restitution used [-].
    """
    v = max(v0, 1e-12)
    e = impact_restitution(settings, quantile, v)
    if model == _HERTZDAMP:
        return cd, episode_zeta(model, relation, e, v, zhd), e
    return 2.0 * impact_xi(settings, e) * math.sqrt(beta * meff), zhd, e
