"""The study tables declared once, and the reference page and JSON Schema made from them.

A study file is a scene (:mod:`pound_mc.scene.schema`: ``[record]`` or ``[[records]]``,
``[left]`` and ``[right]`` or a row ``[[buildings]]``, ``[contact]``, ``[integrator]``) plus
``[study]``, ``[grid]`` and ``[sampling]`` with ``[sampling.vary]``
(:data:`pound_mc.study.sampling.VARY_TABLES`).  The validator
(:func:`pound_mc.study.definition.study_from_text`) walks these declarations; the
same declarations write ``studies/SCHEMA.md`` (:func:`reference_markdown`) and
``studies/pound-mc.schema.json`` (:func:`json_schema`)::

    python -m pound_mc.study            # rewrite both files
    python -m pound_mc.study --check    # exit 1 if either is out of date
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from pound_mc.physics import materials
from pound_mc.scene import schema as scene_schema
from pound_mc.scene.schema import Field, Table
from pound_mc.study import sampling

__all__ = [
    "STUDY",
    "GRID_AXIS",
    "SAMPLING",
    "TOP_LEVEL",
    "MAX_SAMPLES",
    "MAX_AXIS_VALUES",
    "MIN_BYTES_PER_SIMULATION",
    "MATERIAL_KEY",
    "NUMERIC_SCENE_KEYS",
    "ROW_TABLE",
    "ROW_KEY",
    "ROW_VARIED",
    "is_numeric_key",
    "INTENSITY_KEYS",
    "GRID_DIGITS",
    "reference_markdown",
    "json_schema",
    "write_reference",
    "MAX_SEED",
]

#: The least memory one simulation's results hold [bytes]: the per-simulation outputs and run
#: settings of :mod:`pound_mc.study.dataset` (98 bytes), twice (the arrays and the dataset);
#: the tests hold it to them.
MIN_BYTES_PER_SIMULATION = 196
#: Most values of one grid axis: a spectrum of a million points is a typing error.
MAX_AXIS_VALUES = 10**6
#: Largest number of samples per grid point (2^24: Sobol designs and memory stay sane).
MAX_SAMPLES = 2**24
#: Largest seed: the dataset keeps ``seed`` and ``sampling_seed`` as netCDF attributes, whose
#: widest integer type is an unsigned 64-bit one.
MAX_SEED = 2**64 - 1
#: The one non-numeric grid axis: the material whose measured ranges ``{ material = "grid" }``
#: sampled variables take.
MATERIAL_KEY = "contact.material"
#: Scene keys that may be a grid axis or a sampled variable (scalar numbers).
NUMERIC_SCENE_KEYS = frozenset(scene_schema.varied_keys())
#: The table of a row of buildings (``[[buildings]]``, left to right) in place of ``[left]``
#: and ``[right]``; its keys are ``"buildings.N.KEY"`` (N from 0; a wall is no building).
ROW_TABLE = "buildings"
#: Building keys a study may vary in a row: ``KEY`` of ``"buildings.N.KEY"``.
ROW_VARIED = tuple(k.split(".", 1)[1] for k in scene_schema.varied_keys() if k.startswith("left."))
#: A row's varied key, ``"buildings.N.KEY"``: groups N and KEY.
ROW_KEY = re.compile(r"^buildings\.(0|[1-9][0-9]*)\.([A-Za-z_]+)$")


def is_numeric_key(key: str) -> bool:
    """Whether ``key`` may be a grid axis or a sampled key: a scene key or a row's building key.

    ``"buildings.N.KEY"`` with any ``N`` and a building ``KEY``: whether building ``N``
    exists, and may vary ``KEY``, is the study's to check.
    """
    match = ROW_KEY.match(key)
    return key in NUMERIC_SCENE_KEYS or (match is not None and match[2] in ROW_VARIED)


#: Grid axes that scale every record to a target intensity [g] (a multiple-stripe analysis):
#: ``{key: description}``.  Grid axes only (not sampled keys), at most one per study.
INTENSITY_KEYS = {
    "record.pga_g": "peak ground acceleration: each record is scaled so that max |a| = value * g",
    "record.sa_g": "5 %-damped pseudo-spectral acceleration at `sa_period_s` (a key of every "
    "record table): each record is scaled so that Sa(sa_period_s) = value * g",
}
#: Significant digits ``{ start, stop, num }`` grid values snap to (from within 8 units in the
#: last place), so that the value meant (1.0) is the value stored rather than
#: ``np.linspace``'s 0.9999999999999999.
GRID_DIGITS = 12

STUDY = Table(
    "study",
    "What the study is called and the root of its random numbers (study files only).",
    (
        Field("name", "string", "Name of the study and of its dataset: letters, digits, - and "
              "_, at most 100 characters (file names).", required=True,
              pattern=r"^[A-Za-z0-9][A-Za-z0-9_-]{0,99}$"),
        Field("seed", "integer", "Root seed of the sampling.", required=True, minimum=0,
              maximum=MAX_SEED),
        Field("description", "string", "Free text, kept in the dataset.", default=""),
        Field("chunk_size", "integer", "Simulations per chunk file (default about 1/50 of the "
              "study, between 256 and 8192).", minimum=1, maximum=MAX_SAMPLES),
    ),
)  # fmt: skip

GRID_AXIS = Table(
    "grid.KEY",
    "Axes of the spectra, keyed by the scene key they vary (`\"left.period_s\"`): a list of "
    "distinct numbers, or `{ start, stop, num }` (evenly spaced, both ends included; a value "
    f"within 8 units in the last place of a {GRID_DIGITS}-significant-digit number is that "
    "number, so that 1.0 is exactly 1.0).  One "
    f"non-numeric axis: `\"{MATERIAL_KEY}\" = [\"steel\", \"concrete\", ...]` (names of "
    "`pound_mc.physics.materials.MATERIALS`).  A shear building's keys (storey masses, "
    "stiffnesses, damping) may vary too: each simulation then computes its own modes, at the "
    "cost of one scene a simulation.  Intensity axes `record.pga_g` and `record.sa_g` [g] scale "
    "every record to each value (a multiple-stripe analysis; one of them per study).",
    (
        Field("start", "number", "First value.", unit="as the key", required=True),
        Field("stop", "number", "Last value (differs from start when num > 1).",
              unit="as the key", required=True),
        Field("num", "integer", "Number of values.", required=True, minimum=1,
              maximum=MAX_AXIS_VALUES),
    ),
)  # fmt: skip

SAMPLING = Table(
    "sampling",
    "Random variables: `n` samples at every grid point and record, the same design points "
    "everywhere (common random numbers).",
    (
        Field("n", "integer", "Samples per grid point and record; with `method = "
              "\"saltelli\"` the base N, a power of two >= 2: N (D + 2) samples for D sampled "
              "keys.", default=1, minimum=1, maximum=MAX_SAMPLES),
        Field("method", "string", "Design of the samples; `saltelli`: Saltelli's design "
              "(SALib) for Sobol' sensitivity indices (`pound-mc sensitivity`).", default="sobol",
              choices=tuple(sorted(sampling.DESIGNS))),
        Field("seed", "integer", "Seed of the design (default: the study's seed).", minimum=0,
              maximum=MAX_SEED),
        Field("vary", "table", "Sampled scene keys: `\"KEY\" = { ... }` (below)."),
    ),
)  # fmt: skip

#: Every top-level table of a study file, and what it holds.
TOP_LEVEL = {
    "study": STUDY,
    "record": scene_schema.RECORD,
    "records": scene_schema.RECORD,
    "left": scene_schema.BUILDINGS,
    "right": scene_schema.BUILDINGS,
    ROW_TABLE: scene_schema.BUILDINGS,
    "contact": scene_schema.CONTACT,
    "integrator": scene_schema.INTEGRATOR,
    "grid": GRID_AXIS,
    "sampling": SAMPLING,
}


# --------------------------------------------------------------------------- reference page


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _default_text(f: Field) -> str:
    if f.default is None:
        return "required" if f.required else "-"
    if isinstance(f.default, bool):
        return "true" if f.default else "false"
    if isinstance(f.default, str):
        return f'"{f.default}"' if f.default else '""'
    return f"{f.default:g}"


def _table_markdown(heading: str, table: Table) -> list[str]:
    lines = [f"### {heading}", "", table.description, ""]
    lines += ["| key | type | default | unit | allowed | description |",
              "|---|---|---|---|---|---|"]  # fmt: skip
    for f in table.fields:
        if f.choices_doc:
            allowed = f.choices_doc
        elif isinstance(f.choices, tuple):
            allowed = ", ".join(f.choices)
        elif f.pattern:
            allowed = f"`{f.pattern}`"
        else:
            allowed = f.bounds_text()
        kind = "number or list of numbers" if f.type == "numbers" else f.type
        varied = " May be a grid axis or sampled." if f.varied else ""
        lines.append(
            f"| `{f.name}` | {kind} | {_cell(_default_text(f))} | {_cell(f.unit) or '-'} | "
            f"{_cell(allowed) or '-'} | {_cell(f.description + varied)} |"
        )
    return [*lines, ""]


def reference_markdown() -> str:
    """The schema reference page (``studies/SCHEMA.md``), generated from the declarations."""
    out = [
        "# Study and scene files: every key",
        "",
        "<!-- Generated by `python -m pound_mc.study` from pound_mc/scene/schema.py, "
        "pound_mc/study/schema.py and pound_mc/study/sampling.py; do not edit by hand. -->",
        "",
        "A scene (`pound-mc simulate`) holds `[record]`, `[left]`, `[right]`, `[contact]` and "
        "`[integrator]`; a study (`pound-mc run`) adds `[study]`, `[grid]` and `[sampling]`, "
        "and may give several `[[records]]` instead of one `[record]`.  Units are SI and part "
        "of the key names.  Every problem in a file is reported at once, each naming the file "
        "and the key.  Editors can check files with the JSON Schema "
        "`studies/pound-mc.schema.json` (for example with Taplo or Even Better TOML: "
        "`#:schema ./pound-mc.schema.json` on the first line).",
        "",
        "## Scene tables",
        "",
    ]
    out += _table_markdown("[record] / [[records]]", scene_schema.RECORD)
    out += _table_markdown('[left] / [right], model = "sdof"', scene_schema.SDOF)
    out += _table_markdown('[left] / [right], model = "shear"', scene_schema.SHEAR)
    out += _table_markdown('[right], model = "wall"', scene_schema.WALL)
    out += [
        "A scene or study file may give a row of buildings instead of `[left]` and `[right]`: "
        "`[[buildings]]`, two or more tables of the forms above from left to right (a wall "
        "only last), with a contact between neighbours.  A study varies building N's keys as "
        '`"buildings.N.KEY"` (N from 0, left to right; a wall is no building), e.g. '
        '`"buildings.1.period_s"`; its dataset gains per-building outputs along a `building` '
        "dimension (`peak_disp`, `peak_ductility`, `peak_drift`, `residual_drift`), and "
        "`peak_disp_left` ... `..._right` are the first building's and the last's.",
        "",
    ]
    out += _table_markdown("[contact]", scene_schema.CONTACT)
    out += _table_markdown("[integrator]", scene_schema.INTEGRATOR)
    out += ["## Study tables", ""]
    out += _table_markdown("[study]", STUDY)
    out += _table_markdown('[grid]: "KEY" = { start, stop, num } or a list', GRID_AXIS)
    keys = ", ".join(f"`{k}`" for k in sorted(NUMERIC_SCENE_KEYS))
    row = ", ".join(f"`{k}`" for k in ROW_VARIED)
    out += [f"Grid axes and sampled keys: {keys}; in a row, `buildings.N.KEY` for KEY one of "
            f"{row} (as building N's model allows); and the grid axis `{MATERIAL_KEY}`.",
            ""]  # fmt: skip
    out += ["Intensity grid axes (one per study, grid only):", ""]
    out += [f"- `{k}` [g]: {v}." for k, v in INTENSITY_KEYS.items()] + [""]
    out += _table_markdown("[sampling]", SAMPLING)
    for name, table in sampling.VARY_TABLES.items():
        out += _table_markdown(f'[sampling.vary] "KEY" = {{ {name} ... }}', table)
    return "\n".join(out).rstrip() + "\n"


# --------------------------------------------------------------------------- JSON Schema


def _field_schema(f: Field) -> dict:
    number = {"type": "number"}
    if f.minimum is not None:
        number["exclusiveMinimum" if f.exclusive_minimum else "minimum"] = f.minimum
    if f.maximum is not None:
        number["exclusiveMaximum" if f.exclusive_maximum else "maximum"] = f.maximum
    if f.type == "number":
        out = number
    elif f.type == "numbers":
        out = {"anyOf": [number, {"type": "array", "items": number, "minItems": 1}]}
    elif f.type == "integer":
        out = {k: v for k, v in number.items()} | {"type": "integer"}
    elif f.type == "table":
        out = {"type": "object"}
    else:
        out = {"type": f.type}
        if isinstance(f.choices, tuple):
            out["enum"] = list(f.choices)
        if f.pattern:
            out["pattern"] = f.pattern
    if f.type == "string" and callable(f.choices):
        out["enum"] = sorted({*scene_schema.allowed_relations("jankowski"),
                              *scene_schema.allowed_relations("hertzdamp")})  # fmt: skip
    description = f.description + (f" [{f.unit}]" if f.unit else "")
    out["description"] = description
    if f.default is not None:
        out["default"] = f.default
    return out


def _table_schema(table: Table, *, required: bool = True) -> dict:
    out = {
        "type": "object",
        "description": table.description,
        "properties": {f.name: _field_schema(f) for f in table.fields},
        "additionalProperties": False,
    }
    needed = [f.name for f in table.fields if f.required and required]
    if needed:
        out["required"] = needed
    return out


def _building_schema() -> dict:
    sdof = _table_schema(scene_schema.SDOF)
    sdof["properties"]["model"]["enum"] = ["sdof"]
    shear = _table_schema(scene_schema.SHEAR)
    shear["properties"]["model"]["enum"] = ["shear"]
    # a varied key may be missing from the table: it then comes from [grid] or [sampling.vary]
    sdof["required"] = []
    return {"anyOf": [shear, sdof]}


def _wall_schema() -> dict:
    wall = _table_schema(scene_schema.WALL)
    wall["properties"]["model"]["enum"] = ["wall"]
    wall["required"] = ["model"]
    return wall


def _contact_schema() -> dict:
    out = _table_schema(scene_schema.CONTACT)
    out["allOf"] = [
        {
            "if": {"properties": {"model": {"const": "hertzdamp"}}, "required": ["model"]},
            "then": {
                "properties": {
                    "relation": {"enum": list(scene_schema.allowed_relations("hertzdamp"))}
                }
            },
            "else": {
                "properties": {
                    "relation": {"enum": list(scene_schema.allowed_relations("jankowski"))}
                }
            },
        }
    ]
    return out


def _row_key_pattern() -> str:
    """The JSON Schema pattern of a row's varied keys (``"buildings.N.KEY"``)."""
    return ROW_KEY.pattern.replace("([A-Za-z_]+)", f"({'|'.join(ROW_VARIED)})")


