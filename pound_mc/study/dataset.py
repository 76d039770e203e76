"""Study results as a self-describing :class:`xarray.Dataset` and its netCDF file.

Layout (``../shared/DESIGN.md`` section 8): per simulation, dims ``(record, *grid axes,
sample)``: ``peak_force``, ``impacts``, ``max_penetration``, ``peak_disp_left``,
``peak_disp_right``, ``impulse``, ``dissipated_energy``, ``energy_residual``, ``status``.
Per sample: ``e``, ``beta``, ``xi``, ``e_effective`` (with the grid axis instead where that
parameter is a grid axis, scalars where it is fixed).  Summaries over samples:
``peak_force_mean``, ``peak_force_quantile`` (the impact force spectrum) and
``pounding_probability``.  CF-1.13 attributes and provenance in global attributes.

With a shear building the contacts are the pairs of floors at equal height, along a
``contact`` dimension (coordinates ``contact`` 1-based, ``contact_elevation`` [m],
``contact_left_floor`` and ``contact_right_floor`` 1-based): per simulation and contact, dims
``(record, *grid axes, sample, contact)``: ``contact_peak_force``, ``contact_impacts``,
``contact_max_penetration`` and ``contact_impulse``.  The per-simulation variables then sum
(``impacts``, ``impulse``) or take the maximum (``peak_force``, ``max_penetration``) over the
contacts.

A study of a row of buildings (``[[buildings]]``) adds a ``building`` dimension (from 0, left
to right; a wall is none), coordinate ``building_model``: ``peak_disp``, ``peak_ductility``,
``peak_drift`` and ``residual_drift`` per simulation and building; its contacts' coordinate
``contact_pair`` names the building on each contact's left.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from pound_mc.errors import InputError, OutputError
from pound_mc.integrators.accuracy import STATUS_INACCURATE
from pound_mc.integrators.outputs import STATUS_OK
from pound_mc.study.definition import grid_dim_name
from pound_mc.study.files import temporary_beside
from pound_mc.study.schema import ROW_TABLE

__all__ = [
    "RESULT_VARIABLES",
    "RUN_VARIABLES",
    "CONTACT_VARIABLES",
    "CONTACT_COORDINATES",
    "INELASTIC_VARIABLES",
    "BUILDING_VARIABLES",
    "RECORD_VARIABLES",
    "STATUS_FLAGS",
    "QUANTILES",
    "build_dataset",
    "open_dataset",
    "write_netcdf",
    "pounding_counted",
    "study_file",
    "study_folder",
]

#: Per-simulation outputs: name -> (units, long_name, dtype).
RESULT_VARIABLES = {
    "peak_force": ("N", "peak impact force (continuous-time maximum)", "f8"),
    "impacts": ("1", "number of impacts (contact episodes)", "i4"),
    "max_penetration": ("m", "maximum penetration delta", "f8"),
    "peak_disp_left": ("m", "peak absolute displacement of the left building", "f8"),
    "peak_disp_right": ("m", "peak absolute displacement of the right building", "f8"),
    "impulse": ("N s", "total impulse of the impact force", "f8"),
    "dissipated_energy": ("J", "energy dissipated in impacts", "f8"),
    "energy_residual": ("1", "energy balance residual relative to input energy", "f8"),
    "status": ("1", "simulation status", "i1"),
    "max_impact_velocity": (
        "m s-1",
        "largest prior-impact velocity (relative velocity at contact onset) of the impacts",
        "f8",
    ),
    "median_impact_velocity": ("m s-1", "median prior-impact velocity of the impacts", "f8"),
    "peak_force_restitution": (
        "1",
        "coefficient of restitution the contact law really rebounds with at the impact that "
        "holds the peak force (for its damping, fixed or set per impact)",
        "f8",
    ),
}
#: Per-simulation settings a run ended with: the accuracy check's flagged runs are refined
#: (``integrator.dt_s`` halved and ``integrator.substeps`` doubled, at most
#: :data:`~pound_mc.study.engine.MAX_REFINEMENTS` times): name -> (units, long_name, dtype).
RUN_VARIABLES = {
    "run_dt_s": ("s", "integrator step (fixed-step methods) or step bound (adaptive) the run "
                 "ended with", "f8"),
    "run_substeps": ("1", "contact sub-steps per contact duration (adaptive) the run ended "
                     "with", "i4"),
    "refinements": ("1", "times the run was refined (dt_s halved, substeps doubled) because "
                    "the accuracy check flagged it", "i1"),
}  # fmt: skip
#: Per-simulation, per-contact outputs of studies with a shear building (an extra trailing
#: ``contact`` dimension): name -> (units, long_name, dtype).  Each is ``contact_`` and the
#: per-simulation quantity of :data:`RESULT_VARIABLES` it takes its units and dtype from.
CONTACT_VARIABLES = {
    f"contact_{name}": (RESULT_VARIABLES[name][0], long_name, RESULT_VARIABLES[name][2])
    for name, long_name in {
        "peak_force": "peak impact force at the contact",
        "impacts": "number of impacts (contact episodes) at the contact",
        "max_penetration": "maximum penetration delta at the contact",
        "impulse": "impulse of the impact force at the contact",
        "max_impact_velocity": "largest prior-impact velocity at the contact",
    }.items()
}
#: Per-simulation outputs of studies with yielding buildings (DESIGN.md section 9): name ->
#: (units, long_name, dtype).  Drift ratios are NaN for an SDOF without ``height_m``, the
#: ductility of a building that cannot yield is NaN.
INELASTIC_VARIABLES = {
    "peak_ductility_left": ("1", "peak storey drift over yield drift, left building", "f8"),
    "peak_ductility_right": ("1", "peak storey drift over yield drift, right building", "f8"),
    "peak_drift_left": ("1", "peak inter-storey drift ratio of the left building", "f8"),
    "peak_drift_right": ("1", "peak inter-storey drift ratio of the right building", "f8"),
    "residual_drift_left": ("1", "largest inter-storey drift ratio of the left building after "
                            "the free-vibration tail", "f8"),
    "residual_drift_right": ("1", "largest inter-storey drift ratio of the right building "
                             "after the free-vibration tail", "f8"),
    "hysteretic_energy": ("J", "energy dissipated by yielding storeys", "f8"),
    "peak_floor_accel_left": ("m s-2", "peak absolute floor acceleration, left building", "f8"),
    "peak_floor_accel_right": ("m s-2", "peak absolute floor acceleration, right building",
                               "f8"),
}  # fmt: skip
#: Per-storey outputs of studies with yielding shear buildings (an extra trailing ``storey``
#: dimension over the storeys of both buildings, the left building's first; the coordinate
#: ``storey_building`` says whose): name -> (units, long_name, dtype).  The scalar
#: ``peak_drift_left`` ... are their maxima over a building's storeys.
STOREY_VARIABLES = {
    "storey_peak_drift": ("1", "peak inter-storey drift ratio of the storey", "f8"),
    "storey_peak_ductility": ("1", "peak storey drift over yield drift of the storey", "f8"),
    "storey_residual_drift": ("1", "inter-storey drift ratio of the storey after the "
                              "free-vibration tail", "f8"),
}  # fmt: skip
#: Coordinates of the ``storey`` dimension: name -> (units, long_name); text ones have none.
STOREY_COORDINATES = {
    "storey": ("1", "storey index over both buildings (left building's first), 1-based"),
    "storey_building": (None, "building of the storey (left or right)"),
    "storey_number": ("1", "storey within its building, bottom to top, 1-based"),
}
#: Per-building outputs of studies of a row of buildings (``[[buildings]]``; an extra trailing
#: ``building`` dimension from 0, left to right, a wall none): name -> (units, long_name,
#: dtype).  ``peak_disp_left`` / ``..._right`` are the first building's and the last's.
BUILDING_VARIABLES = {
    "peak_disp": ("m", "peak absolute displacement of the building (its floors' largest)",
                  "f8"),
    "peak_ductility": ("1", "peak storey drift over yield drift of the building (NaN: elastic)",
                       "f8"),
    "peak_drift": ("1", "peak inter-storey drift ratio of the building (NaN: elastic or no "
                   "heights)", "f8"),
    "residual_drift": ("1", "largest inter-storey drift ratio of the building after the "
                       "free-vibration tail (NaN: elastic or no heights)", "f8"),
}  # fmt: skip
#: Coordinates of the ``building`` dimension: name -> (units, long_name); text ones have none.
BUILDING_COORDINATES = {
    "building": ("1", "place of the building in the row, left to right, from 0"),
    "building_model": (None, "structural model of the building (sdof or shear)"),
}
#: Coordinates of the ``contact`` dimension: name -> (units, long_name).
CONTACT_COORDINATES = {
    "contact": ("1", "contact index (pair of floors at equal height), 1-based"),
    "contact_elevation": ("m", "elevation of the contact above the ground"),
    "contact_left_floor": ("1", "floor of the left building at the contact, 1-based"),
    "contact_right_floor": ("1", "floor of the right building at the contact, 1-based"),
    "contact_pair": (
        "1",
        "building on the left of the contact, its place in the row from 0 "
        "(the right one is the next)",
    ),
}
#: Per-record variables of studies with an intensity axis or a suite/glob of records:
#: name -> (units, long_name); text ones (no units) are coordinates of ``record``.
RECORD_VARIABLES = {
    "record_event": (None, "earthquake of the record"),
    "record_station": (None, "recording station of the record"),
    "record_pga_g": ("1", "peak ground acceleration of the unscaled record in units of g"),
    "record_sa_period_s": ("s", "period of the record's spectral acceleration"),
    "record_sa_g": (
        "1",
        "5 %-damped pseudo-spectral acceleration of the unscaled record at record_sa_period_s "
        "in units of g",
    ),
    "scale_factor": ("1", "factor that scales the record to the intensity of the grid axis"),
}
#: Status codes of a simulation (CF flag_values / flag_meanings).
STATUS_FLAGS = {0: "ok", 1: "unstable", 2: "not_converged", 3: "inaccurate"}
#: Quantiles of the impact force spectrum.
QUANTILES = (0.05, 0.16, 0.5, 0.84, 0.95)

_PARAMETER_ATTRS = {
    "e": ("1", "coefficient of restitution (target)"),
    "beta": ("N m-1.5", "impact stiffness parameter"),
    "k_N_per_m": ("N m-1", "linear impact stiffness"),
    "xi": ("1", "impact damping ratio (NaN: set at every impact)"),
    "e_effective": (
        "1",
        "coefficient of restitution the contact law really produces (NaN: set at every impact)",
    ),
    "gap_m": ("m", "initial separation gap"),
    "period_s": ("s", "natural period"),
    "damping_ratio": ("1", "structural damping ratio"),
    "mass_kg": ("kg", "mass"),
    "dt_s": ("s", "integration step"),
    "pga_g": ("1", "peak ground acceleration in units of g"),
    "sa_g": ("1", "5 %-damped pseudo-spectral acceleration in units of g"),
    "duration_s": ("s", "record duration kept"),
    "yield_disp_m": ("m", "displacement at yield"),
    "post_yield_ratio": ("1", "post-yield over elastic stiffness"),
    "storey_mass_kg": ("kg", "mass of every floor"),
    "storey_stiffness_N_per_m": ("N m-1", "stiffness of every storey"),
    "storey_yield_disp_m": ("m", "inter-storey drift at yield of every storey"),
}


def _param_attrs(key: str) -> dict:
    table, name = key.split(".", 1) if "." in key else ("", key)
    if table == ROW_TABLE:  # "buildings.N.KEY": building N of a row
        table, _, name = name.partition(".")
        table = f"building {table}"
    units, long_name = _PARAMETER_ATTRS.get(name, ("1", name))
    prefix = f"{table} " if table.startswith(("left", "right", "record", "building")) else ""
    return {"units": units, "long_name": prefix + long_name, "scene_key": key}


def pounding_counted(status: xr.DataArray) -> xr.DataArray:
    """Where a simulation counts for the pounding probability: status ok or inaccurate.

    ``inaccurate`` doubts a run's peak force or displacements
    (:mod:`pound_mc.integrators.accuracy`), not whether it pounded; and most flagged runs had a
    contact, so leaving them out would lower the probability (a newmark study at 5 ms with 94 %
    of its runs flagged read 0 where 94 % pounded).  A run flagged without a contact counts as
    one that did not pound.  Unstable and not converged runs are left out.
    """
    return (status == STATUS_OK) | (status == STATUS_INACCURATE)


def build_dataset(
    study,
    results: dict[str, np.ndarray],
    parameters: dict[str, tuple[tuple[str, ...], np.ndarray]],
    *,
    provenance: dict | None = None,
) -> xr.Dataset:
    """Assemble the study dataset.

    Parameters
    ----------
    study : pound_mc.study.definition.Study
        The validated study (axes, names, text, hash, seed).
    results : dict
        Per-simulation outputs, each an array of shape ``study.shape``; the names of
        :data:`CONTACT_VARIABLES` (optional) of shape ``(*study.shape, n_contacts)``, those of
        :data:`STOREY_VARIABLES` (optional) of shape ``(*study.shape, n_storeys)``.
    parameters : dict
        Contact and sampled parameters: ``{name: (dims, values)}`` (e.g. ``"e": (("sample",),
        array)``); names of :data:`CONTACT_COORDINATES` become coordinates (kept only with
        the contact variables), as are those of :data:`STOREY_COORDINATES` (kept only with the
        storey variables).
    provenance : dict, optional
        Extra global attributes.
    """
    dims = ("record", *(grid_dim_name(k) for k in study.grid), "sample")
    sample_attrs, saltelli = _saltelli_attrs(study)
    coords = {
        "record": ("record", np.asarray(study.record_names, dtype=object), {
            "long_name": "ground-motion record", "cf_role": "timeseries_id"}),
        "sample": ("sample", np.arange(study.n, dtype=np.int32), {
            "long_name": "Monte Carlo sample index", "units": "1", **sample_attrs}),
    }  # fmt: skip
    for key, values in study.grid.items():
        coords[grid_dim_name(key)] = (grid_dim_name(key), values, _param_attrs(key))
    data_vars = {}
    for name, (units, long_name, dtype) in RESULT_VARIABLES.items():
        attrs = {"units": units, "long_name": long_name}
        if name == "status":
            attrs = {
                "long_name": long_name,
                "flag_values": np.array(list(STATUS_FLAGS), dtype=np.int8),
                "flag_meanings": " ".join(STATUS_FLAGS.values()),
                "units": "1",
            }
        data_vars[name] = (dims, np.asarray(results[name]).astype(dtype, copy=False), attrs)
    for name in (n for n in RUN_VARIABLES if n in results):
        units, long_name, dtype = RUN_VARIABLES[name]
        values = np.asarray(results[name]).astype(dtype, copy=False)
        data_vars[name] = (dims, values, {"units": units, "long_name": long_name})
    for name in (n for n in INELASTIC_VARIABLES if n in results):
        units, long_name, dtype = INELASTIC_VARIABLES[name]
        values = np.asarray(results[name]).astype(dtype, copy=False)
        data_vars[name] = (dims, values, {"units": units, "long_name": long_name})
    per_contact = [name for name in CONTACT_VARIABLES if name in results]
    for name in per_contact:
        units, long_name, dtype = CONTACT_VARIABLES[name]
        values = np.asarray(results[name]).astype(dtype, copy=False)
        data_vars[name] = ((*dims, "contact"), values, {"units": units, "long_name": long_name})
    per_storey = [name for name in STOREY_VARIABLES if name in results]
    for name in per_storey:
        units, long_name, dtype = STOREY_VARIABLES[name]
        values = np.asarray(results[name]).astype(dtype, copy=False)
        data_vars[name] = ((*dims, "storey"), values, {"units": units, "long_name": long_name})
    per_building = [name for name in BUILDING_VARIABLES if name in results]
    for name in per_building:
        units, long_name, dtype = BUILDING_VARIABLES[name]
        values = np.asarray(results[name]).astype(dtype, copy=False)
        data_vars[name] = ((*dims, "building"), values, {"units": units, "long_name": long_name})
    for name, (pdims, values) in parameters.items():
        if name in BUILDING_COORDINATES:
            if per_building:
                units, long_name = BUILDING_COORDINATES[name]
                attrs = {"long_name": long_name, **({"units": units} if units else {})}
                coords[name] = (pdims, values, attrs)
            continue
        if name in STOREY_COORDINATES:
            if per_storey:
                units, long_name = STOREY_COORDINATES[name]
                attrs = {"long_name": long_name, **({"units": units} if units else {})}
                coords[name] = (pdims, values, attrs)
            continue
        if name in CONTACT_COORDINATES:
            if per_contact:
                units, long_name = CONTACT_COORDINATES[name]
                coords[name] = (pdims, values, {"units": units, "long_name": long_name})
            continue
        if name in RECORD_VARIABLES:
            units, long_name = RECORD_VARIABLES[name]
            if units is None:
                coords[name] = (pdims, values, {"long_name": long_name})
            else:
                data_vars[name] = (pdims, values, {"units": units, "long_name": long_name})
            continue
        data_vars[name] = (pdims, values, _param_attrs(name))

    ds = xr.Dataset(data_vars, coords=coords)
    ok = ds["status"] == 0
    force = ds["peak_force"].where(ok)
    with warnings.catch_warnings():
        # where every sample was flagged the summaries are NaN, which is the answer
        warnings.filterwarnings("ignore", "All-NaN slice", RuntimeWarning)
        warnings.filterwarnings("ignore", "Mean of empty slice", RuntimeWarning)
        ds["peak_force_mean"] = force.mean("sample")
        q = force.quantile(list(QUANTILES), dim="sample")
    ds["peak_force_mean"].attrs = {"units": "N", "long_name": "mean peak impact force over samples"}
    ds["peak_force_quantile"] = q
    ds["peak_force_quantile"].attrs = {
        "units": "N",
        "long_name": "quantiles of peak impact force over samples (impact force spectrum)",
    }
    ds["quantile"].attrs = {"long_name": "quantile level", "units": "1"}
    pounding = (ds["impacts"] > 0).where(pounding_counted(ds["status"]))
    ds["pounding_probability"] = pounding.mean("sample")
    ds["pounding_probability"].attrs = {
        "units": "1",
        "long_name": "fraction of samples with at least one impact (status ok or inaccurate)",
    }
    for var in ds.variables.values():  # CF: units on every variable (text labels: "1")
        var.attrs.setdefault("units", "1")
    ds.attrs = {
        "Conventions": "CF-1.13",
        "title": f"pound-mc study {study.name}",
        "source": "pound-mc Monte Carlo pounding study",
        "study_name": study.name,
        "study_hash": study.hash,
        "study_text": study.text,
        # where relative record paths of the study text are read from, when analysed again
        **({"study_dir": str(Path(study.path).resolve().parent)} if study.path else {}),
        **({"study_file": Path(study.path).name} if study.path else {}),
        "seed": study.seed,
        "sampling_method": study.method,
        "sampling_seed": study.sampling_seed,
        "sampled_variables": "; ".join(f"{v.key}: {v.source}" for v in study.variables),
        **saltelli,
        **(provenance or {}),
    }
    return ds


def _saltelli_attrs(study) -> tuple[dict, dict]:
    """Saltelli's design as the sensitivity analysis reads it back (``method = "saltelli"``).

    The ``sample`` coordinate's ``comment`` (how its N (D + 2) samples are laid out) and the
    global attributes ``saltelli_base_n`` (N), ``saltelli_n_variables`` (D) and
    ``saltelli_variables`` (the sampled study keys in the design's column order, ``"; "``
    between them); empty for the other designs.
    """
    if study.base_n is None:
        return {}, {}
    d = len(study.variables)
    comment = (
        f"Saltelli's design (SALib, first and total order): sample = {d + 2} b + r for base "
        f"point b (0..{study.base_n - 1}); r = 0 is matrix A's row, r = j (1..{d}) A's row with "
        f"column j from B, r = {d + 1} B's row"
    )
    return {"comment": comment}, {
        "saltelli_base_n": int(study.base_n),
        "saltelli_n_variables": d,
        "saltelli_variables": "; ".join(v.key for v in study.variables),
    }


def study_folder(ds: xr.Dataset, fallback: str | Path | None = None) -> Path | None:
    """The folder of the study file a dataset was run from (``study_dir``), or ``fallback``.

    Relative record paths of the study text are read from there; ``fallback`` where the
    dataset does not say (an older dataset) or that folder is gone.
    """
    folder = ds.attrs.get("study_dir")
    if folder and Path(folder).is_dir():
        return Path(folder)
    return None if fallback is None else Path(fallback)


def study_file(ds: xr.Dataset, fallback: str | Path | None = None) -> Path | None:
    """The study file a dataset was run from, in :func:`study_folder` (None: not known).

    Records given by a relative path are read from its folder, and messages name it; a dataset
    written before ``study_file`` was stored is named ``<study_name>.toml``.
    """
    folder = study_folder(ds, fallback)
    if folder is None:
        return None
    return folder / ds.attrs.get("study_file", f"{ds.attrs.get('study_name', 'study')}.toml")


def write_netcdf(ds: xr.Dataset, path: str | Path) -> Path:
    """Write ``ds`` to ``path`` atomically (a new temporary file renamed into place).

    Coordinates carry no ``_FillValue`` (CF 2.5.1: a coordinate has no missing values);
    float data variables use NaN.  The file is written in a new private folder beside
    ``path`` (:func:`~pound_mc.study.files.temporary_beside`) and renamed over it: a link at
    ``path`` is replaced, never written through.

    Raises
    ------
    pound_mc.errors.OutputError
        The file cannot be written (disk full, read-only folder, a folder in its place): the
        temporary file is removed and the message names ``path``.
    """
    path = Path(path)
    encoding = {}
    for name, var in ds.variables.items():
        if name in ds.coords:
            encoding[name] = {"_FillValue": None}
        elif var.dtype.kind == "f":
            encoding[name] = {"_FillValue": np.nan}
        if var.dtype.kind == "O":
            encoding.setdefault(name, {})["dtype"] = str
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with temporary_beside(path) as tmp:
            ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=encoding)
    except (OSError, RuntimeError) as exc:  # netCDF4 reports a full disk as "NetCDF: HDF error"
        reason = getattr(exc, "strerror", None) or str(exc)
        raise OutputError(f"cannot write the dataset: {reason}", file=str(path)) from None
    return path


def open_dataset(path: str | Path) -> xr.Dataset:
    """Open the study dataset ``pound-mc run`` wrote at ``path`` (``OUT/NAME.nc``).

    The file is opened lazily, as :func:`xarray.open_dataset` does; the ``ds.pound`` accessor
    is registered by ``import pound_mc``.

    Raises
    ------
    pound_mc.errors.InputError
        ``path`` is no file, not a netCDF dataset, or not a pound-mc study dataset (no
        ``peak_force``, ``impacts`` or ``status``); the message names the file.
    """
    path = Path(path)
    if not path.is_file():
        what = "is a folder" if path.is_dir() else "no such file"
        raise InputError(f"{what}; give a study dataset (pound-mc run writes OUT/NAME.nc)",
                         file=str(path))  # fmt: skip
    try:
        ds = xr.open_dataset(path)
    except (OSError, ValueError, TypeError):
        raise InputError(
            "is not a netCDF dataset (pound-mc run writes one as OUT/NAME.nc)", file=str(path)
        ) from None
    missing = [v for v in ("peak_force", "impacts", "status") if v not in ds]
    if missing:
        ds.close()
        raise InputError(
            f"is not a pound-mc study dataset: no variable {missing[0]!r}", file=str(path)
        )
    return ds
