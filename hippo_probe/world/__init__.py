"""The simulated world: arenas, the rat's motion, its senses and their noise."""

from .arena import (Arena, contains, inward_normals, polygon_area, random_arena,
                    random_vertices, regular_polygon, sample_uniform, wall_distance)
from .config import FEATURES, ArenaConfig, MotionConfig, NoiseModel, SensorConfig, WorldConfig
from .motion import simulate_motion
from .sensors import sense, wrap_angle

__all__ = [
    "Arena", "ArenaConfig", "FEATURES", "MotionConfig", "NoiseModel", "SensorConfig",
    "WorldConfig", "contains", "inward_normals", "polygon_area", "random_arena",
    "random_vertices", "regular_polygon", "sample_uniform", "sense", "simulate_motion",
    "wall_distance", "wrap_angle",
]
