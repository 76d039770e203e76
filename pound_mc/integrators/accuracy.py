"""Accuracy flag of the fixed-step methods: contact phases resolved by too few steps.

A fixed-step method (``newmark``, ``newmark-explicit``, ``central-difference``) steps over a
contact with the step ``dt_s`` whatever the contact lasts; a contact of a few steps gives a
peak force off by tens of percent (or by orders of magnitude) while the energy balance still
closes, so the run would read ``ok``.  After the kernel, each run that had an impact is given
the elastic estimate of its shortest contact duration: the deepest penetration
``delta_max`` (the kernel's ``max_penetration``) fixes the impact velocity by energy balance,
``m_eff v0^2 / 2 = E(delta_max)`` with the law's stored energy ``E``, and the law's duration
function (:class:`pound_mc.physics.contact.KernelLaw`) gives ``t_c(v0, beta, m_eff)``.  A run
with ``t_c / dt_s`` below :data:`MIN_STEPS_PER_CONTACT` gets the status ``inaccurate``
(:data:`STATUS_INACCURATE`); its numbers are kept.

Resolving the contacts is not enough: a fixed step also shifts the buildings' phases (a
0.05-s building at 0.01 s) and pounding amplifies any shift into other impacts.  So the batch
runs of a study (:func:`~pound_mc.integrators.batch.simulate_sdof_pairs`,
:func:`~pound_mc.integrators.batch.simulate_scene_batch`) also run every fixed-step simulation
again at ``dt_s / 2`` (step doubling; three times the cost of the run alone) and flag the ones
whose peak force changes by more than :data:`PEAK_FORCE_TOLERANCE`: the error of the run at
``dt_s`` is of the order of that change.

``adaptive`` sub-steps every contact (``substeps`` per estimated duration): one impact is
resolved to about 1e-5, but the state an impact leaves behind carries an error of the same
order into the next, and a light, stiff building that pounds again and again (a 0.05-s
building of 100 kg against a 1-s one at zero gap) amplifies it a thousandfold within ten
impacts: the peak force is then off by up to 25 % whatever ``dt_s``.  So the batch runs also
run every ``adaptive`` simulation that had a contact again with
:data:`ADAPTIVE_SUBSTEPS_FACTOR` times the sub-steps (the same step doubling, on the contact
sub-steps; 1.5 to 2.1 times the cost of the run alone where every run pounds) and flag the
ones whose peak force changes by more than :data:`PEAK_FORCE_TOLERANCE`.  An SDOF-pair run
none of whose sub-steps a bound set by ``substeps`` would shorten at the finer setting is not
run again: the finer run would take the same sub-steps, its peak force bitwise the run's; the
others start their finer run at the last contact onset up to which it takes the run's sub-steps.
The check flags also the runs whose only contacts are round-off touches (identical
buildings at zero gap, penetrations of 1e-15 m, no impact counted): their peak force, 1e-11 N,
is round-off too.  The flag is computed from the kernels' outputs.
"""

from __future__ import annotations

import numpy as np

from pound_mc.integrators.outputs import STATUS_OK
from pound_mc.physics.contact import CONTACT_MODELS

__all__ = [
    "MIN_STEPS_PER_CONTACT",
    "PEAK_FORCE_TOLERANCE",
    "STATUS_INACCURATE",
    "ADAPTIVE_SUBSTEPS_FACTOR",
    "shortest_contact_s",
    "flag_inaccurate",
    "substep_check_due",
]

#: Status of a fixed-step run whose contact phases are under-resolved.
STATUS_INACCURATE = 3
#: Fewest steps per (shortest) contact duration of a fixed-step run that is ``ok``: sampling
#: a half-sine force pulse with ``n`` steps misses its peak by up to ``1 - cos(pi / n)``, which
#: is below 1 % from ``n = 23``; 25 leaves room for the integrator's own period error.
MIN_STEPS_PER_CONTACT = 25
#: Relative change of the peak force from ``dt_s`` to ``dt_s / 2`` above which a fixed-step run
#: is ``inaccurate`` (step doubling): half of the 1 % aimed at, since for a second-order method
#: the error at ``dt_s`` is about 4/3 of the change, and more where impacts reorder.
PEAK_FORCE_TOLERANCE = 0.005
#: ``adaptive``'s check runs with this many times the contact sub-steps (a power of two: the
#: SDOF-pair kernel's bounds at the finer setting are then its own, scaled exactly): the
#: sub-step error falls by 4 to 9 times from 16 to 32 sub-steps, so the error at ``substeps``
#: is at most about 4/3 of the change, as for step doubling (extreme drill: every run off by
#: more than 1 % is flagged, none within 1 % is).
ADAPTIVE_SUBSTEPS_FACTOR = 2


def shortest_contact_s(contact_model: str, max_penetration, beta, m_eff) -> np.ndarray:
    """Elastic estimate of the shortest contact duration [s] from the deepest penetration.

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


def substep_check_due(peak_force, status):
    """Which ``adaptive`` runs the check runs again with more sub-steps.

    Those that ended ``ok`` with a contact (a peak force above 0), whether run in a batch or
    one scene at a time.
    """
    return (np.asarray(peak_force) > 0.0) & (np.asarray(status) == STATUS_OK)


def flag_inaccurate(status, impacts, contact_s, dt_s, peak=None, peak_half=None) -> np.ndarray:
    """``status`` with the ``ok`` runs that are not resolved flagged ``inaccurate``.

    Parameters
    ----------
    status, impacts : array_like
        The kernel's status and impact count of each run.
    contact_s : array_like
        :func:`shortest_contact_s` of each run [s].
    dt_s : array_like
        The run's step [s].
    peak, peak_half : array_like, optional
        Peak force of each run at ``dt_s`` and at ``dt_s / 2`` [N] (step doubling); a run
        without impacts whose half-step run has some is flagged too.
    """
    status = np.array(status, copy=True)
    impacts = np.asarray(impacts)
    bad = np.asarray(contact_s) < MIN_STEPS_PER_CONTACT * np.asarray(dt_s)
    if peak is not None:
        peak, peak_half = np.asarray(peak, float), np.asarray(peak_half, float)
        with np.errstate(invalid="ignore"):
            bad = bad | ~(np.abs(peak - peak_half) <= PEAK_FORCE_TOLERANCE * np.abs(peak_half))
        impacts = np.where(peak_half > 0.0, 1, impacts)
    status[(status == STATUS_OK) & (impacts > 0) & bad] = STATUS_INACCURATE
    return status
