"""Small study files shared by the tests: one base study per shape, overridden table by table.

``study_text(SMALL_SDOF, study={"name": "tiny"}, grid={"contact.gap_m": None})`` is the text
of the base study with ``[study] name`` replaced and the ``contact.gap_m`` grid axis removed.
Each keyword names a top-level table; its dict is merged one level deep into the base table
(a key set to ``None`` is removed), or replaces it in full when wrapped in ``Whole``;
``table=None`` removes the whole table and a list of dicts writes an array of tables
(``record=None, records=[{...}, {...}]``: a new table takes the place of the one removed).
The text is laid out as a person writes it (tables in order, ``1.0e6`` rather than
``1000000.0``, sub-tables such as ``[sampling.vary]`` right after their table), so tests may
edit it with ``str.replace``.

The ``make_study`` and ``make_shear_study`` fixtures of ``conftest.py`` write these texts to
``tmp_path``; module-scoped fixtures call ``write_study`` with their own directory.
``counted_dataset`` builds the reduced result datasets of the fragility and required-gap tests.
"""

import copy
import json
import math
import re
from pathlib import Path

import numpy as np
import xarray as xr

# Two SDOF buildings (T = 0.5 s and 1.0 s, 5 % damping, 1,000 t) on the first 4 s of the
# built-in El Centro record (its strong motion, peak at 2.2 s) scaled to 0.3 g,
# concrete-on-concrete Jankowski contact; 3 x 2 x 8 = 48 simulations, each a fraction of a
# second.  (The first 4 s of K-NET AKT013 are pre-event noise, 1 % of its peak.)
SMALL_SDOF = {
    "study": {"name": "small", "seed": 11},
    "record": {"source": "builtin:elcentro", "duration_s": 4.0, "pga_g": 0.3},
    "left": {"model": "sdof", "period_s": 0.5, "damping_ratio": 0.05, "mass_kg": 1.0e6},
    "right": {"model": "sdof", "period_s": 1.0, "damping_ratio": 0.05, "mass_kg": 1.0e6},
    "contact": {"model": "jankowski", "gap_m": 0.002, "beta": 2.75e9, "e": 0.65},
    "integrator": {"method": "adaptive", "dt_s": 0.01},
    "grid": {"left.period_s": [0.3, 0.5, 0.7], "contact.gap_m": [0.0, 0.002]},
    "sampling": {
        "n": 8,
        "method": "sobol",
        "vary": {
            "contact.e": {"material": "concrete"},
            "contact.beta": {"material": "concrete"},
        },
    },
}

# Shear buildings of three and five storeys (3 m each, 1,000 t a floor, 5 % damping).
SHEAR_3 = {
    "model": "shear",
    "storey_mass_kg": [1.0e6, 1.0e6, 1.0e6],
    "storey_stiffness_N_per_m": [1.2e9, 1.0e9, 0.8e9],
    "storey_height_m": [3.0, 3.0, 3.0],
    "damping_ratio": 0.05,
}
SHEAR_5 = {
    "model": "shear",
    "storey_mass_kg": [1.0e6] * 5,
    "storey_stiffness_N_per_m": [0.9e9, 0.8e9, 0.7e9, 0.6e9, 0.5e9],
    "storey_height_m": [3.0] * 5,
    "damping_ratio": 0.05,
}

# The 3-storey and the 5-storey building on 4.5 s of El Centro 1940 scaled to 0.5 g; three
# contacts (floors 1-3), 2 gaps x 4 samples.
SMALL_SHEAR = {
    "study": {"name": "shear_small", "seed": 11},
    "record": {"source": "builtin:elcentro", "duration_s": 4.5, "pga_g": 0.5},
    "left": SHEAR_3,
    "right": SHEAR_5,
    "contact": {
        "model": "jankowski",
        "gap_m": 0.01,
        "beta": 2.75e9,
        "e": 0.65,
        "relation": "jankowski2008",
    },
    "integrator": {"method": "adaptive", "dt_s": 0.01},
    "grid": {"contact.gap_m": [0.0, 0.01]},
    "sampling": {
        "n": 4,
        "method": "sobol",
        "vary": {
            "contact.e": {"material": "concrete"},
            "contact.beta": {"material": "concrete"},
        },
    },
}


class Whole(dict):
    """A table that replaces the base table in full (its keys in this order), not merged."""


def study_data(base: dict, **tables) -> dict:
    """The base study with each keyword's table merged in (see the module docstring)."""
    items = list(copy.deepcopy(base).items())
    free = None  # where a removed table stood: the next new table takes its place
    for name, table in tables.items():
        names = [n for n, _ in items]
        if table is None:
            if name in names:
                free = names.index(name)
                del items[free]
        elif name in names and isinstance(table, dict) and not isinstance(table, Whole):
            merged = items[names.index(name)][1]
            for key, value in table.items():
                if value is None:
                    merged.pop(key, None)
                else:
                    merged[key] = copy.deepcopy(value)
        elif name in names:
            items[names.index(name)] = (name, copy.deepcopy(dict(table)))
        else:
            new = (name, copy.deepcopy(table if isinstance(table, list) else dict(table)))
            items.insert(len(items) if free is None else free, new)
            free = None
    return dict(items)


