"""Prepared study: records loaded, samples drawn, per-simulation parameters on demand.

:class:`StudyEngine` turns a validated :class:`~pound_mc.study.Study` into arrays the compiled
batch kernel takes, for any half-open range of simulation indices (C order of
``study.shape``).  Everything random is drawn once, in Python, before any range runs, so a
range's results depend only on the study and the indices - not on threads, chunk size or
backend.

SDOF pairs run through :func:`~pound_mc.integrators.simulate_sdof_pairs`; a pair with a shear
building through :func:`~pound_mc.integrators.simulate_scene_batch` with the modes of the
study's one structure (:meth:`~pound_mc.scene.Scene.modal_arrays`, computed once), and then
also gives the per-contact outputs of :data:`~pound_mc.study.dataset.CONTACT_VARIABLES`.
A study that varies a shear building's keys, or whose buildings can yield, runs each
simulation as its own scene (:meth:`StudyEngine.scene_of`, modes computed for it); the
results are still a function of the study and the index only.

The records are read by :mod:`pound_mc.study.inputs`.
"""

from __future__ import annotations

import time
from dataclasses import replace

import netCDF4
import numba
import numpy as np
import scipy
import xarray as xr

import pound_mc.integrators as integrators
from pound_mc._version import __version__
from pound_mc.errors import InputError, InputErrors, named_by
from pound_mc.integrators.accuracy import ADAPTIVE_SUBSTEPS_FACTOR, STATUS_INACCURATE
from pound_mc.integrators.outputs import STATUS_OK
from pound_mc.integrators.threads import numba_threads
from pound_mc.motions import G, record_arrays
from pound_mc.motions.intensity import checked_sa_period, sa_g
from pound_mc.motions.preprocessing import WINDOW_PEAK_WARN
from pound_mc.physics.contact import default_relation, kernel_damping, reported_xi
from pound_mc.physics.relations import restitution_of_xi
from pound_mc.scene import Scene, scene_from_dict, simulate
from pound_mc.scene import schema as scene_schema
from pound_mc.scene.simulation import storey_results
from pound_mc.study.dataset import (
    BUILDING_VARIABLES,
    CONTACT_VARIABLES,
    INELASTIC_VARIABLES,
    RESULT_VARIABLES,
    RUN_VARIABLES,
    STOREY_VARIABLES,
)
from pound_mc.study.definition import INTENSITY_KEYS, MATERIAL_KEY, grid_dim_name, scene_models
from pound_mc.study.inputs import load_traces

__all__ = ["StudyEngine", "STEP_BUDGET"]

#: The most integration steps one simulation may take (record duration over ``dt_s``); a study
#: that needs more is refused before it runs (``check`` and ``run``): at about 0.3 us a step
#: it would take over 10 s per simulation, and ``dt_s`` = 1e-7 s on a 30-s record (3e8 steps)
#: is a typing error rather than a study.
STEP_BUDGET = 3.0e7

# Scene keys the SDOF-pair batch kernel takes per simulation (defaults: the scene's value);
# ``contact.beta`` stands for the stiffness, ``contact.k_N_per_m`` for the linear laws.
_KERNEL_KEYS = (
    "left.period_s",
    "left.damping_ratio",
    "left.mass_kg",
    "right.period_s",
    "right.damping_ratio",
    "right.mass_kg",
    "contact.gap_m",
    "contact.beta",
    "integrator.dt_s",
)
#: Most refinements of a run the accuracy check flags (each halves ``dt_s`` and doubles
#: ``substeps``; :meth:`StudyEngine.run_indices`).
MAX_REFINEMENTS = 3
#: Largest ``integrator.substeps`` a refinement may reach (the key's bound).
MAX_SUBSTEPS = int(scene_schema.INTEGRATOR["substeps"].maximum)
# Dataset variables of STOREY_VARIABLES: their key in a result's ``storeys``.
_STOREY_KEYS = {
    "storey_peak_drift": "peak_drift_ratio",
    "storey_peak_ductility": "peak_ductility",
    "storey_residual_drift": "residual_drift_ratio",
}
# Keys the batch of a pair with a shear building takes per simulation (its modes are fixed).
_SCENE_KERNEL_KEYS = ("contact.gap_m", "contact.beta", "integrator.dt_s")


def _dims_of(study, key: str) -> tuple[str, ...]:
    if key in study.grid:
        return (grid_dim_name(key),)
    if key in study.material_variables:
        return (grid_dim_name(MATERIAL_KEY), "sample")
    if any(v.key == key for v in study.variables):
        return ("sample",)
    return ()


