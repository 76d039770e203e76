"""One deterministic simulation: the scene tables, the model and its run.

:mod:`.schema` declares the tables, :mod:`.model` validates them into a :class:`Scene`,
:mod:`.simulation` runs it.

``from pound_mc.scene import load_scene, simulate, scene_from_dict, Scene`` is the public way
in; :mod:`pound_mc.scene.schema` declares every key of a scene file.
"""

from pound_mc.scene.model import Scene, load_scene, scene_from_dict
from pound_mc.scene.simulation import SimulationResult, simulate

__all__ = ["Scene", "SimulationResult", "scene_from_dict", "load_scene", "simulate"]
