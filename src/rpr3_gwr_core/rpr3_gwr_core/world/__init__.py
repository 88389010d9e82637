"""The world around a mechanism: its bodies, a scene of obstacles and
limits, the collision kernel, and the roadmap restricted to a scene.

Names are loaded on first use (PEP 562): :mod:`.collision` imports the
mechanisms' continuation, which a process reading a body model alone does
not need.
"""

from ..lazy import lazy_exports

_SOURCES = {
    ".bodies": ("Bodies", "BodyModel", "assemble_bodies", "body_model_from_dict",
                "mechanism_bodies"),
    ".collision": ("Collision", "SceneArrays", "check_bodies", "compile_scene",
                   "configuration_collision", "path_collisions"),
    ".scene": ("EMPTY_SCENE", "DiscObstacle", "Limits", "PolygonObstacle", "Scene",
               "scene_from_dict"),
    ".scene_roadmap": ("SceneFeasibility", "SceneRoadmap", "WorldIndex", "scene_roadmap"),
}
_SOURCE_OF = {name: module for module, names in _SOURCES.items() for name in names}

__all__ = [name for names in _SOURCES.values() for name in names]


__getattr__, __dir__ = lazy_exports(__name__, globals(), _SOURCE_OF)
