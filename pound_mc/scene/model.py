"""A scene file (TOML) to a validated :class:`Scene` and the arrays its kernels take.

A scene holds ``[record]``, ``[left]``, ``[right]`` (or a row, ``[[buildings]]``),
``[contact]`` and ``[integrator]`` (``../shared/DESIGN.md`` section 6), declared in
:mod:`pound_mc.scene.schema`; :func:`pound_mc.scene.simulation.simulate` runs it.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from pound_mc.errors import InputError, parse_toml, read_text_file
from pound_mc.motions import load_record, record_arrays
from pound_mc.physics.contact import CONTACT_MODELS, kernel_damping, reported_xi
from pound_mc.physics.structures import (
    Building,
    Contact,
    contacts_between,
    sdof,
    shear_building,
    wall,
)
from pound_mc.scene import schema

__all__ = ["Scene", "scene_from_dict", "load_scene", "ROW_TABLE"]

#: Tables a study adds to a scene (checked by :mod:`pound_mc.study.definition`).
_STUDY_TABLES = {"study", "grid", "sampling", "records"}
#: A row of buildings (``[[buildings]]``, left to right) in place of ``[left]`` and ``[right]``.
ROW_TABLE = "buildings"


#: Fields of a :class:`Scene` the modal arrays depend on (the cache key holds their values).
_MODAL_FIELDS = (
    "left", "right", "contacts", "contact_model", "stiffness", "xi", "e", "restitution",
    "e_quantile",
)  # fmt: skip


@dataclass
class Scene:
    """A validated scene: record specification, two buildings, their contacts and settings.

    The record, once read and preprocessed, and the modal arrays are cached on the scene, so
    that repeated :func:`simulate` calls pay for the kernel only.  Assigning any field drops
    the cache, and each entry is also keyed by the values it was made from (the record table,
    the gaps, the contact parameters), so an edit in place (``scene.record["pga_g"] = 0.4``,
    ``scene.gap_m[0] = 0.02``) is seen too; ``dataclasses.replace`` makes a new scene with an
    empty cache.
    """

    record: dict[str, Any]
    left: Building
    right: Building
    contacts: list[Contact]
    gap_m: np.ndarray
    contact_model: str = "jankowski"
    stiffness: float = 2.75e9
    xi: float = 0.35
    e: float | None = None
    relation: str | None = None
    method: str = "adaptive"
    dt_s: float = 0.001
    substeps: int = 16
    restitution: str = "fixed"
    material: str | None = None
    e_quantile: float | None = None
    outside: str = "clamp"
    row: list[Building] | None = None
    file: str | None = None
    base_dir: Path | None = None
    tail_s: float = 5.0
    accuracy_check: bool = True
    #: ``(record table, folder, (dt, acceleration))`` of :meth:`hold_record` (copies keep it)
    held_record: tuple | None = field(default=None, repr=False, compare=False)
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __setattr__(self, name, value):
        """Set a field; any field but the cache itself drops the cached record and arrays."""
        if name != "_cache" and "_cache" in self.__dict__:
            self._cache.clear()
        object.__setattr__(self, name, value)

    def hold_record(self, record: tuple[float, np.ndarray]) -> None:
        """Run with ``record`` = ``(dt [s], acceleration [m/s^2])`` in place of reading it.

        For a study's simulation whose record the study scaled (an intensity axis): the
        scene's record table names the record, not its scaling.  :meth:`record_arrays` uses
        it while the record table and the folder are those it was held with; copies of the
        scene (``dataclasses.replace``, ``copy``, pickling) keep it.
        """
        self.held_record = (copy.deepcopy(self.record), self.base_dir,
                            (float(record[0]), np.asarray(record[1], dtype=float)))  # fmt: skip

    def __getstate__(self):
        """Pickle and copy without the cache (a worker reads its own record)."""
        return {**self.__dict__, "_cache": {}}

    def _modal_key(self) -> tuple:
        gap = np.asarray(self.gap_m, dtype=float)
        return (
            *(id(getattr(self, f)) for f in ("left", "right", "contacts")),
            len(self.contacts),
            *(getattr(self, f) for f in _MODAL_FIELDS[3:]),
            gap.tobytes(),
        )

    def kernel_arrays(self) -> dict[str, np.ndarray]:
        """The cached :meth:`modal_arrays` (read them, do not modify them)."""
        return self._cached("modal", self.modal_arrays)

    def kernel_storeys(self) -> tuple[np.ndarray, np.ndarray] | None:
        """The cached :meth:`storey_arrays` (read them, do not modify them)."""
        return self._cached("storeys", self.storey_arrays) if self.inelastic else None

    def _cached(self, name, make):
        """``make()``, cached under ``name`` while the buildings and contacts stay the same."""
        key = self._modal_key()
        hit = self._cache.get(name)
        if hit is None or hit[0] != key:
            hit = self._cache[name] = (key, make())
        return hit[1]

    def record_arrays(self) -> tuple[float, np.ndarray]:
        """The scene's record as ``(dt [s], acceleration [m/s^2])``, read once and cached.

        Read it, do not modify it: the array is shared by every later call.
        """
        held = self.held_record
        if held is not None and _same_record(held[0], self.record) and held[1] == self.base_dir:
            return held[2]
        hit = self._cache.get("record")
        if hit is None or not _same_record(hit[0], self.record) or hit[1] != self.base_dir:
            spec = copy.deepcopy(self.record)  # a change of the scene's record reads it again
            hit = self._cache["record"] = (spec, self.base_dir, record_arrays(self.load_record()))
        return hit[2]

    def modal_arrays(self) -> dict[str, np.ndarray]:
        """Arrays the kernels take: modes of both buildings, floor maps and contacts.

        A new set of arrays at every call; :func:`simulate` uses a cached one.
        """
        if self.row is not None:
            return self._row_arrays()
        nl, nr = self.left.omega.size, self.right.omega.size
        fl, fr = self.left.n_floors, self.right.n_floors
        phi = np.zeros((fl + fr, nl + nr))
        phi[:fl, :nl] = self.left.phi
        phi[fl:, nl:] = self.right.phi
        side = np.r_[np.zeros(fl, dtype=np.int64), np.ones(fr, dtype=np.int64)]
        psi = np.array([
            c.weights("left", fl) @ phi[:fl] - c.weights("right", fr) @ phi[fl:]
            if c.kind == "column" else phi[c.left_floor] - phi[fl + c.right_floor]
            for c in self.contacts
        ])  # fmt: skip
        nc = len(self.contacts)
        return {
            "omega": np.r_[self.left.omega, self.right.omega],
            "zeta": np.r_[
                np.full(nl, self.left.damping_ratio), np.full(nr, self.right.damping_ratio)
            ],
            "gamma": np.r_[self.left.gamma, self.right.gamma],
            "phi": phi,
            "side": side,
            "psi": psi.reshape(nc, nl + nr),
            "gap": np.asarray(self.gap_m, dtype=float),
            "meff": np.array([c.m_eff for c in self.contacts]),
            "beta": np.full(nc, float(self.stiffness)),
            "xi": np.full(nc, self._kernel_xi()),
        }

    def _kernel_xi(self) -> float:
        """The kernels' damping parameter of every contact (the ``xi`` array's value).

        ``xi``, or the restitution ``e`` for laws whose damping is set per impact from ``e``
        and the impact velocity (hertzdamp), or with restitution set per impact the quantile
        ``e_quantile`` of the material's ``e`` (the kernels set ``e`` at every impact).
        """
        if self.restitution == "velocity":
            xi = self.e_quantile
        else:
            xi = kernel_damping(self.contact_model, self.e, self.xi)
        return float(xi if xi is not None else 0.0)

    @property
    def inelastic(self) -> bool:
        """Whether a building's storeys can yield (the inelastic kernel runs it)."""
        return any(b.inelastic for b in self.buildings)

    @property
    def buildings(self) -> list:
        """The buildings from left to right (a wall included): the row's, or ``[left, right]``."""
        return list(self.row) if self.row is not None else [self.left, self.right]

    def side_codes(self) -> list[int]:
        """The kernels' code (``side``) of each building from left to right.

        0 the first building, 1 the last (their outputs are ``*_left`` and ``*_right``); in a
        row the buildings between them from 2 on, then a wall that closes the row (a wall is
        no building: the building before it is the last).  A pair: ``[0, 1]``.
        """
        entries = self.buildings
        walls = [k for k, b in enumerate(entries) if b.model == "wall"]
        if len(entries) == 2 or not walls:
            return [0] + [2 + k for k in range(len(entries) - 2)] + [1]
        # a row of three or more closed by a wall: the wall is past the buildings' codes
        return [0] + [2 + k for k in range(len(entries) - 3)] + [1, len(entries) - 1]

    def storey_arrays(self) -> tuple[np.ndarray, np.ndarray] | None:
        """Storeys of every building for the inelastic kernel; None when all are elastic.

        Returns the drift rows in modal coordinates (storeys x modes, ``u = D q``) and the
        storey table (stiffness [N/m], yield drift [m] (inf where elastic), post-yield ratio,
        storey height [m] (NaN: none), the building's code (:meth:`side_codes`: 0 first,
        1 last), Bouc-Wen exponent (0: not Bouc-Wen)), left storeys first.
        """
        if not self.inelastic:
            return None
        buildings = self.buildings
        codes = self.side_codes()
        modes = np.cumsum([0] + [b.omega.size for b in buildings])
        dmat = np.zeros((sum(b.n_floors for b in buildings), modes[-1]))
        rows = []
        start = 0
        for b, bld in enumerate(buildings):
            ns = bld.n_floors
            dmat[start : start + ns, modes[b] : modes[b + 1]] = bld.drift_matrix() @ bld.phi
            uy = bld.yield_disp_m if bld.inelastic else np.full(ns, np.inf)
            n_bw = bld.bw_exponent if bld.hysteresis == "bouc-wen" else 0.0
            for s in range(ns):
                rows.append([bld.storey_stiffness_N_per_m[s], uy[s], bld.post_yield_ratio,
                             bld.storey_height_m[s], codes[b], n_bw])  # fmt: skip
            start += ns
        return dmat, np.array(rows, dtype=float)

    def _row_arrays(self) -> dict[str, np.ndarray]:
        """:meth:`modal_arrays` of a row: contacts between neighbours (``Contact.pair``).

        ``side`` holds each floor's building code (:meth:`side_codes`), so that
        ``peak_disp_left`` is the first building's and ``peak_disp_right`` the last's.
        """
        row = self.row
        floors = np.cumsum([0] + [b.n_floors for b in row])
        modes = np.cumsum([0] + [b.omega.size for b in row])
        phi = np.zeros((floors[-1], modes[-1]))
        for k, b in enumerate(row):
            phi[floors[k] : floors[k + 1], modes[k] : modes[k + 1]] = b.phi
        psi = np.array([
            c.weights("left", row[c.pair].n_floors) @ phi[floors[c.pair] : floors[c.pair + 1]]
            - c.weights("right", row[c.pair + 1].n_floors)
            @ phi[floors[c.pair + 1] : floors[c.pair + 2]]
            for c in self.contacts
        ])  # fmt: skip
        nc = len(self.contacts)
        return {
            "omega": np.concatenate([b.omega for b in row]),
            "zeta": np.concatenate([np.full(b.omega.size, b.damping_ratio) for b in row]),
            "gamma": np.concatenate([b.gamma for b in row]),
            "phi": phi,
            "side": np.repeat(np.array(self.side_codes(), dtype=np.int64),
                              [b.n_floors for b in row]),
            "psi": psi.reshape(nc, modes[-1]),
            "gap": np.asarray(self.gap_m, dtype=float),
            "meff": np.array([c.m_eff for c in self.contacts]),
            "beta": np.full(nc, float(self.stiffness)),
            "xi": np.full(nc, self._kernel_xi()),
        }  # fmt: skip

    def contact_lines(self) -> list[str]:
        """One line per contact (height, floors or column weights, effective mass), or none.

        Lines only where a contact meets a column (a floor between the other building's floors).
        """
        if all(c.kind == "floor" for c in self.contacts):
            return []

        def column(at):
            return " + ".join(
                f"{w:.4g} x " + ("ground" if f < 0 else f"floor {f + 1}") for f, w in at
            )

        lines = []
        for k, c in enumerate(self.contacts):
            if c.right_at:
                what = f"left floor {c.left_floor + 1} on the right column ({column(c.right_at)})"
            elif c.left_at:
                what = f"right floor {c.right_floor + 1} on the left column ({column(c.left_at)})"
            else:
                what = f"left floor {c.left_floor + 1} - right floor {c.right_floor + 1}"
            lines.append(f"contact {k + 1} at {c.elevation_m:g} m: {what}, "
                         f"m_eff {c.m_eff:.6g} kg")  # fmt: skip
        return lines

    def restitution_rule(self) -> dict | None:
        """The kernels' per-impact restitution (``restitution = "velocity"``), else None."""
        if self.restitution != "velocity":
            return None
        return {"material": self.material, "outside": self.outside}

    def load_record(self):
        """The scene's record as an obspy Trace [m/s^2], preprocessed."""
        spec = dict(self.record)
        spec.pop("name", None)
        spec.pop("sa_period_s", None)  # the period of a study's record.sa_g axis, not a step
        source = spec.pop("source")
        return load_record(source, base_dir=self.base_dir, **spec)