#: :meth:`StudyEngine.calibrate` times at least this many simulations, and for at least
#: this long [s], unless told a number.
CALIBRATION_SIZE, CALIBRATION_MIN_S = 64, 1.0


class StudyEngine:
    """Records, samples and base scene of a study, ready to run ranges of simulations.

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        A validated study; its records are read and preprocessed here.

    Raises
    ------
    InputError
        A record that cannot be read or preprocessed, naming the study file and the key.
    """

    def __init__(self, study):
        self.study = study
        self.shape = study.shape
        self.samples = study.draw()
        #: Sampled keys that follow the material axis: ``{key: (n_materials, n)}``.
        self.material_samples = study.draw_materials()
        #: The scene of the first simulation; its fixed values fill the keys nothing varies.
        self.scene = self.scene_of(0)
        traces = load_traces(study)
        #: ``(dt_s, acceleration)`` of every record, read and preprocessed (unscaled by an
        #: intensity axis: see :meth:`record_of`).
        self.records = [record_arrays(trace) for trace in traces]
        #: ``event`` and ``station`` of every record, as its source tells them ("" unknown).
        self.record_labels = {
            what: [str(t.stats.pound.get(what) or "") for t in traces]
            for what in ("event", "station")
        }
        self._intensities()
        #: Warnings on the records as kept (a window that misses the strong motion).
        self.record_warnings = self._window_warnings(traces)
        self._base = self._base_values(study.scene, self.scene)
        self._check_steps()
        #: Whether a building is a shear building: then every simulation runs the modes of
        #: :attr:`arrays` (computed once) through the general batch, and the outputs include
        #: the per-contact arrays of :data:`~pound_mc.study.dataset.CONTACT_VARIABLES`.
        #: Whether the study gives a row of buildings (``[[buildings]]``): each simulation then
        #: runs its own scene, and the dataset holds each building's outputs.
        self.row = self.scene.row is not None
        self.mdof = self.row or any(m in ("shear", "wall") for m in scene_models(study.scene))
        self.arrays = self.scene.modal_arrays() if self.mdof else None
        #: Whether a building can yield: each simulation then runs its own scene (the inelastic
        #: kernels), and the dataset holds the storeys' outputs.
        self.inelastic = self.scene.inelastic
        #: Whether each simulation runs its own scene (:meth:`scene_of`, its modes computed
        #: for it): with yielding buildings, and with a shear building whose keys vary.
        self.per_scene = (
            self.inelastic
            or self.row
            or (
                self.mdof and any(key.split(".", 1)[0] in ("left", "right") for key in self._varied)
            )
        )

    def _intensities(self) -> None:
        """Each record's own PGA and Sa, and the factors that scale it to the intensity axis."""
        study = self.study
        #: The intensity grid axis (``"record.pga_g"``, ``"record.sa_g"``) or None.
        self.intensity_key = study.intensity_key
        #: Unscaled PGA of every record [g].
        self.record_pga_g = np.array([np.max(np.abs(acc)) / G for _dt, acc in self.records])
        #: Period of each record's Sa [s] (NaN where the table has no ``sa_period_s``) and its
        #: unscaled 5 %-damped Sa there [g] (None when no record has a period).
        self.sa_period_s = np.array([float(r.get("sa_period_s", np.nan)) for r in study.records])
        self.record_sa_g = None
        if np.any(np.isfinite(self.sa_period_s)):
            self.record_sa_g = np.full(len(self.records), np.nan)
            for k, ((dt, acc), period) in enumerate(
                zip(self.records, self.sa_period_s, strict=True)
            ):
                if not np.isfinite(period):
                    continue
                try:
                    checked_sa_period(period, dt, acc)
                except InputError as exc:
                    key = study.record_table(k) + ".sa_period_s"
                    raise InputError(exc.message, file=study.path, key=key) from None
                self.record_sa_g[k] = sa_g(dt, acc, period)
        #: ``(n_records, n_intensities)`` factors ``target / own`` (None without an axis).
        self.scale_factors = None
        self._intensity_axis = None
        if self.intensity_key is not None:
            own = self.record_pga_g if self.intensity_key == "record.pga_g" else self.record_sa_g
            targets = study.grid[self.intensity_key]
            if not np.all(own > 0):
                bad = int(np.flatnonzero(~(own > 0))[0])
                raise InputError(
                    f"the record's own {self.intensity_key.split('.')[1]} is zero: it cannot "
                    "be scaled to a target",
                    file=study.path,
                    key=study.record_table(bad) + ".source",
                )
            self.scale_factors = targets[None, :] / own[:, None]
            self._intensity_axis = list(study.grid).index(self.intensity_key) + 1

    def _window_warnings(self, traces) -> list[str]:
        """A warning naming the records whose window misses their strong motion.

        Those whose ``duration_s`` window keeps less than
        :data:`~pound_mc.motions.preprocessing.WINDOW_PEAK_WARN` of their
        peak acceleration: scaled to an intensity, such a window scales what precedes the
        strong motion (pre-event noise of a record that starts early: thousands of times).
        """
        short = []
        for r, trace in enumerate(traces):
            kept = trace.stats.pound.get("window_peak_fraction", 1.0)
            if kept < WINDOW_PEAK_WARN:
                short.append(f"{self.study.record_names[r]} ({100 * kept:.2g} %)")
        if not short:
            return []
        listed = ", ".join(short[:5]) + (f" and {len(short) - 5} more" if len(short) > 5 else "")
        return [
            f"warning: {self.study.path or 'the study'}: the duration_s window of "
            f"{len(short)} of {len(traces)} records keeps less than "
            f"{100 * WINDOW_PEAK_WARN:g} % of their peak acceleration, which comes later: "
            f"{listed}; scaled to an intensity, that window is not the earthquake (give a "
            "longer duration_s, or none)"
        ]

    def _check_steps(self) -> None:
        """Refuse steps the kernels would not take as written, and endless simulations.

        A fixed-step method's ``dt_s`` longer than a record's sampling interval would be
        shortened to it (so would every value of a varied ``dt_s``, whatever the method: its
        axis would be mislabelled); a simulation of more than :data:`STEP_BUDGET` steps would
        not end in reasonable time.
        """
        study = self.study
        key = "integrator.dt_s"
        where = f"grid.{key}" if key in study.grid else key
        if any(v.key == key for v in study.variables):
            where = f"sampling.vary.{key}"
        values = np.asarray(self._values(key, {}, 1) if where == key else
                            study.grid.get(key, self.samples.get(key)), float)  # fmt: skip
        fixed = self._base["integrator.method"] != "adaptive"
        errors = []
        for r, (dt_rec, acc) in enumerate(self.records):
            name = study.record_names[r]
            if (fixed or where != key) and np.max(values) > dt_rec * (1 + 1e-9):
                errors.append(InputError(
                    f"{np.max(values):g} s is longer than the sampling interval {dt_rec:g} s "
                    f"of record {name!r}: the step would be shortened to it; give dt_s <= "
                    f"{dt_rec:g} s", file=study.path, key=where))  # fmt: skip
                break
            steps = (acc.size - 1) * dt_rec / min(float(np.min(values)), dt_rec)
            if steps > STEP_BUDGET:
                errors.append(InputError(
                    f"{np.min(values):g} s makes {steps:.3g} steps per simulation on record "
                    f"{name!r}, more than the budget of {STEP_BUDGET:.0e} steps (the run would "
                    "not end); give a longer dt_s or a shorter record", file=study.path,
                    key=where))  # fmt: skip
                break
        if errors:
            raise InputErrors(errors)

    def record_of(self, index: int) -> tuple[float, np.ndarray]:
        """``(dt_s, acceleration)`` simulation ``index`` runs: its record, scaled to its intensity.

        :func:`pound_mc.scene.simulate` of :meth:`scene_of` with this record reproduces the
        simulation.
        """
        idx = np.unravel_index(int(index), self.shape)
        return self._scaled_record(int(idx[0]), int(idx[self._intensity_axis or 0]))

    def _scaled_record(self, r: int, j: int) -> tuple[float, np.ndarray]:
        dt_rec, acc = self.records[r]
        if self.scale_factors is None:
            return dt_rec, acc
        return dt_rec, acc * self.scale_factors[r, j]

    def varied(self, indices) -> dict[str, np.ndarray]:
        """Values of the varied keys (grid axes, sampled keys) of the simulations ``indices``.

        ``indices`` are flat (C order of :attr:`shape`); one index gives scalars.
        """
        idx = np.unravel_index(np.asarray(indices, dtype=np.int64), self.shape)
        return self.study.values_at(idx, self.samples, self.material_samples)

    def scene_of(self, index: int) -> Scene:
        """The scene of simulation ``index`` (flat, C order of :attr:`shape`).

        Grid values and sampled values replace the scene's own (a varied ``e`` drops a fixed
        ``xi`` and vice versa); :func:`pound_mc.scene.simulate` of it with the record
        :meth:`record_of` ``(index)`` reproduces the simulation (the intensity axis scales the
        record, not the scene).
        """
        record = int(np.unravel_index(int(index), self.shape)[0])
        overrides = {
            key: float(value)
            for key, value in self.varied(int(index)).items()
            if key not in INTENSITY_KEYS
        }
        return scene_from_dict(self.study.scene_dict(record, overrides), file=self.study.path)

    # -- parameters -----------------------------------------------------------------------
    @staticmethod
    def _base_values(tables: dict, scene) -> dict:
        """Fixed scene values (defaults filled in by the validated ``scene``)."""
        left, right = tables.get("left", {}), tables.get("right", {})
        out = {
            "left.period_s": left.get("period_s"),
            "left.damping_ratio": scene.left.damping_ratio,
            "left.mass_kg": left.get("mass_kg"),
            "right.period_s": right.get("period_s"),
            "right.damping_ratio": scene.right.damping_ratio,
            "right.mass_kg": right.get("mass_kg"),
            "contact.gap_m": tables.get("contact", {}).get("gap_m", 0.0),
            "contact.beta": scene.stiffness,
            "contact.k_N_per_m": scene.stiffness,
            "integrator.dt_s": scene.dt_s,
        }
        contact = tables.get("contact", {})
        if "e" in contact:
            out["contact.e"] = contact["e"]
        elif "xi" in contact:
            out["contact.xi"] = contact["xi"]
        out = {k: v for k, v in out.items() if v is not None}
        out["contact.relation"] = scene.relation or default_relation(scene.contact_model) or ""
        out["contact.model"] = scene.contact_model
        out["integrator.method"] = scene.method
        out["integrator.substeps"] = scene.substeps
        out["integrator.accuracy_check"] = scene.accuracy_check
        if scene.restitution == "velocity":
            # restitution set per impact: the kernels' damping parameter is its quantile
            out["contact.e_quantile"] = scene.e_quantile
            out["contact.restitution"] = scene.restitution_rule()
        return out

    def _values(self, key: str, varied: dict, size: int) -> np.ndarray | None:
        """Per-simulation values of ``key``: varied (:meth:`varied`) or the fixed value."""
        if key in varied:
            return varied[key]
        if key in self._base:
            return np.full(size, float(self._base[key]))
        return None

    @property
    def stiffness_key(self) -> str:
        """Scene key of the contact stiffness (``contact.k_N_per_m`` for linear laws)."""
        return (
            "contact.k_N_per_m"
            if self._base["contact.model"] in ("linear", "kelvin")
            else "contact.beta"
        )

    def contact_damping(self, varied: dict, size: int) -> tuple[np.ndarray, np.ndarray | None]:
        """Impact damping per simulation (and the target ``e`` where one is given).

        The damping ratio ``xi`` from ``e`` through the study's relation; the Hertz-damp law
        takes ``e`` itself (its damping follows each impact's velocity).
        """
        if "contact.restitution" in self._base:
            return self._values("contact.e_quantile", varied, size), None
        e = None if "contact.xi" in varied else self._values("contact.e", varied, size)
        if e is not None:
            law = self._base["contact.model"]
            return np.asarray(kernel_damping(law, e, self._reported_xi(e)), float), e
        xi = self._values("contact.xi", varied, size)
        if xi is None:
            xi = np.zeros(size)  # laws without damping (linear, hertz)
        return xi, None

    def _reported_xi(self, e):
        """Damping ratio the kernels run with for ``e`` (NaN for hertzdamp: set per impact)."""
        return reported_xi(self._base["contact.model"], e, self._base["contact.relation"] or None)

    def parameters(self, indices: np.ndarray) -> dict[str, np.ndarray]:
        """Per-simulation kernel parameters of the simulations with flat ``indices``.

        With a shear building (:attr:`mdof`) only the contact keys and the step: the gaps
        ``contact.gap_m`` are then ``(n, n_contacts)`` where the scene fixes them.
        """
        indices = np.asarray(indices, dtype=np.int64)
        varied = self.varied(indices)
        size = indices.size
        out = {}
        for key in _SCENE_KERNEL_KEYS if self.mdof else _KERNEL_KEYS:
            source = self.stiffness_key if key == "contact.beta" else key
            if self.mdof and key == "contact.gap_m" and key not in varied:
                gaps = np.broadcast_to(self.scene.gap_m, (size, self.scene.gap_m.size))
                out[key] = np.ascontiguousarray(gaps, float)  # one gap per contact (the scene's)
                continue
            values = self._values(source, varied, size)
            if values is None:
                raise InputError("is required", file=self.study.path, key=source)
            out[key] = np.ascontiguousarray(values, float)
        out["contact.xi"] = np.ascontiguousarray(self.contact_damping(varied, size)[0], float)
        out["record"] = np.unravel_index(indices, self.shape)[0]
        return out

    # -- running --------------------------------------------------------------------------
    def run_range(self, start: int, stop: int) -> dict[str, np.ndarray]:
        """Run simulations ``start .. stop-1``; returns the per-simulation outputs."""
        return self.run_indices(np.arange(start, stop))

    @property
    def n_contacts(self) -> int:
        """Number of pairs of floors that can pound."""
        return len(self.scene.contacts)

    def result_layout(self) -> dict[str, tuple[tuple[int, ...], str]]:
        """Outputs of :meth:`run_indices`: ``{name: (shape after the simulation axis, dtype)}``.

        :data:`~pound_mc.study.dataset.RESULT_VARIABLES` (one value per simulation), and with a
        shear
        building (:attr:`mdof`) :data:`~pound_mc.study.dataset.CONTACT_VARIABLES` (one per contact).
        """
        out = {name: ((), dtype) for name, (_, _, dtype) in RESULT_VARIABLES.items()}
        out.update({name: ((), dtype) for name, (_, _, dtype) in RUN_VARIABLES.items()})
        if self.mdof:
            nc = self.n_contacts
            out.update({name: ((nc,), dtype) for name, (_, _, dtype) in CONTACT_VARIABLES.items()})
        if self.inelastic:
            out.update({name: ((), dtype) for name, (_, _, dtype) in INELASTIC_VARIABLES.items()})
        if self.per_storey:
            ns = self.scene.storey_arrays()[1].shape[0]
            out.update({name: ((ns,), dtype) for name, (_, _, dtype) in STOREY_VARIABLES.items()})
        if self.row:
            nb = len(self._row_buildings)
            out.update({name: ((nb,), dtype) for name, (_, _, dtype) in BUILDING_VARIABLES.items()})
        return out

    @property
    def _row_buildings(self) -> list:
        """The row's buildings from left to right (a wall is none)."""
        return [b for b in self.scene.buildings if b.model != "wall"]

    @property
    def per_storey(self) -> bool:
        """Whether the dataset holds per-storey outputs (yielding buildings, one a shear one)."""
        return self.inelastic and self.mdof

    @property
    def _varied(self) -> list[str]:
        """Scene keys the study varies (grid axes and sampled keys)."""
        return [*self.study.grid, *(v.key for v in self.study.variables)]

    def _run_scenes(self, indices: np.ndarray, out: dict, level: int = 0) -> dict:
        """Run simulations ``indices`` one by one, each its own :meth:`scene_of`.

        ``level``: the refinement (:meth:`run_indices`), ``dt_s / 2^level`` and ``substeps``
        times ``2^level``.
        """
        names = (*RESULT_VARIABLES, *(INELASTIC_VARIABLES if self.inelastic else ()))
        try:
            for k, index in enumerate(indices):
                scene, record = self.scene_of(int(index)), self.record_of(int(index))
                if level:
                    finer = 2**level if scene.method == "adaptive" else 1
                    scene = replace(scene, dt_s=scene.dt_s * 0.5**level,
                                    substeps=scene.substeps * finer)  # fmt: skip
                res = simulate(scene, record=record)  # with the accuracy check, if on
                for name in names:
                    out[name][k] = res.outputs[name]
                if self.mdof:
                    for name in CONTACT_VARIABLES:
                        out[name][k] = res.contacts[name.removeprefix("contact_")]
                if self.per_storey:
                    for name, key in _STOREY_KEYS.items():
                        out[name][k] = res.storeys[key]
                if self.row:
                    for name in BUILDING_VARIABLES:
                        out[name][k] = [b[name] for b in res.buildings]
        except InputError as exc:  # a law the method cannot step: the key, without the file
            raise named_by(exc, self.study.path) from None
        return out

    def run_indices(self, indices: np.ndarray) -> dict[str, np.ndarray]:
        """Run the simulations with flat ``indices``; the outputs of :meth:`result_layout`.

        With the accuracy check on, the runs it flags ``inaccurate`` are run again with
        ``dt_s`` halved and (``adaptive``) ``substeps`` doubled, at most
        :data:`MAX_REFINEMENTS` times (or until the check's ``substeps`` would pass the key's
        bound); each keeps the outputs of its last run that ended ok or inaccurate, and
        ``run_dt_s``, ``run_substeps``, ``refinements`` say which settings gave them.
        """
        indices = np.asarray(indices, dtype=np.int64)
        out = self._run_level(indices, 0)
        out["refinements"] = np.zeros(indices.size, dtype=np.int8)
        base_sub = int(self._base["integrator.substeps"])
        adaptive = self._base["integrator.method"] == "adaptive"
        eligible = np.ones(indices.size, dtype=bool)
        if self._base["integrator.accuracy_check"]:
            for level in range(1, MAX_REFINEMENTS + 1):
                flagged = np.flatnonzero((out["status"] == STATUS_INACCURATE) & eligible)
                # adaptive's check runs twice the sub-steps: both within the key's bound
                if flagged.size == 0 or (
                    adaptive and base_sub * 2**level * ADAPTIVE_SUBSTEPS_FACTOR > MAX_SUBSTEPS
                ):
                    break
                again = self._run_level(indices[flagged], level)
                # a finer run that failed (unstable, not converged) does not replace a result
                # the analyses can still count: that run keeps its last usable one
                usable = np.isin(again["status"], (STATUS_OK, STATUS_INACCURATE))
                eligible[flagged[~usable]] = False
                for name, values in again.items():
                    out[name][flagged[usable]] = values[usable]
                out["refinements"][flagged[usable]] = level
        dt_s = self.parameters(indices)["integrator.dt_s"]
        out["run_dt_s"] = dt_s * 0.5 ** out["refinements"].astype(float)
        # fixed-step methods have no sub-steps to refine: their substeps stay the study's
        factor = 2 ** out["refinements"].astype(np.int32) if adaptive else 1
        out["run_substeps"] = base_sub * factor
        return out

    def run_at_gaps(self, indices: np.ndarray, gaps: np.ndarray) -> dict[str, np.ndarray]:
        """Run the simulations ``indices`` again, each with its own gap ``gaps`` [m].

        The per-simulation outputs of :data:`~pound_mc.study.dataset.RESULT_VARIABLES`
        (no refinement); SDOF-pair studies only (a separation rule's gap is one number).
        """
        if self.mdof or self.per_scene:
            raise InputError("runs at a gap of their own are for studies of two SDOF "
                             "buildings", file=self.study.path, key="contact.gap_m")  # fmt: skip
        return self._run_level(np.asarray(indices, np.int64), 0, gaps=np.asarray(gaps, float))

    def _run_level(self, indices: np.ndarray, level: int, gaps=None) -> dict[str, np.ndarray]:
        """Run ``indices`` at refinement ``level`` (``dt_s / 2^level``, ``substeps 2^level``).

        ``gaps``: each simulation's gap in place of the study's (:meth:`run_at_gaps`).
        """
        p = self.parameters(indices)
        if gaps is not None:
            p["contact.gap_m"] = gaps
        n = p["record"].size
        out = {
            name: np.empty((n, *tail), dtype=dtype)
            for name, (tail, dtype) in self.result_layout().items()
            if name not in RUN_VARIABLES
        }
        if self.per_scene:
            return self._run_scenes(indices, out, level)
        adaptive = self._base["integrator.method"] == "adaptive"
        settings = {
            "method": self._base["integrator.method"],
            "contact_model": self._base["contact.model"],
            "substeps": self._base["integrator.substeps"] * (2**level if adaptive else 1),
            "accuracy_check": self._base["integrator.accuracy_check"],
            "relation": self._base["contact.relation"] or None,
        }
        if "contact.restitution" in self._base:
            settings["restitution"] = self._base["contact.restitution"]
        # one batch per record and intensity (the intensity axis scales the record)
        group = p["record"]
        if self._intensity_axis is not None:
            n_im = self.shape[self._intensity_axis]
            group = group * n_im + np.unravel_index(indices, self.shape)[self._intensity_axis]
        for g in np.unique(group):
            sel = np.flatnonzero(group == g)
            r, j = divmod(int(g), n_im) if self._intensity_axis is not None else (int(g), 0)
            dt_rec, acc = self._scaled_record(r, j)
            common = {
                "gap_m": p["contact.gap_m"][sel],
                "beta": p["contact.beta"][sel],
                "xi": p["contact.xi"][sel],
                "dt_s": p["integrator.dt_s"][sel] * 0.5**level,
                **settings,
            }
            if self.mdof:
                batch = integrators.simulate_scene_batch
                part, contacts = batch(acc, dt_rec, self.arrays, **common)
                for name in CONTACT_VARIABLES:
                    out[name][sel] = contacts[name.removeprefix("contact_")]
            else:
                structure = {f"{side}_{name}": p[f"{side}.{name}"][sel]
                             for side in ("left", "right")
                             for name in ("period_s", "damping_ratio", "mass_kg")}  # fmt: skip
                part = integrators.simulate_sdof_pairs(acc, dt_rec, **structure, **common)
            for name in RESULT_VARIABLES:
                out[name][sel] = part[name]
        return out

    def calibrate(
        self, workers: int | None = None, n: int | None = None, budget_s: float = 20.0,
        min_s: float = CALIBRATION_MIN_S,
    ) -> tuple[float, float, int]:  # fmt: skip
        """Time a short run of simulations spread evenly over the study.

        ``n`` simulations; ``None``: :data:`CALIBRATION_SIZE`, then as many more as last
        ``min_s`` seconds (or the whole study), since a short run overstates the time per
        simulation (thread start-up, and the linear response samples share before their
        first contact, spread over few: ``studies/benchmark.toml`` on 2 threads, 64 gave 1.7
        times the run's).  Fewer when the first (after compilation) shows that they would
        take more than ``budget_s`` seconds.  Returns the seconds per simulation (after
        compilation, ``workers`` threads), those of the first call (compiling, or loading
        numba's cache) and the number timed.
        """
        total = self.study.n_simulations
        grow = n is None
        n = max(1, min(CALIBRATION_SIZE if n is None else n, total))
        with numba_threads(workers):
            t0 = time.perf_counter()
            self.run_indices(np.zeros(1, dtype=np.int64))  # compile (or load numba's cache)
            first_s = time.perf_counter() - t0
            n = int(max(1, min(n, budget_s / max(first_s, 1e-9))))
            while True:
                indices = np.unique(np.linspace(0, total - 1, n).round().astype(np.int64))
                t1 = time.perf_counter()
                self.run_indices(indices)
                elapsed = time.perf_counter() - t1
                per_sim = max(elapsed, 1e-9) / indices.size
                # enough to last min_s at this rate, within the budget
                want = min(total, 2 * min_s / per_sim, budget_s / per_sim)
                if not grow or elapsed >= min_s or want <= 1.5 * indices.size:
                    break
                n = int(want)
        return per_sim, first_s, int(indices.size)

    # -- dataset ----------------------------------------------------------------------------
    def dataset_parameters(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """Contact parameters for the dataset, each with the dims it varies along.

        ``e``, ``beta`` (or ``k_N_per_m``), ``xi``, ``e_effective`` and every other sampled key.
        """
        study = self.study
        out = {}
        e_dims = _dims_of(study, "contact.e")
        xi_dims = _dims_of(study, "contact.xi")
        per_impact = "contact.restitution" in self._base
        if per_impact:  # e and xi set at every impact from its velocity: no one value
            dims, xi = (), np.asarray(np.nan)
        elif ("contact.e" in self._base and not xi_dims) or e_dims:
            dims = e_dims
            e = (
                study.grid["contact.e"]
                if dims == (grid_dim_name("contact.e"),)
                else self._sampled("contact.e", self._base.get("contact.e"))
            )
            e = np.asarray(e, float)
            xi = np.asarray(self._reported_xi(e), float)
            out["e"] = (dims, e)
        else:
            dims = xi_dims
            xi = (
                study.grid["contact.xi"]
                if dims == (grid_dim_name("contact.xi"),)
                else self._sampled("contact.xi", self._base.get("contact.xi", 0.0))
            )
            xi = np.asarray(xi, float)
        out["xi"] = (dims, xi)
        if self._base["contact.model"] == "jankowski":
            e_eff = np.asarray(np.nan) if per_impact else restitution_of_xi(xi)
            out["e_effective"] = (dims, np.asarray(e_eff, float))
        skey = self.stiffness_key
        name = "beta" if skey == "contact.beta" else "k_N_per_m"
        bdims = _dims_of(study, skey)
        if bdims and bdims[-1] == "sample":
            out[name] = (bdims, self._sampled(skey, None))
        elif not bdims:
            out[name] = ((), np.asarray(float(self._base[skey])))
        for key in self.samples:
            if key not in ("contact.e", "contact.xi", skey):
                out[grid_dim_name(key)] = (_dims_of(study, key), self._sampled(key, None))
        if MATERIAL_KEY in study.grid_labels:
            names = np.asarray(study.grid_labels[MATERIAL_KEY], dtype=object)
            out["material"] = ((grid_dim_name(MATERIAL_KEY),), names)
        if self.mdof:
            out.update(self.contact_coordinates())
        if self.row:
            dims = ("building",)
            models = [b.model for b in self._row_buildings]
            out["building"] = (dims, np.arange(len(models), dtype=np.int32))
            out["building_model"] = (dims, np.asarray(models, dtype=object))
        if self.per_storey:
            table = self.scene.storey_arrays()[1]
            which = storey_results(table, np.zeros((table.shape[0], 2)))
            dims = ("storey",)
            out["storey"] = (dims, np.arange(1, table.shape[0] + 1, dtype=np.int32))
            out["storey_building"] = (dims, which["building"].astype(object))
            out["storey_number"] = (dims, which["storey"])
        out.update(self.record_variables())
        return out

    def record_variables(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """Per-record metadata for the dataset (studies with an intensity axis or a suite/glob).

        ``record_event``, ``record_station`` (text), ``record_pga_g`` and, where a record has
        ``sa_period_s``, ``record_sa_period_s`` and ``record_sa_g`` (unscaled) [g], and with an
        intensity axis ``scale_factor`` ``(record, intensity axis)`` [-].  Nothing for other
        studies (their datasets stay as they were).
        """
        study = self.study
        if self.intensity_key is None and not study.record_meta:
            return {}
        dims = ("record",)
        meta = study.record_meta or [{} for _ in study.records]
        out = {
            name: (dims, np.asarray([m.get(what) or label for m, label in
                                     zip(meta, self.record_labels[what], strict=True)],
                                    dtype=object))
            for name, what in (("record_event", "event"), ("record_station", "station"))
        }  # fmt: skip
        out["record_pga_g"] = (dims, self.record_pga_g)
        if self.record_sa_g is not None:
            out["record_sa_period_s"] = (dims, self.sa_period_s)
            out["record_sa_g"] = (dims, self.record_sa_g)
        if self.scale_factors is not None:
            im_dims = ("record", grid_dim_name(self.intensity_key))
            out["scale_factor"] = (im_dims, self.scale_factors)
        return out

    def contact_coordinates(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """Coordinates of the ``contact`` dimension (floors 1-based, elevations [m])."""
        contacts = self.scene.contacts
        elevation = [np.nan if c.elevation_m is None else c.elevation_m for c in contacts]
        dims = ("contact",)
        return {
            "contact": (dims, np.arange(1, len(contacts) + 1, dtype=np.int32)),
            "contact_elevation": (dims, np.asarray(elevation, dtype=float)),
            "contact_left_floor": (dims, np.array([c.left_floor + 1 for c in contacts], np.int32)),
            "contact_right_floor": (
                dims,
                np.array([c.right_floor + 1 for c in contacts], np.int32),
            ),
            **(
                {"contact_pair": (dims, np.array([c.pair for c in contacts], np.int32))}
                if self.row
                else {}
            ),  # fmt: skip
        }

    def _sampled(self, key: str, default) -> np.ndarray:
        """Sampled values of ``key``: ``(n_materials, n)`` if it follows the material axis."""
        if key in self.material_samples:
            return self.material_samples[key]
        if key in self.samples:
            return self.samples[key]
        return np.asarray(default)

    def provenance(self) -> dict:
        """Versions of the software that produced the numbers."""
        return {
            "pound_mc_version": __version__,
            "numba_version": numba.__version__,
            "numpy_version": np.__version__,
            "scipy_version": scipy.__version__,
            "xarray_version": xr.__version__,
            "netcdf4_version": netCDF4.__version__,
            "integrator_method": self._base["integrator.method"],
            "contact_model": self._base["contact.model"],
            "xi_relation": self._base["contact.relation"],
        }
