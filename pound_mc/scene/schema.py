"""The scene tables declared once: each key's type, bounds, default, unit and description.

A scene file (``../shared/DESIGN.md`` section 6) holds ``[record]``, ``[left]`` and ``[right]``
(``model = "sdof"`` or ``"shear"``), ``[contact]`` and ``[integrator]``.  Each table is a
:class:`Table` of :class:`Field` entries; :func:`check_table` walks one and reports every
problem it finds (unknown keys, missing keys, wrong types, values out of bounds or not among
the choices), each naming the file and the dotted key.  The same declarations generate the
reference page ``studies/SCHEMA.md`` and the JSON Schema ``studies/pound-mc.schema.json``
(:mod:`pound_mc.study.schema`), so the documentation cannot drift from the validator.

Rules that tie several keys together (``beta`` or ``k_N_per_m`` by law, ``xi`` or ``e``, the
number of gaps) are checked by :func:`pound_mc.scene.model.scene_from_dict`.
"""

from __future__ import annotations

import math
import numbers
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pound_mc.errors import InputError, InputErrors, did_you_mean
from pound_mc.integrators import METHODS
from pound_mc.motions import UNITS_TEXT, builtin_catalogue, suites, synthetic
from pound_mc.physics import contact
from pound_mc.physics.contact import CONTACT_MODELS
from pound_mc.physics.materials import MATERIALS, PER_IMPACT_OUTSIDE
from pound_mc.physics.relations import largest_xi
from pound_mc.physics.structures import HYSTERESIS

__all__ = [
    "Field",
    "Table",
    "check_table",
    "raise_all",
    "allowed_relations",
    "default_relation",
    "source_problem",
    "RECORD",
    "SDOF",
    "SHEAR",
    "BUILDINGS",
    "CONTACT",
    "INTEGRATOR",
    "SCENE_TABLES",
    "LINEAR_LAWS",
    "varied_keys",
    "SHORTEST_PERIOD_S",
]

#: Type names of :class:`Field` and what they accept (``numbers``: a number or a list of them).
TYPES = ("number", "integer", "boolean", "string", "table", "numbers")


@dataclass(frozen=True)
class Field:
    """One key of a TOML table.

    Attributes
    ----------
    name : str
        The key.
    type : str
        One of :data:`TYPES`.
    description : str
        What it means (one sentence or two).
    unit : str
        SI unit of a number (``"s"``, ``"N/m^1.5"``); empty when dimensionless or not a number.
    default : object
        Value taken when the key is absent (``None``: no default).
    required : bool
        Whether the key must be given.
    minimum, maximum : float, optional
        Bounds of a number (every element of a list); ``exclusive_*`` makes them strict.
    choices : tuple or callable, optional
        Allowed values; a callable takes the table's values checked so far (keys earlier in
        the table) and returns them, for choices that depend on another key.
    choices_doc : str
        How dependent choices are described in the reference (default: the choices listed).
    no_choices : str
        The problem where dependent choices are none (``str.format`` of the table's values).
    pattern : str, optional
        Regular expression a string must match (JSON Schema syntax).
    varied : bool
        Whether a study may make the key a grid axis or a sampled variable.
    """

    name: str
    type: str
    description: str
    unit: str = ""
    default: Any = None
    required: bool = False
    minimum: float | None = None
    exclusive_minimum: bool = False
    maximum: float | None = None
    exclusive_maximum: bool = False
    choices: tuple | Callable[[dict], tuple] | None = None
    choices_doc: str = ""
    no_choices: str = ""
    pattern: str | None = None
    varied: bool = False

    def bounds_text(self) -> str:
        """The bounds as text (``"> 0"``, ``"[0, 1)"``), empty without bounds."""
        lo, hi = (_bound_text(x) for x in (self.minimum, self.maximum))
        if lo is not None and hi is not None:
            left = "(" if self.exclusive_minimum else "["
            right = ")" if self.exclusive_maximum else "]"
            return f"{left}{lo}, {hi}{right}"
        if lo is not None:
            return f"{'>' if self.exclusive_minimum else '>='} {lo}"
        if hi is not None:
            return f"{'<' if self.exclusive_maximum else '<='} {hi}"
        return ""

    def choices_for(self, values: dict) -> tuple | None:
        """Allowed values given the table's other values (``None``: any value of the type)."""
        return self.choices(values) if callable(self.choices) else self.choices

    def problem(self, value, values: dict | None = None) -> str | None:
        """What is wrong with ``value`` for this key, or ``None`` if nothing is."""
        kind = self.type
        if kind in ("number", "numbers"):
            items = value if (kind == "numbers" and isinstance(value, list)) else [value]
            if kind == "numbers" and not items:
                return "must be a number or a non-empty list of numbers, got []"
            if not all(_is_number(x) for x in items):
                what = "a finite number" + (" or a list of them" if kind == "numbers" else "")
                return f"must be {what}, got {value!r}"
            bounds = self.bounds_text()
            if bounds and not all(self._within(float(x)) for x in items):
                return f"must be {_bounds_phrase(self)}, got {value!r}"
            return None
        if kind == "integer":
            if not (isinstance(value, numbers.Integral) and not isinstance(value, bool)):
                return f"must be an integer, got {value!r}"
            if not self._within(value):
                return f"must be an integer {_bounds_phrase(self)}, got {value!r}"
            return None
        checks = {"boolean": (bool, "true or false"), "string": (str, "a string"),
                  "table": (dict, "a table")}  # fmt: skip
        python_type, what = checks[kind]
        if not isinstance(value, python_type):
            return f"must be {what}, got {value!r}"
        choices = self.choices_for(values or {})
        if choices == ():  # no value fits the table's other keys
            return (self.no_choices or "takes no value here; remove it").format(**(values or {}))
        if choices is not None and value not in choices:
            return f"unknown value {value!r}; allowed: {', '.join(map(str, choices))}"
        if self.pattern is not None and not _matches(self.pattern, value):
            return f"must match {self.pattern} ({self.description.lower().rstrip('.')})"
        return None

    def _within(self, x: float) -> bool:
        if self.minimum is not None:
            if x < self.minimum or (self.exclusive_minimum and x == self.minimum):
                return False
        if self.maximum is not None:
            if x > self.maximum or (self.exclusive_maximum and x == self.maximum):
                return False
        return True