def _building(spec, side: str, file, errors: list, wall_ok: bool | None = None) -> Building | None:
    """Check ``[left]`` or ``[right]`` against its model's table and build it.

    ``wall_ok``: whether it may be a wall (default: on the right only).
    """
    model = spec.get("model", "sdof")
    table = schema.BUILDINGS.get(model) if isinstance(model, str) else None
    if table is None:
        problem = schema.SDOF["model"].problem(model)
        errors.append(InputError(problem, file=file, key=f"{side}.model"))
        return None
    local: list[InputError] = []
    v = schema.check_table(table, spec, file=file, prefix=f"{side}.", errors=local)
    errors.extend(local)
    if local:
        return None
    if model == "wall" and not (side == "right" if wall_ok is None else wall_ok):
        errors.append(InputError("a wall stands only on the right", file=file, key=f"{side}.model"))
        return None
    try:
        if model == "wall":
            return wall(v.get("height_m"), file=file, prefix=f"{side}.")
        if model == "sdof":
            return sdof(v["period_s"], v["mass_kg"], v["damping_ratio"], v.get("height_m"),
                        hysteresis=v["hysteresis"], yield_disp_m=v.get("yield_disp_m"),
                        post_yield_ratio=v.get("post_yield_ratio"), file=file,
                        prefix=f"{side}.", bw_exponent=v.get("bw_exponent"))  # fmt: skip
        building = shear_building(v["storey_mass_kg"], v["storey_stiffness_N_per_m"],
                                  v["storey_height_m"], v["damping_ratio"],
                                  hysteresis=v["hysteresis"],
                                  storey_yield_disp_m=v.get("storey_yield_disp_m"),
                                  post_yield_ratio=v.get("post_yield_ratio"), file=file,
                                  prefix=f"{side}.",
                                  bw_exponent=v.get("bw_exponent"))  # fmt: skip
    except InputError as exc:  # rules across keys: storey lists of equal length
        errors.append(exc)
        return None
    shortest = 2.0 * math.pi / float(np.max(building.omega))
    if shortest < schema.SHORTEST_PERIOD_S:  # the period_s bound, for storeys
        errors.append(
            InputError(f"storeys with a shortest period of {shortest:.3g} s, below "
                       f"{schema.SHORTEST_PERIOD_S:g} s (stiffer than any building; the step "
                       "control would take billions of steps)", file=file,
                       key=f"{side}.storey_stiffness_N_per_m")
        )  # fmt: skip
        return None
    return building


