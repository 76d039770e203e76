"""Independent tight-tolerance reference solution of a scene (SciPy, pure Python).

Used to check the compiled kernels of :mod:`pound_mc.integrators`; it shares none of their
code.  The buildings are integrated in *physical* floor coordinates (not modes),

``M x'' + C x' + K x = -M 1 a_g(t) + f_c(x, x')``,

with the mass, stiffness and (classical) damping matrices of
:class:`pound_mc.physics.structures.Building`.
At a contact between left floor ``i`` and right floor ``j`` the penetration is
``delta = x_i - x_j - gap`` and the force ``F >= 0`` acts as ``-F`` on the left floor and ``+F`` on
the right floor (``../shared/DESIGN.md`` section 2).  The force laws are written out here:

``jankowski`` (seed eq. 1.1)
    approach (``delta_dot > 0``): ``F = beta delta^1.5 + c delta_dot`` with
    ``c = 2 xi sqrt(beta sqrt(delta) m_eff)``; restitution: ``F = beta delta^1.5``.
``hertz``
    ``F = beta delta^1.5``.
``linear`` / ``kelvin``
    ``F = k delta`` / ``F = k delta + 2 xi sqrt(k m_eff) delta_dot``.
``hertzdamp``
    ``F = max(0, beta delta^1.5 (1 + zeta delta_dot))`` with ``zeta`` from ``e`` and ``v0``,
    the approach velocity of the episode, by the scene's relation (default Ye et al. 2009,
    ``zeta = 8 (1 - e) / (5 e v0)``).

The ground acceleration is the record's samples linearly interpolated, so the right-hand side
has kinks at the samples: the solution is integrated sample interval by sample interval, each a
smooth problem, with SciPy's ``DOP853`` at ``rtol = 1e-11``.  Every contact carries an explicit
phase (open, approach, restitution); the switches are terminal events (open -> approach when
``delta`` crosses 0 upwards, approach -> restitution when ``delta_dot`` crosses 0 downwards,
restitution -> open when ``delta`` crosses 0 downwards, restitution -> approach when
``delta_dot`` crosses 0 upwards) and the integration restarts after each with the new phases,
so the right-hand side is smooth inside every segment.  Peak force and peak displacements are
continuous-time maxima: the dense output of every segment is sampled finely and the best sample
refined with :func:`scipy.optimize.minimize_scalar`.

With ``restitution = "velocity"`` each impact's ``e`` is
:func:`pound_mc.physics.materials.restitution_at` (the seed's Table 2) at the relative
velocity at the onset event, and its damping (``xi`` by
:func:`pound_mc.physics.relations.xi_from_e`, or ``zeta``) is fixed for that episode.

This is slow (seconds for a 30 s SDOF-pair record) and meant for tests and checks only.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from pound_mc.integrators.outputs import IMPACT_MIN_PENETRATION_M
from pound_mc.motions import record_arrays
from pound_mc.physics.contact import CONTACT_MODELS
from pound_mc.physics.materials import restitution_at
from pound_mc.physics.relations import (
    HERTZDAMP_RELATIONS,
    single_impact_restitution,
    single_impact_restitution_hertzdamp,
    xi_from_e,
)

__all__ = ["reference_solution"]

_OPEN, _APPROACH, _RESTITUTION = 0, 1, 2
#: Dense-output samples per solver step when looking for maxima.
_SAMPLES_PER_STEP = 8
_MODELS = ("jankowski", "hertz", "linear", "kelvin", "hertzdamp")


def _contact_force(model, d, dd, beta, xi, m_eff, zhd, phase):
    """Contact force [N] in a phase (0 open, 1 approach, 2 restitution); arrays allowed."""
    if phase == _OPEN:
        return np.zeros_like(np.asarray(d, dtype=float))
    d = np.maximum(d, 0.0)
    if model == "jankowski":
        f = beta * d**1.5
        if phase == _APPROACH:
            f = f + 2.0 * xi * np.sqrt(beta * np.sqrt(d) * m_eff) * dd
        return f
    if model == "hertz":
        return beta * d**1.5
    if model == "linear":
        return beta * d
    if model == "kelvin":
        return beta * d + 2.0 * xi * np.sqrt(beta * m_eff) * dd
    # hertzdamp
    return np.maximum(beta * d**1.5 * (1.0 + zhd * dd), 0.0)


def _refine_max(fun, t_lo, t_hi, f_guess):
    """Maximum of a smooth scalar ``fun`` on ``[t_lo, t_hi]`` (bounded Brent)."""
    if t_hi <= t_lo:
        return f_guess
    res = minimize_scalar(
        lambda t: -fun(t),
        bounds=(t_lo, t_hi),
        method="bounded",
        options={"xatol": 1e-13 * max(1.0, abs(t_hi)), "maxiter": 200},
    )
    return max(f_guess, -float(res.fun))


def _raise_abs_peaks(peaks, rows, grid, rows_at) -> None:
    """Raise ``peaks[i]`` to the continuous-time maximum of ``|rows[i]|``, in place.

    ``rows`` are sampled at the times ``grid`` [s], ``rows_at(t)`` gives them at any ``t``; a row
    whose sampled maximum comes within 0.1 % of its peak so far is refined around it
    (:func:`_refine_max`).
    """
    sampled = np.abs(rows)
    for i in range(peaks.size):
        kk = int(np.argmax(sampled[i]))
        val = sampled[i, kk]
        if val > peaks[i] * (1.0 - 1e-3):
            lo = grid[max(kk - 1, 0)]
            hi = grid[min(kk + 1, grid.size - 1)]
            val = _refine_max(lambda t, i=i: abs(rows_at(t)[i]), lo, hi, val)
            peaks[i] = max(peaks[i], val)


def reference_solution(
    scene,
    record=None,
    rtol: float = 1e-11,
    atol_scale: float = 1e-12,
    *,
    x0=None,
    v0=None,
    contact_work: bool = False,
) -> dict:
    """Solve ``scene`` with SciPy's DOP853 at a tight tolerance.

    Parameters
    ----------
    scene : pound_mc.scene.Scene
        The scene (buildings, contacts, gap, contact law; its integrator settings are ignored).
    record : tuple (dt_s, acceleration), optional
        Sampling interval [s] and samples [m/s^2]; default the scene's own record
        (``scene.load_record()``).  The simulation runs from t = 0 to the last sample.
    rtol : float
        Relative tolerance of the ODE solver.
    atol_scale : float
        Absolute tolerance relative to the response scale (displacement ``PGA / omega_min^2``
        or the initial state, velocities that times ``omega_max``).
    x0, v0 : array_like, optional
        Initial floor displacements [m] and velocities [m/s] relative to the ground, left
        building's floors (bottom to top) then right building's; default at rest.
    contact_work : bool
        Also integrate the work done on the contacts, ``int sum_j F_j delta_dot_j dt``, as a
        state of the ODE (under the solver's error control): ``contact_work`` [J] and
        ``dissipated_energy`` (that less the energy stored in the contacts at the end) [J].

    Returns
    -------
    dict
        ``peak_force`` [N], ``impacts``, ``max_penetration`` [m] (0 without impacts),
        ``peak_disp_left``, ``peak_disp_right`` [m] (max over floors and time of ``|x|``;
        in a row the first building's and the last's), ``buildings`` (per building from the
        left, a wall none: ``building``, ``peak_disp``, ``peak_ductility``, ``peak_drift``,
        ``residual_drift``),
        ``impact_times`` (list [s]), ``impact_velocities`` (list [m/s], the onset velocity of
        every impact), ``peak_force_restitution`` (the restitution the law rebounds with for
        the damping of the peak-force episode, by a single-impact integration; NaN with fixed
        restitution), ``peak_force_time`` [s], per-contact arrays
        ``contact_peak_force`` and ``contact_impacts``, ``x_end``, ``v_end`` (final state),
        ``x_samples``, ``f_samples`` (floor displacements [m] and contact forces [N] at the
        record's samples, one row per sample),
        ``segments`` (solver calls), ``wall_s``.
    """
    t_wall = time.perf_counter()
    model = scene.contact_model
    if model not in _MODELS:
        raise ValueError(f"unsupported contact model {model!r}")
    if record is None:
        record = record_arrays(scene.load_record())
    dt_rec, acc = record
    dt_rec = float(dt_rec)
    acc = np.asarray(acc, dtype=float)
    npts = acc.size

    # a row of buildings (``scene.row``) or the two; the left one's floors first
    buildings = getattr(scene, "row", None) or [scene.left, scene.right]
    starts = np.cumsum([0] + [b.n_floors for b in buildings])
    n = int(starts[-1])
    m = np.zeros((n, n))
    k = np.zeros((n, n))
    c = np.zeros((n, n))
    for j, b in enumerate(buildings):
        sl = slice(starts[j], starts[j + 1])
        m[sl, sl] = b.mass_matrix()
        k[sl, sl] = b.stiffness_matrix()
        c[sl, sl] = b.damping_matrix()
    # a wall (infinite mass) stays with the ground: no acceleration of its own
    fixed = np.flatnonzero(~np.isfinite(np.diag(m)))
    minv = np.linalg.inv(m) if fixed.size == 0 else np.diag(1.0 / np.diag(m))
    # first-order system y = [x, v]: y' = A y + b(t) + contact terms
    a_lin = np.zeros((2 * n, 2 * n))
    a_lin[:n, n:] = np.eye(n)
    a_lin[n:, :n] = -minv @ k
    a_lin[n:, n:] = -minv @ c
    masses = np.diag(m)

    nc = len(scene.contacts)
    # penetration of contact j: w[j] @ x - gap (a floor, or a column interpolated between
    # floors, of each building); its force acts on the floors by the same weights
    w = np.zeros((nc, n))
    for j, ct in enumerate(scene.contacts):
        p = getattr(ct, "pair", 0)
        w[j, starts[p] : starts[p + 1]] = ct.weights("left", buildings[p].n_floors)
        w[j, starts[p + 1] : starts[p + 2]] -= ct.weights("right", buildings[p + 1].n_floors)
    meff = np.array([ct.m_eff for ct in scene.contacts], dtype=float)
    gap = np.broadcast_to(np.asarray(scene.gap_m, dtype=float), (nc,)).copy()
    beta = float(scene.stiffness)
    velocity = getattr(scene, "restitution", "fixed") == "velocity"
    if model == "hertzdamp":
        e_coef = float(scene.e) if not velocity else 1.0
        xi0 = 0.0
        zeta_of = HERTZDAMP_RELATIONS[scene.relation or "ye2009"]
    else:
        e_coef = 1.0
        xi0 = float(scene.xi) if scene.xi is not None else 0.0
    xi = np.full(nc, xi0)
    zhd = np.zeros(nc)
    e_episode = np.full(nc, np.nan)
    v_episode = np.zeros(nc)
    impact_velocities: list[float] = []
    peak_e = peak_xi = np.nan

    def start_episode(j, vimp):
        """Damping of an episode of contact ``j`` starting at velocity ``vimp`` [m/s]."""
        v_episode[j] = vimp
        if velocity:
            e_episode[j] = restitution_at(
                scene.material, max(vimp, 1e-12), scene.e_quantile, outside=scene.outside
            )
            if model == "hertzdamp":
                zhd[j] = zeta_of(e_episode[j], max(vimp, 1e-12))
            else:
                xi[j] = xi_from_e(e_episode[j], scene.relation)
        elif model == "hertzdamp":
            zhd[j] = zeta_of(e_coef, max(vimp, 1e-12))

    # storeys: drift u_s = x[top] - x[bottom] (bottom -1: the ground); a bilinear storey resists
    # alpha k u + (1 - alpha) k z, i.e. k u less (1 - alpha) k u_p with u_p = u - z its plastic
    # drift; mode 0 elastic (u_p fixed), +1 / -1 yielding (z = +-u_y, u_p follows u).  A
    # Bouc-Wen storey's z is a state of the ODE (after x and v), its smooth law needs no events;
    # the last state is then its hysteretic dissipation (1 - alpha) k int z du_p
    s_top, s_bot, s_k, s_uy, s_alpha, s_side, s_h, s_bw = [], [], [], [], [], [], [], []
    for b, bld in enumerate(buildings):
        off = int(starts[b])
        for st in range(bld.n_floors):
            s_top.append(off + st)
            s_bot.append(off + st - 1 if st > 0 else -1)
            s_k.append(bld.storey_stiffness_N_per_m[st])
            s_uy.append(bld.yield_disp_m[st] if bld.inelastic else np.inf)
            s_alpha.append(bld.post_yield_ratio)
            s_side.append(b)  # the building's place from the left
            s_h.append(bld.storey_height_m[st])
            s_bw.append(bld.bw_exponent if bld.hysteresis == "bouc-wen" else 0.0)
    s_top, s_bot = np.array(s_top), np.array(s_bot)
    s_k, s_uy, s_alpha = np.array(s_k, float), np.array(s_uy, float), np.array(s_alpha, float)
    ns = s_top.size
    s_bw = np.array(s_bw, float)
    bw = s_bw > 0.0
    bw_idx = np.flatnonzero(bw)
    nz = bw_idx.size
    inelastic_storey = np.isfinite(s_uy)
    yielding = inelastic_storey & ~bw  # bilinear storeys (located events)
    uy_finite = np.where(inelastic_storey, s_uy, 0.0)
    # (1 - alpha) k of the yielding storeys, 0 elsewhere (a wall's infinite k never enters)
    k_plastic = (1.0 - s_alpha) * np.where(inelastic_storey, s_k, 0.0)
    s_mode = np.zeros(ns, dtype=int)
    s_up = np.zeros(ns)
    e_hyst = 0.0

    def drifts(x):
        xb = (
            np.where(s_bot[:, None] >= 0, x[np.maximum(s_bot, 0)], 0.0)
            if x.ndim > 1
            else (np.where(s_bot >= 0, x[np.maximum(s_bot, 0)], 0.0))
        )
        return x[s_top] - xb

    def plastic_drift(u, yy=None):
        up = np.where(s_mode == 0, s_up, u - s_mode * uy_finite)
        if nz and yy is not None:
            up[bw_idx] = u[bw_idx] - yy[2 * n : 2 * n + nz]
        return up

    y = np.zeros(2 * n + (nz + 1 if nz else 0) + (1 if contact_work else 0))
    if x0 is not None:
        y[:n] = np.asarray(x0, dtype=float)
        y[2 * n : 2 * n + nz] = drifts(y[:n])[bw_idx]
    if v0 is not None:
        y[n : 2 * n] = np.asarray(v0, dtype=float)

    # tolerances
    omega_all = np.concatenate([b.omega for b in buildings])
    pga = float(np.max(np.abs(acc))) if npts else 0.0
    x_scale = max(pga / omega_all.min() ** 2, np.max(np.abs(y[:n])), 1e-300)
    x_scale = max(x_scale, np.max(np.abs(y[n : 2 * n])) / omega_all.min())
    atol = np.r_[
        np.full(n, atol_scale * x_scale), np.full(n, atol_scale * x_scale * omega_all.max())
    ]
    if nz:
        e_scale = float(np.max(k_plastic[bw_idx] * uy_finite[bw_idx] * x_scale))
        atol = np.r_[atol, np.full(nz, atol_scale * x_scale), atol_scale * e_scale]
    if contact_work:
        m_finite = masses[np.isfinite(masses)]
        w_scale = float(m_finite.max()) * (x_scale * omega_all.max()) ** 2
        atol = np.r_[atol, atol_scale * w_scale]

    # phases at the start (already in contact: by the sign of delta_dot, not counted)
    phase = np.zeros(nc, dtype=int)
    for j in range(nc):
        d = w[j] @ y[:n] - gap[j]
        if d > 0.0:
            dd = w[j] @ y[n : 2 * n]
            phase[j] = _APPROACH if dd > 0.0 else _RESTITUTION
            start_episode(j, dd)

    state = {"ag0": 0.0, "slope": 0.0, "t0": 0.0}

    def forces(x, v):
        f = np.zeros(nc)
        for j in range(nc):
            if phase[j] != _OPEN:
                d = w[j] @ x - gap[j]
                dd = w[j] @ v
                f[j] = _contact_force(model, d, dd, beta, xi[j], meff[j], zhd[j], phase[j])
        return f

    def rhs(t, yy):
        dy = a_lin @ yy[: 2 * n]
        dy[n:] -= state["ag0"] + state["slope"] * (t - state["t0"])
        dy[n + fixed] = 0.0
        power_c = 0.0
        if np.any(phase):
            f = forces(yy[:n], yy[n : 2 * n])
            dy[n:] -= (w.T @ f) / masses
            power_c = float(f @ (w @ yy[n : 2 * n]))
        if inelastic_storey.any():
            # the plastic drifts' forces (1 - alpha) k u_p pull the floor above a storey back
            # and push the floor below
            fp = k_plastic * plastic_drift(drifts(yy[:n]), yy)
            np.add.at(dy, n + s_top, fp / masses[s_top])
            below = s_bot >= 0
            np.subtract.at(dy, n + s_bot[below], fp[below] / masses[s_bot[below]])
            dy[n + fixed] = 0.0
        if nz:
            # Bouc-Wen: z' = u' (1 - |z / u_y|^n (0.5 sign(u' z) + 0.5))
            ud = drifts(yy[n : 2 * n])[bw_idx]
            z = yy[2 * n : 2 * n + nz]
            r = np.abs(z / uy_finite[bw_idx]) ** s_bw[bw_idx]
            zd = ud * (1.0 - r * (0.5 * np.sign(ud * z) + 0.5))
            power = np.sum(k_plastic[bw_idx] * z * (ud - zd))
            dy = np.r_[dy, zd, power]
        if contact_work:
            dy = np.r_[dy, power_c]
        return dy

    def unload(st, yy):
        """Storey ``st`` leaves its yielding branch at state ``yy`` (its new plastic drift).

        Returns the hysteretic energy of the plastic drift's change.
        """
        up_new = drifts(yy[:n])[st] - s_mode[st] * s_uy[st]
        energy = (1.0 - s_alpha[st]) * s_k[st] * s_uy[st] * abs(up_new - s_up[st])
        s_up[st] = up_new
        s_mode[st] = 0
        return energy

    def make_storey_event(st, which, direction):
        bot = s_bot[st]

        def drift_of(yy, off=0):
            return yy[off + s_top[st]] - (yy[off + bot] if bot >= 0 else 0.0)

        if which == "yield":

            def ev(_t, yy):
                return drift_of(yy) - s_up[st] - direction * s_uy[st]

        else:

            def ev(_t, yy):
                return drift_of(yy, n)

        ev.terminal = True
        ev.direction = direction
        return ev

    def make_event(j, which, direction):
        if which == "d":

            def ev(_t, yy):
                return w[j] @ yy[:n] - gap[j]

        else:

            def ev(_t, yy):
                return w[j] @ yy[n : 2 * n]

        ev.terminal = True
        ev.direction = direction
        return ev

    ev_d_up = [make_event(j, "d", 1.0) for j in range(nc)]
    ev_dd_down = [make_event(j, "dd", -1.0) for j in range(nc)]
    ev_d_down = [make_event(j, "d", -1.0) for j in range(nc)]
    ev_dd_up = [make_event(j, "dd", 1.0) for j in range(nc)]

    peak_x = np.zeros(n)
    peak_u = np.zeros(ns)
    peak_f = np.zeros(nc)
    peak_f_time = 0.0
    impacts = np.zeros(nc, dtype=int)
    pending = np.zeros(nc, dtype=bool)  # episodes not yet counted as impacts
    max_pen = np.full(nc, -np.inf)
    impact_times: list[float] = []
    segments = 0
    h_last = None
    # segments in a row that ended where they started: a contact whose penetration and its rate
    # are both zero (identical buildings at zero gap) switches onset -> turn -> separation at one
    # instant for ever; after one such round it runs to the end of the interval without them
    stalled = 0
    for f_idx in range(n):
        peak_x[f_idx] = abs(y[f_idx])
    # floor displacements at the record's samples (the dense output of the segment holding each)
    x_samples = np.full((npts, n), np.nan)
    x_samples[0] = y[:n]
    f_samples = np.zeros((npts, nc))  # contact forces there (0 while a contact is open)

    def scan_segment(sol_t, dense):
        """Continuous-time maxima of |x| per floor and of the contact forces."""
        nonlocal peak_f_time, peak_e, peak_xi
        tt = np.asarray(sol_t)
        if tt.size < 2:
            return
        # samples in the segment, to round-off of the times ((npts - 1) dt / dt may fall short)
        k = np.arange(
            max(math.ceil(tt[0] / dt_rec - 1e-9), 0),
            min(math.floor(tt[-1] / dt_rec + 1e-9), npts - 1) + 1,
        )
        y_k = dense(k * dt_rec) if k.size else None
        if k.size:
            x_samples[k] = y_k[:n].T
        frac = np.linspace(0.0, 1.0, _SAMPLES_PER_STEP + 1)[:-1]
        grid = (tt[:-1, None] + np.diff(tt)[:, None] * frac[None, :]).ravel()
        grid = np.r_[grid, tt[-1]]
        yy = dense(grid)
        _raise_abs_peaks(peak_x, yy[:n], grid, dense)
        _raise_abs_peaks(peak_u, drifts(yy[:n]), grid, lambda t: drifts(dense(t)))
        for j in range(nc):
            if phase[j] == _OPEN:
                continue

            def force_of(s, j=j):
                # penetration and its rate from the state (displacements, then velocities)
                d = w[j] @ s[:n] - gap[j]
                dd = w[j] @ s[n : 2 * n]
                return _contact_force(model, d, dd, beta, xi[j], meff[j], zhd[j], phase[j])

            def force_at(t, force_of=force_of):
                return force_of(dense(t))

            if y_k is not None:
                f_samples[k, j] = force_of(y_k)
            fs = force_of(yy)
            kk = int(np.argmax(fs))
            val = float(fs[kk])
            t_best = grid[kk]
            if val > peak_f[j] * (1.0 - 1e-3):
                lo = grid[max(kk - 1, 0)]
                hi = grid[min(kk + 1, grid.size - 1)]
                if hi > lo:
                    res = minimize_scalar(
                        lambda t: -float(force_at(t)),
                        bounds=(lo, hi),
                        method="bounded",
                        options={"xatol": 1e-13 * max(1.0, hi), "maxiter": 200},
                    )
                    if -res.fun > val:
                        val = -float(res.fun)
                        t_best = float(res.x)
            if val > peak_f[j]:
                peak_f[j] = val
                if val >= peak_f.max():
                    peak_f_time = t_best
                    peak_e, peak_xi = e_episode[j], xi[j]

    for i in range(npts - 1):
        t_a = i * dt_rec
        t_b = (i + 1) * dt_rec
        state["ag0"] = acc[i]
        state["slope"] = (acc[i + 1] - acc[i]) / dt_rec
        state["t0"] = t_a
        t = t_a
        while t_b - t > 1e-14 * max(1.0, t_b):
            events, kinds = [], []
            for j in range(nc if stalled < 3 else 0):
                if phase[j] == _OPEN:
                    events.append(ev_d_up[j])
                    kinds.append((j, "onset"))
                elif phase[j] == _APPROACH:
                    events.append(ev_dd_down[j])
                    kinds.append((j, "turn"))
                else:
                    events.append(ev_d_down[j])
                    kinds.append((j, "separation"))
                    events.append(ev_dd_up[j])
                    kinds.append((j, "reapproach"))
            for st in np.flatnonzero(yielding):
                if s_mode[st] == 0:
                    for sign in (1.0, -1.0):
                        events.append(make_storey_event(st, "yield", sign))
                        kinds.append((st, "yield"))
                else:
                    events.append(make_storey_event(st, "unload", -float(s_mode[st])))
                    kinds.append((st, "unload"))
            kw = {}
            if h_last is not None:
                kw["first_step"] = min(h_last, t_b - t)
            sol = solve_ivp(
                rhs,
                (t, t_b),
                y,
                method="DOP853",
                rtol=rtol,
                atol=atol,
                events=events,
                dense_output=True,
                **kw,
            )
            segments += 1
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
            if sol.t.size >= 2 and sol.t[-1] > sol.t[0]:
                # not after an event at the segment's start (identical buildings touching by
                # round-off at rest): its zero step is no first step for the next segment
                steps = np.diff(sol.t)
                h_last = float(steps.max())
            scan_segment(sol.t, sol.sol)
            y = sol.y[:, -1].copy()
            stalled = stalled + 1 if sol.t[-1] <= t else 0
            t = float(sol.t[-1])
            if sol.status == 1:
                fired = [(float(te[0]), idx) for idx, te in enumerate(sol.t_events) if te.size > 0]
                _, idx = min(fired)
                j, kind = kinds[idx]
                if kind == "yield":
                    u = drifts(y[:n])[j]
                    s_mode[j] = 1 if u - s_up[j] > 0.0 else -1
                elif kind == "unload":
                    e_hyst += unload(j, y)
                elif kind == "onset":
                    phase[j] = _APPROACH
                    pending[j] = True  # an impact once the penetration is deep enough
                    impact_times.append(t)
                    start_episode(j, w[j] @ y[n : 2 * n])
                    h_last = None  # let the solver choose a step for the stiff contact
                elif kind == "turn":
                    phase[j] = _RESTITUTION
                    pen = w[j] @ y[:n] - gap[j]  # a maximum of the penetration
                    max_pen[j] = max(max_pen[j], pen)
                    if pending[j] and pen > IMPACT_MIN_PENETRATION_M:
                        impacts[j] += 1
                        pending[j] = False
                        impact_velocities.append(float(v_episode[j]))
                elif kind == "separation":
                    phase[j] = _OPEN
                else:
                    phase[j] = _APPROACH
                # a yielding storey already unloading: its event fell at this event's instant
                # and the solver reports one (a storey against a wall turns with the contact,
                # the same velocity vanishing); from the next segment's start, where it is past
                # zero, it would never be found and the storey would go on yielding
                rates = drifts(y[n : 2 * n])
                for st in np.flatnonzero(s_mode * rates < 0.0):
                    e_hyst += unload(st, y)

    # a record that ends inside an episode: its penetration so far counts (an impact once it
    # is deep enough, as the turn above would count it), as it does in the kernels
    for j in np.flatnonzero(phase != _OPEN):
        pen = w[j] @ y[:n] - gap[j]
        max_pen[j] = max(max_pen[j], pen)
        if pending[j] and pen > IMPACT_MIN_PENETRATION_M:
            impacts[j] += 1
            pending[j] = False
            impact_velocities.append(float(v_episode[j]))
    # "left" and "right": the first building and the last (in a row closed by a wall, the
    # building before it: a wall is no building; a pair's right wall stays "right")
    last = len(buildings) - 1
    if last > 1 and buildings[last].model == "wall":
        last -= 1
    x_left = peak_x[: starts[1]]
    x_right = peak_x[starts[last] : starts[last + 1]]
    u_end = drifts(y[:n])
    up_end = plastic_drift(u_end, y)
    e_hyst += float(np.sum(np.where(yielding, k_plastic * uy_finite * np.abs(up_end - s_up), 0)))
    if nz:
        e_hyst += float(y[2 * n + nz])
    side_of = np.array(s_side)
    per_building = []
    for b, bld in enumerate(buildings):
        side = side_of == b
        duct = peak_u[side] / s_uy[side]
        mine = side & (np.array(s_h) > 0.0)  # storeys of known height (not an SDOF without one)
        hs = np.array(s_h)[mine]
        per_building.append({
            "building": b,
            "peak_disp": float(peak_x[starts[b] : starts[b + 1]].max()),
            "peak_ductility": float(duct.max()) if bld.inelastic else np.nan,
            "peak_drift": float(np.max(peak_u[mine] / hs)) if hs.size else np.nan,
            "residual_drift": float(np.max(np.abs(u_end[mine]) / hs)) if hs.size else np.nan,
        })  # fmt: skip
    storey_out = {"buildings": [r for r, bld in zip(per_building, buildings, strict=True)
                                if bld.model != "wall"]}  # fmt: skip
    for name, b in (("left", 0), ("right", last)):
        for key in ("peak_ductility", "peak_drift", "residual_drift"):
            storey_out[f"{key}_{name}"] = per_building[b][key]
    total_impacts = int(impacts.sum())
    if np.isfinite(peak_e):  # the law's rebound for that episode's damping, integrated here
        if model == "hertzdamp":
            peak_e = single_impact_restitution_hertzdamp(peak_e, scene.relation or "ye2009")
        elif model == "jankowski":
            peak_e = single_impact_restitution(peak_xi)
    return {
        "peak_force": float(peak_f.max()) if nc else 0.0,
        "peak_force_time": float(peak_f_time),
        "impacts": total_impacts,
        "max_penetration": float(max_pen.max()) if total_impacts else 0.0,
        "peak_disp_left": float(x_left.max()),
        "peak_disp_right": float(x_right.max()),
        "impact_times": impact_times,
        "impact_velocities": impact_velocities,
        "peak_force_restitution": float(peak_e),
        "contact_peak_force": peak_f.copy(),
        "contact_impacts": impacts.copy(),
        "x_end": y[:n].copy(),
        "v_end": y[n : 2 * n].copy(),
        "x_samples": x_samples,
        "f_samples": f_samples,
        "segments": segments,
        "wall_s": time.perf_counter() - t_wall,
        **storey_out,
        "peak_storey_drift": peak_u.copy(),
        "plastic_drift_end": up_end,
        "hysteretic_energy": e_hyst,
        **(_contact_energies(model, y[-1], w @ y[:n] - gap, phase, beta) if contact_work else {}),
    }


def _contact_energies(model, work, penetration, phase, beta) -> dict:
    """``contact_work`` and ``dissipated_energy`` [J]: the work less the energy held at the end."""
    stored = CONTACT_MODELS[model].kernel.stored
    held = sum(float(stored(max(float(d), 0.0), beta)) for d, p in zip(penetration, phase,
               strict=True) if p != _OPEN)  # fmt: skip
    return {"contact_work": float(work), "dissipated_energy": float(work) - held}