@dataclass(frozen=True)
class Table:
    """One TOML table: its name (``"contact"``), a description and its fields, in order."""

    name: str
    description: str
    fields: tuple[Field, ...]
    #: For the reference page: a variant of a table chosen by a key (``model = "shear"``).
    variant: str = ""
    #: An array of tables (``[[records]]``) rather than one table.
    array: bool = False
    _by_name: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        object.__setattr__(self, "_by_name", {f.name: f for f in self.fields})

    @property
    def keys(self) -> tuple[str, ...]:
        """The allowed keys, in declaration order."""
        return tuple(self._by_name)

    def __getitem__(self, name: str) -> Field:
        return self._by_name[name]


def _bound_text(x: float | None) -> str | None:
    """A bound as written: an integer in full (a seed's 2^64 - 1), a float with ``:g``."""
    if x is None:
        return None
    return str(x) if isinstance(x, int) else f"{x:g}"


def _is_number(x) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _matches(pattern: str, value: str) -> bool:
    return re.match(pattern, value) is not None


def _bounds_phrase(f: Field) -> str:
    lo, hi = f.minimum, f.maximum
    if lo is not None and hi is not None:
        return f"in {f.bounds_text()}"
    return f.bounds_text()


def check_table(
    table: Table, data: dict, *, file: str | None, prefix: str, errors: list[InputError]
) -> dict:
    """Check one table against its declaration; problems are appended to ``errors``.

    Parameters
    ----------
    table : Table
        The declaration.
    data : dict
        The table as read.
    file : str, optional
        The file, named in every message.
    prefix : str
        Dotted prefix of the keys in messages (``"left."``, ``"records[1]."``).
    errors : list of InputError
        Where problems go.

    Returns
    -------
    dict
        The values that passed, defaults filled in for absent keys that have one.
    """
    for key in sorted(set(data) - set(table.keys), key=str):
        errors.append(
            InputError(
                f"unknown key{did_you_mean(key, table.keys)}; allowed: {', '.join(table.keys)}",
                file=file,
                key=prefix + key,
            )
        )
    out: dict = {}
    for f in table.fields:
        if f.name not in data:
            if f.required:
                note = f" for {table.variant}" if table.variant else ""
                errors.append(InputError(f"is required{note}", file=file, key=prefix + f.name))
            elif f.default is not None:
                out[f.name] = f.default
            continue
        problem = f.problem(data[f.name], out)
        if problem is None:
            out[f.name] = data[f.name]
        else:
            errors.append(InputError(problem, file=file, key=prefix + f.name))
    return out


