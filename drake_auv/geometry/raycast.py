"""First-hit ray casting against a triangle mesh with Embree (through embreex), built once.

The Embree scene is built in the constructor and reused for every query; a query of n rays is
one vectorised call. Embree works in float32, so the vertices are shifted to the centre of the
mesh's bounding box first (georeferenced worlds have coordinates of 1e5-1e6 m): precision is
then about 1e-7 of the mesh size. Ranges and points are returned in the caller's frame, float64.
"""

from typing import NamedTuple  # RayHits' fields are evaluated (its generated __new__ cannot
# resolve postponed annotations: no `from __future__ import annotations` here)

import numpy as np
import trimesh
from embreex import rtcore_scene
from embreex.mesh_construction import TriangleMesh

from drake_auv.resources import map_chunks


class RayHits(NamedTuple):
    """Result of `RayCaster.cast` for n rays.

    ranges: (n,) distance to the first hit, m; NaN where the ray hit nothing within max_range.
    faces: (n,) index into `mesh.faces` of the face hit, -1 for no hit.
    points: (n, 3) hit points in the mesh frame, NaN rows for no hit.
    """

    ranges: np.ndarray
    faces: np.ndarray
    points: np.ndarray


def validate_mesh(mesh) -> trimesh.Trimesh:
    """Returns `mesh` if it is a non-empty, finite triangle mesh; raises ValueError otherwise."""
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(
            f"mesh must be a trimesh.Trimesh of triangles, got {type(mesh).__name__}")
    faces = np.asarray(mesh.faces)
    vertices = np.asarray(mesh.vertices)
    if faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError(f"mesh faces must be triangles, shape (n, 3); got {faces.shape}")
    if len(faces) == 0 or len(vertices) == 0:
        raise ValueError("mesh is empty: it needs at least one triangle face")
    if not np.all(np.isfinite(vertices)):
        raise ValueError("mesh vertices must be finite (no NaN or inf)")
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise ValueError(f"mesh faces index vertices outside [0, {len(vertices) - 1}]")
    return mesh


def face_centroids(vertices: np.ndarray, faces: np.ndarray, chunk: int = 1 << 18) -> np.ndarray:
    """(F, 3) centroids of the faces: trimesh's `triangles_center` to the bit, a coordinate at
    a time and `chunk` faces at a time on the usable cores (without trimesh's (F, 3, 3)
    triangle array and cache checks)."""
    centroids = np.empty((len(faces), 3))

    def part(s: slice) -> None:
        v0, v1, v2 = (vertices[faces[s, k]] for k in range(3))
        centroids[s] = (v0 + v1 + v2) / 3.0

    map_chunks(part, len(faces), chunk)
    return centroids


def face_normals_and_areas(vertices: np.ndarray, faces: np.ndarray,
                           chunk: int = 1 << 18) -> tuple[np.ndarray, np.ndarray]:
    """((F, 3) unit normals, zero for a degenerate face, (F,) areas) of the faces: trimesh's
    `face_normals` and `area_faces` to the bit (from the cross products of the edges v1 - v0
    and v2 - v1), computed a coordinate at a time and `chunk` faces at a time on the usable
    cores, without trimesh's (F, 3, 3) triangle array and cache checks (on a grid of 4 M
    cells: a tenth of trimesh's memory)."""
    normals = np.empty((len(faces), 3))
    areas = np.empty(len(faces))

    def part(s: slice) -> None:
        v0, v1, v2 = (vertices[faces[s, k]] for k in range(3))
        a, b = v1 - v0, v2 - v1
        crosses = np.column_stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
                                   a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                                   a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]])
        areas[s] = np.sqrt((crosses ** 2).sum(axis=1)) / 2.0
        unit, valid = trimesh.util.unitize(crosses, check_valid=True)
        if valid.all():
            normals[s] = unit
        else:
            normals[s] = 0.0
            normals[s][valid] = unit

    map_chunks(part, len(faces), chunk)
    return normals, areas


