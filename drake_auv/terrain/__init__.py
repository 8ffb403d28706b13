"""Bathymetric grids and structure meshes: readers, synthetic sites, slope and classification."""

from drake_auv.terrain.bathymetry import Bathymetry

__all__ = ["Bathymetry"]