def raise_all(errors: list[InputError]) -> None:
    """Raise the one problem in ``errors`` as it is, several as :class:`InputErrors`."""
    if len(errors) == 1:
        raise errors[0]
    if errors:
        raise InputErrors(errors)


# --------------------------------------------------------------------------- contact relations

#: Contact laws whose stiffness is ``k_N_per_m`` [N/m] (the others take ``beta`` [N/m^1.5]).
LINEAR_LAWS = ("linear", "kelvin")


def allowed_relations(model: str) -> tuple[str, ...]:
    """Names of the e-to-damping relations the contact law ``model`` takes (its declaration)."""
    return contact.allowed_relations(model) if model in contact.CONTACT_MODELS else ()


def default_relation(model: str) -> str | None:
    """The relation a law uses when ``contact.relation`` is not given (None: no damping)."""
    return contact.default_relation(model) if model in contact.CONTACT_MODELS else None


# --------------------------------------------------------------------------- record sources


def source_problem(source: str, base_dir: str | Path | None) -> str | None:
    """Why a ``record.source`` cannot be read (an unknown name, a missing file), or ``None``.

    Only existence is checked here; reading and preprocessing happen when a study engine or
    :func:`pound_mc.scene.simulate` loads the record.
    """
    kind, sep, rest = source.partition(":")
    kind = kind.strip().lower()
    if sep and kind == "builtin":
        names = builtin_catalogue()
        if rest.strip().lower() not in names:
            return f"unknown built-in record {rest!r}; choose one of {', '.join(names)}"
        return None
    if sep and kind == "suite":
        if rest.strip().lower() not in suites.SUITES:
            return f"unknown record suite {rest!r}; choose one of " + ", ".join(
                f"'suite:{name}'" for name in suites.SUITES
            )
        return None
    if sep and kind == "synthetic":
        if rest.strip().lower() not in synthetic.SYNTHETIC_MODELS:
            return (
                f"unknown synthetic model {rest!r}; choose one of "
                f"{', '.join(synthetic.SYNTHETIC_MODELS)}"
            )
        return None
    path = Path(source).expanduser()
    if not path.is_absolute() and base_dir is not None:
        path = Path(base_dir) / path
    if path.is_symlink() and not path.exists():
        return f"symbolic link that leads nowhere (a loop, or its target is missing): {path}"
    if not path.exists():
        if re.match(r"^[A-Za-z][\w-]+:", source):
            return (
                f"unknown source kind {kind + ':'!r} (and no such file); use a path, "
                "'builtin:NAME', 'synthetic:MODEL' or 'suite:NAME'"
            )
        return f"file not found: {path}"
    if not path.is_file():
        return f"not a file (a directory?): {path}"
    return None


# --------------------------------------------------------------------------- the tables

#: Shortest building period a scene takes [s]: stiffer than any building (a 1-kHz mode); a
#: shorter one makes the step control take billions of steps (a run that does not end).
SHORTEST_PERIOD_S = 1.0e-3

