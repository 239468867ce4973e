"""Sensing: the pressure array (nodes, cells, sampling a base pressure), the capacitive node model and the bench
record a sensor bench hands over; may import nothing else of controller."""

from .bench_record import BenchRecord
from .capacitive import CapacitiveNode, NodeRealization
from .sensor import (Interpolation, PressureField, SensorArray, capacitive_array, cell_force_operator,
                     resample_time_series, sample)

__all__ = ["BenchRecord", "CapacitiveNode", "NodeRealization", "Interpolation", "PressureField", "SensorArray",
           "capacitive_array", "cell_force_operator", "resample_time_series", "sample"]
