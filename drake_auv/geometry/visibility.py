"""Which faces of the true world a camera or a sonar fan sees, unoccluded, and how well.

Camera: a circular cone of aperture `aperture` (full angle, rad) about its axis, out to
`max_range` (water clarity). A face is seen when its centroid lies in the cone and in range,
the face turns its front to the camera, and a ray from the camera to the centroid meets
nothing nearer (one ray per candidate face, candidates from a KD-tree of centroids built once).
This measures coverage at face resolution without the holes a sparse ray grid leaves.

Viewing angle, 0 is ideal: the angle between the sensor axis and the inward surface normal
(the reference's definition), so a down-looking camera over flat ground views every face at 0.
For a sonar fan, the faces its beams hit are seen, at the angle between beam and normal.

`CoverageMap` keeps the best (smallest) viewing angle per target face; coverage is the seen
share of the target area.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from drake_auv.geometry.raycast import RayCaster, RayHits, face_centroids
from drake_auv.resources import map_chunks


def _poses(origins, axes, aperture: float, max_range: float):
    """(n, 3) origins and unit axes of camera poses, the aperture and range checked."""
    origins = np.atleast_2d(np.asarray(origins, dtype=float))
    axes = np.atleast_2d(np.asarray(axes, dtype=float))
    if not (0 < aperture < np.pi):
        raise ValueError(f"aperture must be in (0, 180) deg, got {np.degrees(aperture)} deg")
    if not (np.isfinite(max_range) and max_range > 0):
        raise ValueError(f"max_range must be > 0 m, got {max_range}")
    return origins, axes / np.linalg.norm(axes, axis=1, keepdims=True)


class FaceVisibility:
    """Visibility queries against one world, built once.

    Args:
        caster: ray caster of the world.
        target_faces: (F,) bool, the faces to report (all if None); occlusion uses all faces.
    """

    def __init__(self, caster: RayCaster, target_faces=None):
        self.caster = caster
        mesh = caster.mesh
        num_faces = caster.num_faces
        target = (np.ones(num_faces, bool) if target_faces is None
                  else np.asarray(target_faces, dtype=bool))
        if target.shape != (num_faces,):
            raise ValueError(f"target_faces must be a bool mask of the {num_faces} world faces, "
                             f"got shape {target.shape}")
        if not target.any():
            raise ValueError("target_faces is empty: select at least one face")
        self.target_index = np.flatnonzero(target)  # world face index of each target face
        every = len(self.target_index) == num_faces  # the caster's arrays shared, never written
        faces = np.asarray(mesh.faces)
        self.centroids = face_centroids(np.asarray(mesh.vertices, dtype=float),
                                        faces if every else faces[self.target_index])
        self.normals = caster.face_normals if every else caster.face_normals[self.target_index]
        self.areas = caster.face_areas if every else caster.face_areas[self.target_index]
        self._tree = None  # of the centroids, built on the first camera query
        # Target slot of each world face (-1: not a target), to map sonar hits.
        self._slot = np.full(num_faces, -1, dtype=np.int64)
        self._slot[self.target_index] = np.arange(len(self.target_index))

    def _centroid_tree(self) -> cKDTree:
        if self._tree is None:
            self._tree = cKDTree(self.centroids)
        return self._tree

    def _cone_candidates(self, origin, axis, half: float, max_range: float) -> np.ndarray:
        """Target slots whose centroid may lie in the cone (half angle `half`, length R): those
        in its bounding ball, centred R/2 along the axis with radius R sqrt(1/4 + sin^2(half))
        when half <= 45 deg (about a third of the range ball's volume), else the range ball."""
        if half <= np.pi / 4:
            centre = origin + 0.5 * max_range * axis
            radius = max_range * np.sqrt(0.25 + np.sin(half) ** 2)
        else:
            centre, radius = origin, max_range
        return np.asarray(self._centroid_tree().query_ball_point(centre, radius), dtype=np.int64)

    def camera(self, origin, axis, aperture: float, max_range: float):
        """Target faces a camera sees: (slots (k,) into the target faces, angles (k,) rad)."""
        origin = np.asarray(origin, dtype=float)
        axis = np.asarray(axis, dtype=float)
        axis = axis / np.linalg.norm(axis)
        if not (0 < aperture < np.pi):
            raise ValueError(f"aperture must be in (0, 180) deg, got {np.degrees(aperture)} deg")
        if not (np.isfinite(max_range) and max_range > 0):
            raise ValueError(f"max_range must be > 0 m, got {max_range}")
        slots = self._cone_candidates(origin, axis, 0.5 * aperture, max_range)
        if len(slots) == 0:
            return slots, np.zeros(0)
        v = self.centroids[slots] - origin
        dist = np.linalg.norm(v, axis=1)
        u = v / np.maximum(dist, 1e-12)[:, None]
        normals = self.normals[slots]
        keep = ((u @ axis >= np.cos(0.5 * aperture)) & (dist <= max_range)
                & (np.einsum("ij,ij->i", u, normals) < 0))
        slots, u, dist, normals = slots[keep], u[keep], dist[keep], normals[keep]
        if len(slots) == 0:
            return slots, np.zeros(0)
        hits = self.caster.cast(origin, u, max_range)
        tol = 1e-3 + 1e-4 * dist
        seen = (hits.faces == self.target_index[slots]) | ~(hits.ranges < dist - tol)
        angles = np.arccos(np.clip(-(normals[seen] @ axis), -1.0, 1.0))
        return slots[seen], angles

    def cameras(self, origins, axes, aperture: float, max_range: float, chunk: int = 1024):
        """`camera` for many poses at once, batched (one KD-tree query and one ray cast per
        chunk of poses): (slots (k,), angles (k,) rad, pose index (k,)) of every face a pose
        sees, a face once per pose that sees it."""
        origins, axes = _poses(origins, axes, aperture, max_range)
        half = 0.5 * aperture
        if half <= np.pi / 4:
            centres = origins + 0.5 * max_range * axes
            radius = max_range * np.sqrt(0.25 + np.sin(half) ** 2)
        else:
            centres, radius = origins, max_range
        out_s, out_a, out_p = [], [], []
        for c0 in range(0, len(origins), chunk):
            lists = self._centroid_tree().query_ball_point(centres[c0:c0 + chunk], radius)
            counts = np.fromiter((len(x) for x in lists), dtype=np.int64, count=len(lists))
            if counts.sum() == 0:
                continue
            slots = np.concatenate([np.asarray(x, dtype=np.int64) for x in lists])
            pose = c0 + np.repeat(np.arange(len(lists)), counts)
            v = self.centroids[slots] - origins[pose]
            dist = np.linalg.norm(v, axis=1)
            u = v / np.maximum(dist, 1e-12)[:, None]
            normals = self.normals[slots]
            keep = ((np.einsum("ij,ij->i", u, axes[pose]) >= np.cos(half)) & (dist <= max_range)
                    & (np.einsum("ij,ij->i", u, normals) < 0))
            slots, pose, u, dist, normals = slots[keep], pose[keep], u[keep], dist[keep], normals[keep]
            if len(slots) == 0:
                continue
            ranges, faces = self.caster.cast_unit(origins[pose], u, max_range)
            seen = (faces == self.target_index[slots]) | ~(ranges < dist - (1e-3 + 1e-4 * dist))
            out_s.append(slots[seen])
            out_p.append(pose[seen])
            out_a.append(np.arccos(np.clip(-np.einsum("ij,ij->i", normals[seen],
                                                      axes[pose[seen]]), -1.0, 1.0)))
        if not out_s:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64)
        return np.concatenate(out_s), np.concatenate(out_a), np.concatenate(out_p)

    def seen_by(self, origins, axes, aperture: float, max_range: float, slots=None,
                chunk: int = 16384) -> np.ndarray:
        """Whether any of the cameras at `origins` looking along `axes` sees each target face
        of `slots` (all if None): the test of `cameras` pair by pair, the pairs found from the
        faces' side (a KD-tree of the poses, built here, against one of each chunk of faces),
        so a subset of faces costs in proportion to its size; the chunks run on the usable
        cores (`resources.map_chunks`). (len(slots),) bool."""
        origins, axes = _poses(origins, axes, aperture, max_range)
        slots = (np.arange(len(self.target_index)) if slots is None
                 else np.asarray(slots, dtype=np.int64))
        if len(origins) == 0 or len(slots) == 0:
            return np.zeros(len(slots), dtype=bool)
        tree = cKDTree(origins, balanced_tree=False, compact_nodes=False)
        cos_half = np.cos(0.5 * aperture)

        def seen_in(chunk_slots: slice) -> np.ndarray:
            s = slots[chunk_slots]
            seen = np.zeros(len(s), dtype=bool)
            pairs = cKDTree(self.centroids[s]).sparse_distance_matrix(tree, max_range,
                                                                      output_type="ndarray")
            face, pose = pairs["i"].astype(np.int64), pairs["j"].astype(np.int64)
            v = self.centroids[s[face]] - origins[pose]
            dist = np.linalg.norm(v, axis=1)
            u = v / np.maximum(dist, 1e-12)[:, None]
            keep = ((np.einsum("ij,ij->i", u, axes[pose]) >= cos_half) & (dist <= max_range)
                    & (np.einsum("ij,ij->i", u, self.normals[s[face]]) < 0))
            face, pose, u, dist = face[keep], pose[keep], u[keep], dist[keep]
            if len(face):
                ranges, hit = self.caster.cast_unit(origins[pose], u, max_range)
                ok = (hit == self.target_index[s[face]]) | ~(ranges < dist - (1e-3 + 1e-4 * dist))
                seen[face[ok]] = True
            return seen

        return np.concatenate(map_chunks(seen_in, len(slots), chunk))

    def beams(self, hits: RayHits, directions):
        """Target faces hit by sonar beams: (slots, angles between beam and inward normal)."""
        directions = np.asarray(directions, dtype=float)
        faces = np.asarray(hits.faces)
        hit = faces >= 0
        slots = self._slot[faces[hit]]
        target = slots >= 0
        d = directions[hit][target]
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        cosang = np.abs(np.einsum("ij,ij->i", self.normals[slots[target]], d))
        return slots[target], np.arccos(np.clip(cosang, -1.0, 1.0))


