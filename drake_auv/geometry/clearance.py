"""Signed clearance to a world mesh and the sea: negative inside the world or out of the water.

The world is a triangle mesh whose surfaces face the water (`drake_auv.scenarios`): closed
solids (blocks, a boulder) with outward normals, open surfaces (a seabed tile, a pool's walls)
with their normals towards the water. A point is INSIDE the world when, for some connected
part of the mesh (faces sharing vertices), the first face of that part met by a ray cast
upwards from the point is seen from behind (the ray leaves through it: its normal points along
the ray). For a closed part that is containment; for an open seabed it is "below it". Each part
is judged on its own first face, so a block sunk into the seabed does not hide the seabed from
a point under both. Three rays, 0.05 degrees off the vertical at three azimuths (none parallel to
an axis-aligned wall), vote; rays that meet nothing vote "outside". The rays pass a part's faces
seen from the front (the underside of an overhang, a block's bottom) and go on, at most
`MAX_LAYERS` faces each, so a query costs a bounded number of Embree casts per point.

The signed clearance of a point is its exact distance to the mesh (`mesh_distance`), negated
inside the world; above the sea surface (z > 0) it is at most -z (out of the water counts as
contact however far the world is). Contact is a signed clearance at or below the vehicle's
radius.
"""

from __future__ import annotations

import numpy as np
import trimesh

from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.raycast import RayCaster

SEA_SURFACE_Z = 0.0  # m, world frame z up
TILT = np.radians(0.05)  # of the inside rays from the vertical (0.9 m at 1 km)
AZIMUTHS = np.radians([17.0, 137.0, 257.0])  # of the inside rays, none along an axis
MAX_LAYERS = 32  # faces a ray passes before its vote is "outside"


def _rays() -> np.ndarray:
    """(3, 3) unit directions of the inside rays."""
    return np.column_stack([np.sin(TILT) * np.cos(AZIMUTHS), np.sin(TILT) * np.sin(AZIMUTHS),
                            np.full(len(AZIMUTHS), np.cos(TILT))])


class WorldClearance:
    """Signed clearance and inside-ness of points against one world mesh; immutable.

    Args:
        world: the world, a `trimesh.Trimesh` whose surfaces face the water (m, z up).
        caster: a `RayCaster` of `world` to share (default: built here).
    """

    def __init__(self, world: trimesh.Trimesh, caster: RayCaster | None = None):
        self.world = world
        self.caster = caster if caster is not None else RayCaster(world)
        merged = trimesh.Trimesh(np.asarray(world.vertices), np.asarray(world.faces),
                                 process=False)
        merged.merge_vertices()  # STL-like files repeat every vertex
        self.part = trimesh.graph.connected_component_labels(
            merged.face_adjacency, node_count=len(merged.faces)).astype(np.int64)
        lo, hi = np.asarray(world.bounds, dtype=float)
        self._centre, self._extent = 0.5 * (lo + hi), float(np.linalg.norm(hi - lo))
        self._top = float(hi[2])
        self._step = max(1e-3, 1e-6 * self._extent)  # m past a face, above float32's rounding

    def __deepcopy__(self, memo):
        return self  # immutable, holds a native scene

    def inside(self, points) -> np.ndarray:
        """(n,) True where a point (n, 3) lies inside the world (module docstring)."""
        points = self._points(points)
        if not len(points):
            return np.zeros(0, bool)
        votes = sum(self._inside_along(points, d).astype(int) for d in _rays())
        return votes >= 2

    def _inside_along(self, points: np.ndarray, direction: np.ndarray) -> np.ndarray:
        n = len(points)
        reach = self._extent + float(np.linalg.norm(points - self._centre, axis=1).max()) + 1.0
        normals = self.caster.face_normals
        inside = np.zeros(n, bool)
        seen = np.full((n, MAX_LAYERS), -1, dtype=np.int64)  # parts met, in order
        travelled = np.zeros(n)
        active = np.arange(n)
        for layer in range(MAX_LAYERS):
            origins = points[active] + travelled[active, None] * direction
            ranges, faces = self.caster.cast_unit(origins, np.tile(direction, (len(active), 1)),
                                                  reach)
            hit = faces >= 0
            active, ranges, faces = active[hit], ranges[hit].astype(float), faces[hit]
            part = self.part[faces]
            new = ~np.any(seen[active, :layer] == part[:, None], axis=1)
            behind = normals[faces] @ direction > 0.0
            inside[active[new & behind]] = True
            seen[active, layer] = part
            travelled[active] += ranges + self._step
            active = active[~(new & behind)]
            if not len(active):
                break
        return inside

    def signed(self, points) -> np.ndarray:
        """(n,) signed clearance of points (n, 3), m: the distance to the world, negative
        inside it; above the sea surface at most -z."""
        points = self._points(points)
        if not len(points):
            return np.zeros(0)
        distance = mesh_distance(self.world, points)
        out = np.where(self.inside(points), -distance, distance)
        return np.minimum(out, np.where(points[:, 2] > SEA_SURFACE_Z, SEA_SURFACE_Z - points[:, 2],
                                        np.inf))

    def top(self, xy) -> np.ndarray:
        """(n,) elevation of the world's highest face at each (x, y) (n, 2), m; NaN where no
        face lies at it."""
        xy = np.atleast_2d(np.asarray(xy, dtype=float))[:, :2]
        if not len(xy):
            return np.zeros(0)
        origins = np.column_stack([xy, np.full(len(xy), self._top + 1.0)])
        down = np.tile([0.0, 0.0, -1.0], (len(xy), 1))
        ranges, _ = self.caster.cast_unit(origins, down, self._extent + 2.0)
        return self._top + 1.0 - ranges.astype(float)

    def misplaced(self, points) -> list[str | None]:
        """Per point (n, 3): None in the water, else one phrase naming its depth against the
        world's top surface there (the seabed, or a structure's top), e.g. "depth 500 m is
        470.00 m inside the world (its top surface there: 30.0 m deep)"."""
        points = self._points(points)
        clearance = self.signed(points)
        out = []
        for (_, _, z), c, t in zip(points, clearance, self.top(points[:, :2])):
            there = ("none" if not np.isfinite(t) else f"{-t:.1f} m deep" if t <= SEA_SURFACE_Z
                     else f"{t:.1f} m above the sea surface")
            if z > SEA_SURFACE_Z:
                out.append(f"depth {-z:g} m is {z:.2f} m above the sea surface (the world's "
                           f"top surface there: {there})")
            elif c < 0.0:
                out.append(f"depth {-z:g} m is {-c:.2f} m inside the world (its top surface "
                           f"there: {there})")
            else:
                out.append(None)
        return out

    @staticmethod
    def _points(points) -> np.ndarray:
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        if not np.all(np.isfinite(points)):
            raise ValueError("clearance: points must be finite (n, 3), m")
        return points
