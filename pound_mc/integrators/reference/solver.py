"""The reference solution itself: the scene's equations, its events and its maxima.

See :mod:`pound_mc.integrators.reference` for what it solves and how; the contact physics comes
from :mod:`~pound_mc.integrators.reference.impact`, the matrices from
:mod:`~pound_mc.integrators.reference.frame`, both written for the reference.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from pound_mc.integrators.reference.frame import building_matrices, column_mass, storey_heights
from pound_mc.integrators.reference.impact import (
    APPROACH,
    IMPACT_MIN_PENETRATION_M,
    OPEN,
    RESTITUTION,
    contact_force,
    hertzdamp_rebound,
    jankowski_rebound,
    restitution_at_velocity,
    stored,
    xi_of_e,
    zeta_of_e,
)

__all__ = ["reference_solution"]

#: Dense-output samples per solver step when looking for maxima.
_SAMPLES_PER_STEP = 8
_MODELS = ("jankowski", "hertz", "linear", "kelvin", "hertzdamp")
#: The relation a law runs with when the scene gives ``e`` and names none.
_DEFAULT_RELATION = {"jankowski": "jankowski2008", "kelvin": "kelvin", "hertzdamp": "ye2009"}


def _yields(building) -> bool:
    """Whether the building's storeys can yield (a hysteresis other than elastic)."""
    return getattr(building, "hysteresis", "elastic") != "elastic"


def _contact_point(at, floor, building):
    """A contact's weights on ``building``'s floors and the mass [kg] that meets there.

    ``at``: the ``(floor, weight)`` pairs of a column point (linear between the floors below
    and above), empty for floor ``floor`` itself.
    """
    masses = np.asarray(building.storey_mass_kg, dtype=float)
    w = np.zeros(masses.size)
    for f, wf in at or ((floor, 1.0),):
        if f >= 0:  # the ground (-1) does not move
            w[f] += wf
    return w, (column_mass(at, masses) if at else float(masses[floor]))


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
    if scene.contact_model not in _MODELS:
        raise ValueError(f"unsupported contact model {scene.contact_model!r}")
    if record is None:  # the scene's record as read and preprocessed (an obspy Trace)
        trace = scene.load_record()
        record = (float(trace.stats.delta), np.asarray(trace.data, dtype=float))
    ref = _Reference(scene, record, atol_scale, x0, v0, contact_work)
    ref.run(rtol)
    return ref.results(t_wall)


