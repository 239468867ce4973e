"""Sensing: the pressure array (nodes, cells, sampling a base pressure) and the capacitive node model; may import
nothing else of controller."""

from .capacitive import CapacitiveNode
from .sensor import (Interpolation, PressureField, SensorArray, capacitive_array, cell_force_operator,
                     resample_time_series, sample)

__all__ = ["CapacitiveNode", "Interpolation", "PressureField", "SensorArray", "capacitive_array",
           "cell_force_operator", "resample_time_series", "sample"]
