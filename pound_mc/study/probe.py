"""A study's varied values against the scene: every grid value and sampled value must be valid.

:func:`probe` checks each varied key's values against the key's declared bounds (a
distribution that draws values outside them is reported once, on its own key), then every
record's scene as written, then each varied key at its smallest and largest value, the
others at the study's first simulation.  :func:`fixed_partner` refuses a varied damping ratio
that would silently drop the restitution coefficient the scene gives.
"""

from __future__ import annotations

from pound_mc.errors import InputError, InputErrors
from pound_mc.scene import scene_from_dict
from pound_mc.scene.schema import BUILDINGS, CONTACT, INTEGRATOR, Field
from pound_mc.study.schema import INTENSITY_KEYS, MATERIAL_KEY, ROW_KEY, ROW_TABLE

__all__ = ["EXCLUSIVE", "probe", "fixed_partner"]

# Keys that replace each other: varying e drops a fixed xi from the scene and vice versa.
EXCLUSIVE = {"contact.e": "contact.xi", "contact.xi": "contact.e"}


def _scene_errors(data: dict, file) -> list[InputError]:
    """Problems :func:`pound_mc.scene.scene_from_dict` finds in scene tables."""
    try:
        scene_from_dict(data, file=file)
    except InputErrors as exc:
        return list(exc.errors)
    except InputError as exc:
        return [exc]
    return []


def _field(scene: dict, key: str) -> Field | None:
    """The declaration of a varied scene key (``"left.period_s"``), or None if unknown."""
    table, name = key.split(".", 1)
    row = ROW_KEY.match(key)
    if row is not None:  # "buildings.N.KEY": building N of the row
        buildings = scene.get(ROW_TABLE)
        n, name = int(row[1]), row[2]
        spec = buildings[n] if isinstance(buildings, list) and n < len(buildings) else None
        model = spec.get("model", "sdof") if isinstance(spec, dict) else "sdof"
        declared = BUILDINGS.get(model) if isinstance(model, str) else None
    elif table in ("left", "right"):
        spec = scene.get(table)
        model = spec.get("model", "sdof") if isinstance(spec, dict) else "sdof"
        declared = BUILDINGS.get(model) if isinstance(model, str) else None
    else:
        declared = {"contact": CONTACT, "integrator": INTEGRATOR}.get(table)
    return declared[name] if declared is not None and name in declared.keys else None


def _out_of_bounds(study, ranges: list, file, errors: list) -> set[str]:
    """Varied values outside their key's bounds; the keys that have them.

    A grid axis names each end value that is out; a sampled key is reported once, as its
    distribution's: the same draws meet every grid point.
    """
    sources = {v.key: v.source for v in study.variables}
    bad = set()
    for where, key, values in ranges:
        declared = _field(study.scene, key)
        ends = dict.fromkeys((float(values.min()), float(values.max())))
        problems = [(v, declared.problem(v)) for v in ends] if declared is not None else []
        problems = [(v, p) for v, p in problems if p is not None]
        if problems and where.startswith("sampling."):
            errors.append(InputError(f"{sources.get(key, 'the distribution')} draws values "
                                     f"outside the key's bounds: {problems[0][1]}", file=file,
                                     key=where))  # fmt: skip
        else:
            errors += [InputError(f"value {v:g}: {p}", file=file, key=where) for v, p in problems]
        bad.update([key] if problems else [])
    return bad


def probe(study, prefixes: list[str], file, errors: list) -> None:
    """Every record's scene, and every grid value and sampled value, must make a valid scene.

    Each varied key's values are first held against its declared bounds.  The scene as
    written is checked once per record, a key that only a grid axis or a sampled variable
    gives taking its value at the study's first simulation; then each varied key at its
    smallest and largest value, the others at the first simulation's.
    """
    draws = study.draw() if study.variables else {}
    first = {
        key: float(value)
        for key, value in study.values_at((0,) * (len(study.grid) + 2), draws).items()
        if key not in INTENSITY_KEYS  # not scene keys: they scale the record (see _intensity)
    }
    found = len(errors)
    ranges = [
        (f"grid.{k}", k, v)
        for k, v in study.grid.items()
        if k != MATERIAL_KEY and k not in INTENSITY_KEYS
    ]
    ranges += [(f"sampling.vary.{k}", k, v) for k, v in draws.items()]
    bad = _out_of_bounds(study, ranges, file, errors)
    for i in range(len(study.records)):
        scene = study.scene_dict(i)
        for key, value in first.items():
            table, leaf = key.split(".", 1)
            partner = EXCLUSIVE.get(key, "").partition(".")[2]
            row = ROW_KEY.match(key)
            if row is not None:  # building N of a row (a study's own check names a bad N)
                leaf = row[2]
                present = scene[ROW_TABLE][int(row[1])]
            else:
                present = scene.setdefault(table, {})
            if leaf not in present and partner not in present and key not in bad:
                present[leaf] = value
        for err in _scene_errors(scene, file):
            key = err.key or ""
            if key in bad:
                continue  # a key only a varied value gives, reported above
            if key.startswith("record") and prefixes[i]:
                key = prefixes[i] + key.split(".", 1)[-1] if "." in key else prefixes[i][:-1]
            elif i > 0:
                continue  # scene problems are reported once, with the first record
            errors.append(InputError(err.message, file=file, key=key or None))
    if len(errors) > found or not study.records:
        return  # the scene itself is wrong: its varied values would repeat the problem
    for where, key, values in ranges:
        for value in dict.fromkeys((float(values.min()), float(values.max()))):
            overrides = {**first, key: value}
            for err in _scene_errors(study.scene_dict(0, overrides), file)[:1]:
                errors.append(InputError(f"value {value:g}: {err.message}", file=file, key=where))


def fixed_partner(scene: dict, grid: dict, variables: list, file, errors: list) -> None:
    """A varied ``contact.xi`` with ``e`` in ``[contact]``: refused, as a scene refuses both.

    Varying xi would drop the scene's e without a word.  (A varied ``contact.e`` replaces a
    fixed ``xi``: the restitution coefficient sampled from a material's measured range, as
    in DESIGN.md's example study.)
    """
    contact = scene.get("contact")
    if not isinstance(contact, dict) or "e" not in contact:
        return
    varied = [f"grid.{k}" for k in grid] + [f"sampling.vary.{v.key}" for v in variables]
    for where in varied:
        if where.endswith(".contact.xi"):
            errors.append(InputError(f"varies contact.xi while [contact] gives e = "
                                     f"{contact['e']!r} (contact.e): give either xi or e, not "
                                     "both; remove e from [contact]", file=file,
                                     key=where))  # fmt: skip