def json_schema() -> dict:
    """A JSON Schema (draft 2020-12) of study and scene files, for editors.

    It checks keys, types, bounds and choices; rules across keys that need the file's other
    tables (a varied key missing from the scene, the number of gaps, record files) are left
    to ``pound-mc check``.
    """
    record = _table_schema(scene_schema.RECORD)
    axis = _table_schema(GRID_AXIS)
    grid_values = {"anyOf": [{"type": "array", "items": {"type": "number"}, "minItems": 1}, axis]}
    grid = {
        "type": "object",
        "description": GRID_AXIS.description,
        "propertyNames": {
            "anyOf": [
                {"enum": sorted([*NUMERIC_SCENE_KEYS, *INTENSITY_KEYS, MATERIAL_KEY])},
                {"pattern": _row_key_pattern()},
            ]
        },  # fmt: skip
        "additionalProperties": grid_values,
        "properties": {
            MATERIAL_KEY: {
                "type": "array",
                "items": {"enum": list(materials.MATERIALS)},
                "minItems": 1,
                "uniqueItems": True,
            }
        },
    }
    vary = {
        "type": "object",
        "description": "Sampled scene keys and their distributions.",
        "propertyNames": {
            "anyOf": [
                {"enum": sorted(NUMERIC_SCENE_KEYS)},
                {"pattern": _row_key_pattern()},
            ]
        },  # fmt: skip
        "additionalProperties": {
            "anyOf": [_table_schema(t) for t in sampling.VARY_TABLES.values()]
        },
    }
    samp = _table_schema(SAMPLING)
    samp["properties"]["vary"] = vary
    contact = _contact_schema()
    integrator = _table_schema(scene_schema.INTEGRATOR)
    building = _building_schema()
    wall = _wall_schema()
    return {
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "$id": "https://pound-mc.invalid/pound-mc.schema.json",
        "title": "pound-mc study or scene file",
        "description": "Generated by `python -m pound_mc.study`; see studies/SCHEMA.md.",
        "type": "object",
        "properties": {
            "study": _table_schema(STUDY),
            "record": record,
            "records": {"type": "array", "items": record, "minItems": 1},
            "left": building,
            "right": {"anyOf": [*building["anyOf"], wall]},
            "buildings": {
                "type": "array",
                "description": "A row of buildings, left to right (a wall only last).",
                "prefixItems": [building],  # the first is no wall
                "items": {"anyOf": [*building["anyOf"], wall]},
                "minItems": 2,
            },
            "contact": contact,
            "integrator": integrator,
            "grid": grid,
            "sampling": samp,
        },
        # a pair or a row, not both
        "oneOf": [
            {"required": ["left", "right"], "not": {"required": ["buildings"]}},
            {
                "required": ["buildings"],
                "not": {"anyOf": [{"required": [k]} for k in ("left", "right")]},
            },
        ],
        "additionalProperties": False,
        "not": {"required": ["record", "records"]},
    }