class RayCaster:
    """First-hit ray queries against one mesh; immutable after construction.

    Args:
        mesh: the world, a `trimesh.Trimesh` of triangles (any frame; rays use the same frame).
        robust: Embree's robust traversal (RTC_SCENE_FLAG_ROBUST, the default): watertight, a
            ray through an edge or vertex shared by faces hits one of them. Without it
            traversal is faster, but such rays can pass between the faces: a sonar beam
            through the seabed (measured: docs/benchmarks.md; kept for comparison only).
    """

    def __init__(self, mesh: trimesh.Trimesh, robust: bool = True):
        self.mesh = validate_mesh(mesh)
        vertices = np.asarray(mesh.vertices, dtype=float)
        self._offset = 0.5 * (vertices.min(axis=0) + vertices.max(axis=0))
        self._scene = rtcore_scene.EmbreeScene(robust=bool(robust))
        TriangleMesh(scene=self._scene,
                     vertices=(vertices - self._offset).astype(np.float32),
                     indices=np.asarray(mesh.faces).astype(np.int32))
        self.face_normals, self.face_areas = face_normals_and_areas(vertices,
                                                                    np.asarray(mesh.faces))

    @property
    def num_faces(self) -> int:
        return len(self.face_normals)

    def __deepcopy__(self, memo):
        # Immutable and holds a native scene: copies share it (Drake may deep-copy parameters).
        return self

    def cast(self, origins, directions, max_range) -> RayHits:
        """Casts rays and returns their first hits within `max_range`.

        Args:
            origins: (n, 3) or (3,) ray origins, m (a single origin is shared by all rays).
            directions: (n, 3) ray directions (normalised here; must be non-zero).
            max_range: scalar or (n,) maximum range, m, > 0.
        """
        directions = np.atleast_2d(np.asarray(directions, dtype=float))
        if directions.ndim != 2 or directions.shape[1] != 3:
            raise ValueError(f"directions must have shape (n, 3), got {directions.shape}")
        n = len(directions)
        origins = np.asarray(origins, dtype=float)
        if origins.shape == (3,):
            origins = np.broadcast_to(origins, (n, 3))
        if origins.shape != (n, 3):
            raise ValueError(f"origins must have shape (3,) or ({n}, 3), got {origins.shape}")
        max_range = np.broadcast_to(np.asarray(max_range, dtype=float), (n,))
        if not np.all(np.isfinite(max_range)) or np.any(max_range <= 0):
            raise ValueError("max_range must be finite and > 0 m")
        norms = np.linalg.norm(directions, axis=1)
        if not np.all(np.isfinite(norms)) or np.any(norms < 1e-12) or not np.all(
                np.isfinite(origins)):
            raise ValueError("origins must be finite and directions finite and non-zero")
        unit = directions / norms[:, None]
        points = np.full((n, 3), np.nan)
        if n == 0:
            return RayHits(np.full(0, np.nan), np.full(0, -1, dtype=np.int64), points)
        ranges, faces = self.cast_unit(origins, unit, max_range)
        hit = faces >= 0
        points[hit] = origins[hit] + ranges[hit, None] * unit[hit]
        return RayHits(ranges, faces, points)

    def cast_unit(self, origins, unit_directions, max_range, chunk: int = 65536):
        """The fast path of `cast` for trusted input (no checks, no points). A batch of more
        than `chunk` rays is cast `chunk` at a time on the usable cores (Embree's queries
        release the GIL: `resources.map_chunks`).

        Args:
            origins: (3,) or (n, 3) finite; unit_directions: (n, 3) unit vectors;
            max_range: scalar or (n,) > 0.
        Returns:
            (ranges (n,) with NaN for no hit, faces (n,) with -1 for no hit).
        """
        n = len(unit_directions)
        shifted = origins - self._offset
        if shifted.ndim == 1:  # one origin for all rays (Embree reads one per ray)
            origins32 = np.empty((n, 3), dtype=np.float32)
            origins32[:] = shifted  # the same float32 rounding as astype
        else:
            origins32 = np.asarray(shifted, dtype=np.float32)
        directions32 = np.asarray(unit_directions, dtype=np.float32)
        if isinstance(max_range, (float, int, np.floating)):
            dists = np.empty(n, dtype=np.float32)
            dists.fill(max_range)
        else:
            dists = np.array(max_range, dtype=np.float32)  # Embree writes the hits into it

        def cast(s: slice) -> tuple[np.ndarray, np.ndarray]:
            out = self._scene.run(origins32[s], directions32[s], dists=dists[s], output=1)
            return out["tfar"], out["primID"]

        parts = map_chunks(cast, n, chunk)
        ranges = np.concatenate([np.zeros(0, np.float32)] + [r for r, _ in parts])
        faces = np.concatenate([np.zeros(0, np.int64)] + [f for _, f in parts])
        ranges[faces < 0] = np.nan
        return ranges, faces
