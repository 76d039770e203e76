"""How charts and reports name a dataset's dimensions and values: as people write them.

One place decides how a coordinate reads in a title, a legend or a line of text:
``coord_text(ds, "contact_gap_m", 0)`` is ``"gap 20 mm"`` (not ``"contact_gap_m = 0.02"``),
``coord_text(ds, "sa_g", 1)`` is ``"Sa(T = 1.0 s) 0.2 g"``, a material axis gives the
material's name, and text stored as bytes is decoded.  Units are the charts' (lengths in mm,
forces in MN, intensities in g: :data:`UNITS`).  No matplotlib here: the command line's text
output uses it too.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__ = [
    "UNITS",
    "chart_units",
    "name_and_units",
    "intensity_name",
    "dim_text",
    "key_text",
    "value_text",
    "coord_text",
    "coords_text",
    "text_of",
]

#: Chart units of a dataset's units: ``{dataset units: (chart units, factor)}``.
UNITS = {"m": ("mm", 1e3), "N": ("MN", 1e-6), "N s": ("kN s", 1e-3), "J": ("kJ", 1e-3)}

#: Short names of the study keys a grid varies, by the key's last part (``"left.period_s"``
#: reads ``"left period"``).  A key not listed reads as its dataset ``long_name``.
SHORT_NAMES = {
    "gap_m": "gap",
    "period_s": "period",
    "damping_ratio": "damping ratio",
    "mass_kg": "mass",
    "height_m": "height",
    "yield_disp_m": "yield displacement",
    "post_yield_ratio": "post-yield ratio",
    "storey_mass_kg": "storey mass",
    "storey_stiffness_N_per_m": "storey stiffness",
    "storey_yield_disp_m": "storey yield drift",
    "e": "e",
    "e_quantile": "e quantile",
    "beta": "beta",
    "xi": "xi",
    "k_N_per_m": "k",
    "material": "material",
    "dt_s": "dt",
    "duration_s": "duration",
    "substeps": "substeps",
}
#: Dimensions that are not study keys, by name.
_DIM_NAMES = {
    "record": "record",
    "sample": "sample",
    "contact": "contact",
    "building": "building",
    "storey": "storey",
    "contact_material": "material",
    "contact_gap_m": "gap",
}
#: Intensity axes (``record.pga_g``, ``record.sa_g``) and how people write them.
_INTENSITY = {"pga_g": "PGA", "sa_g": "Sa"}


def text_of(value) -> str:
    """``value`` as text: bytes and numpy byte strings decoded, everything else ``str``."""
    if isinstance(value, bytes | np.bytes_):
        return bytes(value).decode("utf-8", errors="replace")
    return str(value)


def chart_units(units: str | None) -> tuple[str, float]:
    """Units a chart draws a quantity stored in ``units`` in, and the factor to them."""
    units = (units or "").strip()
    if units in UNITS:
        return UNITS[units]
    return ("-" if units in ("", "1") else units), 1.0


def name_and_units(attrs: dict, fallback: str) -> tuple[str, str]:
    """``(long_name, units)`` of a variable's attributes; a multiple of g says ``"g"``."""
    name = str(attrs.get("long_name", fallback))
    units = str(attrs.get("units", ""))
    if name.endswith(" in units of g"):  # dimensionless multiples of g: say [g] once
        return name[: -len(" in units of g")], "g"
    return name, units


def _period_text(period: float) -> str:
    """A period [s] as people write it: ``1.0``, ``0.5``, ``0.25``."""
    text = f"{period:g}"
    return text if ("." in text or "e" in text) else f"{text}.0"


def intensity_name(ds: xr.Dataset, dim: str) -> str:
    """``"PGA"``, or ``"Sa(T = 1.0 s)"`` with the period of the records' Sa.

    The period is ``record_sa_period_s`` of the dataset (one per record); records with
    different periods list them (``"Sa(T = 0.5, 1.0 s)"``), and a dataset without it says
    ``"Sa"``.
    """
    name = _INTENSITY[dim]
    if dim != "sa_g" or "record_sa_period_s" not in ds:
        return name
    periods = np.asarray(ds["record_sa_period_s"].values, dtype=float).ravel()
    periods = np.unique(periods[np.isfinite(periods)])
    if not periods.size:
        return name
    return f"{name}(T = {', '.join(_period_text(p) for p in periods)} s)"


def dim_text(ds: xr.Dataset, dim: str) -> str:
    """The short name of dimension ``dim``: ``"gap"``, ``"left period"``, ``"PGA"``.

    Study keys by their last part (:data:`SHORT_NAMES`), with the building they belong to
    (``"left"``, ``"right"``, ``"building 1"``); the intensity axes as
    :func:`intensity_name`; other dimensions by their ``long_name``.
    """
    if dim in _INTENSITY:
        return intensity_name(ds, dim)
    if dim in _DIM_NAMES:
        return _DIM_NAMES[dim]
    attrs = ds[dim].attrs if dim in ds.variables else {}
    key = str(attrs.get("scene_key", ""))
    if not key:  # a dataset made by hand: the key its name was made from, where it is plain
        table, _, name = dim.partition("_")
        key = f"{table}.{name}" if table in ("left", "right") and name in SHORT_NAMES else ""
    return key_text(key) if key else str(attrs.get("long_name", dim))


def key_text(key: str) -> str:
    """A study key as people write it: ``"left.period_s"`` reads ``"left period"``.

    By the key's last part (:data:`SHORT_NAMES`), with the building it belongs to; a key
    not listed reads as itself.
    """
    parts = key.split(".")
    short = SHORT_NAMES.get(parts[-1])
    if short is None:
        return key
    if parts[0] in ("left", "right"):
        return f"{parts[0]} {short}"
    if parts[0] == "buildings" and len(parts) == 3:
        return f"building {parts[1]} {short}"
    return short


def value_text(ds: xr.Dataset, dim: str, i: int) -> str:
    """The ``i``-th value of coordinate ``dim`` as text, in chart units (``"10 mm"``).

    A material axis (``contact_material`` with a ``material`` variable of names) gives the name;
    text stored as bytes is decoded; a yield displacement at which no run of the building
    yields says so (a study's elastic variant, e.g. ``left.yield_disp_m = 1000``:
    "1e+06 mm (never yields)").
    """
    if dim == "contact_material" and "material" in ds and ds["material"].dims == (dim,):
        return text_of(ds["material"].values[i])
    value = ds[dim].values[i]
    if not isinstance(value, float | np.floating | int | np.integer):
        return text_of(value)
    _, units = name_and_units(ds[dim].attrs, dim)
    shown, factor = chart_units(units)
    text = f"{float(value) * factor:.4g}" + ("" if shown == "-" else f" {shown}")
    side = dim.removesuffix("_yield_disp_m")
    ductility = ds.get(f"peak_ductility_{side}") if side != dim else None
    if ductility is not None and dim in ductility.dims:
        if not bool((ductility.isel({dim: i}) > 1.0).any()):
            text += " (never yields)"
    return text


def coord_text(ds: xr.Dataset, dim: str, i: int) -> str:
    """Dimension ``dim`` at index ``i`` as people write it: ``"gap 20 mm"``, ``"PGA 0.2 g"``."""
    return f"{dim_text(ds, dim)} {value_text(ds, dim, i)}"


def coords_text(ds: xr.Dataset, where: dict) -> str:
    """``{dim: index}`` as text: ``"gap 20 mm, PGA 0.2 g"`` (empty for none)."""
    return ", ".join(coord_text(ds, d, int(i)) for d, i in where.items())
