"""Occupied voxels of the on-line octree map in Meshcat: one point cloud, coloured by depth.

`draw_octree` draws the map's occupied voxel centres once (e.g. at the end of a mission);
`OctreeVisualizer` redraws them periodically during a simulation so a live viewer sees the
map grow. Points are drawn at the voxel size so the cloud reads as a voxel map.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from pydrake.common.value import AbstractValue
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.framework import LeafSystem

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.visualization.legend import LegendEntry, swatch


def depth_colours(z: np.ndarray, cmap: str = "viridis") -> np.ndarray:
    """(n, 3) uint8 colours of elevations `z` (m) across their range."""
    z = np.asarray(z, dtype=float)
    span = np.ptp(z) if len(z) else 0.0
    t = (z - z.min()) / span if span > 0 else np.zeros_like(z)
    return (255 * colormaps[cmap](t)[:, :3]).astype(np.uint8)


def octree_legend(path: str, cmap: str = "viridis") -> LegendEntry:
    """The legend's entry of the voxels drawn at `path`."""
    return LegendEntry("octree", "viridis dots", "the on-line map's occupied voxels by depth: "
                       "purple deep, yellow shallow",
                       swatch(colormaps[cmap](np.linspace(0, 1, 5))), path)


def draw_octree(meshcat, path: str, octree_map: OctreeMap, point_size: float | None = None,
                cmap: str = "viridis") -> int:
    """Draws the occupied voxels of `octree_map` at `path`; returns how many were drawn."""
    points = octree_map.occupied_points()
    cloud = PointCloud(len(points), Fields(BaseField.kXYZs | BaseField.kRGBs))
    if len(points):
        cloud.mutable_xyzs()[:] = points.T
        cloud.mutable_rgbs()[:] = depth_colours(points[:, 2], cmap).T
    size = octree_map.resolution if point_size is None else float(point_size)
    meshcat.SetObject(path, cloud, point_size=size)
    return len(points)


class OctreeVisualizer(LeafSystem):
    """Redraws the map from its `map` input (the mapper's `OnlineMap`) every `period` s."""

    def __init__(self, meshcat, path: str, period: float = 2.0):
        super().__init__()
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"OctreeVisualizer period must be > 0 s, got {period}")
        self.meshcat, self.path = meshcat, path
        self.map_input = self.DeclareAbstractInputPort("map",
                                                       AbstractValue.Make(OnlineMap(0.5)))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish_map)

    def _publish_map(self, context):
        draw_octree(self.meshcat, self.path, self.map_input.Eval(context).map)
