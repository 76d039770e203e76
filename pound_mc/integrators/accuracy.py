"""The accuracy flag ``inaccurate``: every run that could be off is judged by a second run.

A run that ends ``ok`` may still be off: its energy balance closes while a fixed step resolves
a contact in a few steps (peak forces off by tens of percent), shifts the phase of a stiff
building (a 0.05-s building at 5 ms), or while repeated pounding of a light, stiff building
amplifies the error ``adaptive`` leaves at each impact (1e-5 a thousandfold within ten
impacts).  With ``integrator.accuracy_check`` on (the default), every path that runs a scene
(:func:`pound_mc.scene.simulate`, ``pound-mc simulate``, the batches of a study,
:func:`~pound_mc.integrators.simulate_sdof_pairs` and
:func:`~pound_mc.integrators.simulate_scene_batch`) compares each ``ok`` run with a second
run and flags it ``inaccurate`` (:data:`STATUS_INACCURATE`; its numbers are kept) where the
two differ by more than :data:`TOLERANCE` in any judged quantity (:func:`judged_change`): the
peak force, each contact's peak force (against the run's peak force, so that a contact that
barely touches does not flag everything), each building's peak displacement (against the
larger building's) and, with yielding buildings, each building's peak ductility (against the
larger one).  A run flagged for its displacements alone may have had no contact.

The second run:

* a fixed-step run (``newmark``, ``newmark-explicit``, ``central-difference``) is compared with
  ``adaptive`` at the scene file's defaults (:data:`COMPANION_DT_S`, :data:`COMPANION_SUBSTEPS`):
  exact between contacts, every contact sub-stepped, so the difference is the fixed-step run's
  error, not a change of it.  Step doubling (``dt_s / 2``), the check before, moved the
  ``newmark`` case of issue #38 (El Centro at 0.3 g, 8-s 100-kg building against a 1-s one at
  zero gap, beta 1e7, e 0.1, ``dt_s`` 1e-3) by 0.34 % while it was 3.7 % off; the ``adaptive``
  run costs about as much as ``newmark`` at 1e-3 s on an SDOF pair (B1: 0.84 against 0.82 ms),
  the run at ``dt_s / 2`` twice as much.
* an ``adaptive`` run is run again with :data:`ADAPTIVE_SUBSTEPS_FACTOR` times the contact
  sub-steps (step doubling on the sub-steps): one impact is resolved to about 1e-5, and the
  change from 16 to 32 sub-steps is the error's order where impacts amplify it.  Runs that
  cannot move are not run again (:func:`substep_check_due`): a run without contact (its steps
  are exact) and an SDOF-pair run none of whose sub-steps a bound set by ``substeps`` would
  shorten at the finer setting (the finer run would take the same sub-steps, bit for bit).
  The SDOF pairs' finer run starts at the last contact onset up to which it is the run and
  computes the peak force and the floors' peaks alone (``PRE_RESUME_ONSET``); the general
  kernel's is a full run from the shared linear response (its contacts' peak forces too).

A run whose second run fails (unstable, not converged) is flagged.  Without the check
(``accuracy_check = false``) a fixed-step run is still flagged where its shortest contact, by
the elastic estimate :func:`shortest_contact_s`, lasts fewer than
:data:`MIN_STEPS_PER_CONTACT` steps (free: from the run's own outputs).

Measured by :mod:`pound_mc.numerics.accuracy_drill` (``docs/integrators.md``): on an extreme
grid of SDOF, shear and yielding pairs against the SciPy reference (800-1,000 runs a method),
no run of any method ``ok`` while more than 1 % off, none within 0.5 % flagged.  Its cost:
one second run where it is due; ``studies/benchmark.toml`` (every run pounds, 79 % with a
sub-step bound set by ``substeps``) runs at about 0.6 of its throughput without the check.
"""

from __future__ import annotations

import numpy as np

