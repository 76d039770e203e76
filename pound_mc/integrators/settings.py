"""Kernel settings: the names of a run (law, relation, method, restitution) as kernel codes.

:func:`kernel_settings` turns names into the :data:`KernelSettings` the compiled kernels take
(integer codes, the step bound, and the tables of restitution set per impact);
:func:`fixed_restitution` reports the restitution of runs with one restitution for every
impact.

Methods (names pinned by DESIGN.md section 4): ``adaptive`` (default,
:mod:`~pound_mc.integrators.adaptive`, :mod:`~pound_mc.integrators.adaptive_pair` and
:mod:`~pound_mc.integrators.adaptive_bilinear` for SDOF pairs), ``newmark``,
``newmark-explicit`` and ``central-difference`` (:mod:`~pound_mc.integrators.fixed`,
:mod:`~pound_mc.integrators.pair` for SDOF pairs, :mod:`~pound_mc.integrators.hysteretic`
for yielding buildings).
"""

from __future__ import annotations

import functools
import math
from collections import namedtuple

import numpy as np

from pound_mc.errors import InputError
from pound_mc.integrators.fixed import CENTRAL_DIFFERENCE, NEWMARK, NEWMARK_EXPLICIT
from pound_mc.integrators.laws import LAW_CODES, RELATION_CODES
from pound_mc.integrators.outputs import PEAK_FORCE, PEAK_FORCE_RESTITUTION, STATUS
from pound_mc.physics.contact import CONTACT_MODELS, check_relation, reported_xi
from pound_mc.physics.materials import E_FLOOR, PER_IMPACT_OUTSIDE, restitution_rows
from pound_mc.physics.relations import (
    RELATIONS,
    hertzdamp_restitution,
    largest_xi,
    restitution_of_xi,
)

__all__ = ["METHODS", "KernelSettings", "kernel_settings", "fixed_restitution"]

ADAPTIVE = 0
_METHOD_CODES = {
    "adaptive": ADAPTIVE,
    "newmark": NEWMARK,
    "newmark-explicit": NEWMARK_EXPLICIT,
    "central-difference": CENTRAL_DIFFERENCE,
}
#: Integration methods by name (DESIGN.md section 4); the first is the default.
METHODS = tuple(_METHOD_CODES)

#: Settings of one kernel run, as the kernels take them: codes of the contact law, of its
#: damping relation and of the method, the step bound ``dt_s`` [s] and the contact sub-steps
#: per contact duration (``adaptive``), then the restitution set per impact (empty arrays:
#: fixed restitution): the policy outside the measured velocities (0 clamp, 1 extrapolate) and
#: the lowest restitution it may reach, the table of the relation's ``xi`` on a uniform grid of
#: ``e`` (start, spacing), the seed's Table 2 rows (velocities [m/s], ``e_min``, ``e_max``)
#: and that ``xi`` table.  Build it with :func:`kernel_settings`.
KernelSettings = namedtuple(
    "KernelSettings",
    "model relation method dt_s substeps outside rest_floor xi_e0 xi_de rest_v rest_lo rest_hi "
    "xi_tab",
)
_LAW_NAMES = {code: name for name, code in LAW_CODES.items()}
#: Largest damping ratio of the ``exact`` table [-]: :func:`~pound_mc.physics.relations.largest_xi`.
_XI_MAX = largest_xi()
#: Spacing of the ``e`` grid of a relation's ``xi`` table [-] (linear interpolation in it is
#: within 2e-8 of the relation for e >= 0.3).
XI_TABLE_DE = 1e-4


def _restitution_arrays(model: str, relation: str | None, restitution: dict | None) -> tuple:
    """Settings fields of per-impact restitution (:data:`KernelSettings`), empty without."""
    empty = np.zeros(0)
    if restitution is None:
        return 0, 0.0, 0.0, 1.0, empty, empty, empty, empty
    outside = restitution.get("outside", "clamp")
    if outside not in PER_IMPACT_OUTSIDE:
        raise InputError(
            f"unknown policy {outside!r}; choose one of {list(PER_IMPACT_OUTSIDE)}",
            key="contact.outside",
        )
    if CONTACT_MODELS[model].damping is None:
        raise InputError(
            f"the {model!r} law has no damping to set per impact", key="contact.restitution"
        )
    v, lo, hi = restitution_rows(restitution["material"])
    e_grid = np.linspace(E_FLOOR, 1.0, int(round((1.0 - E_FLOOR) / XI_TABLE_DE)) + 1)
    xi_tab = (
        empty if CONTACT_MODELS[model].damping == "zeta"
        else np.asarray(reported_xi(model, e_grid, relation), dtype=np.float64)
    )  # fmt: skip
    de = float(e_grid[1] - e_grid[0])
    return (PER_IMPACT_OUTSIDE.index(outside), E_FLOOR, E_FLOOR, de, v, lo, hi, xi_tab)


