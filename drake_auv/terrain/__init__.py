"""Bathymetric grids and structure meshes: readers, synthetic sites, slope and classification.

`Bathymetry` is imported eagerly; the rest loads on first use.
"""

from drake_auv.terrain.bathymetry import Bathymetry

_LAZY = {
    "read_bathymetry": "drake_auv.terrain.readers",
    "TerrainLabels": "drake_auv.terrain.slope",
    "classify": "drake_auv.terrain.slope",
    "slope_map": "drake_auv.terrain.slope",
    "caldera_site": "drake_auv.terrain.synthetic",
}

__all__ = ["Bathymetry", "TerrainLabels", "caldera_site", "classify", "read_bathymetry", "slope_map"]


def __getattr__(name):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'drake_auv.terrain' has no attribute {name!r}")