from pound_mc.integrators.outputs import (
    C_PEAK_FORCE,
    IMPACTS,
    N_OUT,
    PEAK_DISP_LEFT,
    PEAK_DISP_RIGHT,
    PEAK_FORCE,
    STATUS,
    STATUS_OK,
)
from pound_mc.physics.contact import CONTACT_MODELS

__all__ = [
    "MIN_STEPS_PER_CONTACT",
    "TOLERANCE",
    "PEAK_FORCE_TOLERANCE",
    "STATUS_INACCURATE",
    "ADAPTIVE_SUBSTEPS_FACTOR",
    "COMPANION_DT_S",
    "COMPANION_SUBSTEPS",
    "shortest_contact_s",
    "judged_change",
    "flag_inaccurate",
    "substep_check_due",
    "judged_outputs",
    "output_change",
    "check_substeps",
]

#: Status of an ``ok`` run the check finds off.
STATUS_INACCURATE = 3
#: Fewest steps per (shortest) contact duration of a fixed-step run that is ``ok`` without the
#: check: sampling a half-sine force pulse with ``n`` steps misses its peak by up to
#: ``1 - cos(pi / n)``, below 1 % from ``n = 23``; 25 leaves room for the period error.
MIN_STEPS_PER_CONTACT = 25
#: Largest relative difference of a judged quantity between a run and its second run for the
#: run to stay ``ok``: half of the 1 % aimed at (the second run has an error of its own, and
#: the change from ``substeps`` to twice as many is 15/16 of the error only asymptotically).
TOLERANCE = 0.005
#: The name of :data:`TOLERANCE` while the check judged the peak force alone.
PEAK_FORCE_TOLERANCE = TOLERANCE
#: ``adaptive``'s check runs with this many times the contact sub-steps (a power of two: the
#: SDOF-pair kernel's bounds at the finer setting are then its own, scaled exactly).
ADAPTIVE_SUBSTEPS_FACTOR = 2
#: Step bound [s] and contact sub-steps of the ``adaptive`` run a fixed-step run is compared
#: with: the defaults of the scene file's ``[integrator]`` (held to 1e-5 of the SciPy
#: reference by the tests).
COMPANION_DT_S, COMPANION_SUBSTEPS = 1.0e-3, 16


def shortest_contact_s(contact_model: str, max_penetration, beta, m_eff) -> np.ndarray:
    """Elastic estimate of the shortest contact duration [s] from the deepest penetration.

    The deepest penetration ``delta_max`` fixes the impact velocity by energy balance,
    ``m_eff v0^2 / 2 = E(delta_max)`` with the law's stored energy ``E``, and the law's
    duration function (:class:`pound_mc.physics.contact.KernelLaw`) gives
    ``t_c(v0, beta, m_eff)``.

    Parameters
    ----------
    contact_model : str
        Name in :data:`pound_mc.physics.contact.CONTACT_MODELS`.
    max_penetration : array_like
        Deepest penetration of each run [m]; 0 (or NaN) where there was no contact.
    beta : array_like
        Impact stiffness [N/m^1.5, or N/m for the linear laws].
    m_eff : array_like
        Effective mass of the contact [kg].

    Returns
    -------
    numpy.ndarray
        Duration [s]; ``inf`` where there was no contact.
    """
    law = CONTACT_MODELS[contact_model].kernel
    stored = np.vectorize(getattr(law.stored, "py_func", law.stored), otypes=[float])
    duration = np.vectorize(getattr(law.duration, "py_func", law.duration), otypes=[float])
    d, beta, m_eff = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in
                                           (max_penetration, beta, m_eff)))  # fmt: skip
    out = np.full(d.shape, np.inf)
    hit = np.isfinite(d) & (d > 0.0)
    if np.any(hit):
        v0 = np.sqrt(2.0 * stored(d[hit], beta[hit]) / m_eff[hit])
        out[hit] = duration(v0, beta[hit], m_eff[hit])
    return out