def write_reference(folder: str | Path, *, check: bool = False) -> list[Path]:
    """Write ``SCHEMA.md`` and ``pound-mc.schema.json`` into ``folder`` (``studies/``).

    With ``check=True`` write nothing and return the files that are out of date.
    """
    folder = Path(folder)
    texts = {
        folder / "SCHEMA.md": reference_markdown(),
        folder / "pound-mc.schema.json": json.dumps(json_schema(), indent=2) + "\n",
    }
    stale = []
    for path, text in texts.items():
        if not path.is_file() or path.read_text(encoding="utf-8") != text:
            stale.append(path)
            if not check:
                path.write_text(text, encoding="utf-8")
    return stale


def main(argv: list[str] | None = None) -> int:
    """``python -m pound_mc.study [--check] [FOLDER]``."""
    parser = argparse.ArgumentParser(prog="python -m pound_mc.study")
    parser.add_argument("folder", nargs="?", default="studies")
    parser.add_argument("--check", action="store_true", help="only say whether they are stale")
    args = parser.parse_args(argv)
    stale = write_reference(args.folder, check=args.check)
    for path in stale:
        print(f"{'out of date' if args.check else 'wrote'}: {path}")
    return 1 if (args.check and stale) else 0


if __name__ == "__main__":
    sys.exit(main())