def merge_best(best: np.ndarray, slots: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Copy of `best` (NaN: unseen) with the smaller angle kept for each observed slot."""
    out = np.array(best, dtype=float)
    if len(slots):
        current = np.full(len(out), np.inf)
        np.minimum.at(current, slots, angles)
        out = np.fmin(out, current)
        out[np.isinf(out)] = np.nan
    return out


def coverage_share(best: np.ndarray, areas: np.ndarray) -> float:
    """Seen share of the area (faces with a finite best angle)."""
    return float(areas[np.isfinite(best)].sum() / areas.sum())


def angle_histogram(best: np.ndarray, areas: np.ndarray, bin_deg: float = 5.0):
    """Area (m^2) seen per viewing-angle bin: (area (k,), edges (k + 1,) deg, 0 to 90)."""
    if not (np.isfinite(bin_deg) and 0 < bin_deg <= 90):
        raise ValueError(f"bin_deg must be in (0, 90] deg, got {bin_deg}")
    edges = np.arange(0.0, 90.0 + 0.5 * bin_deg, bin_deg)
    seen = np.isfinite(best)
    area, edges = np.histogram(np.degrees(best[seen]), bins=edges, weights=areas[seen])
    return area, edges


class CoverageMap:
    """Pure accumulator of the best viewing angle per target face (no Drake): for offline
    evaluation of a sequence of poses and for tests."""

    def __init__(self, caster: RayCaster, target_faces=None):
        self.visibility = FaceVisibility(caster, target_faces)
        self.best = np.full(len(self.visibility.target_index), np.nan)

    def observe_camera(self, origin, axis, aperture: float, max_range: float) -> None:
        slots, angles = self.visibility.camera(origin, axis, aperture, max_range)
        self.best = merge_best(self.best, slots, angles)

    def observe_beams(self, hits: RayHits, directions) -> None:
        slots, angles = self.visibility.beams(hits, directions)
        self.best = merge_best(self.best, slots, angles)

    def coverage(self) -> float:
        return coverage_share(self.best, self.visibility.areas)

    def histogram(self, bin_deg: float = 5.0):
        return angle_histogram(self.best, self.visibility.areas, bin_deg)
