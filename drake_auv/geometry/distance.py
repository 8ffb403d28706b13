"""Exact distance from points to a triangle mesh's surface (pure numpy/scipy).

Used for the truth measures of the missions: clearance (no contact) and distance to the
inspected structure, and for scoring reconstructed surfaces. trimesh's own proximity queries
need rtree, which is not a dependency.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import cKDTree


def mesh_distance(mesh: trimesh.Trimesh, points, chunk: int = 256) -> np.ndarray:
    """(n,) exact distance from each point (n, 3) to the mesh's surface, m.

    A triangle whose centroid is c and whose vertices lie within r of c is at least
    |p - c| - r from p, and the nearest centroid of all, at u, bounds the true distance from
    above. So only the triangles whose centroid lies within u + r are tested exactly. The
    triangles are grouped by r in powers of two, each group with its own KD-tree and reach:
    a few large triangles (a reconstructed surface's hole fillers, a coarse seabed's edge)
    then widen the search of their group only, not that of every point.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    if points.shape[1] != 3 or not np.all(np.isfinite(points)):
        raise ValueError(f"mesh_distance: points must be finite (n, 3), got {points.shape}")
    triangles = np.asarray(mesh.triangles)
    centroids = triangles.mean(axis=1)
    radius = np.linalg.norm(triangles - centroids[:, None], axis=2).max(axis=1)
    level = np.ceil(np.log2(np.maximum(radius, 1e-12) / max(np.median(radius), 1e-12)))
    groups = []
    for value in np.unique(np.maximum(level, 0)):
        faces = np.flatnonzero(np.maximum(level, 0) == value)
        groups.append((faces, cKDTree(centroids[faces]), float(radius[faces].max())))
    bound = np.min([tree.query(points)[0] for _, tree, _ in groups], axis=0)
    out = np.full(len(points), np.inf)
    for start in range(0, len(points), chunk):
        block = slice(start, start + chunk)
        for faces_of, tree, reach in groups:
            candidates = tree.query_ball_point(points[block], bound[block] + reach)
            counts = [len(c) for c in candidates]
            if not sum(counts):
                continue
            owner = np.repeat(np.arange(len(candidates)), counts)
            faces = faces_of[np.concatenate(candidates).astype(int)]
            closest = trimesh.triangles.closest_point(triangles[faces], points[block][owner])
            dist = np.linalg.norm(closest - points[block][owner], axis=1)
            np.minimum.at(out[block], owner, dist)
    return out