def _contact(ct: dict, n_contacts: int | None, file, errors: list) -> dict:
    """Check ``[contact]``: the table, then the rules that tie its keys together."""
    local: list[InputError] = []
    v = schema.check_table(schema.CONTACT, ct, file=file, prefix="contact.", errors=local)
    errors.extend(local)
    model = v.get("model")
    if model is None:
        return v
    skey = "k_N_per_m" if model in schema.LINEAR_LAWS else "beta"
    other = "beta" if skey == "k_N_per_m" else "k_N_per_m"
    if other in ct:
        errors.append(
            InputError(f"the {model!r} law takes {skey!r}, not {other!r}", file=file,
                       key=f"contact.{other}")
        )  # fmt: skip
    v["stiffness"] = v.get(skey)
    velocity = v.get("restitution") == "velocity"
    if velocity:
        for key in ("material", "e_quantile"):
            if key not in ct:
                errors.append(InputError("is needed with restitution = 'velocity'", file=file,
                                         key=f"contact.{key}"))  # fmt: skip
        for key in ("e", "xi"):
            if key in ct:
                errors.append(InputError("is set per impact with restitution = 'velocity'",
                                         file=file, key=f"contact.{key}"))  # fmt: skip
        if CONTACT_MODELS[model].damping is None:
            errors.append(InputError(f"the {model!r} law has no damping to set per impact",
                                     file=file, key="contact.restitution"))  # fmt: skip
        v["relation"] = v.get("relation") or schema.default_relation(model)
        return _contact_gaps(v, n_contacts, file, errors)
    for key in ("material", "e_quantile"):
        if key in ct:
            errors.append(InputError("applies only with restitution = 'velocity'", file=file,
                                     key=f"contact.{key}"))  # fmt: skip
    if CONTACT_MODELS[model].damping is None:  # its declaration lists neither xi nor e
        for key in ("xi", "e"):
            if key in ct:
                errors.append(InputError(f"the {model!r} law has no damping (elastic: it "
                                         f"rebounds with e = 1) and takes no {key!r}",
                                         file=file, key=f"contact.{key}"))  # fmt: skip
    if "xi" in ct and "e" in ct:
        errors.append(InputError("give either xi or e, not both", file=file, key="contact.xi"))
    elif "e" not in ct and "xi" not in ct and model in ("jankowski", "kelvin"):
        errors.append(InputError(f"the {model!r} law needs xi or e", file=file, key="contact.xi"))
    if model == "hertzdamp" and "e" not in ct:
        errors.append(InputError("the 'hertzdamp' law needs e", file=file, key="contact.e"))
    if "e" in v:
        # the damping the kernels run with (NaN for hertzdamp: set per impact from e and the
        # impact velocity; 0 for laws without damping)
        v["relation"] = v.get("relation") or schema.default_relation(model)
        try:
            v["xi"] = float(reported_xi(model, v["e"], v["relation"]))
        except InputError as exc:
            key = exc.key or "relation"  # relations name their own argument ("e", "relation")
            key = key if key.startswith("contact.") else f"contact.{key}"
            errors.append(InputError(exc.message, file=file, key=key))
    elif "relation" in ct:
        v.pop("relation", None)  # without e the relation says nothing
    return _contact_gaps(v, n_contacts, file, errors)