def study_text(base: dict = SMALL_SDOF, **tables) -> str:
    """TOML text of ``study_data(base, **tables)``."""
    return dump_toml(study_data(base, **tables))


def write_study(directory: Path, base: dict = SMALL_SDOF, **tables) -> Path:
    """Write the study to ``directory / "<study name>.toml"`` and return that path."""
    text = study_text(base, **tables)
    path = Path(directory) / f"{study_data(base, **tables)['study']['name']}.toml"
    path.write_text(text)
    return path


def _float(x: float) -> str:
    """``1.0e6`` and ``2.75e9`` for large and tiny magnitudes, ``repr`` otherwise."""
    if not math.isfinite(x):
        return "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
    if x == 0 or 1e-4 <= abs(x) < 1e5:
        return repr(x)
    exponent = math.floor(math.log10(abs(x)))
    short = f"{x / 10.0**exponent!r}e{exponent}"
    return short if float(short) == x else repr(x)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return _float(value)
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a TOML basic string
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_value(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _table(name: str, table: dict, array: bool = False) -> list[str]:
    """Lines of one table: its keys, then its tables of tables as ``[name.key]``."""
    lines = [f"[[{_key(name)}]]" if array else f"[{_key(name)}]"]
    subtables = {}
    for key, value in table.items():
        if isinstance(value, dict) and value and all(isinstance(v, dict) for v in value.values()):
            subtables[key] = value
        else:
            lines.append(f"{_key(key)} = {_value(value)}")
    for key, sub in subtables.items():
        lines.append(f"[{_key(name)}.{_key(key)}]")
        lines.extend(f"{_key(k)} = {_value(v)}" for k, v in sub.items())
    return lines


def dump_toml(data: dict) -> str:
    """TOML text of a study dict: tables (or arrays of tables) separated by blank lines."""
    blocks = []
    for name, table in data.items():
        if isinstance(table, list):
            blocks.extend("\n".join(_table(name, t, array=True)) for t in table)
        else:
            blocks.append("\n".join(_table(name, table)))
    return "\n\n".join(blocks) + "\n"


def counted_dataset(counts, pga, gaps, n: int, pga_attrs: dict, attrs=None):
    """A study dataset reduced to what the fragility and the required gap read.

    ``n`` records x 1 sample on a ``(pga_g, contact_gap_m)`` grid; the first
    ``counts[pga, gap]`` records pound (one impact of 1 MN), the others do not; every status ok.
    """
    counts = np.asarray(counts)
    impacts = (np.arange(n)[:, None, None, None] < counts[None, :, :, None]).astype(np.int64)
    dims = ("record", "pga_g", "contact_gap_m", "sample")
    return xr.Dataset(
        {
            "impacts": (dims, impacts),
            "peak_force": (dims, impacts * 1e6),
            "status": (dims, np.zeros_like(impacts)),
        },
        coords={
            "pga_g": ("pga_g", pga, pga_attrs),
            "contact_gap_m": ("contact_gap_m", gaps, {"units": "m", "long_name": "gap"}),
        },
        attrs=attrs or {},
    )


# Run statuses (DESIGN.md section 4; pound_mc.integrators.outputs and .accuracy): 0 ok,
# 1 unstable, 2 not converged, 3 inaccurate (stable, a contact under-resolved: the peak force is
# in doubt, not that the run pounded).  A pounding count takes 0 and 3 and leaves 1 and 2 out; a
# peak-force or ductility summary takes 0 alone.  Written out here, not imported, so that a
# change of what the code counts fails the tests that count by hand.
POUNDING_STATUSES = (0, 3)
STATUS_UNSTABLE, STATUS_INACCURATE = 1, 3


def pounding_counted(ds: xr.Dataset) -> xr.DataArray:
    """Where a run counts for the pounding probability, fragility and required gap."""
    return ds["status"].isin(POUNDING_STATUSES)


def with_flagged_runs(ds: xr.Dataset) -> xr.Dataset:
    """``ds`` with every third pounding run flagged inaccurate and every fifth run unstable.

    The flagged runs keep their numbers (as the engine keeps them); an unstable run keeps its
    impacts too, so a count that took it would be off.  Raises where the dataset has nothing
    to flag (a check that could not fail would prove nothing).
    """
    status = ds["status"].values.copy()
    flat = status.reshape(-1)
    pounded = np.flatnonzero((ds["impacts"].values.reshape(-1) > 0) & (flat == 0))
    flat[pounded[::3]] = STATUS_INACCURATE
    flat[np.arange(4, flat.size, 5)] = STATUS_UNSTABLE
    if not (flat == STATUS_INACCURATE).any():
        raise ValueError("no pounding run to flag")
    return ds.assign(status=(ds["status"].dims, status, ds["status"].attrs))
