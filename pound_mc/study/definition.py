"""Study files: schema, validation and the plan of simulations.

A study is a scene (``[record]`` or ``[[records]]``, ``[left]``, ``[right]``, ``[contact]``,
``[integrator]``; see :mod:`pound_mc.scene`) plus

``[study]``
    ``name`` (letters, digits, ``-``, ``_``), ``seed`` (integer >= 0), optional
    ``description`` and ``chunk_size`` (simulations per chunk file; default about 1/50 of the
    study, between 256 and 8192: :func:`pound_mc.study.runner.default_chunk_size`).
``[grid]``
    Axes of the spectra, keyed by the scene key they vary (``"left.period_s"``): a list of
    numbers or ``{ start, stop, num }`` (evenly spaced, both ends included).  One non-numeric
    axis: ``"contact.material" = ["steel", "concrete", ...]`` (names of
    :data:`pound_mc.physics.materials.MATERIALS`); ``[sampling.vary]`` entries
    ``{ material = "grid" }`` for ``contact.e`` and ``contact.beta`` then take each grid
    point's material's ranges (the same design points for every material: common random
    numbers).  The axis's values are the materials' indices in ``MATERIALS`` (0 steel,
    1 concrete, 2 timber, 3 ceramics); their names are in ``Study.grid_labels``.
``[sampling]``
    ``n`` samples per grid point and record, ``method`` (``random`` | ``lhs`` | ``sobol``,
    default ``sobol``), optional ``seed`` (default: the study's), and ``[sampling.vary]``
    (:mod:`pound_mc.study.sampling`).

With a shear building (``model = "shear"`` in ``[left]`` or ``[right]``) the modes are
computed once per study, so its grid axes and sampled keys are ``contact.*`` keys and
``integrator.dt_s`` only; a ``left.*`` or ``right.*`` key there is refused.

Every problem in a file is reported at once (:class:`~pound_mc.errors.InputErrors`), each
naming the file and the key.  Nothing is written while validating.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import math
import re
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pound_mc.errors import InputError, InputErrors
from pound_mc.physics import materials
from pound_mc.study import sampling

__all__ = [
    "Study",
    "load_study",
    "study_from_text",
    "NUMERIC_SCENE_KEYS",
    "MATERIAL_KEY",
    "grid_dim_name",
]

_STUDY_KEYS = {"name", "seed", "description", "chunk_size"}
_SAMPLING_KEYS = {"n", "method", "seed", "vary"}
#: Largest number of samples per grid point (2^24: Sobol designs and memory stay sane).
MAX_SAMPLES = 2**24
_TOP_LEVEL = {"study", "record", "records", "left", "right", "contact", "integrator", "grid",
              "sampling"}  # fmt: skip

#: Scene keys that may be a grid axis or a sampled variable (scalar numbers).
NUMERIC_SCENE_KEYS = {
    "left.period_s",
    "left.damping_ratio",
    "left.mass_kg",
    "right.period_s",
    "right.damping_ratio",
    "right.mass_kg",
    "contact.gap_m",
    "contact.beta",
    "contact.k_N_per_m",
    "contact.xi",
    "contact.e",
    "integrator.dt_s",
}
#: The one non-numeric grid axis: the material whose measured ranges ``{ material = "grid" }``
#: sampled variables take.
MATERIAL_KEY = "contact.material"
# Keys that replace each other: varying e drops a fixed xi from the scene and vice versa.
_EXCLUSIVE = {"contact.e": "contact.xi", "contact.xi": "contact.e"}
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")


def grid_dim_name(key: str) -> str:
    """Dataset dimension name of a scene key (``"left.period_s"`` -> ``"left_period_s"``)."""
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
    #: ``(dt_s, acceleration)`` of every record, read and preprocessed while validating.
    record_arrays: list = field(default_factory=list, repr=False)
    #: Names behind a non-numeric grid axis's values (``{"contact.material": ["steel", ...]}``).
    grid_labels: dict[str, list[str]] = field(default_factory=dict)
    #: Sampled keys that follow the material axis: ``{key: [variable per material]}`` (the
    #: variable in ``variables`` is the first material's, standing for all of them).
    material_variables: dict[str, list] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, ...]:
        """Shape of the per-simulation arrays: (record, *grid axes, sample)."""
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
    """Set ``"table.key"`` in a scene dict, dropping the key it replaces (``e`` <-> ``xi``)."""
    table, name = key.split(".", 1)
    data.setdefault(table, {})[name] = value
    other = _EXCLUSIVE.get(key)
    if other is not None:
        t2, n2 = other.split(".", 1)
        data.get(t2, {}).pop(n2, None)


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _parse_grid_axis(key, spec, file, errors) -> np.ndarray | None:
    where = f"grid.{key}"
    if isinstance(spec, list):
        if not spec:
            errors.append(InputError("needs at least one value", file=file, key=where))
            return None
        if not all(_is_number(v) for v in spec):
            errors.append(InputError("values must be finite numbers", file=file, key=where))
            return None
        values = np.asarray(spec, dtype=float)
        if np.unique(values).size != values.size:
            errors.append(InputError("values must be distinct", file=file, key=where))
            return None
        return values
    if isinstance(spec, dict):
        extra = set(spec) - {"start", "stop", "num"}
        missing = {"start", "stop", "num"} - set(spec)
        if extra or missing:
            errors.append(
                InputError(
                    "needs exactly start, stop and num"
                    + (f" (unknown {sorted(extra)})" if extra else "")
                    + (f" (missing {sorted(missing)})" if missing else ""),
                    file=file,
                    key=where,
                )
            )
            return None
        ok = True
        for name in ("start", "stop"):
            if not _is_number(spec[name]):
                errors.append(
                    InputError("must be a finite number", file=file, key=f"{where}.{name}")
                )
                ok = False
        if not _is_int(spec["num"]) or spec["num"] < 1:
            errors.append(InputError("must be an integer >= 1", file=file, key=f"{where}.num"))
            ok = False
        if not ok:
            return None
        if spec["num"] > 1 and spec["start"] == spec["stop"]:
            errors.append(InputError("start and stop must differ", file=file, key=where))
            return None
        return np.linspace(float(spec["start"]), float(spec["stop"]), spec["num"])
    errors.append(
        InputError("must be a list of numbers or { start, stop, num }", file=file, key=where)
    )
    return None


def _parse_material_axis(spec, file, errors) -> list[str] | None:
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


def _validate_scene(data: dict, file, prefix: str, errors: list) -> None:
    """Validate scene tables with the scene module, re-labelling keys with ``prefix``."""
    from pound_mc.scene import scene_from_dict

    try:
        scene_from_dict(data, file=file)
    except InputErrors as exc:
        for err in exc.errors:
            key = f"{prefix}{err.key}" if (prefix and err.key) else (err.key or prefix or None)
            errors.append(InputError(err.message, file=file, key=key))
    except InputError as exc:
        key = f"{prefix}{exc.key}" if (prefix and exc.key) else (exc.key or prefix or None)
        errors.append(InputError(exc.message, file=file, key=key))


def _load_records(records: list[dict], prefixes: list[str], file, errors: list) -> list:
    """Read and preprocess every record; problems go to ``errors`` keyed in the study file."""
    from pound_mc.motions import load_record, record_arrays

    fname = None if file is None else str(file)
    base_dir = None if file is None else Path(file).parent
    out = []
    for i, record in enumerate(records):
        spec = dict(record)
        spec.pop("name", None)
        source = spec.pop("source")
        where = prefixes[i] or "record."
        try:
            trace = load_record(source, base_dir=base_dir, **spec)
        except InputError as exc:
            key = exc.key or "record.source"
            key = where + key.split(".", 1)[-1] if key.startswith("record") else key
            detail = exc.message
            if exc.file and exc.file != fname:
                detail = f"{exc.file}: {detail}"
            errors.append(InputError(detail, file=fname, key=key))
            continue
        except (OSError, ValueError, TypeError) as exc:
            errors.append(
                InputError(f"cannot read {source!r}: {exc}", file=fname, key=where + "source")
            )
            continue
        out.append(record_arrays(trace))
    return out


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
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML: {exc}", file=fname) from None
    errors: list[InputError] = []

    for key in sorted(set(data) - _TOP_LEVEL):
        errors.append(
            InputError(f"unknown table; allowed {sorted(_TOP_LEVEL)}", file=fname, key=key)
        )
    for key in sorted(set(data) & _TOP_LEVEL):
        value = data[key]
        is_table = isinstance(value, dict)
        if key == "records":
            is_table = isinstance(value, list) and all(isinstance(r, dict) for r in value)
        if not is_table:
            what = "an array of tables [[records]]" if key == "records" else f"a table [{key}]"
            errors.append(InputError(f"must be {what}, got {value!r}", file=fname, key=key))
    if errors:
        # the tables themselves are malformed: checking their keys would only add noise
        raise InputErrors(errors)

    # [study]
    head = data.get("study")
    name, seed, chunk_size, description = "study", 0, None, ""
    if not isinstance(head, dict):
        errors.append(
            InputError("missing table [study] with name and seed", file=fname, key="study")
        )
        head = {}
    for key in sorted(set(head) - _STUDY_KEYS):
        errors.append(
            InputError(
                f"unknown key; allowed {sorted(_STUDY_KEYS)}", file=fname, key=f"study.{key}"
            )
        )
    if "name" in head or isinstance(data.get("study"), dict):
        name = head.get("name")
        if not isinstance(name, str) or not _NAME_RE.match(name):
            errors.append(
                InputError(
                    "must be a name of letters, digits, '-' and '_'", file=fname, key="study.name"
                )
            )
            name = "study"
        seed = head.get("seed")
        if not _is_int(seed) or seed < 0:
            errors.append(InputError("must be an integer >= 0", file=fname, key="study.seed"))
            seed = 0
    if "chunk_size" in head:
        chunk_size = head["chunk_size"]
        if not _is_int(chunk_size) or chunk_size < 1:
            errors.append(InputError("must be an integer >= 1", file=fname, key="study.chunk_size"))
            chunk_size = None
    if "description" in head:
        description = head["description"]
        if not isinstance(description, str):
            errors.append(InputError("must be a string", file=fname, key="study.description"))
            description = ""

    # records
    if "record" in data and "records" in data:
        errors.append(
            InputError("give either [record] or [[records]], not both", file=fname, key="records")
        )
    if "records" in data:
        records = data["records"]
        if (
            not isinstance(records, list)
            or not records
            or not all(isinstance(r, dict) for r in records)
        ):
            errors.append(
                InputError("must be one or more [[records]] tables", file=fname, key="records")
            )
            records = []
        prefixes = [f"records[{i}]." for i in range(len(records))]
    elif "record" in data:
        records = [data["record"]] if isinstance(data["record"], dict) else []
        if not records:
            errors.append(InputError("must be a table", file=fname, key="record"))
        prefixes = [""]
    else:
        errors.append(
            InputError("missing table [record] (or [[records]])", file=fname, key="record")
        )
        records, prefixes = [], []

    scene = {k: data[k] for k in ("left", "right", "contact", "integrator") if k in data}

    # [grid]
    grid: dict[str, np.ndarray] = {}
    grid_spec = data.get("grid", {})
    if not isinstance(grid_spec, dict):
        errors.append(InputError("must be a table", file=fname, key="grid"))
        grid_spec = {}
    grid_labels: dict[str, list[str]] = {}
    for key, spec in grid_spec.items():
        if key == MATERIAL_KEY:
            names = _parse_material_axis(spec, fname, errors)
            if names is not None:
                grid_labels[key] = names
                grid[key] = np.array([materials.MATERIALS.index(m) for m in names], dtype=float)
            continue
        if key not in NUMERIC_SCENE_KEYS:
            errors.append(
                InputError(
                    f"not a numeric scene key; a grid axis is one of {sorted(NUMERIC_SCENE_KEYS)}",
                    file=fname,
                    key=f"grid.{key}",
                )
            )
            continue
        values = _parse_grid_axis(key, spec, fname, errors)
        if values is None:
            continue
        grid[key] = values

    # [sampling]
    spec = data.get("sampling", {})
    n, method, sampling_seed, variables = 1, "sobol", seed, []
    if not isinstance(spec, dict):
        errors.append(InputError("must be a table", file=fname, key="sampling"))
        spec = {}
    for key in sorted(set(spec) - _SAMPLING_KEYS):
        errors.append(
            InputError(
                f"unknown key; allowed {sorted(_SAMPLING_KEYS)}", file=fname, key=f"sampling.{key}"
            )
        )
    if "n" in spec:
        n = spec["n"]
        if not _is_int(n) or not 1 <= n <= MAX_SAMPLES:
            errors.append(
                InputError(
                    f"must be an integer in [1, {MAX_SAMPLES:,}], got {n!r}",
                    file=fname,
                    key="sampling.n",
                )
            )
            n = 1
    if "method" in spec:
        method = spec["method"]
        if not isinstance(method, str) or method not in sampling.DESIGNS:
            errors.append(
                InputError(
                    f"unknown method {method!r}; choose one of {sorted(sampling.DESIGNS)}",
                    file=fname,
                    key="sampling.method",
                )
            )
            method = "sobol"
    if "seed" in spec:
        sampling_seed = spec["seed"]
        if not _is_int(sampling_seed) or sampling_seed < 0:
            errors.append(InputError("must be an integer >= 0", file=fname, key="sampling.seed"))
            sampling_seed = 0
    vary = spec.get("vary", {})
    if not isinstance(vary, dict):
        errors.append(InputError("must be a table", file=fname, key="sampling.vary"))
        vary = {}
    material_variables: dict[str, list] = {}
    for key, vspec in vary.items():
        if isinstance(vspec, dict) and vspec.get("material") == "grid":
            if MATERIAL_KEY not in grid_labels:
                errors.append(
                    InputError(
                        f'material = "grid" needs a grid axis "{MATERIAL_KEY}" '
                        "(a list of material names)",
                        file=fname,
                        key=f"sampling.vary.{key}.material",
                    )
                )
                continue
            per_material = []
            for material in grid_labels[MATERIAL_KEY]:
                variable, errs = sampling.parse_variable(
                    key, {**vspec, "material": material}, file=fname
                )
                errors.extend(errs)
                if variable is None:
                    break
                per_material.append(variable)
            else:
                material_variables[key] = per_material
                names = grid_labels[MATERIAL_KEY]
                source = per_material[0].source.replace(
                    f"over {names[0]},", f"over the grid point's material ({' | '.join(names)}),"
                )
                variables.append(dataclasses.replace(per_material[0], source=source))
            continue
        if key not in NUMERIC_SCENE_KEYS:
            errors.append(
                InputError(
                    f"not a numeric scene key; choose from {sorted(NUMERIC_SCENE_KEYS)}",
                    file=fname,
                    key=f"sampling.vary.{key}",
                )
            )
            continue
        if key in grid:
            errors.append(
                InputError(
                    "is also a grid axis; vary it in one place",
                    file=fname,
                    key=f"sampling.vary.{key}",
                )
            )
            continue
        variable, errs = sampling.parse_variable(key, vspec, file=fname)
        errors.extend(errs)
        if variable is not None:
            variables.append(variable)
    follows_axis = [
        k for k, v in vary.items() if isinstance(v, dict) and v.get("material") == "grid"
    ]
    if MATERIAL_KEY in grid_labels and not follows_axis:
        errors.append(
            InputError(
                "the material axis changes nothing: give contact.e and/or contact.beta "
                '{ material = "grid" } in [sampling.vary]',
                file=fname,
                key=f"grid.{MATERIAL_KEY}",
            )
        )
    if "contact.e" in vary and "contact.xi" in vary:
        errors.append(
            InputError(
                "vary either contact.e or contact.xi, not both", file=fname, key="sampling.vary"
            )
        )

    # a study with a shear building computes the modes once: no structural grid or variable
    shear = [side for side in ("left", "right") if scene_model(scene, side) == "shear"]
    if shear:
        varied = [(f"grid.{k}", k) for k in grid] + [
            (f"sampling.vary.{v.key}", v.key) for v in variables
        ]
        for where, key in varied:
            if key.split(".", 1)[0] in ("left", "right"):
                errors.append(
                    InputError(
                        f"cannot vary the structural key {key!r} in a study with a shear "
                        f"building ([{shear[0]}] model = 'shear'): the modes are computed once "
                        "per study; vary contact.* keys or integrator.dt_s",
                        file=fname,
                        key=where,
                    )
                )
                grid.pop(key, None)
        variables = [v for v in variables if v.key.split(".", 1)[0] not in ("left", "right")]

    # the scene as written, once per record; a key that only a grid axis or a sampled
    # variable gives takes its first value (the other values are checked below)
    draws = sampling.draw(variables, n, sampling_seed, method) if variables else {}
    first = {key: float(values[0]) for key, values in grid.items() if key != MATERIAL_KEY}
    first.update({key: float(values[0]) for key, values in draws.items()})
    scene_ok = True
    for i, record in enumerate(records):
        probe = copy.deepcopy(scene)
        probe["record"] = record
        for key, value in first.items():
            table, leaf = key.split(".", 1)
            partner = _EXCLUSIVE.get(key, "").partition(".")[2]
            present = probe.get(table, {})
            if leaf not in present and partner not in present:
                probe.setdefault(table, {})[leaf] = value
        local: list[InputError] = []
        _validate_scene(probe, fname, "", local)
        for err in local:
            key = err.key or ""
            if key.startswith("record") and prefixes[i]:
                key = prefixes[i] + key.split(".", 1)[-1] if "." in key else prefixes[i][:-1]
            elif i > 0:
                continue  # scene problems are reported once, with the first record
            scene_ok = False
            errors.append(InputError(err.message, file=fname, key=key or None))

    # every grid value and every sampled value must make a valid scene: check the extremes
    if records and scene_ok:
        ranges = [(f"grid.{k}", k, v) for k, v in grid.items() if k != MATERIAL_KEY]
        ranges += [(f"sampling.vary.{k}", k, v) for k, v in draws.items()]
        for where, key, values in ranges:
            for value in dict.fromkeys((float(values.min()), float(values.max()))):
                probe = copy.deepcopy(scene)
                probe["record"] = copy.deepcopy(records[0])
                for k2, v2 in first.items():
                    set_key(probe, k2, v2)
                set_key(probe, key, value)
                local = []
                _validate_scene(probe, fname, "", local)
                for err in local[:1]:
                    errors.append(
                        InputError(f"value {value:g}: {err.message}", file=fname, key=where)
                    )

    # records: read and preprocess each one now, so a missing file is reported here
    loaded: list[tuple[float, np.ndarray]] = []
    if not errors:
        loaded = _load_records(records, prefixes, file, errors)

    if errors:
        raise InputErrors(errors)

    digest = hashlib.sha256(text.encode()).hexdigest()
    names = []
    for i, record in enumerate(records):
        label = str(record.get("name") or record.get("source", f"record{i}"))
        names.append(label if label not in names else f"{label}#{i}")
    return Study(
        path=None if file is None else Path(file),
        name=name,
        seed=seed,
        text=text,
        hash=digest,
        scene=scene,
        records=records,
        grid=grid,
        n=n,
        method=method,
        sampling_seed=sampling_seed,
        variables=variables,
        chunk_size=chunk_size,
        description=description,
        record_names=names,
        record_arrays=loaded,
        grid_labels=grid_labels,
        material_variables=material_variables,
    )


def load_study(path: str | Path) -> Study:
    """Read and validate a study file (see the module docstring for the schema)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise InputError("study file not found", file=str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read study file: {exc}", file=str(path)) from None
    return study_from_text(text, file=path)
