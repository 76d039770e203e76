"""Boundary of the compiled integrators: names in, named arrays out.

Everything above :mod:`pound_mc.integrators` passes names (contact law, relation, method) and
receives outputs by name; the integer codes the kernels switch on and the positions of the
outputs in the kernels' vectors stay below this module.

Both buildings are integrated in their modal coordinates (:mod:`pound_mc.physics.structures`): for
each mode ``q'' + 2 zeta omega q' + omega^2 q = -gamma a_g(t) - sum_c F_c psi_c`` with
``psi_c = phi[left floor of c] - phi[right floor of c]``, so that the penetration of contact
``c`` is ``delta_c = psi_c . q - gap_c`` and its force pushes the floors apart.  The ground
acceleration is the record's samples linearly interpolated (``../shared/DESIGN.md`` section 2).

Methods and their codes: :mod:`~pound_mc.integrators.settings`.  Batches run on Python
threads (:func:`~pound_mc.integrators.numba_threads`), each calling a serial ``nogil`` kernel
over a slice of the simulations, one kernel per method family and structure, so that a run
compiles only the method it uses.

Every run returns the outputs of :data:`OUTPUTS` and a status: 0 ok, 1 unstable (non-finite or
diverging state, or an energy balance broken either way by more than
:data:`UNSTABLE_ENERGY_FRACTION` of the energy put in), 2 not converged (Newton).
Fixed-step methods report maxima over their step points.
"""

from __future__ import annotations

import functools
import math
from concurrent.futures import ThreadPoolExecutor
from typing import NamedTuple

import numba
import numpy as np

from pound_mc._jit import jit
from pound_mc.integrators.accuracy import (
    COMPANION_DT_S,
    COMPANION_SUBSTEPS,
    check_substeps,
    flag_inaccurate,
    output_change,
    shortest_contact_s,
)
from pound_mc.integrators.adaptive import adaptive
from pound_mc.integrators.adaptive_bilinear import adaptive_bilinear, bilinear_pair_steps
from pound_mc.integrators.adaptive_pair import adaptive_pair
from pound_mc.integrators.adaptive_rk import adaptive_rk
from pound_mc.integrators.central_hysteretic import central_hysteretic
from pound_mc.integrators.fixed import CENTRAL_DIFFERENCE, NEWMARK, NEWMARK_EXPLICIT, fixed
from pound_mc.integrators.hysteretic import N_STOREY_COLUMNS, newmark_hysteretic
from pound_mc.integrators.outputs import (
    C_MAX_PENETRATION,
    CONTACT_OUTPUTS,
    IMPACTS,
    MAX_PENETRATION,
    N_COUT,
    N_OUT,
    ONSET_SIZE,
    OUTPUTS,
    PEAK_DISP_LEFT,
    PEAK_DISP_RIGHT,
    PRE_MODE,
    PRE_RESUME,
    PRE_RESUME_ONSET,
    PRE_RUN_TO_CONTACT,
    STATUS,
    STATUS_NOT_CONVERGED,
    STATUS_OK,
    UNSTABLE_ENERGY_FRACTION,
    fail,
    pre_size,
)
from pound_mc.integrators.pair import newmark_pair
from pound_mc.integrators.settings import (
    ADAPTIVE,
    METHODS,
    KernelSettings,
    fixed_restitution,
    kernel_settings,
)
from pound_mc.integrators.toolkit import MAX_STEPS

__all__ = [
    "FINER_SIZE",
    "METHODS",
    "OUTPUTS",
    "CONTACT_OUTPUTS",
    "UNSTABLE_ENERGY_FRACTION",
    "KernelSettings",
    "KernelResult",
    "kernel_settings",
    "run_kernel",
    "simulate_sdof_pairs",
    "simulate_scene_batch",
]


class KernelResult(NamedTuple):
    """Outputs of one kernel run, by name.

    ``outputs``: ``{name: float}`` for :data:`OUTPUTS`; ``contacts``: ``{name: (n_contacts,)}``
    for :data:`CONTACT_OUTPUTS`; ``history``: ``(floor displacements, penetrations, forces)``
    at the record's samples, or None.
    """

    outputs: dict
    contacts: dict
    history: tuple | None
    #: Peak displacement [m] of each building code (``side``: 0 the first, 1 the last, 2...)
    code_peaks: np.ndarray


@jit(inline=True)
def _endless(ag, dt_rec, settings):
    """Whether the step bound is so small (or not positive) that the run could not end."""
    dt_s = settings.dt_s
    return not (dt_s > 0.0) or (ag.size - 1) * dt_rec / dt_s > MAX_STEPS


