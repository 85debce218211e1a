"""The simulated world: arenas, the rat's motion, its senses and their noise, in two named
worlds (``"darkness"``, the study's, and ``"compass"``)."""

from .arena import (Arena, contains, inward_normals, polygon_area, random_arena,
                    random_vertices, regular_polygon, sample_uniform, wall_distance)
from .config import (FEATURES, WORLDS, ArenaConfig, MotionConfig, NoiseModel, SensorConfig,
                     WorldConfig, world_config)
from .motion import simulate_motion
from .sensors import heading_drift, sense, wrap_angle

__all__ = [
    "Arena", "ArenaConfig", "FEATURES", "MotionConfig", "NoiseModel", "SensorConfig",
    "WORLDS", "WorldConfig", "contains", "heading_drift", "inward_normals", "polygon_area",
    "random_arena", "random_vertices", "regular_polygon", "sample_uniform", "sense",
    "simulate_motion",
    "wall_distance", "world_config", "wrap_angle",
]
