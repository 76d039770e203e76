"""How a dataset's dimensions and values are named when a chart or a summary holds them.

The charts' ``sel``, the accessor's keyword coordinates and ``pound-mc plot --sel/--line/--by``
take a dimension by its name (``left_period_s``) or by the study file's key
(``left.period_s``), and the material axis by the materials' names (``"steel"``) as well as
its coordinate values; a material the axis does not hold is refused, never the nearest.
"""

from __future__ import annotations

import numpy as np

from pound_mc.study.definition import grid_dim_name

__all__ = ["MATERIAL_DIM", "dim_name", "material_names", "no_value_message", "selection"]

#: Dimension of the material grid axis (values: indices; variable ``material``: the names).
MATERIAL_DIM = "contact_material"


def dim_name(ds, key: str) -> str:
    """The dimension ``key`` names: itself, or the study file's key of one.

    ``left.period_s`` names ``left_period_s``; anything else is returned as it is.
    """
    return key if key in ds.dims or grid_dim_name(key) not in ds.dims else grid_dim_name(key)


def selection(ds, sel: dict | None) -> dict:
    """``sel`` with the study file's keys named as dimensions and materials by name.

    ``{"left.period_s": 0.6}`` holds ``left_period_s``; on the material axis
    (:data:`MATERIAL_DIM`) a name (``"steel"``) stands for its coordinate value.  Anything
    else is passed on as given.
    """
    out = {}
    for key, value in (sel or {}).items():
        dim = dim_name(ds, key)
        if dim == MATERIAL_DIM and "material" in ds:
            many = np.ndim(value) > 0 and not isinstance(value, str)
            picked = [_material_value(ds, v) for v in (value if many else [value])]
            value = picked if many else picked[0]
        out[dim] = value
    return out


def _material_value(ds, value):
    """The material axis' coordinate for a material's name or number (one on the axis)."""
    if isinstance(value, str):
        names = material_names(ds)
        if value not in names:
            raise ValueError(no_value_message("material", value, names))
        return ds[MATERIAL_DIM].values[names.index(value)]
    if not np.any(ds[MATERIAL_DIM].values == value):  # a number on the axis, or refused
        raise ValueError(no_value_message(MATERIAL_DIM, value, material_names(ds)))
    return value


def material_names(ds) -> list[str]:
    """Names of the materials along :data:`MATERIAL_DIM`, in its order."""
    return [str(n) for n in np.atleast_1d(ds["material"].values)]


def no_value_message(dim: str, value, coord) -> str:
    """``dim has no value ...; it has`` its first six values as text, and how many in all."""
    names = [str(c) for c in coord]
    more = f", ... ({len(names)} in all)" if len(names) > 6 else ""
    shown = value.item() if isinstance(value, np.generic) else value  # 1.0, not np.float64(1.0)
    return f"{dim} has no value {shown!r}; it has {', '.join(names[:6])}{more}"
