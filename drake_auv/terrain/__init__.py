"""Bathymetric grids and structure meshes: readers, synthetic sites, slope and classification."""

from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.slope import TerrainLabels, classify, slope_map

__all__ = ["Bathymetry", "TerrainLabels", "classify", "read_bathymetry", "slope_map"]
