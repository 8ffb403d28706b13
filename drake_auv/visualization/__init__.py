"""Meshcat scene, vehicle visualiser and standalone HTML recording."""

from drake_auv.visualization.scene import Scene, VehicleVisualizer

__all__ = ["Scene", "VehicleVisualizer"]
