"""One deterministic simulation: the scene tables (:mod:`.schema`) and the model (:mod:`.model`).

``from pound_mc.scene import load_scene, simulate, scene_from_dict, Scene`` is the public way
in; :mod:`pound_mc.scene.schema` declares every key of a scene file.
"""

from pound_mc.scene.model import Scene, SimulationResult, load_scene, scene_from_dict, simulate

__all__ = ["Scene", "SimulationResult", "scene_from_dict", "load_scene", "simulate"]
