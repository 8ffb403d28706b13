"""Exact distance from points to a triangle mesh's surface (pure numpy/scipy).

Used for the truth measures of the missions: clearance (no contact) and distance to the
inspected structure. trimesh's own proximity queries need rtree, which is not a dependency.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import cKDTree


def mesh_distance(mesh: trimesh.Trimesh, points, chunk: int = 256) -> np.ndarray:
    """(n,) exact distance from each point (n, 3) to the mesh's surface, m.

    The nearest triangle's centroid lies within d + r of the point, d being the true distance
    (at most the distance to the nearest centroid) and r the largest centroid-to-vertex
    distance of any triangle, so only the triangles in that ball are tested exactly.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if points.shape[1] != 3 or not np.all(np.isfinite(points)):
        raise ValueError(f"mesh_distance: points must be finite (n, 3), got {points.shape}")
    triangles = np.asarray(mesh.triangles)
    centroids = triangles.mean(axis=1)
    reach = float(np.linalg.norm(triangles - centroids[:, None], axis=2).max())
    tree = cKDTree(centroids)
    nearest, _ = tree.query(points)
    out = np.empty(len(points))
    for start in range(0, len(points), chunk):
        block = slice(start, start + chunk)
        candidates = tree.query_ball_point(points[block], nearest[block] + reach)
        owner = np.repeat(np.arange(len(candidates)), [len(c) for c in candidates])
        faces = np.concatenate(candidates).astype(int)
        closest = trimesh.triangles.closest_point(triangles[faces], points[block][owner])
        dist = np.linalg.norm(closest - points[block][owner], axis=1)
        out[block] = np.full(len(candidates), np.inf)
        np.minimum.at(out[block], owner, dist)
    return out