def _scaled(a, b, scale) -> np.ndarray:
    """Largest ``|a - b| / scale`` over the last axis (0 where both are NaN, inf where one is)."""
    a, b = np.atleast_2d(np.asarray(a, float)), np.atleast_2d(np.asarray(b, float))
    both = np.isnan(a) & np.isnan(b)
    with np.errstate(invalid="ignore", divide="ignore"):
        d = np.where(both, 0.0, np.abs(a - b) / np.asarray(scale, float)[:, None])
    d = np.where(np.isnan(d), np.inf, d)  # a quantity one run lacks
    return d.max(axis=1) if d.shape[1] else np.zeros(d.shape[0])


def _scale(a, b) -> np.ndarray:
    """The larger of two runs' largest finite value per row (NaN where neither has one)."""
    both = np.concatenate((np.atleast_2d(np.asarray(a, float)),
                           np.atleast_2d(np.asarray(b, float))), axis=1)  # fmt: skip
    finite = np.where(np.isfinite(both), both, -np.inf)
    top = finite.max(axis=1) if both.shape[1] else np.full(both.shape[0], -np.inf)
    return np.where(top > 0.0, top, np.nan)


def judged_change(run: dict, other: dict) -> np.ndarray:
    """Largest relative difference of the judged quantities of two runs of the same scenes.

    Parameters
    ----------
    run, other : dict
        Per run (first axis): ``peak_force`` [N] and ``impacts``; ``peak_disp`` [m], one
        column per building; optional ``peak_ductility`` [-] (a column per building, NaN for
        one that cannot yield) and ``contact_peak_force`` [N] (a column per contact).

    Returns
    -------
    numpy.ndarray
        Per run: the largest of ``|F - F'| / max(F, F')`` (peak force, and each contact's peak
        force against the same run peak; not judged where neither run had an impact: a
        penetration below ``IMPACT_MIN_PENETRATION_M`` gives a force of round-off size), of
        each building's ``|x - x'|`` over the largest peak displacement of any building, and
        of each building's ductility difference over the largest ductility.  ``inf`` where a
        quantity is NaN in one run only (a second run that failed); 0 for nothing to judge.
    """
    f, f2 = np.atleast_1d(np.asarray(run["peak_force"], float)), np.asarray(other["peak_force"])
    n = f.size
    force_scale = np.maximum(np.abs(f), np.abs(np.atleast_1d(np.asarray(f2, float))))
    impact = (np.atleast_1d(run["impacts"]) > 0) | (np.atleast_1d(other["impacts"]) > 0)
    change = np.where(impact, _scaled(f[:, None], np.reshape(f2, (n, 1)), force_scale), 0.0)
    if "contact_peak_force" in run and "contact_peak_force" in other:
        fc = np.reshape(run["contact_peak_force"], (n, -1))
        fc2 = np.reshape(other["contact_peak_force"], (n, -1))
        change = np.maximum(change, np.where(impact, _scaled(fc, fc2, force_scale), 0.0))
    for key in ("peak_disp", "peak_ductility"):
        if key not in run or key not in other:
            continue
        a, b = np.reshape(run[key], (n, -1)), np.reshape(other[key], (n, -1))
        change = np.maximum(change, _scaled(a, b, _scale(a, b)))
    return np.where(np.isnan(change), np.inf, change)


def substep_check_due(peak_force, status):
    """Which ``adaptive`` runs the check runs again with more sub-steps.

    Those that ended ``ok`` with a contact (a peak force above 0): the steps of a run without
    one are exact, and a finer setting takes the same.
    """
    return (np.asarray(peak_force) > 0.0) & (np.asarray(status) == STATUS_OK)