RECORD = Table(
    "record",
    "The ground motion: one `[record]` table, or several `[[records]]` tables in a study "
    "(each a record axis entry, with the same keys).  Steps in order: read, demean, filter, "
    "resample, truncate to `duration_s`, scale to `pga_g` (or, in a study, to the grid axis "
    "`record.pga_g` or `record.sa_g`).",
    (
        Field("source", "string", "A file path (AT2, MiniSEED, SAC, K-NET, EVT, ...; relative "
              "to the file that names it), `builtin:NAME` (`pound-mc records`) or "
              "`synthetic:clough-penzien`; in a study also `suite:fema-p695-farfield` or "
              "`suite:fema-p695-nearfield` (one record per horizontal component; a single "
              "component with `component`) or a glob such as `records/*.AT2` (one record per "
              "file, sorted by path).", required=True),
        Field("name", "string", "Label of the record in the dataset (default: the source)."),
        Field("demean", "boolean", "Remove the mean of the whole record as read.",
              default=True),
        Field("duration_s", "number", "Keep the samples with t <= duration_s.", unit="s",
              minimum=0.0, exclusive_minimum=True),
        Field("pga_g", "number", "Scale so that max |a| of the kept samples is pga_g * g.",
              unit="g", minimum=0.0, exclusive_minimum=True),
        Field("units", "string", "Units of the file's values: " + UNITS_TEXT + ".  Overrides "
              "the units an AT2 header's third line names (`UNITS OF G`, `IN CM/S/S`, ...: the "
              "same spellings); an AT2 header that names none is in g (the PEER convention), "
              "one that names units not listed here is refused until this key gives them.  "
              "Required for formats without units (MiniSEED, SAC, ...); K-NET and Kinemetrics "
              "EVT files carry their own.  `pound-mc records info` says which units a record "
              "is read in and where they came from."),
        Field("component", "string", "Trace of a multi-trace file (e.g. `EW`, `HNE`), or a "
              "suite's component (e.g. `NORTHR/MUL009`)."),
        Field("sa_period_s", "number", "Period of the 5 %-damped spectral acceleration of the "
              "study grid axis `record.sa_g`; no longer than the record.", unit="s",
              minimum=0.0, exclusive_minimum=True),
        Field("seed", "integer", "Realisation of a synthetic motion (required for "
              "`synthetic:`).", minimum=0, maximum=2**64 - 1),
        Field("params", "table", "Parameters of a synthetic motion "
              "(`pound_mc.motions.synthetic`)."),
        Field("resample_hz", "number", "New sampling rate (Fourier resampling, no taper), "
              "before truncation.", unit="Hz", minimum=0.0, exclusive_minimum=True, maximum=1.0e4),
        Field("filter", "table", "Arguments of obspy's `Trace.filter`, e.g. "
              "`{ type = \"bandpass\", freqmin = 0.1, freqmax = 25.0 }`."),
    ),
)  # fmt: skip

_BUILDING_DAMPING = Field(
    "damping_ratio", "number", "Viscous damping ratio of every mode (classical damping).",
    default=0.05, minimum=0.0, maximum=1.0, exclusive_maximum=True, varied=True,
)  # fmt: skip

_HYSTERESIS = Field(
    "hysteresis", "string", "Storey law: `elastic`, `bilinear` (kinematic hardening: storey "
    "force alpha k u + (1 - alpha) k z, z elastic-perfectly-plastic with |z| <= yield drift) "
    "or `bouc-wen` (same force, z smooth: z' = u' (1 - |z/u_y|^n (0.5 sign(u' z) + 0.5)), no "
    "degradation or pinching); damping from the initial elastic modes.  Every method runs "
    "yielding buildings; `adaptive` with error-controlled steps and located yield and unload "
    "events.",
    default="elastic", choices=HYSTERESIS,
)  # fmt: skip
_POST_YIELD = Field(
    "post_yield_ratio", "number", "Post-yield over elastic storey stiffness alpha (bilinear; "
    "default 0, elastic-perfectly-plastic; every method takes any value from 0).",
    minimum=0.0, maximum=1.0, exclusive_maximum=True,
    varied=True,
)  # fmt: skip
_BW_EXPONENT = Field(
    "bw_exponent", "number", "Bouc-Wen exponent n (bouc-wen only; default 2): the sharpness "
    "of the transition to yield, large n approaching the bilinear law.", minimum=1.0,
    maximum=50.0,
)  # fmt: skip

SDOF = Table(
    "sdof",
    "A single-degree-of-freedom building (`[left]` or `[right]` with `model = \"sdof\"`, the "
    "default).",
    (
        Field("model", "string", "Building model.", default="sdof",
              choices=("sdof", "shear", "wall")),
        Field("period_s", "number", "Natural period, from 1e-3 s (stiffer than any building; "
              "a shorter one makes the step control take billions of steps) up to 1e6 s (a "
              "nearly free mass, as in verification against closed forms).", unit="s",
              required=True, minimum=SHORTEST_PERIOD_S, maximum=1.0e6, varied=True),
        Field("mass_kg", "number", "Mass.", unit="kg", required=True, minimum=0.0,
              exclusive_minimum=True, maximum=1.0e10, varied=True),
        _BUILDING_DAMPING,
        Field("height_m", "number", "Height of the mass; needed only to pair it with a shear "
              "building's floors.", unit="m", minimum=0.0, exclusive_minimum=True),
        _HYSTERESIS,
        Field("yield_disp_m", "number", "Displacement at yield (required for bilinear and "
              "bouc-wen).", unit="m", minimum=0.0, exclusive_minimum=True, varied=True),
        _POST_YIELD,
        _BW_EXPONENT,
    ),
    variant="model = 'sdof'",
)  # fmt: skip