def _contact_gaps(v: dict, n_contacts: int | None, file, errors: list) -> dict:
    """``contact.gap_m`` as one gap per contact."""
    if "gap_m" in v and n_contacts is not None:
        gaps = np.atleast_1d(np.asarray(v["gap_m"], dtype=float))
        if gaps.size == 1:
            gaps = np.full(n_contacts, gaps[0])
        elif gaps.size != n_contacts:
            errors.append(
                InputError(f"gives {gaps.size} gaps for {n_contacts} contacts", file=file,
                           key="contact.gap_m")
            )  # fmt: skip
        v["gap_m"] = gaps
    return v


def scene_from_dict(data: dict, *, file: str | Path | None = None) -> Scene:
    """Validate a scene (the parsed TOML tables) against :mod:`pound_mc.scene.schema`.

    Every table is checked, and every problem reported at once.  A record's source must exist
    (a file, a built-in record, a synthetic model); it is read when the scene is simulated.

    Raises
    ------
    InputError
        Naming the file and the key of the problem (:class:`~pound_mc.errors.InputErrors`
        when there are several).
    """
    file_s = None if file is None else str(file)
    base_dir = None if file is None else Path(file).parent
    errors: list[InputError] = []
    extra = sorted(set(data) - set(schema.SCENE_TABLES) - _STUDY_TABLES - {ROW_TABLE})
    for key in extra:
        errors.append(
            InputError(f"unknown table; allowed: {', '.join(schema.SCENE_TABLES)}", file=file_s,
                       key=key)
        )  # fmt: skip
    is_row = ROW_TABLE in data
    if is_row:
        row_specs = data[ROW_TABLE]
        if not (isinstance(row_specs, list) and len(row_specs) >= 2
                and all(isinstance(b, dict) for b in row_specs)):  # fmt: skip
            errors.append(InputError("must be two or more [[buildings]] tables, left to right",
                                     file=file_s, key=ROW_TABLE))  # fmt: skip
        for table in ("left", "right"):
            if table in data:
                errors.append(InputError(f"give [{table}] or [[buildings]], not both",
                                         file=file_s, key=table))  # fmt: skip
    for table in ("record",) if is_row else ("record", "left", "right"):
        if not isinstance(data.get(table), dict):
            errors.append(InputError("is required (a table)", file=file_s, key=table))
    for table in ("contact", "integrator"):
        if table in data and not isinstance(data[table], dict):
            errors.append(
                InputError(f"must be a table, got {data[table]!r}", file=file_s, key=table)
            )
    if errors:
        schema.raise_all(errors)
    record = dict(data["record"])
    checked = schema.check_table(schema.RECORD, record, file=file_s, prefix="record.",
                                 errors=errors)  # fmt: skip
    if "source" in checked:
        problem = schema.source_problem(checked["source"], base_dir)
        if problem is not None:
            errors.append(InputError(problem, file=file_s, key="record.source"))
    level = data.get("contact", {}).get("level_tolerance_m", 0.0)
    level = level if isinstance(level, int | float) and level >= 0 else 0.0
    row = None
    if is_row:
        row = [_building(b, f"{ROW_TABLE}[{k}]", file_s, errors, wall_ok=k == len(row_specs) - 1)
               for k, b in enumerate(row_specs)]  # fmt: skip
        left, right = row[0], row[-1]
    else:
        left = _building(data["left"], "left", file_s, errors)
        right = _building(data["right"], "right", file_s, errors)
    contacts = None
    if row is not None and all(b is not None for b in row):
        contacts = []
        for k in range(len(row) - 1):
            try:
                pair = contacts_between(row[k], row[k + 1], file=file_s, level_tolerance_m=level)
                contacts += [replace(c, pair=k) for c in pair]
            except InputError as exc:  # "left.height_m" is building k's, "right..." k + 1's
                side, _, rest = (exc.key or "").partition(".")
                at = {"left": k, "right": k + 1}.get(side)
                key = f"{ROW_TABLE}[{k + 1}]" if at is None else f"{ROW_TABLE}[{at}].{rest}"
                errors.append(InputError(exc.message, file=file_s, key=key))
    elif row is None and left is not None and right is not None:
        try:
            contacts = contacts_between(left, right, file=file_s, level_tolerance_m=level)
        except InputError as exc:
            errors.append(exc)
    ct = _contact(dict(data.get("contact", {})), None if contacts is None else len(contacts),
                  file_s, errors)  # fmt: skip
    it = schema.check_table(schema.INTEGRATOR, dict(data.get("integrator", {})), file=file_s,
                            prefix="integrator.", errors=errors)  # fmt: skip
    schema.raise_all(errors)
    return Scene(
        record=record,
        left=left,
        right=right,
        contacts=contacts,
        gap_m=ct["gap_m"],
        contact_model=ct["model"],
        stiffness=float(ct["stiffness"]),
        xi=None if ct.get("xi") is None else float(ct["xi"]),
        e=None if ct.get("e") is None else float(ct["e"]),
        relation=ct.get("relation"),
        method=it["method"],
        dt_s=float(it["dt_s"]),
        substeps=it["substeps"],
        tail_s=float(it["tail_s"]),
        accuracy_check=bool(it["accuracy_check"]),
        restitution=ct.get("restitution", "fixed"),
        material=ct.get("material"),
        e_quantile=None if ct.get("e_quantile") is None else float(ct["e_quantile"]),
        outside=ct.get("outside", "clamp"),
        row=row,
        file=file_s,
        base_dir=base_dir,
    )


def load_scene(path: str | Path) -> Scene:
    """Read and validate a scene file (TOML)."""
    path = Path(path)
    data = parse_toml(read_text_file(path, "scene file"), str(path))
    return scene_from_dict(data, file=path)


def _same_record(cached: dict, record: dict) -> bool:
    """Whether ``record`` still equals the cached copy of the record table."""
    try:
        return bool(cached == record)
    except ValueError:  # values without a truth value of their equality (arrays)
        return False