def flag_inaccurate(status, impacts, contact_s, dt_s, peak=None, peak_half=None, *,
                    change=None) -> np.ndarray:  # fmt: skip
    """``status`` with the ``ok`` runs the check finds off flagged ``inaccurate``.

    Parameters
    ----------
    status, impacts : array_like
        The kernel's status and impact count of each run.
    contact_s : array_like
        :func:`shortest_contact_s` of each run [s] (``inf``: not judged).
    dt_s : array_like
        The run's step [s].
    peak, peak_half : array_like, optional
        Peak force of each run and of its second run [N] (the check of the peak force alone);
        a run without impacts whose second run has some is flagged too.
    change : array_like, optional
        :func:`judged_change` of each run and its second run: the check.  Given, it alone
        decides (``contact_s`` is the criterion of runs without the check); ``ok`` runs with
        a change above :data:`TOLERANCE` (or NaN) are flagged, with a contact or not.
    """
    status = np.array(status, copy=True)
    ok = status == STATUS_OK
    if change is not None:
        status[ok & ~(np.asarray(change) <= TOLERANCE)] = STATUS_INACCURATE
        return status
    impacts = np.asarray(impacts)
    bad = np.asarray(contact_s) < MIN_STEPS_PER_CONTACT * np.asarray(dt_s)
    if peak is not None:
        peak, peak_half = np.asarray(peak, float), np.asarray(peak_half, float)
        with np.errstate(invalid="ignore"):
            bad = bad | ~(np.abs(peak - peak_half) <= TOLERANCE * np.abs(peak_half))
        impacts = np.where(peak_half > 0.0, 1, impacts)
    status[ok & (impacts > 0) & bad] = STATUS_INACCURATE
    return status


def judged_outputs(out, cout=None) -> dict:
    """The quantities the check judges (:func:`~pound_mc.integrators.accuracy.judged_change`)."""
    got = {"peak_force": out[:, PEAK_FORCE], "impacts": out[:, IMPACTS],
           "peak_disp": out[:, [PEAK_DISP_LEFT, PEAK_DISP_RIGHT]]}  # fmt: skip
    if cout is not None:
        got["contact_peak_force"] = cout[:, :, C_PEAK_FORCE]
    return got


def output_change(out, other, cout=None, other_cout=None) -> np.ndarray:
    """Judged change of each run against its second run (NaN rows: none, change 0)."""
    change = judged_change(judged_outputs(out, cout), judged_outputs(other, other_cout))
    return np.where(np.isnan(other[:, STATUS]), 0.0, change)


def check_substeps(out, settings, rerun, same=None, cout=None) -> None:
    """``adaptive``: flag the runs whose judged quantities change with more contact sub-steps.

    ``rerun(hit, finer, fine[, fine_cout])`` runs simulations ``hit`` again with ``finer``,
    the run's ``settings`` with :data:`~pound_mc.integrators.accuracy.ADAPTIVE_SUBSTEPS_FACTOR`
    times the sub-steps, into ``fine`` (and the per-contact outputs into ``fine_cout`` where
    ``cout``, the run's, is given); every run with a contact (status ok) is checked
    (:mod:`pound_mc.integrators.accuracy`), except those that ``same`` (a mask, optional) says
    the finer run would take with the same sub-steps (every sub-step bound set by ``substeps``
    slack even at the finer setting): its outputs would be theirs, bit for bit.
    """
    check = substep_check_due(out[:, PEAK_FORCE], out[:, STATUS])
    if same is not None:
        check &= ~same
    hit = np.flatnonzero(check)
    if hit.size == 0:
        return
    finer = settings._replace(substeps=settings.substeps * ADAPTIVE_SUBSTEPS_FACTOR)
    fine = np.empty((hit.size, min(out.shape[1], N_OUT + 1)))  # no onset slots: none taken
    other = np.full((out.shape[0], N_OUT), np.nan)
    other_cout = None
    if cout is None:
        rerun(hit, finer, fine)
    else:
        other_cout = np.full_like(cout, np.nan)
        fine_cout = np.empty((hit.size, *cout.shape[1:]))
        rerun(hit, finer, fine, fine_cout)
        other_cout[hit] = fine_cout
    other[hit] = fine[:, :N_OUT]
    change = output_change(out, other, cout, other_cout)
    out[:, STATUS] = flag_inaccurate(out[:, STATUS], None, np.inf, 0.0, change=change)