@jit(entry=True)
def _run_adaptive(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """One run of ``adaptive`` (method 0) on any pair of buildings (the general modal kernel).

    A step that could not end is not converged.
    """
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        return
    adaptive(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
             q, v, out, cout, hx, hd, hf, pre)  # fmt: skip


@jit(inline=True)
def _run_adaptive_pair(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """One run of ``adaptive`` on an SDOF pair: the scalar-state kernel (histories included).

    Chosen in Python (:func:`_is_sdof_pair`), so that SDOF studies never compile the general
    modal kernel; inlined into the batch kernel (one compiled layer fewer on a first run).
    """
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        return
    adaptive_pair(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                  settings, q, v, out, cout, hx, hd, hf, pre)  # fmt: skip


def _is_sdof_pair(omega, gap, phi) -> bool:
    """Two single-mode buildings and one contact (diagonal floor map)."""
    phi = np.asarray(phi)
    return (
        np.size(omega) == 2 and np.size(gap) == 1 and phi.shape == (2, 2)
        and phi[0, 1] == 0.0 and phi[1, 0] == 0.0
    )  # fmt: skip


@jit(entry=True)
def _run_fixed(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, pre,
):  # fmt: skip
    """One run of a fixed-step method: the scalar SDOF-pair kernel where it applies."""
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        return
    method = settings.method
    if (
        (method == NEWMARK or method == NEWMARK_EXPLICIT) and omega.size == 2 and gap.size == 1
        and phi.shape[0] == 2 and phi[0, 1] == 0.0 and phi[1, 0] == 0.0 and hx.shape[0] == 0
    ):  # fmt: skip
        newmark_pair(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                     settings, q, v, out, cout)  # fmt: skip
    else:
        fixed(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
              q, v, out, cout, hx, hd, hf)  # fmt: skip


def _inelastic_run(storeys, sout, kernel):
    """A run of an inelastic kernel with the storeys bound (the signature of ``_RUNS``).

    ``sout`` (storeys x 2) receives each storey's peak and final drift [m].  ``kernel``:
    ``"pair"`` (``adaptive`` on a bilinear SDOF pair, exact steps per branch), ``"rk"``
    (``adaptive`` on any other yielding scene, :mod:`~pound_mc.integrators.adaptive_rk`) or
    ``"newmark"`` (the inelastic ``newmark`` kernel, both variants) or ``"central"`` (the
    inelastic ``central-difference`` kernel).
    """
    dmat = np.ascontiguousarray(storeys[0], dtype=np.float64)
    store = np.ascontiguousarray(storeys[1], dtype=np.float64).reshape(-1, N_STOREY_COLUMNS)

    def run(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings, q, v,
            out, cout, hx, hd, hf, pre):  # fmt: skip
        if kernel == "pair":
            _run_adaptive_bilinear(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff,
                                   beta, xi, settings, q, v, out, cout, hx, hd, hf, store,
                                   sout)  # fmt: skip
        elif kernel == "rk":  # dt_s is its first step only: no bound to check
            adaptive_rk(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                        settings, q, v, out, cout, hx, hd, hf, dmat, store, sout)  # fmt: skip
        else:
            fixed_run = _run_central if kernel == "central" else _run_inelastic
            fixed_run(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                      settings, q, v, out, cout, hx, hd, hf, dmat, store, sout)  # fmt: skip

    return run


@jit
def _run_adaptive_bilinear(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, store, sout,
):  # fmt: skip
    """One run of ``adaptive`` on a bilinear SDOF pair; a step bound that cannot end fails."""
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        sout[:] = np.nan
        return
    adaptive_bilinear(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                      settings, q, v, out, cout, hx, hd, hf, store, sout)  # fmt: skip


@jit
def _run_inelastic(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """One run of the inelastic ``newmark`` kernel; a step that could not end is not converged."""
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        sout[:] = np.nan
        return
    newmark_hysteretic(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                       settings, q, v, out, cout, hx, hd, hf, dmat, store, sout)  # fmt: skip


@jit
def _run_central(
    ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi, settings,
    q, v, out, cout, hx, hd, hf, dmat, store, sout,
):  # fmt: skip
    """One run of the inelastic ``central-difference`` kernel, as :func:`_run_inelastic`."""
    if _endless(ag, dt_rec, settings):
        fail(out, cout, STATUS_NOT_CONVERGED)
        sout[:] = np.nan
        return
    central_hysteretic(ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap, meff, beta, xi,
                       settings, q, v, out, cout, hx, hd, hf, dmat, store, sout)  # fmt: skip


#: One run of each method (same arguments), by method code: a run compiles only its method's
#: kernel (numba compiles a kernel with everything it calls, on first use).
_RUNS = {
    ADAPTIVE: _run_adaptive,
    NEWMARK: _run_fixed,
    NEWMARK_EXPLICIT: _run_fixed,
    CENTRAL_DIFFERENCE: _run_fixed,
}


def _threaded(kernel, n: int, *args) -> None:
    """Call ``kernel(*args, lo, hi)`` over slices of ``range(n)`` on Python threads.

    As many threads as numba's thread count (:func:`~pound_mc.integrators.numba_threads`);
    the kernels release the GIL and each simulation writes only its own slots, so the results
    do not depend on the threads or on the slicing.
    """
    workers = min(numba.get_num_threads(), n)
    if workers <= 1:
        kernel(*args, 0, n)
        return
    # a few slices per thread balance simulations of unequal cost
    bounds = [int(b) for b in np.linspace(0, n, min(n, 4 * workers) + 1).round()]
    with ThreadPoolExecutor(workers) as pool:
        done = [
            pool.submit(kernel, *args, lo, hi)
            for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)
        ]
        for future in done:
            future.result()


def _named(out):
    """``{name: column}`` of an output matrix (one row per simulation) with integer counts."""
    result = {name: out[..., k] for k, name in enumerate(OUTPUTS)}
    result["impacts"] = result["impacts"].astype(np.int32)
    result["status"] = result["status"].astype(np.int8)
    result["steps"] = result["steps"].astype(np.int64)
    return result


#: The empty ``pre`` of a plain run (kernels never write an empty array).
_NO_PRE = np.zeros(0)
#: Length of :func:`run_kernel`'s ``finer_start``.
FINER_SIZE = 1 + ONSET_SIZE


@functools.lru_cache(maxsize=64)
def _no_histories(nf: int, nc: int) -> tuple:
    """Empty history arrays of a run without histories (shared: nothing writes them)."""
    return np.zeros((0, nf)), np.zeros((0, nc)), np.zeros((0, nc))


def run_kernel(
    ag,
    dt_rec,
    omega,
    zeta,
    gamma,
    phi,
    side,
    psi,
    gap,
    meff,
    beta,
    xi,
    *,
    model: str = "jankowski",
    method: str = "adaptive",
    relation: str | None = None,
    dt_s: float = 0.001,
    substeps: int = 16,
    q0=None,
    v0=None,
    history: bool = False,
    storeys=None,
    restitution: dict | None = None,
    storey_out=None,
    contact_steps_flag: bool = True,
    finer_start=None,
    resume=None,
) -> KernelResult:
    """Run one simulation on prepared modal arrays.

    :func:`pound_mc.scene.simulate` is the scene-level entry point; the arrays are those of
    :meth:`pound_mc.scene.Scene.modal_arrays` (``xi`` the damping ratio per contact, the
    restitution ``e`` for ``hertzdamp``).

    Parameters
    ----------
    model, method, relation : str
        Contact law, integration method and the law's damping relation (None: its default).
    dt_s : float
        Step (fixed-step methods) or bound on the steps between contacts [s].
    substeps : int
        Contact sub-steps per estimated contact duration (``adaptive``).
    q0, v0 : array_like, optional
        Initial modal state (default at rest).
    history : bool
        Also return histories at the record's samples (NaN after a run that stopped).
    storeys : tuple (drift rows, storey table), optional
        Yielding storeys (:meth:`pound_mc.scene.Scene.storey_arrays`): run the inelastic
        kernel (``newmark``, ``newmark-explicit``, or ``adaptive`` for an SDOF pair).
    restitution : dict, optional
        Restitution set per impact (:func:`kernel_settings`); ``xi`` then holds its quantile.
    storey_out : numpy.ndarray, optional
        ``(n_storeys, 2)`` float array that receives each yielding run's storey peak
        ``|drift|`` and final drift [m] (rows as the storey table; NaN unless ok).
    contact_steps_flag : bool
        Flag a fixed-step run ``inaccurate`` where its shortest contact lasts fewer than
        :data:`~pound_mc.integrators.accuracy.MIN_STEPS_PER_CONTACT` steps (the criterion of a
        run without the accuracy check; :func:`pound_mc.scene.simulate` runs the check).
    finer_start : numpy.ndarray, optional
        :data:`FINER_SIZE` values that receive (``adaptive`` on an SDOF pair, else NaN) 1.0
        where the accuracy check's finer run would be this run, bit for bit (no sub-step
        shortened by a bound set by ``substeps``), else 0; then the state at the last contact
        onset up to which it is this run.
    resume : numpy.ndarray, optional
        ``finer_start[1:]`` of a run of the same pair: run from there (``PRE_RESUME_ONSET``),
        for the peak force and the floors' peaks alone (the accuracy check's finer run).
    """
    settings = kernel_settings(model, method, relation=relation, dt_s=dt_s, substeps=substeps,
                               restitution=restitution)  # fmt: skip
    pair = _is_sdof_pair(omega, gap, phi)
    n = omega.size
    nc = gap.size
    nf = phi.shape[0]
    q = np.zeros(n) if q0 is None else np.array(q0, dtype=float)
    v = np.zeros(n) if v0 is None else np.array(v0, dtype=float)
    # a row's buildings past the first and last: each code's peak past the outputs
    n_codes = int(np.max(side)) + 1 if np.size(side) else 0
    run = _RUNS[settings.method]
    if run is _run_adaptive and pair and storeys is None:
        run = _run_adaptive_pair
    # past the outputs: each code's peak (a row), or a pair's finer_start
    onsets = ONSET_SIZE if finer_start is not None and resume is None else 0
    out = np.empty(N_OUT + (n_codes if n_codes > 2 else (1 + onsets) * (run is _run_adaptive_pair)))
    pre = _NO_PRE
    if resume is not None and run is _run_adaptive_pair:
        pre = np.array(resume, dtype=np.float64)
        pre[PRE_MODE] = PRE_RESUME_ONSET
    cout = np.empty((nc, N_COUT))
    if history:  # NaN where a run that stopped (unstable, not converged) did not reach
        hx, hd, hf = (np.full((ag.size, k), np.nan) for k in (nf, nc, nc))
    else:
        hx, hd, hf = _no_histories(nf, nc)
    f8 = np.float64
    if storeys is not None:
        if storey_out is None:
            storey_out = np.empty((np.size(storeys[1]) // N_STOREY_COLUMNS, 2))
        kernel = "central" if settings.method == CENTRAL_DIFFERENCE else "newmark"
        if settings.method == ADAPTIVE:
            steps = pair and settings.rest_v.size == 0
            kernel = "pair" if steps and bilinear_pair_steps(storeys[1], zeta) else "rk"
        run = _inelastic_run(storeys, storey_out, kernel)
    run(
        np.ascontiguousarray(ag, dtype=f8), f8(dt_rec),
        np.ascontiguousarray(omega, dtype=f8), np.ascontiguousarray(zeta, dtype=f8),
        np.ascontiguousarray(gamma, dtype=f8), np.ascontiguousarray(phi, dtype=f8),
        np.ascontiguousarray(side, dtype=np.int64), np.ascontiguousarray(psi, dtype=f8),
        np.ascontiguousarray(gap, dtype=f8), np.ascontiguousarray(meff, dtype=f8),
        np.ascontiguousarray(beta, dtype=f8), np.ascontiguousarray(xi, dtype=f8),
        settings, q, v, out, cout, hx, hd, hf, pre,
    )  # fmt: skip
    fixed_restitution(out, settings, xi[0] if np.size(xi) else 0.0)
    if settings.method != ADAPTIVE and contact_steps_flag:
        t_c = shortest_contact_s(model, cout[:, C_MAX_PENETRATION], beta, meff).min()
        out[STATUS] = flag_inaccurate(out[STATUS], out[IMPACTS], t_c, dt_s)
    outputs = dict(zip(OUTPUTS, out[:N_OUT].tolist(), strict=True))
    contacts = dict(zip(CONTACT_OUTPUTS, cout.T.copy(), strict=True))
    code_peaks = out[N_OUT:].copy() if n_codes > 2 else out[[PEAK_DISP_LEFT, PEAK_DISP_RIGHT]]
    if finer_start is not None:
        finer_start[:] = np.nan
        if run is _run_adaptive_pair:
            finer_start[: out.size - N_OUT] = out[N_OUT:]
    return KernelResult(outputs, contacts, (hx, hd, hf) if history else None, code_peaks)


@jit(inline=True)
def _with_step(settings, dt_s):
    """``settings`` with the step bound ``dt_s`` of one simulation."""
    return KernelSettings(settings.model, settings.relation, settings.method, dt_s,
                          settings.substeps, settings.outside, settings.rest_floor,
                          settings.xi_e0, settings.xi_de, settings.rest_v, settings.rest_lo,
                          settings.rest_hi, settings.xi_tab)  # fmt: skip


@jit(inline=True)
def _sdof_arrays(k, tl, zl, ml, tr, zr, mr, gap, beta, xi):
    """Modal arrays of SDOF pair ``k`` (mass-normalised: q = sqrt(m) x)."""
    omega = np.empty(2)
    zeta = np.empty(2)
    gamma = np.empty(2)
    phi = np.zeros((2, 2))
    side = np.zeros(2, dtype=np.int64)
    side[1] = 1
    psi = np.empty((1, 2))
    omega[0] = 2.0 * math.pi / tl[k]
    omega[1] = 2.0 * math.pi / tr[k]
    zeta[0] = zl[k]
    zeta[1] = zr[k]
    gamma[0] = math.sqrt(ml[k])
    gamma[1] = math.sqrt(mr[k])
    phi[0, 0] = 1.0 / gamma[0]
    phi[1, 1] = 1.0 / gamma[1]
    psi[0, 0] = phi[0, 0]
    psi[0, 1] = -phi[1, 1]
    g = np.full(1, gap[k])
    me = np.full(1, ml[k] * mr[k] / (ml[k] + mr[k]))
    be = np.full(1, beta[k])
    x = np.full(1, xi[k])
    return omega, zeta, gamma, phi, side, psi, g, me, be, x


@jit
def _sdof_adaptive(ag, dt_rec, tl, zl, ml, tr, zr, mr, gap, beta, xi, dt_s, settings, out,
                   index, group, shared, mode, lo, hi):  # fmt: skip
    """``adaptive``: simulations ``index[lo:hi]``, or the linear response of groups ``lo:hi``.

    A group gathers the simulations that differ only in contact parameters.  With ``mode``
    ``PRE_RUN_TO_CONTACT``, its linear response up to the first contact is run once, from
    member ``index[g]``, into ``shared[g]``; else every simulation ``k`` resumes from
    ``shared[group[k]]`` in that mode (``PRE_RESUME``, or ``PRE_RESUME_PEAK`` and
    ``PRE_RESUME_ONSET`` for the peak force (and the floors' peaks),
    :mod:`~pound_mc.integrators.outputs`).
    One kernel for every pass: the SDOF-pair kernel is linked into one compiled caller, not
    several.
    """
    empty = np.zeros((0, 2))
    empty1 = np.zeros((0, 1))
    for i in range(lo, hi):
        k = index[i]
        omega, zeta, gamma, phi, side, psi, g, me, be, x = _sdof_arrays(
            k, tl, zl, ml, tr, zr, mr, gap, beta, xi
        )
        o = np.empty(N_OUT) if mode == PRE_RUN_TO_CONTACT else out[k]
        _run_adaptive_pair(ag, dt_rec, omega, zeta, gamma, phi, side, psi, g, me, be, x,
                           _with_step(settings, dt_s[k]), np.zeros(2), np.zeros(2), o,
                           np.empty((1, N_COUT)), empty, empty1, empty1,
                           _member_pre(i, k, group, shared, mode))  # fmt: skip


@jit(inline=True)
def _member_pre(i, k, group, shared, mode):
    """The ``pre`` of pass entry ``i`` (simulation ``k``) of a grouped batch kernel, in ``mode``.

    ``PRE_RUN_TO_CONTACT``: group ``i``'s own row of ``shared``, which the run fills; else a
    copy of simulation ``k``'s group row to resume from (each run writes its own).
    """
    pre = shared[i] if mode == PRE_RUN_TO_CONTACT else shared[group[k]].copy()
    pre[PRE_MODE] = mode
    return pre


def _linear_groups(key) -> tuple[np.ndarray, np.ndarray]:
    """Groups of the simulations whose rows of ``key`` are equal (the same linear response).

    Returns the first member of each group and each simulation's group, both int64.
    """
    _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return first.astype(np.int64), group.ravel().astype(np.int64)


@jit
def _sdof_fixed(ag, dt_rec, tl, zl, ml, tr, zr, mr, gap, beta, xi, dt_s, settings, out, lo,
                hi):  # fmt: skip
    """A fixed-step method: simulations ``lo:hi``."""
    empty = np.zeros((0, 2))
    empty1 = np.zeros((0, 1))
    for k in range(lo, hi):
        omega, zeta, gamma, phi, side, psi, g, me, be, x = _sdof_arrays(
            k, tl, zl, ml, tr, zr, mr, gap, beta, xi
        )
        _run_fixed(ag, dt_rec, omega, zeta, gamma, phi, side, psi, g, me, be, x,
                   _with_step(settings, dt_s[k]), np.zeros(2), np.zeros(2), out[k],
                   np.empty((1, N_COUT)), empty, empty1, empty1, np.zeros(0))  # fmt: skip


def simulate_sdof_pairs(
    acc,
    dt_rec,
    *,
    left_period_s,
    left_damping_ratio,
    left_mass_kg,
    right_period_s,
    right_damping_ratio,
    right_mass_kg,
    gap_m,
    beta,
    xi,
    dt_s,
    method: str = "adaptive",
    contact_model: str = "jankowski",
    relation: str | None = None,
    substeps: int = 16,
    restitution: dict | None = None,
    accuracy_check: bool = True,
) -> dict[str, np.ndarray]:
    """Run many SDOF-pair simulations on one record in threads.

    Every argument after ``dt_rec`` is an array with one value per simulation (or a scalar);
    ``xi`` is the damping ratio (the restitution ``e`` for ``hertzdamp``), ``relation`` the
    law's damping relation (None: its default).  Returns ``{output name: array}`` for every
    name in :data:`OUTPUTS`; each simulation writes only its own slot, so results do not
    depend on the number of threads.  ``restitution``: set per impact (:func:`kernel_settings`;
    ``xi`` then holds its quantile).  ``accuracy_check``: run the second, finer run of
    :mod:`~pound_mc.integrators.accuracy` that flags ``inaccurate`` runs (False: only the
    steps-per-contact criterion of the fixed-step methods).
    """
    settings = kernel_settings(contact_model, method, relation=relation, substeps=substeps,
                               restitution=restitution)  # fmt: skip
    arrays = [
        left_period_s, left_damping_ratio, left_mass_kg, right_period_s, right_damping_ratio,
        right_mass_kg, gap_m, beta, xi, dt_s,
    ]  # fmt: skip
    arrays = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in arrays])
    arrays = [np.array(a.ravel(), order="C") for a in arrays]  # writable: one compiled type
    nsim = arrays[0].size
    acc = np.ascontiguousarray(acc, dtype=np.float64)
    dt_rec = float(dt_rec)
    if settings.method != ADAPTIVE:
        out = np.empty((nsim, N_OUT))
        _threaded(_sdof_fixed, nsim, acc, dt_rec, *arrays, settings, out)
        fixed_restitution(out, settings, arrays[8])
        if accuracy_check:  # against adaptive at its defaults (pound_mc.integrators.accuracy)
            hit = np.flatnonzero(out[:, STATUS] == STATUS_OK)
            other = np.full((nsim, N_OUT), np.nan)
            other[hit] = _sdof_adaptive_batch(
                acc, dt_rec, [a[hit] for a in arrays[:9]], _companion(settings),
                np.full(hit.size, COMPANION_DT_S),
            )[:, :N_OUT]  # fmt: skip
            out[:, STATUS] = flag_inaccurate(out[:, STATUS], None, np.inf, 0.0,
                                             change=output_change(out, other))  # fmt: skip
        else:
            ml, mr, beta_k, dt_k = arrays[2], arrays[5], arrays[7], arrays[9]
            t_c = shortest_contact_s(contact_model, out[:, MAX_PENETRATION], beta_k,
                                     ml * mr / (ml + mr))  # fmt: skip
            out[:, STATUS] = flag_inaccurate(out[:, STATUS], out[:, IMPACTS], t_c, dt_k)
        return _named(out)
    out = _sdof_adaptive_batch(acc, dt_rec, arrays[:9], settings, arrays[9])
    fixed_restitution(out, settings, arrays[8])
    if accuracy_check:
        # the finer run gives its peak force and the floors' peaks (those of a full run,
        # faster), from the last contact onset up to which it is the run; a run whose finer
        # run would take its very sub-steps (the slot past the outputs) is not run again
        check_substeps(out, settings, lambda hit, finer, fine: _threaded(
            _sdof_adaptive, hit.size, acc, dt_rec, *[a[hit] for a in arrays], finer, fine,
            np.arange(hit.size, dtype=np.int64), np.arange(hit.size, dtype=np.int64),
            out[hit, N_OUT + 1 :], PRE_RESUME_ONSET,
        ), same=out[:, N_OUT] == 1.0)  # fmt: skip
    return _named(out[:, :N_OUT])


def _sdof_adaptive_batch(acc, dt_rec, arrays, settings, dt_s) -> tuple:
    """``adaptive`` on SDOF pairs (``arrays``: :func:`simulate_sdof_pairs`'s first nine).

    Simulations that differ only in contact parameters share their linear response up to the
    first contact (periods, damping ratios, masses, gap and step define a group): it is run
    once per group into ``shared``, and every simulation resumes from its group's row.
    Returns the outputs; past them a slot (1 where the accuracy check's finer run would be the
    run) and the state from which that run may start (``PRE_RESUME_ONSET``).
    """
    arrays = [*arrays, np.array(dt_s, dtype=np.float64, order="C")]
    nsim = arrays[0].size
    first, group = _linear_groups(np.stack([arrays[k] for k in (0, 1, 2, 3, 4, 5, 6, 9)], axis=1))
    shared = np.zeros((first.size, pre_size(2, 2)))
    out = np.zeros((nsim, N_OUT + 1 + ONSET_SIZE))
    _threaded(_sdof_adaptive, first.size, acc, dt_rec, *arrays, settings, out, first, group,
              shared, PRE_RUN_TO_CONTACT)  # fmt: skip
    everyone = np.arange(nsim, dtype=np.int64)
    _threaded(_sdof_adaptive, nsim, acc, dt_rec, *arrays, settings, out, everyone, group, shared,
              PRE_RESUME)  # fmt: skip
    return out


def _companion(settings):
    """The settings of the ``adaptive`` run a fixed-step run is compared with (its defaults)."""
    return settings._replace(method=ADAPTIVE, substeps=float(COMPANION_SUBSTEPS))


@jit(inline=True)
def _scene_args(k, ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap, beta, xi, dt_s,
                settings, out, cout, pre):  # fmt: skip
    """The kernel arguments of simulation ``k`` of one pair of buildings (no histories)."""
    n = omega.size
    nc = psi.shape[0]
    empty1 = np.zeros((0, nc))
    return (ag, dt_rec, omega, zeta, gamma, phi, side, psi, gap[k].copy(), meff,
            np.full(nc, beta[k]), np.full(nc, xi[k]), _with_step(settings, dt_s[k]), np.zeros(n),
            np.zeros(n), out[k], cout[k], np.zeros((0, phi.shape[0])), empty1, empty1,
            pre)  # fmt: skip


@jit
def _scene_adaptive(ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap, beta, xi, dt_s,
                    settings, out, cout, index, group, shared, mode, lo, hi):  # fmt: skip
    """``adaptive``: simulations ``index[lo:hi]`` of one pair of buildings, or groups ``lo:hi``.

    As :func:`_sdof_adaptive`: with ``mode`` ``PRE_RUN_TO_CONTACT`` the linear response of
    group ``g`` up to its first contact is run once, from member ``index[g]``, into
    ``shared[g]``; else every simulation ``k`` resumes from ``shared[group[k]]`` in that mode
    (``PRE_RESUME``, or ``PRE_RESUME_PEAK`` for the peak force alone).
    """
    for i in range(lo, hi):
        k = index[i]
        _run_adaptive(*_scene_args(k, ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap,
                                   beta, xi, dt_s, settings, out, cout,
                                   _member_pre(i, k, group, shared, mode)))  # fmt: skip


@jit
def _scene_fixed(ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap, beta, xi, dt_s,
                 settings, out, cout, pre, lo, hi):  # fmt: skip
    """A fixed-step method: simulations ``lo:hi`` of one pair of buildings (``pre`` empty)."""
    for k in range(lo, hi):
        _run_fixed(*_scene_args(k, ag, dt_rec, omega, zeta, gamma, phi, side, psi, meff, gap,
                                beta, xi, dt_s, settings, out, cout, pre))  # fmt: skip


def simulate_scene_batch(
    acc,
    dt_rec,
    arrays: dict,
    *,
    gap_m,
    beta,
    xi,
    dt_s,
    method: str = "adaptive",
    contact_model: str = "jankowski",
    relation: str | None = None,
    substeps: int = 16,
    restitution: dict | None = None,
    accuracy_check: bool = True,
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Run many simulations of one pair of buildings (any model) on one record, in threads.

    Parameters
    ----------
    acc, dt_rec
        Ground acceleration [m/s^2] and its sampling interval [s].
    arrays : dict
        :meth:`pound_mc.scene.Scene.modal_arrays` of the pair (shared by every simulation).
    gap_m : array_like
        Gaps [m], shape ``(nsim,)`` (every contact) or ``(nsim, n_contacts)``.
    beta, xi, dt_s : array_like
        Per simulation: impact stiffness [N/m^1.5, or N/m for linear laws], damping ratio (the
        restitution ``e`` for ``hertzdamp``) and step bound [s].
    method, contact_model, relation : str
        Integration method, contact law and its damping relation (None: the law's default).
    substeps : int
        Contact sub-steps per estimated contact duration (``adaptive``).
    restitution : dict, optional
        Restitution set per impact (:func:`kernel_settings`; ``xi`` then holds its quantile).
    accuracy_check : bool
        Run the second, finer run of :mod:`~pound_mc.integrators.accuracy` that flags
        ``inaccurate`` runs (False: only the steps-per-contact criterion of the fixed-step
        methods).

    Returns
    -------
    outputs : dict
        ``{name: (nsim,)}`` for every name in :data:`OUTPUTS`.
    contacts : dict
        ``{name: (nsim, n_contacts)}`` for every name in :data:`CONTACT_OUTPUTS`.
    """
    settings = kernel_settings(contact_model, method, relation=relation, substeps=substeps,
                               restitution=restitution)  # fmt: skip
    nc = arrays["psi"].shape[0]
    beta, xi, dt_s = np.broadcast_arrays(
        *[np.asarray(a, dtype=np.float64) for a in (beta, xi, dt_s)]
    )
    # writable copies: numba compiles a read-only (broadcast) array as another type
    beta, xi, dt_s = (np.array(a.ravel(), order="C") for a in (beta, xi, dt_s))
    nsim = beta.size
    gap = np.asarray(gap_m, dtype=np.float64)
    gap = np.array(
        np.broadcast_to(gap.reshape(gap.shape[0] if gap.ndim else 1, -1), (nsim, nc)), order="C"
    )
    out = np.empty((nsim, N_OUT))
    cout = np.empty((nsim, nc, N_COUT))
    f8 = np.float64
    pair = (
        np.ascontiguousarray(acc, dtype=f8),
        f8(dt_rec),
        *(np.ascontiguousarray(arrays[k], dtype=f8) for k in ("omega", "zeta", "gamma", "phi")),
        np.ascontiguousarray(arrays["side"], dtype=np.int64),
        np.ascontiguousarray(arrays["psi"], dtype=f8),
        np.ascontiguousarray(arrays["meff"], dtype=f8),
        gap,
        beta,
        xi,
    )  # fmt: skip
    if settings.method != ADAPTIVE:
        _threaded(_scene_fixed, nsim, *pair, dt_s, settings, out, cout, _NO_PRE)
        fixed_restitution(out, settings, xi)  # before the flags: runs flagged keep their numbers
        if accuracy_check:  # against adaptive at its defaults (pound_mc.integrators.accuracy)
            hit = np.flatnonzero(out[:, STATUS] == STATUS_OK)
            other, other_cout = np.full_like(out, np.nan), np.full_like(cout, np.nan)
            other[hit], other_cout[hit] = _scene_adaptive_batch(
                pair[:-3], gap[hit], beta[hit], xi[hit], np.full(hit.size, COMPANION_DT_S),
                _companion(settings),
            )[:2]  # fmt: skip
            change = output_change(out, other, cout, other_cout)
            out[:, STATUS] = flag_inaccurate(out[:, STATUS], None, np.inf, 0.0, change=change)
        else:
            meff = np.asarray(arrays["meff"], dtype=f8)[None, :]
            t_c = shortest_contact_s(contact_model, cout[:, :, C_MAX_PENETRATION],
                                     beta[:, None], meff).min(axis=1)  # fmt: skip
            out[:, STATUS] = flag_inaccurate(out[:, STATUS], out[:, IMPACTS], t_c, dt_s)
    else:
        out, cout, group, shared = _scene_adaptive_batch(pair[:-3], gap, beta, xi, dt_s,
                                                         settings)  # fmt: skip
        fixed_restitution(out, settings, xi)
        if accuracy_check:  # the finer run resumes from the shared linear response
            check_substeps(out, settings, lambda hit, finer, fine, fine_cout: _threaded(
                _scene_adaptive, hit.size, *pair[:-3], gap[hit], beta[hit], xi[hit], dt_s[hit],
                finer, fine, fine_cout, np.arange(hit.size, dtype=np.int64), group[hit],
                shared, PRE_RESUME,
            ), cout=cout)  # fmt: skip
    contacts = {name: cout[:, :, k] for k, name in enumerate(CONTACT_OUTPUTS)}
    contacts["impacts"] = contacts["impacts"].astype(np.int32)
    return _named(out), contacts


def _scene_adaptive_batch(buildings, gap, beta, xi, dt_s, settings) -> tuple:
    """``adaptive`` on many simulations of one pair of buildings.

    ``buildings``: the record and the modal arrays, in :func:`_scene_args`'s order up to
    ``meff``.

    Simulations with the same gaps and step share their linear response up to the first
    contact: run once per group into ``shared``, every simulation resumes from its group's
    row.  Returns the outputs, the per-contact outputs, each simulation's group and ``shared``.
    """
    nsim, nc = gap.shape
    first, group = _linear_groups(np.column_stack([gap, dt_s]))
    omega, phi = buildings[2], buildings[5]
    shared = np.zeros((first.size, pre_size(omega.size, phi.shape[0])))
    out, cout = np.empty((nsim, N_OUT)), np.empty((nsim, nc, N_COUT))
    _threaded(_scene_adaptive, first.size, *buildings, gap, beta, xi, dt_s, settings,
              np.empty_like(out), np.empty_like(cout), first, group, shared,
              PRE_RUN_TO_CONTACT)  # fmt: skip
    _threaded(_scene_adaptive, nsim, *buildings, gap, beta, xi, dt_s, settings, out, cout,
              np.arange(nsim, dtype=np.int64), group, shared, PRE_RESUME)  # fmt: skip
    return out, cout, group, shared