SHEAR = Table(
    "shear",
    "A shear building (`[left]` or `[right]` with `model = \"shear\"`): storey lists bottom to "
    "top, of equal length; floors of the two buildings at equal height can pound.  A study "
    "may vary its masses, stiffnesses, yield drifts (a number: every storey the same), "
    "damping ratio and post-yield ratio; its modes are then computed per simulation.",
    (
        Field("model", "string", "Building model.", required=True,
              choices=("sdof", "shear", "wall")),
        Field("storey_mass_kg", "numbers", "Floor masses, bottom to top.", unit="kg",
              required=True, minimum=0.0, exclusive_minimum=True, maximum=1.0e10, varied=True),
        Field("storey_stiffness_N_per_m", "numbers", "Storey shear stiffnesses, bottom to top.",
              unit="N/m", required=True, minimum=0.0, exclusive_minimum=True, maximum=1.0e14,
              varied=True),
        Field("storey_height_m", "numbers", "Storey heights, bottom to top (floor elevations "
              "are their cumulative sums).", unit="m", required=True, minimum=0.0,
              exclusive_minimum=True),
        _BUILDING_DAMPING,
        _HYSTERESIS,
        Field("storey_yield_disp_m", "numbers", "Inter-storey drift at yield, bottom to top, "
              "or one for every storey (required for bilinear and bouc-wen).", unit="m",
              minimum=0.0, exclusive_minimum=True, varied=True),
        _POST_YIELD,
        _BW_EXPONENT,
    ),
    variant="model = 'shear'",
)  # fmt: skip

WALL = Table(
    "wall",
    "A rigid, immovable wall (`[right]` with `model = \"wall\"`): a moat wall or an abutment, "
    "of infinite mass (a contact's effective mass is the building floor's mass).",
    (
        Field("model", "string", "Building model.", required=True,
              choices=("sdof", "shear", "wall")),
        Field("height_m", "number", "Height of the wall's top: it meets the other building's "
              "floors at or below it (default: only its lowest floor).", unit="m", minimum=0.0,
              exclusive_minimum=True),
    ),
    variant="model = 'wall'",
)  # fmt: skip

#: Building tables by ``model``.
BUILDINGS = {"sdof": SDOF, "shear": SHEAR, "wall": WALL}

CONTACT = Table(
    "contact",
    "The impact law between the buildings (Jankowski 2008 and the laws compared with it).  "
    "Give the damping as `xi` or as a restitution coefficient `e` (with `relation`), not "
    "both; `jankowski` and `kelvin` need one of them, `hertzdamp` needs `e`, the elastic "
    "`linear` and `hertz` laws take neither.",
    (
        Field("model", "string", "Contact law.", default="jankowski",
              choices=tuple(CONTACT_MODELS)),
        Field("gap_m", "numbers", "Initial separation: one value, or one per contact (pair of "
              "floors at equal height, bottom to top).", unit="m", default=0.0, minimum=0.0,
              varied=True),
        Field("beta", "number", "Impact stiffness parameter of the Hertz-type laws "
              "(jankowski, hertz, hertzdamp).", unit="N/m^1.5", default=2.75e9, minimum=0.0,
              exclusive_minimum=True, varied=True),
        Field("k_N_per_m", "number", "Linear impact stiffness of the linear and kelvin laws.",
              unit="N/m", default=2.75e9, minimum=0.0, exclusive_minimum=True, varied=True),
        Field("xi", "number", "Impact damping ratio, up to 71.17: the end of the table of the "
              "restitution the Jankowski law rebounds with (e = 0.00785).", minimum=0.0,
              maximum=largest_xi(), varied=True),
        Field("e", "number", "Coefficient of restitution; the damping follows from it through "
              "`relation`.", minimum=0.0, exclusive_minimum=True, maximum=1.0, varied=True),
        Field("relation", "string", "Relation from e to the damping, one of the law's own (default:"
              " its first); the linear and hertz laws have no damping and take none.",
              choices=lambda values: allowed_relations(values.get("model", "jankowski")),
              choices_doc="; ".join(
                  f"{name}: {', '.join(law.relations)}"
                  for name, law in contact.CONTACT_MODELS.items() if law.relations
              ),
              no_choices="the {model!r} law has no damping and takes no relation; remove it"),
        Field("restitution", "string", "`fixed`: one restitution (`e` or `xi`) for every impact; "
              "`velocity`: each impact's e from the seed's Table 2 at its prior-impact velocity "
              "(the relative velocity at contact onset) for `material`, at quantile `e_quantile` "
              "of the measured range, its damping from `relation`, fixed for that impact (under "
              "`jankowski2008` the impact rebounds above that e; `exact` rebounds with it).",
              default="fixed", choices=("fixed", "velocity")),
        Field("material", "string", "Material of Table 2 (restitution = \"velocity\").",
              choices=MATERIALS),
        Field("e_quantile", "number", "Quantile of Table 2's measured range of e at each "
              "impact's velocity (restitution = \"velocity\"): 0 its lower, 1 its upper bound.",
              minimum=0.0, maximum=1.0, varied=True),
        Field("outside", "string", "Restitution outside Table 2's velocities (restitution = "
              "\"velocity\"): `clamp` holds the nearest measured range, `extrapolate` continues "
              "the end segments linearly (e kept within [0.05, 1]).", default="clamp",
              choices=PER_IMPACT_OUTSIDE),
        Field("level_tolerance_m", "number", "Floors of the two buildings within this of equal "
              "height meet floor to floor; any other floor between two floors of the other "
              "building meets its column, whose displacement there is interpolated linearly "
              "between those floors, with the column's effective mass 1 / sum(w^2 / m).",
              unit="m", default=0.0, minimum=0.0),
    ),
)  # fmt: skip