def kernel_settings(
    model: str = "jankowski",
    method: str = "adaptive",
    *,
    relation: str | None = None,
    dt_s: float = 0.001,
    substeps: int = 16,
    restitution: dict | None = None,
) -> KernelSettings:
    """Kernel settings from names (``relation`` None: the law's default).

    ``restitution``: ``{"material": NAME, "outside": "clamp" | "extrapolate"}`` sets each
    impact's restitution from the seed's Table 2 at its onset velocity (the kernels' ``xi``
    then holds the quantile of the measured range); None: fixed.

    Raises
    ------
    InputError
        For an unknown law or method, or a relation the law does not accept.
    """
    if restitution is None:
        return _plain_settings(model, method, relation, float(dt_s), float(substeps))
    return _settings(model, method, relation, dt_s, substeps, restitution)


@functools.lru_cache(maxsize=256)
def _plain_settings(model, method, relation, dt_s, substeps) -> KernelSettings:
    """:func:`kernel_settings` with one restitution for every impact, made once per set."""
    return _settings(model, method, relation, dt_s, substeps, None)


def _settings(model, method, relation, dt_s, substeps, restitution) -> KernelSettings:
    relation = check_relation(model, relation)
    if method not in _METHOD_CODES:
        raise InputError(
            f"unknown method {method!r}; allowed: {', '.join(METHODS)}", key="integrator.method"
        )
    rel = RELATION_CODES[model][relation] if relation is not None else 0
    return KernelSettings(
        LAW_CODES[model], rel, _METHOD_CODES[method], float(dt_s), float(substeps),
        *_restitution_arrays(model, relation, restitution),
    )  # fmt: skip


def fixed_restitution(out, settings, xi) -> None:
    """``peak_force_restitution``: the restitution the law really rebounds with.

    Of the ok runs with a contact (NaN without one, as the kernels leave it).

    With one restitution for every impact, from the run's damping parameter: ``xi`` by the
    exact single impact (Jankowski), ``exp(-pi xi / sqrt(1 - xi^2))`` (Kelvin), the rebound
    of the Hertz-damp law for the ``e`` its ``xi`` holds
    (:func:`~pound_mc.physics.relations.hertzdamp_restitution`), 1 for the undamped laws.
    With restitution set per impact, the kernels give the peak-force impact's ``e`` from the
    seed's Table 2, which becomes the law's rebound for it the same way (the ``xi`` its
    relation gives, or Hertz-damp's rebound).
    """
    ok = (out[..., STATUS] == 0) & (out[..., PEAK_FORCE] > 0.0)  # NaN without a contact
    if settings.rest_v.size > 0:  # the table's e at the peak-force impact
        target = np.where(ok, out[..., PEAK_FORCE_RESTITUTION], np.nan)
        e = _rebound_of_e(settings.model, settings.relation, target)
    elif out.ndim == 1:  # one run: the scalar, computed once per law and ``xi``
        e = _restitution_one(settings.model, settings.relation, float(xi))
    else:
        xi = np.broadcast_to(np.asarray(xi, dtype=float), out.shape[:-1])
        e = _restitution(settings.model, settings.relation, xi)
    out[..., PEAK_FORCE_RESTITUTION] = np.where(ok, e, out[..., PEAK_FORCE_RESTITUTION])


def _restitution(model: int, relation: int, xi: np.ndarray) -> np.ndarray:
    """Restitution [-] the law of code ``model`` rebounds with, per damping parameter ``xi``.

    ``xi`` is the restitution aimed at for Hertz-damp (its relation, of code ``relation``,
    gives ``zeta`` from it).
    """
    law = CONTACT_MODELS[_LAW_NAMES[model]]
    if law.damping is None:
        return np.ones_like(xi)
    if law.damping == "zeta":
        return np.asarray(hertzdamp_restitution(xi, law.relations[relation]), dtype=float)
    if law.name == "kelvin":
        return np.exp(-math.pi * xi / np.sqrt(np.maximum(1.0 - xi * xi, 1e-300)))
    known = np.isfinite(xi)
    e = np.full(np.shape(xi), np.nan)
    e[known] = restitution_of_xi(np.clip(xi[known], 0.0, _XI_MAX))
    return e


def _rebound_of_e(model: int, relation: int, e: np.ndarray) -> np.ndarray:
    """:func:`_restitution` of the damping that ``e`` gives under the run's relation (NaN kept)."""
    law = CONTACT_MODELS[_LAW_NAMES[model]]
    if law.damping != "xi":
        return _restitution(model, relation, e)
    known = np.isfinite(e)
    xi = np.full(e.shape, np.nan)
    xi[known] = RELATIONS[law.relations[relation]](e[known])
    return _restitution(model, relation, xi)


@functools.lru_cache(maxsize=256)
def _restitution_one(model: int, relation: int, xi: float) -> float:
    """:func:`_restitution` of one run (a scene looped over in a notebook pays it once)."""
    return float(_restitution(model, relation, np.asarray(xi)))
