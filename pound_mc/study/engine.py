"""Prepared study: records loaded, samples drawn, per-simulation parameters on demand.

:class:`StudyEngine` turns a validated :class:`~pound_mc.study.Study` into arrays the compiled
batch kernel takes, for any half-open range of simulation indices (C order of
``study.shape``).  Everything random is drawn once, in Python, before any range runs, so a
range's results depend only on the study and the indices - not on threads, chunk size or
backend.

SDOF pairs run through :func:`~pound_mc.integrators.simulate_sdof_pairs`; a pair with a shear
building through :func:`~pound_mc.integrators.kernels.simulate_scene_batch` with the modes of the
study's one structure (:meth:`~pound_mc.scene.Scene.modal_arrays`, computed once), and then
also gives the per-contact outputs of :data:`~pound_mc.study.dataset.CONTACT_VARIABLES`.
"""

from __future__ import annotations

import time

import numba
import numpy as np
import xarray as xr

from pound_mc._version import __version__
from pound_mc.errors import InputError
from pound_mc.integrators.threads import numba_threads
from pound_mc.physics.contact import default_relation, reported_xi
from pound_mc.physics.relations import restitution_of_xi
from pound_mc.study.dataset import CONTACT_VARIABLES, RESULT_VARIABLES
from pound_mc.study.definition import MATERIAL_KEY, grid_dim_name, scene_model

__all__ = ["StudyEngine"]

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


