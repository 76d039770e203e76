"""Study files: validation against the declared tables, and the plan of simulations.

A study is a scene (``[record]`` or ``[[records]]``, ``[left]`` and ``[right]`` or a row
``[[buildings]]``, ``[contact]``, ``[integrator]``; see :mod:`pound_mc.scene`) plus

``[study]``
    ``name`` (letters, digits, ``-``, ``_``), ``seed`` (integer >= 0), optional
    ``description`` and ``chunk_size`` (simulations per chunk file; default about 1/50 of the
    study, between 256 and 8192: :func:`pound_mc.study.runner.default_chunk_size`).
``[grid]``
    Axes of the spectra, keyed by the scene key they vary (``"left.period_s"``): a list of
    numbers or ``{ start, stop, num }`` (evenly spaced, both ends included, round-off snapped
    to :data:`~pound_mc.study.schema.GRID_DIGITS` significant digits: :func:`grid_values`).
    Intensity axes ``"record.pga_g"`` or ``"record.sa_g"`` [g] (one per study) scale every
    record to each value: a multiple-stripe analysis (``record.sa_g`` at each record table's
    ``sa_period_s``); the factors are computed by the study engine.  One non-numeric
    axis: ``"contact.material" = ["steel", "concrete", ...]`` (names of
    :data:`pound_mc.physics.materials.MATERIALS`); ``[sampling.vary]`` entries
    ``{ material = "grid" }`` for ``contact.e`` and ``contact.beta`` then take each grid
    point's material's ranges (the same design points for every material: common random
    numbers).  The axis's values are the materials' indices in ``MATERIALS`` (0 steel,
    1 concrete, 2 timber, 3 ceramics); their names are in ``Study.grid_labels``.
``[[records]]``
    One record per table; a table whose ``source`` is a suite (``"suite:fema-p695-farfield"``)
    or a glob (``"records/*.AT2"``, relative to the study file) stands for one record per
    component or file (sorted), each with the table's other keys
    (:func:`pound_mc.study.records.expand_records`).
    Validation counts a suite's components from its metadata and a glob's files.
``[sampling]``
    ``n`` samples per grid point and record, ``method`` (``random`` | ``lhs`` | ``sobol`` |
    ``saltelli``, default ``sobol``), optional ``seed`` (default: the study's), and
    ``[sampling.vary]`` (:mod:`pound_mc.study.sampling`).  With ``saltelli`` ``n`` is the
    base N of Saltelli's design, a power of two >= 2, and the study runs N (D + 2) samples at
    every grid point (D sampled keys, at least one): :attr:`Study.n` is that number,
    :attr:`Study.base_n` is N.

A building's keys may be varied as its model allows (``left.period_s`` of an SDOF building,
``left.storey_stiffness_N_per_m`` of a shear building: a number stands for every storey; yield
keys and ``post_yield_ratio`` of both); a key of the other model is refused.  In a row,
building N's keys are ``"buildings.N.KEY"`` (N from 0, left to right; a wall is none).  A
study that varies a shear building's keys, or gives a row, computes its modes per simulation
(:class:`~pound_mc.study.engine.StudyEngine`), others once per study.

Every key is declared once, with its type, bounds, default, unit and description, in
:mod:`pound_mc.scene.schema` (scene tables) and :mod:`pound_mc.study.schema` (study tables);
``studies/SCHEMA.md`` is generated from them.  Every problem in a file is reported at once
(:class:`~pound_mc.errors.InputErrors`), each naming the file and the key.  Validation checks
keys, types, bounds and that record files exist; the records are read by
:class:`~pound_mc.study.engine.StudyEngine`.  Nothing is written while validating.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pound_mc.errors import InputError, InputErrors, parse_toml, read_text_file
from pound_mc.physics import materials
from pound_mc.scene.schema import BUILDINGS, check_table
from pound_mc.study import records as records_mod
from pound_mc.study import sampling
from pound_mc.study.probe import EXCLUSIVE, fixed_partner, probe
from pound_mc.study.schema import (
    GRID_AXIS,
    GRID_DIGITS,
    INTENSITY_KEYS,
    MATERIAL_KEY,
    MAX_SAMPLES,
    MIN_BYTES_PER_SIMULATION,
    NUMERIC_SCENE_KEYS,
    ROW_KEY,
    ROW_TABLE,
    SAMPLING,
    STUDY,
    TOP_LEVEL,
    is_numeric_key,
)

__all__ = [
    "Study",
    "load_study",
    "study_from_text",
    "NUMERIC_SCENE_KEYS",
    "MATERIAL_KEY",
    "MAX_SAMPLES",
    "INTENSITY_KEYS",
    "grid_dim_name",
    "grid_values",
]

#: The scene tables a study shares between its records.
_SCENE_TABLES = ("left", "right", ROW_TABLE, "contact", "integrator")


def grid_dim_name(key: str) -> str:
    """Dataset dimension name of a grid key (``"left.period_s"`` -> ``"left_period_s"``).

    The intensity axes are ``pga_g`` and ``sa_g`` (``record_pga_g`` and ``record_sa_g`` are
    the records' own, unscaled intensities).
    """
    if key in INTENSITY_KEYS:
        return key.split(".", 1)[1]
    return key.replace(".", "_")


@dataclass
class Study:
    """A validated study definition."""

    path: Path | None
    name: str
    seed: int
    text: str
    hash: str
    scene: dict  # the scene tables ([left], [right], [contact], [integrator]) as read
    records: list[dict]  # one [record] table per record
    grid: dict[str, np.ndarray]
    n: int
    method: str
    sampling_seed: int
    variables: list[sampling.RandomVariable]
    chunk_size: int | None = None
    description: str = ""
    record_names: list[str] = field(default_factory=list)
    #: Where each record's table is in the file (``"record"``, ``"records[2]"``), for messages.
    record_tables: list[str] = field(default_factory=list)
    #: Names behind a non-numeric grid axis's values (``{"contact.material": ["steel", ...]}``).
    grid_labels: dict[str, list[str]] = field(default_factory=dict)
    #: Sampled keys that follow the material axis: ``{key: [variable per material]}`` (the
    #: variable in ``variables`` is the first material's, standing for all of them).
    material_variables: dict[str, list] = field(default_factory=dict)
    #: Per record, what a suite tells of it (``event``, ``station``, ...; empty dicts for other
    #: records); non-empty only when a table was expanded (a suite or a glob).
    record_meta: list[dict] = field(default_factory=list)
    #: Base N of Saltelli's design (``method = "saltelli"``; ``n`` is then N (D + 2)), else None.
    base_n: int | None = None

    @property
    def intensity_key(self) -> str | None:
        """The intensity grid axis (``"record.pga_g"`` or ``"record.sa_g"``), if any."""
        return next((k for k in self.grid if k in INTENSITY_KEYS), None)

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the per-simulation arrays: ``(record, *grid axes, sample)``."""
        return (len(self.records), *(v.size for v in self.grid.values()), self.n)

    @property
    def n_simulations(self) -> int:
        """Total number of simulations."""
        return int(np.prod(self.shape))

    def scene_dict(self, record: int = 0, overrides: dict | None = None) -> dict:
        """The scene tables for one record with ``{"table.key": value}`` overrides applied."""
        data = copy.deepcopy(self.scene)
        data["record"] = copy.deepcopy(self.records[record])
        for key, value in (overrides or {}).items():
            set_key(data, key, value)
        return data

    def record_table(self, i: int) -> str:
        """The table of record ``i`` as messages name it (``"record"`` or ``"records[i]"``)."""
        if self.record_tables:
            return self.record_tables[i]
        return "record" if len(self.records) == 1 else f"records[{i}]"

    def values_at(
        self, idx: tuple, samples: dict[str, np.ndarray], material_samples: dict | None = None
    ) -> dict[str, np.ndarray]:
        """Values of the varied scene keys at unravelled indices (the one place that maps them).

        Parameters
        ----------
        idx : tuple of int or numpy.ndarray
            Positions along ``(record, *grid axes, sample)`` (:attr:`shape`), as
            :func:`numpy.unravel_index` gives them.
        samples : dict
            :meth:`draw`'s values.
        material_samples : dict, optional
            :meth:`draw_materials`'s values (keys that follow the material axis).

        Returns
        -------
        dict
            ``{key: value(s)}`` for every grid axis but the material one and every sampled key.
        """
        out = {}
        for axis, (key, values) in enumerate(self.grid.items(), start=1):
            if key != MATERIAL_KEY:  # the material axis is not a scene key: it picks ranges
                out[key] = values[idx[axis]]
        material_samples = material_samples or {}
        for key, values in samples.items():
            if key in material_samples:
                m = idx[list(self.grid).index(MATERIAL_KEY) + 1]
                out[key] = material_samples[key][m, idx[-1]]
            else:
                out[key] = values[idx[-1]]
        return out

    def draw(self) -> dict[str, np.ndarray]:
        """Sampled values ``{key: (n,)}``; the same at every grid point and record.

        A key in :attr:`material_variables` gets its first material's values here; see
        :meth:`draw_materials`.
        """
        return sampling.draw(self.variables, self.n, self.sampling_seed, self.method)

    def draw_materials(self) -> dict[str, np.ndarray]:
        """Values of the keys that follow the material axis, ``{key: (n_materials, n)}``.

        Row ``m`` maps the same design column as :meth:`draw` through the ranges of the
        axis's ``m``-th material, so every material meets the same design points.
        """
        if not self.material_variables:
            return {}
        u = sampling.design(self.n, len(self.variables), self.sampling_seed, self.method)
        out = {}
        for j, variable in enumerate(self.variables):
            per_material = self.material_variables.get(variable.key)
            if per_material is not None:
                out[variable.key] = np.stack([v.ppf(u[:, j]) for v in per_material])
        return out


def set_key(data: dict, key: str, value) -> None:
    """Set ``"table.key"`` in a scene dict, dropping the key it replaces (``e`` <-> ``xi``).

    A number for a key the scene gives as a list (a shear building's storey lists) stands for
    every element: ``[value] * len(list)``.  ``"buildings.N.KEY"`` sets building N's of a row.
    """
    row = ROW_KEY.match(key)
    if row is not None:
        owner, name = data[ROW_TABLE][int(row[1])], row[2]
    else:
        table, name = key.split(".", 1)
        owner = data.setdefault(table, {})
    current = owner.get(name)
    if isinstance(current, list) and not isinstance(value, list):
        value = [value] * len(current)
    owner[name] = value
    other = EXCLUSIVE.get(key)
    if other is not None:
        t2, n2 = other.split(".", 1)
        data.get(t2, {}).pop(n2, None)


def _grid_axis(key, spec, file, errors) -> np.ndarray | None:
    """A numeric grid axis: a list of distinct numbers or ``{ start, stop, num }``."""
    where = f"grid.{key}"
    if isinstance(spec, list):
        if not spec:
            errors.append(InputError("needs at least one value", file=file, key=where))
            return None
        if not all(GRID_AXIS["start"].problem(v) is None for v in spec):
            errors.append(InputError("values must be finite numbers", file=file, key=where))
            return None
        values = np.asarray(spec, dtype=float)
        if np.unique(values).size != values.size:
            errors.append(InputError("values must be distinct", file=file, key=where))
            return None
        return values
    if not isinstance(spec, dict):
        errors.append(
            InputError("must be a list of numbers or { start, stop, num }", file=file, key=where)
        )
        return None
    local: list[InputError] = []
    v = check_table(GRID_AXIS, spec, file=file, prefix=f"{where}.", errors=local)
    errors.extend(local)
    if local:
        return None
    if v["num"] > 1 and v["start"] == v["stop"]:
        errors.append(InputError("start and stop must differ", file=file, key=where))
        return None
    return grid_values(v["start"], v["stop"], v["num"])


def grid_values(start: float, stop: float, num: int) -> np.ndarray:
    """``num`` evenly spaced values from ``start`` to ``stop``, rounded to the value meant.

    :func:`numpy.linspace` gives ``0.9999999999999999`` for the 10th of 20 values from 0.1 to
    2.0.  A value within 8 units in the last place of its
    :data:`~pound_mc.study.schema.GRID_DIGITS` (12) significant digit form is replaced by that
    form, so the grid holds 1.0 and a pair of buildings with equal periods is really equal;
    values that are not short decimals (0.32105263157894737 of 20 from 0.3 to 0.7) stay as
    :func:`numpy.linspace` gives them.

    Parameters
    ----------
    start, stop : float
        First and last value (as the key).
    num : int
        Number of values, >= 1.

    Returns
    -------
    numpy.ndarray
        float64 values.
    """
    values = np.linspace(float(start), float(stop), int(num))
    short = np.array([float(f"{x:.{GRID_DIGITS}g}") for x in values], dtype=float)
    near = np.abs(short - values) <= 8 * np.spacing(np.abs(values))
    return np.where(near, short, values)


def _material_axis(spec, file, errors) -> list[str] | None:
    """Validate a ``"contact.material"`` grid axis: distinct names of known materials."""
    where = f"grid.{MATERIAL_KEY}"
    if not isinstance(spec, list) or not spec or not all(isinstance(m, str) for m in spec):
        errors.append(
            InputError(
                f"must be a list of material names from {list(materials.MATERIALS)}",
                file=file,
                key=where,
            )
        )
        return None
    unknown = [m for m in spec if m not in materials.MATERIALS]
    if unknown:
        errors.append(
            InputError(
                f"unknown material(s) {unknown}; choose from {list(materials.MATERIALS)}",
                file=file,
                key=where,
            )
        )
        return None
    if len(set(spec)) != len(spec):
        errors.append(InputError("values must be distinct", file=file, key=where))
        return None
    return list(spec)


def scene_model(data: dict, side: str) -> str:
    """The building model of ``[left]`` or ``[right]`` (default ``"sdof"``)."""
    table = data.get(side)
    return table.get("model", "sdof") if isinstance(table, dict) else "sdof"


def scene_models(data: dict) -> list[str]:
    """The models of a scene's buildings from left to right (a row's, or left and right)."""
    row = data.get(ROW_TABLE)
    if isinstance(row, list):
        return [b.get("model", "sdof") if isinstance(b, dict) else "sdof" for b in row]
    return [scene_model(data, side) for side in ("left", "right")]


def _top_level(data: dict, file, errors: list) -> None:
    """Unknown tables, and tables that are not tables."""
    for key in sorted(set(data) - set(TOP_LEVEL)):
        errors.append(InputError(f"unknown table; allowed {list(TOP_LEVEL)}", file=file, key=key))
    for key in sorted(set(data) & set(TOP_LEVEL)):
        value = data[key]
        if key in ("records", ROW_TABLE):
            ok = isinstance(value, list) and all(isinstance(r, dict) for r in value)
        else:
            ok = isinstance(value, dict)
        if not ok:
            what = (
                f"an array of tables [[{key}]]"
                if key in ("records", ROW_TABLE)
                else f"a table [{key}]"
            )
            errors.append(InputError(f"must be {what}, got {value!r}", file=file, key=key))


def _head(data: dict, file, errors: list) -> dict:
    """``[study]``: name, seed, description, chunk_size (defaults where it is broken)."""
    if "study" not in data:
        errors.append(
            InputError("missing table [study] with name and seed", file=file, key="study")
        )
        return {"name": "study", "seed": 0, "description": ""}
    v = check_table(STUDY, data["study"], file=file, prefix="study.", errors=errors)
    return {"name": "study", "seed": 0} | v


def _records(data: dict, file, errors: list) -> tuple[list[dict], list[str], list[dict]]:
    """The record tables (suites and globs expanded), their keys' prefixes and metadata."""
    if "record" in data and "records" in data:
        errors.append(
            InputError("give either [record] or [[records]], not both", file=file, key="records")
        )
    if "records" in data:
        tables = data["records"]
        if not tables:
            errors.append(InputError("must be one or more [[records]] tables", file=file,
                                     key="records"))  # fmt: skip
        return records_mod.expand_records(tables, file, errors)
    if "record" in data:
        return [data["record"]], [""], [{}]
    errors.append(InputError("missing table [record] (or [[records]])", file=file, key="record"))
    return [], [], []


def _quote_hint(key: str, value) -> str:
    """For ``contact.gap_m = ...`` unquoted (TOML's table ``contact``): quote the dotted key."""
    if not (isinstance(value, dict) and key in _SCENE_TABLES + ("record",)):
        return ""

    def dotted(prefix, v, depth):  # buildings.1.period_s is nested twice
        if depth == 0 or not isinstance(v, dict):
            return [prefix]
        return [d for name, inner in v.items()
                for d in dotted(f"{prefix}.{name}", inner, depth - 1)]  # fmt: skip

    quoted = ", ".join(f'"{d}" = ...' for d in dotted(key, value, 2 if key == ROW_TABLE else 1))
    return f" (a dotted key must be quoted: {quoted})"


def _grid(spec: dict, file, errors: list) -> tuple[dict, dict]:
    """``[grid]``: the axes' values and the names behind the material axis."""
    grid: dict[str, np.ndarray] = {}
    labels: dict[str, list[str]] = {}
    for key, axis in spec.items():
        if key == MATERIAL_KEY:
            names = _material_axis(axis, file, errors)
            if names is not None:
                labels[key] = names
                grid[key] = np.array([materials.MATERIALS.index(m) for m in names], dtype=float)
        elif not is_numeric_key(key) and key not in INTENSITY_KEYS:
            errors.append(
                InputError(
                    f"not a numeric scene key{_quote_hint(key, axis)}; a grid axis is one of "
                    f"{sorted([*NUMERIC_SCENE_KEYS, *INTENSITY_KEYS])} (in a row, "
                    '"buildings.N.KEY")',
                    file=file,
                    key=f"grid.{key}",
                )
            )
        else:
            values = _grid_axis(key, axis, file, errors)
            if values is not None and key in INTENSITY_KEYS and not np.all(values > 0):
                errors.append(InputError("intensities must be > 0 [g]", file=file,
                                         key=f"grid.{key}"))  # fmt: skip
            elif values is not None:
                grid[key] = values
    both = [k for k in INTENSITY_KEYS if k in spec]
    if len(both) > 1:
        errors.append(
            InputError("give one intensity axis, record.pga_g or record.sa_g", file=file,
                       key=f"grid.{both[1]}")
        )  # fmt: skip
    return grid, labels


def _material_variable(key, vspec, names: list[str], file, errors: list):
    """A ``{ material = "grid" }`` entry: one variable per material of the axis."""
    per_material = []
    for material in names:
        variable, errs = sampling.parse_variable(key, {**vspec, "material": material}, file=file)
        errors.extend(errs)
        if variable is None:
            return None, None
        per_material.append(variable)
    source = per_material[0].source.replace(
        f"over {names[0]},", f"over the grid point's material ({' | '.join(names)}),"
    )
    return dataclasses.replace(per_material[0], source=source), per_material


def _vary(vary: dict, grid: dict, labels: dict, file, errors: list) -> tuple[list, dict]:
    """``[sampling.vary]``: the random variables, and those that follow the material axis."""
    variables, material_variables = [], {}
    for key, vspec in vary.items():
        where = f"sampling.vary.{key}"
        if isinstance(vspec, dict) and vspec.get("material") == "grid":
            if MATERIAL_KEY not in labels:
                errors.append(
                    InputError(
                        f'material = "grid" needs a grid axis "{MATERIAL_KEY}" '
                        "(a list of material names)",
                        file=file,
                        key=f"{where}.material",
                    )
                )
                continue
            variable, per_material = _material_variable(
                key, vspec, labels[MATERIAL_KEY], file, errors
            )
            if variable is not None:
                material_variables[key] = per_material
                variables.append(variable)
        elif not is_numeric_key(key):
            errors.append(
                InputError(
                    f"not a numeric scene key{_quote_hint(key, vspec)}; choose from "
                    f'{sorted(NUMERIC_SCENE_KEYS)} (in a row, "buildings.N.KEY")',
                    file=file,
                    key=where,
                )
            )
        elif key in grid:
            errors.append(
                InputError("is also a grid axis; vary it in one place", file=file, key=where)
            )
        else:
            variable, errs = sampling.parse_variable(key, vspec, file=file)
            errors.extend(errs)
            if variable is not None:
                variables.append(variable)
    if (
        MATERIAL_KEY in labels
        and not material_variables
        and not any(isinstance(v, dict) and v.get("material") == "grid" for v in vary.values())
    ):
        errors.append(
            InputError(
                "the material axis changes nothing: give contact.e and/or contact.beta "
                '{ material = "grid" } in [sampling.vary]',
                file=file,
                key=f"grid.{MATERIAL_KEY}",
            )
        )
    if "contact.e" in vary and "contact.xi" in vary:
        errors.append(
            InputError("vary either contact.e or contact.xi, not both", file=file,
                       key="sampling.vary")
        )  # fmt: skip
    return variables, material_variables


def _structure_keys(scene: dict, grid: dict, variables: list, file, errors: list) -> list:
    """A varied building key must be one its building's model may vary.

    ``left.*`` / ``right.*`` in a pair, ``"buildings.N.KEY"`` in a row (N one of its
    buildings, from 0; a wall is none).
    """
    varied = [(f"grid.{k}", k) for k in grid] + [
        (f"sampling.vary.{v.key}", v.key) for v in variables
    ]
    row = scene.get(ROW_TABLE)
    row = row if isinstance(row, list) else None
    refused = set()
    for where, key in varied:
        problem = _building_key_problem(scene, row, key)
        if problem is not None:
            errors.append(InputError(problem, file=file, key=where))
            grid.pop(key, None)
            refused.add(key)
    return [v for v in variables if v.key not in refused]


def _building_key_problem(scene: dict, row: list | None, key: str) -> str | None:
    """Why ``key`` cannot vary a building of ``scene`` (None: it can, or it is no building's)."""
    match = ROW_KEY.match(key)
    side, _, name = key.partition(".")
    if match is None and side not in ("left", "right"):
        return None
    if row is not None and match is None:
        return (f"the study gives a row of buildings ([[{ROW_TABLE}]]): vary building N's "
                f'key as "{ROW_TABLE}.N.{name}" (N from 0, left to right)')  # fmt: skip
    if row is None and match is not None:
        return (
            f"names a row's building, but the study gives [left] and [right], not [[{ROW_TABLE}]]"
        )
    if match is not None:
        n, name = int(match[1]), match[2]
        models = [b.get("model", "sdof") if isinstance(b, dict) else None for b in row]
        buildings = [k for k, m in enumerate(models) if m != "wall"]
        if n not in buildings:
            where = "a wall, which is no building" if n < len(models) else "no such building"
            return (f"building {n} is {where}: the row's buildings are "
                    f"{', '.join(map(str, buildings))} (from 0, left to right)")  # fmt: skip
        model, label, prefix = models[n], f"[[{ROW_TABLE}]] {n}", f"{ROW_TABLE}.{n}"
    else:
        model, label, prefix = scene_model(scene, side), f"[{side}]", side
    table = BUILDINGS.get(model) if isinstance(model, str) else None  # else: scene's error
    allowed = sorted(f"{prefix}.{f.name}" for f in table.fields if f.varied) if table else []
    if table is not None and f"{prefix}.{name}" not in allowed:
        return (
            f"not a structural key of a {model} building ({label} model = '{model}'); "
            f"vary one of {allowed}"
        )
    return None


def _record_names(records: list[dict]) -> list[str]:
    names: list[str] = []
    for i, record in enumerate(records):
        label = str(record.get("name") or record.get("source", f"record{i}"))
        names.append(label if label not in names else f"{label}#{i}")
    return names


def _samples(spec: dict, variables: list, file, errors: list) -> tuple[int, int | None]:
    """Samples per grid point, and Saltelli's base N (None for the other designs).

    ``saltelli`` takes ``n`` as the base N: a power of two >= 2 (SALib's design and the
    balance of its Sobol' points ask for it), at least one sampled key, and N (D + 2) samples
    within :data:`~pound_mc.study.schema.MAX_SAMPLES`.  Where it is refused, the samples of the
    smallest design stand in, so the probe still checks the sampled keys' values and every
    problem is reported at once.
    """
    n = spec.get("n", 1)
    d = len(variables)
    if spec.get("method") != "saltelli":
        return n, None
    problem = None
    if not variables:
        problem = ('method = "saltelli" needs at least one sampled key in [sampling.vary]',
                   "sampling.vary")  # fmt: skip
    elif any(e.key == "sampling.n" for e in errors):  # n itself refused already
        pass
    elif not sampling.is_saltelli_base(n):
        problem = (
            f'must be a power of two >= 2 with method = "saltelli" (the base N of Saltelli\'s '
            f"design, which runs N (D + 2) = N x {d + 2} samples), got {n}; e.g. "
            f"{max(2, 1 << n.bit_length() - 1)} or {max(4, 1 << n.bit_length())}",
            "sampling.n",
        )
    elif sampling.saltelli_samples(n, d) > MAX_SAMPLES:
        problem = (f"N (D + 2) = {n} x {d + 2} = {sampling.saltelli_samples(n, d):,} samples, "
                   f"more than {MAX_SAMPLES:,}", "sampling.n")  # fmt: skip
    else:
        return sampling.saltelli_samples(n, d), n
    if problem is not None:
        errors.append(InputError(problem[0], file=file, key=problem[1]))
    return sampling.saltelli_samples(2, d), None


def study_from_text(text: str, *, file: str | Path | None = None) -> Study:
    """Parse and validate a study from TOML text.

    Parameters
    ----------
    text : str
        The study file's contents.
    file : str or Path, optional
        Where it came from (used in messages and to resolve relative record paths).

    Raises
    ------
    InputErrors
        Listing every problem found, each with the file and key.
    """
    fname = None if file is None else str(file)
    data = parse_toml(text, fname)
    errors: list[InputError] = []
    _top_level(data, fname, errors)
    if errors:  # the tables themselves are malformed: checking their keys would only add noise
        raise InputErrors(errors)
    head = _head(data, fname, errors)
    records, prefixes, meta = _records(data, fname, errors)
    scene = {k: data[k] for k in _SCENE_TABLES if k in data}
    grid, labels = _grid(data.get("grid", {}), fname, errors)
    spec = check_table(SAMPLING, data.get("sampling", {}), file=fname, prefix="sampling.",
                       errors=errors)  # fmt: skip
    vary = sampling.per_impact(spec.get("vary", {}), scene, fname, errors)
    variables, material_variables = _vary(vary, grid, labels, fname, errors)
    variables = _structure_keys(scene, grid, variables, fname, errors)
    fixed_partner(scene, grid, variables, fname, errors)
    n, base_n = _samples(spec, variables, fname, errors)
    study = Study(
        path=None if file is None else Path(file),
        name=head["name"],
        seed=head["seed"],
        text=text,
        hash=hashlib.sha256(text.encode()).hexdigest(),
        scene=scene,
        records=records,
        grid=grid,
        n=n,
        method=spec.get("method", "sobol"),
        sampling_seed=spec.get("seed", head["seed"]),
        variables=variables,
        chunk_size=head.get("chunk_size"),
        description=head.get("description", ""),
        record_names=_record_names(records),
        record_tables=[p[:-1] if p else "record" for p in prefixes],
        grid_labels=labels,
        material_variables=material_variables,
        record_meta=meta if any(meta) else [],
        base_n=base_n,
    )
    records_mod.check_intensity(study, prefixes, fname, errors)
    if not errors:  # before anything the size allocates (the probe draws the samples)
        check_size(study)
    probe(study, prefixes, fname, errors)
    if errors:
        raise InputErrors(errors)
    return study


def check_size(study: Study) -> None:
    """Refuse a study whose results could not fit in this machine's memory, before anything.

    The least a simulation holds (:data:`~pound_mc.study.schema.MIN_BYTES_PER_SIMULATION`)
    times the simulations, against the physical memory; the run checks its full layout again
    (:func:`~pound_mc.study.runner.run_study`).  Names the grid axis or ``sampling.n`` that
    makes the study largest.
    """
    need = study.n_simulations * MIN_BYTES_PER_SIMULATION
    have = physical_memory()
    if have is None or need <= have:
        return
    sizes = {f"grid.{k}": v.size for k, v in study.grid.items()} | {"sampling.n": study.n}
    largest = max(sizes, key=sizes.get)
    raise InputError(
        f"{study.n_simulations:,} simulations need at least {need / 2**30:,.1f} GiB of memory "
        f"for their results, more than this machine's {have / 2**30:,.1f} GiB; make the grid "
        "or the number of samples smaller", file=None if study.path is None else str(study.path),
        key=largest)  # fmt: skip


def physical_memory() -> int | None:
    """Bytes of physical memory of this machine, if the system says."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return None


def load_study(path: str | Path) -> Study:
    """Read and validate a study file (see the module docstring for the schema)."""
    path = Path(path)
    return study_from_text(read_text_file(path, "study file"), file=path)
