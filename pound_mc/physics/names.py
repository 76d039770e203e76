"""Names of the physics registries, importable without their implementations.

The command line offers them as choices and in its help, and ``pound-mc --help`` imports
neither scipy nor numba, which the implementations need; the tests hold each registry to its
names here.
"""

from __future__ import annotations

__all__ = ["RELATION_NAMES"]

#: Names of the xi-e relations of :data:`pound_mc.physics.relations.RELATIONS`, in its order.
RELATION_NAMES = ("jankowski2008", "jankowski2006", "exact", "kelvin")