class StudyEngine:
    """Records, samples and base scene of a study, ready to run ranges of simulations.

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        A validated study (its records already read and preprocessed).
    """

    def __init__(self, study):
        from pound_mc.motions.records import load_record, record_arrays
        from pound_mc.scene import scene_from_dict

        self.study = study
        overrides = {
            key: float(values[0]) for key, values in study.grid.items() if key != MATERIAL_KEY
        }
        self.samples = study.draw()
        #: Sampled keys that follow the material axis: ``{key: (n_materials, n)}``.
        self.material_samples = study.draw_materials()
        overrides.update({key: float(values[0]) for key, values in self.samples.items()})
        self.scene = scene_from_dict(study.scene_dict(0, overrides), file=study.path)
        if study.record_arrays:
            self.records = list(study.record_arrays)
        else:  # a Study built by hand: read the records now
            base_dir = None if study.path is None else study.path.parent
            self.records = []
            for spec in study.records:
                spec = dict(spec)
                spec.pop("name", None)
                trace = load_record(spec.pop("source"), base_dir=base_dir, **spec)
                self.records.append(record_arrays(trace))
        self.shape = study.shape
        self._base = self._base_values(study.scene, self.scene)
        #: Whether a building is a shear building: then every simulation runs the modes of
        #: :attr:`arrays` (computed once) through the general batch, and the outputs include
        #: the per-contact arrays of :data:`~pound_mc.study.dataset.CONTACT_VARIABLES`.
        self.mdof = any(scene_model(study.scene, side) == "shear" for side in ("left", "right"))
        self.arrays = self.scene.modal_arrays() if self.mdof else None

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
        return out

    def _values(self, key: str, idx: tuple[np.ndarray, ...]) -> np.ndarray | None:
        """Per-simulation values of ``key`` at unravelled indices ``idx``."""
        study = self.study
        if key in study.grid:
            axis = list(study.grid).index(key) + 1
            return study.grid[key][idx[axis]]
        if key in self.material_samples:
            axis = list(study.grid).index(MATERIAL_KEY) + 1
            return self.material_samples[key][idx[axis], idx[-1]]
        if key in self.samples:
            return self.samples[key][idx[-1]]
        if key in self._base:
            return np.full(idx[0].shape, float(self._base[key]))
        return None

    @property
    def stiffness_key(self) -> str:
        """Scene key of the contact stiffness (``contact.k_N_per_m`` for linear laws)."""
        return (
            "contact.k_N_per_m"
            if self._base["contact.model"] in ("linear", "kelvin")
            else "contact.beta"
        )

    def contact_damping(self, idx) -> tuple[np.ndarray, np.ndarray | None]:
        """Impact damping ratio per simulation (and the target ``e`` where one is given)."""
        varied = set(self.study.grid) | set(self.samples)
        e = None if "contact.xi" in varied else self._values("contact.e", idx)
        if e is not None:
            return np.asarray(self._reported_xi(e), float), e
        xi = self._values("contact.xi", idx)
        if xi is None:
            xi = np.zeros(idx[0].shape)  # laws without damping (linear, hertz)
        return xi, None

    def _reported_xi(self, e):
        """Damping ratio the kernels run with for ``e`` (NaN for hertzdamp: set per impact)."""
        return reported_xi(self._base["contact.model"], e, self._base["contact.relation"] or None)

    def parameters(self, indices: np.ndarray) -> dict[str, np.ndarray]:
        """Per-simulation kernel parameters of the simulations with flat ``indices``.

        With a shear building (:attr:`mdof`) only the contact keys and the step: the gaps
        ``contact.gap_m`` are then ``(n, n_contacts)`` where the scene fixes them.
        """
        idx = np.unravel_index(np.asarray(indices, dtype=np.int64), self.shape)
        out = {}
        for key in _SCENE_KERNEL_KEYS if self.mdof else _KERNEL_KEYS:
            source = self.stiffness_key if key == "contact.beta" else key
            if self.mdof and key == "contact.gap_m" and _dims_of(self.study, key) == ():
                gaps = np.broadcast_to(self.scene.gap_m, (idx[0].size, self.scene.gap_m.size))
                out[key] = np.ascontiguousarray(gaps, float)  # one gap per contact (the scene's)
                continue
            values = self._values(source, idx)
            if values is None:
                raise InputError("is required", file=self.study.path, key=source)
            out[key] = np.ascontiguousarray(values, float)
        xi, e = self.contact_damping(idx)
        if self._base["contact.model"] == "hertzdamp":
            xi = e  # the Hertz-damp law takes the restitution coefficient itself
        out["contact.xi"] = np.ascontiguousarray(xi, float)
        out["record"] = idx[0]
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
        if self.mdof:
            nc = self.n_contacts
            out.update({name: ((nc,), dtype) for name, (_, _, dtype) in CONTACT_VARIABLES.items()})
        return out

    def run_indices(self, indices: np.ndarray) -> dict[str, np.ndarray]:
        """Run the simulations with flat ``indices``; the outputs of :meth:`result_layout`."""
        from pound_mc.integrators import kernels as integrators

        p = self.parameters(indices)
        n = p["record"].size
        out = {
            name: np.empty((n, *tail), dtype=dtype)
            for name, (tail, dtype) in self.result_layout().items()
        }
        settings = {
            "method": self._base["integrator.method"],
            "contact_model": self._base["contact.model"],
            "substeps": self._base["integrator.substeps"],
            "relation": self._base["contact.relation"] or None,
        }
        if self.mdof:
            for r in np.unique(p["record"]):
                sel = np.flatnonzero(p["record"] == r)
                dt_rec, acc = self.records[r]
                part, contacts = integrators.simulate_scene_batch(
                    acc,
                    dt_rec,
                    self.arrays,
                    gap_m=p["contact.gap_m"][sel],
                    beta=p["contact.beta"][sel],
                    xi=p["contact.xi"][sel],
                    dt_s=p["integrator.dt_s"][sel],
                    **settings,
                )
                for name in RESULT_VARIABLES:
                    out[name][sel] = part[name]
                for name in CONTACT_VARIABLES:
                    out[name][sel] = contacts[name.removeprefix("contact_")]
            return out
        for r in np.unique(p["record"]):
            sel = np.flatnonzero(p["record"] == r)
            dt_rec, acc = self.records[r]
            part = integrators.simulate_sdof_pairs(
                acc,
                dt_rec,
                left_period_s=p["left.period_s"][sel],
                left_damping_ratio=p["left.damping_ratio"][sel],
                left_mass_kg=p["left.mass_kg"][sel],
                right_period_s=p["right.period_s"][sel],
                right_damping_ratio=p["right.damping_ratio"][sel],
                right_mass_kg=p["right.mass_kg"][sel],
                gap_m=p["contact.gap_m"][sel],
                beta=p["contact.beta"][sel],
                xi=p["contact.xi"][sel],
                dt_s=p["integrator.dt_s"][sel],
                **settings,
            )
            for name in RESULT_VARIABLES:
                out[name][sel] = part[name]
        return out

    def calibrate(self, workers: int | None = None, n: int = 64) -> tuple[float, float]:
        """Time a short run of ``n`` simulations spread evenly over the study.

        Returns
        -------
        seconds_per_simulation : float
            Measured after compilation, with ``workers`` threads.
        compile_seconds : float
            Time of the first (compiling, or cache-loading) call.
        """
        total = self.study.n_simulations
        n = max(1, min(n, total))
        indices = np.unique(np.linspace(0, total - 1, n).round().astype(np.int64))
        with numba_threads(workers):
            t0 = time.perf_counter()
            self.run_indices(indices[:1])  # compile (or load numba's cache)
            t1 = time.perf_counter()
            self.run_indices(indices)
            t2 = time.perf_counter()
        return (t2 - t1) / indices.size, t1 - t0

    # -- dataset ----------------------------------------------------------------------------
    def dataset_parameters(self) -> dict[str, tuple[tuple[str, ...], np.ndarray]]:
        """Contact parameters for the dataset, each with the dims it varies along.

        ``e``, ``beta`` (or ``k_N_per_m``), ``xi``, ``e_effective`` and every other sampled key.
        """
        study = self.study
        out = {}
        e_dims = _dims_of(study, "contact.e")
        xi_dims = _dims_of(study, "contact.xi")
        if ("contact.e" in self._base and not xi_dims) or e_dims:
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
            out["e_effective"] = (dims, np.asarray(restitution_of_xi(xi), float))
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
        import netCDF4
        import scipy

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