INTEGRATOR = Table(
    "integrator",
    "The time integration (docs/integrators.md).",
    (
        Field("method", "string", "Integration method.", default="adaptive",
              choices=tuple(METHODS)),
        Field("dt_s", "number", "Step of the fixed-step methods, or the bound on steps between "
              "contacts (adaptive with elastic buildings; with yielding ones the first step, "
              "the error estimate bounds the others).", unit="s", default=0.001, minimum=0.0,
              exclusive_minimum=True, maximum=1.0, varied=True),
        Field("substeps", "integer", "Sub-steps per contact-duration estimate while in contact "
              "(adaptive; with yielding buildings the error tolerance, 1e-9 (16 / substeps)^2 "
              "relative to the response).", default=16, minimum=4, maximum=1024),
        Field("tail_s", "number", "Free vibration after the record (zero ground acceleration) "
              "of runs with yielding buildings, for their residual drift.", unit="s",
              default=5.0, minimum=0.0, maximum=600.0),
        Field("accuracy_check", "boolean", "Compare every run that ends ok with a second run "
              "(fixed-step methods: adaptive at its defaults; adaptive with a contact: twice "
              "the sub-steps) and flag it inaccurate where its peak force, a contact's peak "
              "force, a building's peak displacement or ductility differs by more than 0.5 % "
              "(of the peak force, the larger building's); pound-mc simulate and every study "
              "run alike.  A study then runs each flagged simulation again with dt_s halved "
              "and substeps doubled, up to 3 times (dataset: run_dt_s, run_substeps, "
              "refinements).  False saves that second run (up to the cost of the run) and "
              "leaves sensitive runs unflagged.", default=True),
    ),
)  # fmt: skip

#: Scene tables by name (``left`` and ``right`` are :data:`BUILDINGS` chosen by ``model``).
SCENE_TABLES = {"record": RECORD, "left": BUILDINGS, "right": BUILDINGS, "contact": CONTACT,
                "integrator": INTEGRATOR}  # fmt: skip


def varied_keys() -> tuple[str, ...]:
    """Scene keys a study may vary (``"left.period_s"``): the numeric fields marked ``varied``.

    A shear building's storey lists are among them: a varied number stands for every storey.
    """
    out = []
    for side in ("left", "right"):
        out += [f"{side}.{f.name}" for f in SDOF.fields if f.varied]
        out += [f"{side}.{f.name}" for f in SHEAR.fields if f.varied and f not in SDOF.fields]
    for table in (CONTACT, INTEGRATOR):
        out += [f"{table.name}.{f.name}" for f in table.fields if f.varied]
    return tuple(out)