class _Reference:
    """One reference solution in progress: the scene's equations, its phases and its maxima.

    Built from the arguments of :func:`reference_solution`; :meth:`run` integrates the record
    interval by interval and :meth:`results` collects the outputs.  The contacts' phases and
    episode damping and the storeys' branches change in place as the events fire; the
    right-hand side (:meth:`rhs`) and the event functions read them.
    """

    def __init__(self, scene, record, atol_scale, x0, v0, contact_work):
        self.scene = scene
        self.model = scene.contact_model
        dt_rec, acc = record
        self.dt_rec = float(dt_rec)
        self.acc = np.asarray(acc, dtype=float)
        self.npts = self.acc.size
        self.contact_work = contact_work
        self._matrices()
        self._contacts()
        self._storeys()
        self._start(x0, v0, atol_scale)
        self._maxima()

    def _matrices(self):
        """The floors' mass, stiffness and damping as a first-order system ``y' = A y``."""
        scene = self.scene
        # a row of buildings (``scene.row``) or the two; the left one's floors first
        buildings = getattr(scene, "row", None) or [scene.left, scene.right]
        starts = np.cumsum([0] + [np.asarray(b.storey_mass_kg).size for b in buildings])
        n = int(starts[-1])
        m = np.zeros((n, n))
        k = np.zeros((n, n))
        c = np.zeros((n, n))
        omegas = []
        for j, b in enumerate(buildings):
            sl = slice(starts[j], starts[j + 1])
            m[sl, sl], k[sl, sl], c[sl, sl], omega = building_matrices(b)
            omegas.append(omega)
        # a wall (infinite mass) stays with the ground: no acceleration of its own
        fixed = np.flatnonzero(~np.isfinite(np.diag(m)))
        minv = np.linalg.inv(m) if fixed.size == 0 else np.diag(1.0 / np.diag(m))
        # first-order system y = [x, v]: y' = A y + b(t) + contact terms
        a_lin = np.zeros((2 * n, 2 * n))
        a_lin[:n, n:] = np.eye(n)
        a_lin[n:, :n] = -minv @ k
        a_lin[n:, n:] = -minv @ c
        self.buildings, self.starts, self.n = buildings, starts, n
        self.fixed, self.a_lin, self.masses = fixed, a_lin, np.diag(m)
        self.omega = np.concatenate(omegas)

    def _contacts(self):
        """The contacts' weights on the floors, their laws' constants and the episodes' damping."""
        scene, model, starts, buildings = self.scene, self.model, self.starts, self.buildings
        nc = len(scene.contacts)
        # penetration of contact j: w[j] @ x - gap (a floor, or a column interpolated between
        # floors, of each building); its force acts on the floors by the same weights
        w = np.zeros((nc, self.n))
        self.meff = np.zeros(nc)
        for j, ct in enumerate(scene.contacts):
            p = getattr(ct, "pair", 0)
            w_l, m_l = _contact_point(ct.left_at, ct.left_floor, buildings[p])
            w_r, m_r = _contact_point(ct.right_at, ct.right_floor, buildings[p + 1])
            w[j, starts[p] : starts[p + 1]] = w_l
            w[j, starts[p + 1] : starts[p + 2]] -= w_r
            # the masses that meet, m1 m2 / (m1 + m2); against a wall's infinite mass, m1
            self.meff[j] = m_l if math.isinf(m_r) else m_l * m_r / (m_l + m_r)
        self.nc, self.w = nc, w
        self.gap = np.broadcast_to(np.asarray(scene.gap_m, dtype=float), (nc,)).copy()
        self.beta = float(scene.stiffness)
        self.velocity = getattr(scene, "restitution", "fixed") == "velocity"
        self.relation = getattr(scene, "relation", None) or _DEFAULT_RELATION.get(model)
        e = getattr(scene, "e", None)
        self.e_coef = 1.0
        xi0 = 0.0
        if model == "hertzdamp":
            self.e_coef = float(e) if not self.velocity else 1.0
        elif e is not None and model in ("jankowski", "kelvin") and not self.velocity:
            xi0 = xi_of_e(e, self.relation)  # the scene gives e: xi by its relation, here
        elif scene.xi is not None:
            xi0 = float(scene.xi)
        self.xi = np.full(nc, xi0)
        self.zhd = np.zeros(nc)
        self.e_episode = np.full(nc, np.nan)
        self.v_episode = np.zeros(nc)
        self.impact_velocities: list[float] = []
        self.peak_e = self.peak_xi = np.nan
        self.ev_d_up = [self.make_event(j, "d", 1.0) for j in range(nc)]
        self.ev_dd_down = [self.make_event(j, "dd", -1.0) for j in range(nc)]
        self.ev_d_down = [self.make_event(j, "d", -1.0) for j in range(nc)]
        self.ev_dd_up = [self.make_event(j, "dd", 1.0) for j in range(nc)]

    def start_episode(self, j, vimp):
        """Damping of an episode of contact ``j`` starting at velocity ``vimp`` [m/s]."""
        scene, model = self.scene, self.model
        self.v_episode[j] = vimp
        if self.velocity:
            self.e_episode[j] = restitution_at_velocity(
                scene.material, max(vimp, 1e-12), scene.e_quantile, scene.outside
            )
            if model == "hertzdamp":
                self.zhd[j] = zeta_of_e(self.e_episode[j], max(vimp, 1e-12), self.relation)
            else:
                self.xi[j] = xi_of_e(self.e_episode[j], self.relation)
        elif model == "hertzdamp":
            self.zhd[j] = zeta_of_e(self.e_coef, max(vimp, 1e-12), self.relation)

    def _storeys(self):
        """Every storey's floors, stiffness, yield drift and law, and its branch at the start.

        Storeys: drift u_s = x[top] - x[bottom] (bottom -1: the ground); a bilinear storey
        resists alpha k u + (1 - alpha) k z, i.e. k u less (1 - alpha) k u_p with u_p = u - z
        its plastic drift; mode 0 elastic (u_p fixed), +1 / -1 yielding (z = +-u_y, u_p
        follows u).  A Bouc-Wen storey's z is a state of the ODE (after x and v), its smooth
        law needs no events; the last state is then its hysteretic dissipation
        (1 - alpha) k int z du_p.
        """
        s_top, s_bot, s_k, s_uy, s_alpha, s_side, s_h, s_bw = [], [], [], [], [], [], [], []
        for b, bld in enumerate(self.buildings):
            off = int(self.starts[b])
            heights = storey_heights(bld)
            for st in range(int(self.starts[b + 1]) - off):
                s_top.append(off + st)
                s_bot.append(off + st - 1 if st > 0 else -1)
                s_k.append(bld.storey_stiffness_N_per_m[st])
                s_uy.append(bld.yield_disp_m[st] if _yields(bld) else np.inf)
                s_alpha.append(bld.post_yield_ratio)
                s_side.append(b)  # the building's place from the left
                s_h.append(heights[st])
                s_bw.append(bld.bw_exponent if bld.hysteresis == "bouc-wen" else 0.0)
        self.s_top, self.s_bot = np.array(s_top), np.array(s_bot)
        self.s_k, self.s_uy = np.array(s_k, float), np.array(s_uy, float)
        self.s_alpha = np.array(s_alpha, float)
        self.s_side, self.s_h = s_side, s_h
        self.ns = self.s_top.size
        self.s_bw = np.array(s_bw, float)
        bw = self.s_bw > 0.0
        self.bw_idx = np.flatnonzero(bw)
        self.nz = self.bw_idx.size
        self.inelastic_storey = np.isfinite(self.s_uy)
        self.yielding = self.inelastic_storey & ~bw  # bilinear storeys (located events)
        self.uy_finite = np.where(self.inelastic_storey, self.s_uy, 0.0)
        # (1 - alpha) k of the yielding storeys, 0 elsewhere (a wall's infinite k never enters)
        self.k_plastic = (1.0 - self.s_alpha) * np.where(self.inelastic_storey, self.s_k, 0.0)
        self.s_mode = np.zeros(self.ns, dtype=int)
        self.s_up = np.zeros(self.ns)
        self.e_hyst = 0.0

    def drifts(self, x):
        """The storeys' drifts of the floor displacements ``x`` (rows of ``x`` where 2-d)."""
        s_bot = self.s_bot
        xb = (
            np.where(s_bot[:, None] >= 0, x[np.maximum(s_bot, 0)], 0.0)
            if x.ndim > 1
            else (np.where(s_bot >= 0, x[np.maximum(s_bot, 0)], 0.0))
        )
        return x[self.s_top] - xb

    def plastic_drift(self, u, yy=None):
        """The storeys' plastic drifts at drifts ``u`` (Bouc-Wen ones from the state ``yy``)."""
        up = np.where(self.s_mode == 0, self.s_up, u - self.s_mode * self.uy_finite)
        if self.nz and yy is not None:
            n = self.n
            up[self.bw_idx] = u[self.bw_idx] - yy[2 * n : 2 * n + self.nz]
        return up

    def _start(self, x0, v0, atol_scale):
        """The initial state, the solver's absolute tolerances and the contacts' phases."""
        n, nz, acc = self.n, self.nz, self.acc
        y = np.zeros(2 * n + (nz + 1 if nz else 0) + (1 if self.contact_work else 0))
        if x0 is not None:
            y[:n] = np.asarray(x0, dtype=float)
            y[2 * n : 2 * n + nz] = self.drifts(y[:n])[self.bw_idx]
        if v0 is not None:
            y[n : 2 * n] = np.asarray(v0, dtype=float)

        # tolerances
        omega_all = self.omega
        pga = float(np.max(np.abs(acc))) if self.npts else 0.0
        x_scale = max(pga / omega_all.min() ** 2, np.max(np.abs(y[:n])), 1e-300)
        x_scale = max(x_scale, np.max(np.abs(y[n : 2 * n])) / omega_all.min())
        atol = np.r_[
            np.full(n, atol_scale * x_scale), np.full(n, atol_scale * x_scale * omega_all.max())
        ]
        if nz:
            bw_idx = self.bw_idx
            e_scale = float(np.max(self.k_plastic[bw_idx] * self.uy_finite[bw_idx] * x_scale))
            atol = np.r_[atol, np.full(nz, atol_scale * x_scale), atol_scale * e_scale]
        if self.contact_work:
            m_finite = self.masses[np.isfinite(self.masses)]
            w_scale = float(m_finite.max()) * (x_scale * omega_all.max()) ** 2
            atol = np.r_[atol, atol_scale * w_scale]
        self.y, self.atol = y, atol

        # phases at the start (already in contact: by the sign of delta_dot, not counted)
        w, gap = self.w, self.gap
        self.phase = np.zeros(self.nc, dtype=int)
        for j in range(self.nc):
            d = w[j] @ y[:n] - gap[j]
            if d > 0.0:
                dd = w[j] @ y[n : 2 * n]
                self.phase[j] = APPROACH if dd > 0.0 else RESTITUTION
                self.start_episode(j, dd)
        # the ground acceleration ag0 + slope (t - t0) of the record interval being solved
        self.ag0 = self.slope = self.t0 = 0.0

    def _maxima(self):
        """The peaks, impacts and counters of the run, and the records at the samples."""
        n, nc, npts = self.n, self.nc, self.npts
        self.peak_x = np.zeros(n)
        self.peak_u = np.zeros(self.ns)
        self.peak_f = np.zeros(nc)
        self.peak_f_time = 0.0
        self.impacts = np.zeros(nc, dtype=int)
        self.pending = np.zeros(nc, dtype=bool)  # episodes not yet counted as impacts
        self.max_pen = np.full(nc, -np.inf)
        self.impact_times: list[float] = []
        self.segments = 0
        self.h_last = None
        # segments in a row that ended where they started: a contact whose penetration and its
        # rate are both zero (identical buildings at zero gap) switches onset -> turn ->
        # separation at one instant for ever; after one such round it runs to the end of the
        # interval without them
        self.stalled = 0
        for f_idx in range(n):
            self.peak_x[f_idx] = abs(self.y[f_idx])
        # floor displacements at the record's samples (the dense output of the segment holding
        # each)
        self.x_samples = np.full((npts, n), np.nan)
        self.x_samples[0] = self.y[:n]
        self.f_samples = np.zeros((npts, nc))  # contact forces there (0 while a contact is open)

    def forces(self, x, v):
        """The contacts' forces [N] at floor displacements ``x`` and velocities ``v``."""
        w, gap, phase = self.w, self.gap, self.phase
        f = np.zeros(self.nc)
        for j in range(self.nc):
            if phase[j] != OPEN:
                d = w[j] @ x - gap[j]
                dd = w[j] @ v
                f[j] = contact_force(self.model, d, dd, self.beta, self.xi[j], self.meff[j],
                                      self.zhd[j], phase[j])  # fmt: skip
        return f

    def rhs(self, t, yy):
        """The right-hand side ``y'`` at time ``t`` [s] in the record interval being solved."""
        n, masses, fixed, w = self.n, self.masses, self.fixed, self.w
        dy = self.a_lin @ yy[: 2 * n]
        dy[n:] -= self.ag0 + self.slope * (t - self.t0)
        dy[n + fixed] = 0.0
        power_c = 0.0
        if np.any(self.phase):
            f = self.forces(yy[:n], yy[n : 2 * n])
            dy[n:] -= (w.T @ f) / masses
            power_c = float(f @ (w @ yy[n : 2 * n]))
        if self.inelastic_storey.any():
            # the plastic drifts' forces (1 - alpha) k u_p pull the floor above a storey back
            # and push the floor below
            s_top, s_bot = self.s_top, self.s_bot
            fp = self.k_plastic * self.plastic_drift(self.drifts(yy[:n]), yy)
            np.add.at(dy, n + s_top, fp / masses[s_top])
            below = s_bot >= 0
            np.subtract.at(dy, n + s_bot[below], fp[below] / masses[s_bot[below]])
            dy[n + fixed] = 0.0
        if self.nz:
            # Bouc-Wen: z' = u' (1 - |z / u_y|^n (0.5 sign(u' z) + 0.5))
            bw_idx = self.bw_idx
            ud = self.drifts(yy[n : 2 * n])[bw_idx]
            z = yy[2 * n : 2 * n + self.nz]
            r = np.abs(z / self.uy_finite[bw_idx]) ** self.s_bw[bw_idx]
            zd = ud * (1.0 - r * (0.5 * np.sign(ud * z) + 0.5))
            power = np.sum(self.k_plastic[bw_idx] * z * (ud - zd))
            dy = np.r_[dy, zd, power]
        if self.contact_work:
            dy = np.r_[dy, power_c]
        return dy

    def unload(self, st, yy):
        """Storey ``st`` leaves its yielding branch at state ``yy`` (its new plastic drift).

        Returns the hysteretic energy of the plastic drift's change.
        """
        up_new = self.drifts(yy[: self.n])[st] - self.s_mode[st] * self.s_uy[st]
        energy = (
            (1.0 - self.s_alpha[st]) * self.s_k[st] * self.s_uy[st] * abs(up_new - self.s_up[st])
        )
        self.s_up[st] = up_new
        self.s_mode[st] = 0
        return energy

    def make_storey_event(self, st, which, direction):
        """Storey ``st``'s terminal event: its drift reaching yield, or its rate vanishing."""
        n, s_top, s_up, s_uy = self.n, self.s_top, self.s_up, self.s_uy
        bot = self.s_bot[st]

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

    def make_event(self, j, which, direction):
        """Contact ``j``'s terminal event: its penetration (``"d"``) or its rate crossing 0."""
        n, w, gap = self.n, self.w, self.gap
        if which == "d":

            def ev(_t, yy):
                return w[j] @ yy[:n] - gap[j]

        else:

            def ev(_t, yy):
                return w[j] @ yy[n : 2 * n]

        ev.terminal = True
        ev.direction = direction
        return ev

    def scan_segment(self, sol_t, dense):
        """Continuous-time maxima of |x| per floor and of the contact forces."""
        n, nc, dt_rec, npts = self.n, self.nc, self.dt_rec, self.npts
        w, gap, phase, peak_f = self.w, self.gap, self.phase, self.peak_f
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
            self.x_samples[k] = y_k[:n].T
        frac = np.linspace(0.0, 1.0, _SAMPLES_PER_STEP + 1)[:-1]
        grid = (tt[:-1, None] + np.diff(tt)[:, None] * frac[None, :]).ravel()
        grid = np.r_[grid, tt[-1]]
        yy = dense(grid)
        _raise_abs_peaks(self.peak_x, yy[:n], grid, dense)
        _raise_abs_peaks(self.peak_u, self.drifts(yy[:n]), grid, lambda t: self.drifts(dense(t)))
        for j in range(nc):
            if phase[j] == OPEN:
                continue

            def force_of(s, j=j):
                # penetration and its rate from the state (displacements, then velocities)
                d = w[j] @ s[:n] - gap[j]
                dd = w[j] @ s[n : 2 * n]
                return contact_force(self.model, d, dd, self.beta, self.xi[j], self.meff[j],
                                      self.zhd[j], phase[j])  # fmt: skip

            def force_at(t, force_of=force_of):
                return force_of(dense(t))

            if y_k is not None:
                self.f_samples[k, j] = force_of(y_k)
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
                    self.peak_f_time = t_best
                    self.peak_e, self.peak_xi = self.e_episode[j], self.xi[j]

    def _events(self):
        """The terminal events the phases and branches watch now, and what each is."""
        events, kinds = [], []
        phase = self.phase
        for j in range(self.nc if self.stalled < 3 else 0):
            if phase[j] == OPEN:
                events.append(self.ev_d_up[j])
                kinds.append((j, "onset"))
            elif phase[j] == APPROACH:
                events.append(self.ev_dd_down[j])
                kinds.append((j, "turn"))
            else:
                events.append(self.ev_d_down[j])
                kinds.append((j, "separation"))
                events.append(self.ev_dd_up[j])
                kinds.append((j, "reapproach"))
        for st in np.flatnonzero(self.yielding):
            if self.s_mode[st] == 0:
                for sign in (1.0, -1.0):
                    events.append(self.make_storey_event(st, "yield", sign))
                    kinds.append((st, "yield"))
            else:
                events.append(self.make_storey_event(st, "unload", -float(self.s_mode[st])))
                kinds.append((st, "unload"))
        return events, kinds

    def run(self, rtol):
        """Integrate the record interval by interval, segment by segment between events."""
        dt_rec, acc = self.dt_rec, self.acc
        for i in range(self.npts - 1):
            t_a = i * dt_rec
            t_b = (i + 1) * dt_rec
            self.ag0 = acc[i]
            self.slope = (acc[i + 1] - acc[i]) / dt_rec
            self.t0 = t_a
            t = t_a
            while t_b - t > 1e-14 * max(1.0, t_b):
                events, kinds = self._events()
                kw = {}
                if self.h_last is not None:
                    kw["first_step"] = min(self.h_last, t_b - t)
                sol = solve_ivp(
                    self.rhs,
                    (t, t_b),
                    self.y,
                    method="DOP853",
                    rtol=rtol,
                    atol=self.atol,
                    events=events,
                    dense_output=True,
                    **kw,
                )
                self.segments += 1
                if sol.status < 0:
                    raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
                if sol.t.size >= 2 and sol.t[-1] > sol.t[0]:
                    # not after an event at the segment's start (identical buildings touching by
                    # round-off at rest): its zero step is no first step for the next segment
                    steps = np.diff(sol.t)
                    self.h_last = float(steps.max())
                self.scan_segment(sol.t, sol.sol)
                self.y = sol.y[:, -1].copy()
                self.stalled = self.stalled + 1 if sol.t[-1] <= t else 0
                t = float(sol.t[-1])
                if sol.status == 1:
                    fired = [(float(te[0]), idx) for idx, te in enumerate(sol.t_events)
                             if te.size > 0]  # fmt: skip
                    _, idx = min(fired)
                    self._fire(*kinds[idx], t)

    def _fire(self, j, kind, t):
        """The event ``kind`` of contact or storey ``j`` at time ``t`` [s]: the new phases."""
        n, y, w, phase = self.n, self.y, self.w, self.phase
        if kind == "yield":
            u = self.drifts(y[:n])[j]
            self.s_mode[j] = 1 if u - self.s_up[j] > 0.0 else -1
        elif kind == "unload":
            self.e_hyst += self.unload(j, y)
        elif kind == "onset":
            phase[j] = APPROACH
            self.pending[j] = True  # an impact once the penetration is deep enough
            self.impact_times.append(t)
            self.start_episode(j, w[j] @ y[n : 2 * n])
            self.h_last = None  # let the solver choose a step for the stiff contact
        elif kind == "turn":
            phase[j] = RESTITUTION
            pen = w[j] @ y[:n] - self.gap[j]  # a maximum of the penetration
            self._count(j, pen)
        elif kind == "separation":
            phase[j] = OPEN
        else:
            phase[j] = APPROACH
        # a yielding storey already unloading: its event fell at this event's instant
        # and the solver reports one (a storey against a wall turns with the contact,
        # the same velocity vanishing); from the next segment's start, where it is past
        # zero, it would never be found and the storey would go on yielding
        rates = self.drifts(y[n : 2 * n])
        for st in np.flatnonzero(self.s_mode * rates < 0.0):
            self.e_hyst += self.unload(st, y)

    def _count(self, j, pen):
        """Contact ``j``'s episode reached penetration ``pen`` [m]: an impact once deep enough."""
        self.max_pen[j] = max(self.max_pen[j], pen)
        if self.pending[j] and pen > IMPACT_MIN_PENETRATION_M:
            self.impacts[j] += 1
            self.pending[j] = False
            self.impact_velocities.append(float(self.v_episode[j]))

    def results(self, t_wall):
        """The outputs of :func:`reference_solution` (``t_wall``: when it started)."""
        n, y, model, buildings, starts = self.n, self.y, self.model, self.buildings, self.starts
        # a record that ends inside an episode: its penetration so far counts (an impact once it
        # is deep enough, as the turn above would count it), as it does in the kernels
        for j in np.flatnonzero(self.phase != OPEN):
            pen = self.w[j] @ y[:n] - self.gap[j]
            self._count(j, pen)
        # "left" and "right": the first building and the last (in a row closed by a wall, the
        # building before it: a wall is no building; a pair's right wall stays "right")
        last = len(buildings) - 1
        if last > 1 and buildings[last].model == "wall":
            last -= 1
        x_left = self.peak_x[: starts[1]]
        x_right = self.peak_x[starts[last] : starts[last + 1]]
        u_end = self.drifts(y[:n])
        up_end = self.plastic_drift(u_end, y)
        e_hyst = self.e_hyst + float(np.sum(np.where(
            self.yielding, self.k_plastic * self.uy_finite * np.abs(up_end - self.s_up), 0
        )))  # fmt: skip
        if self.nz:
            e_hyst += float(y[2 * n + self.nz])
        storey_out = self._buildings(u_end, last)
        peak_e, total_impacts = self.peak_e, int(self.impacts.sum())
        if np.isfinite(peak_e):  # the law's rebound for that episode's damping, integrated here
            if model == "hertzdamp":
                peak_e = hertzdamp_rebound(peak_e, self.relation)
            elif model == "jankowski":
                peak_e = jankowski_rebound(self.peak_xi)
        energies = {}
        if self.contact_work:
            energies = _contact_energies(model, y[-1], self.w @ y[:n] - self.gap, self.phase,
                                         self.beta)  # fmt: skip
        return {
            "peak_force": float(self.peak_f.max()) if self.nc else 0.0,
            "peak_force_time": float(self.peak_f_time),
            "impacts": total_impacts,
            "max_penetration": float(self.max_pen.max()) if total_impacts else 0.0,
            "peak_disp_left": float(x_left.max()),
            "peak_disp_right": float(x_right.max()),
            "impact_times": self.impact_times,
            "impact_velocities": self.impact_velocities,
            "peak_force_restitution": float(peak_e),
            "contact_peak_force": self.peak_f.copy(),
            "contact_impacts": self.impacts.copy(),
            "x_end": y[:n].copy(),
            "v_end": y[n : 2 * n].copy(),
            "x_samples": self.x_samples,
            "f_samples": self.f_samples,
            "segments": self.segments,
            "wall_s": time.perf_counter() - t_wall,
            **storey_out,
            "peak_storey_drift": self.peak_u.copy(),
            "plastic_drift_end": up_end,
            "hysteretic_energy": e_hyst,
            **energies,
        }

    def _buildings(self, u_end, last):
        """Per building, and for the first and the ``last``: peaks, ductility and drifts."""
        peak_u, s_h, starts = self.peak_u, self.s_h, self.starts
        side_of = np.array(self.s_side)
        per_building = []
        for b, bld in enumerate(self.buildings):
            side = side_of == b
            duct = peak_u[side] / self.s_uy[side]
            mine = side & (np.array(s_h) > 0.0)  # storeys of known height (not an SDOF without one)
            hs = np.array(s_h)[mine]
            per_building.append({
                "building": b,
                "peak_disp": float(self.peak_x[starts[b] : starts[b + 1]].max()),
                "peak_ductility": float(duct.max()) if _yields(bld) else np.nan,
                "peak_drift": float(np.max(peak_u[mine] / hs)) if hs.size else np.nan,
                "residual_drift": float(np.max(np.abs(u_end[mine]) / hs)) if hs.size else np.nan,
            })  # fmt: skip
        storey_out = {"buildings": [r for r, bld in zip(per_building, self.buildings, strict=True)
                                    if bld.model != "wall"]}  # fmt: skip
        for name, b in (("left", 0), ("right", last)):
            for key in ("peak_ductility", "peak_drift", "residual_drift"):
                storey_out[f"{key}_{name}"] = per_building[b][key]
        return storey_out


def _contact_energies(model, work, penetration, phase, beta) -> dict:
    """``contact_work`` and ``dissipated_energy`` [J]: the work less the energy held at the end."""
    held = sum(stored(model, d, beta) for d, p in zip(penetration, phase, strict=True)
               if p != OPEN)  # fmt: skip
    return {"contact_work": float(work), "dissipated_energy": float(work) - held}
