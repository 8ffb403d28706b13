"""Scoring a reconstruction (or a raw point cloud) against the true structure.

Accuracy: the distance from EVERY reconstructed vertex (or point) to the true world (the
target, or the whole world when given: a vertex on the seabed is then right, one on a surface
Poisson invented is not), its mean, median and 95th percentile, m. Completeness: the share of
the target's AREA lying within `tolerance` (0.5 m) of the reconstructed surface (or of a
point), estimated on points sampled uniformly by area on the target's faces (seeded, about one
per `spacing`^2); `completeness_seen`: the same share of the target's area the points saw
(within `tolerance` of at least `SEEN_POINTS` points: one stray return, clutter or a ghost,
does not make an area seen), which a surface can reach whatever the path missed. All in
one frame, the caller's (the missions use the local frame of the true world). Pure numpy/scipy.
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from drake_auv.geometry.distance import mesh_distance

TOLERANCE = 0.5  # m, completeness: a target point counts as reconstructed within this distance
SEEN_POINTS = 3  # points within TOLERANCE that make a target point seen
MAX_SCORED = 200_000  # points (and target samples) the statistics are estimated from


def surface_samples(mesh: trimesh.Trimesh, spacing: float = 0.1, seed: int = 0,
                    max_samples: int = 100_000) -> np.ndarray:
    """(m, 3) points uniform by area on `mesh`, about one per spacing^2 m^2 (at least 1000, at
    most `max_samples`): face chosen with probability proportional to its area, then a uniform
    barycentric point in it."""
    areas = np.asarray(mesh.area_faces, dtype=float)
    count = int(np.clip(areas.sum() / spacing ** 2, 1000, max_samples))
    rng = np.random.default_rng(seed)
    faces = rng.choice(len(areas), size=count, p=areas / areas.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    a, b, c = np.asarray(mesh.triangles)[faces].transpose(1, 0, 2)
    return a + u[:, None] * (b - a) + v[:, None] * (c - a)


def accuracy(errors: np.ndarray) -> dict:
    """`mean_m`, `median_m` and `p95_m` of distances to the truth, m, and their count `n`."""
    if len(errors) == 0:
        return dict(mean_m=None, median_m=None, p95_m=None, n=0)
    return dict(mean_m=float(errors.mean()), median_m=float(np.median(errors)),
                p95_m=float(np.percentile(errors, 95)), n=int(len(errors)))


def covered(points, samples, tolerance: float = TOLERANCE, at_least: int = 1) -> np.ndarray:
    """(m,) bool: which of `samples` lie within `tolerance` m of `at_least` points of
    `points`."""
    if len(points) < at_least:
        return np.zeros(len(samples), bool)
    d, _ = cKDTree(np.asarray(points, dtype=float)).query(
        samples, k=at_least, distance_upper_bound=tolerance)
    return np.reshape(d, (len(samples), -1))[:, -1] <= tolerance


def completeness_of_points(points, samples, tolerance: float = TOLERANCE) -> float:
    """Share of `samples` (target area) within `tolerance` m of some point of `points`."""
    return float(np.mean(covered(points, samples, tolerance)))


def completeness_of_mesh(mesh: trimesh.Trimesh, samples, tolerance: float = TOLERANCE) -> float:
    """Share of `samples` (target area) within `tolerance` m of the surface of `mesh`."""
    if len(mesh.faces) == 0 or len(samples) == 0:
        return 0.0
    return float(np.mean(mesh_distance(mesh, samples) <= tolerance))


def score(target: trimesh.Trimesh, mesh: trimesh.Trimesh | None, points,
          tolerance: float = TOLERANCE, spacing: float = 0.1, seed: int = 0,
          world: trimesh.Trimesh | None = None) -> tuple[dict, np.ndarray | None]:
    """Accuracy (every vertex, or point, to `world`, default `target`) and completeness (of
    `target`'s area, all of it and the part the points saw) of a reconstructed `mesh` (None:
    not scored) and of the raw `points` (n, 3) it came from; returns (summary, per-vertex
    distance of `mesh` to the truth, m, or None).

    summary: `surface` and `point_cloud`, each with `accuracy_mean_m`, `accuracy_median_m`,
    `accuracy_p95_m`, `completeness`, `completeness_seen` and the count of vertices or points;
    `tolerance_m`, `target_area_m2`, `seen_area_m2`, `accuracy_to` ("world" or "target").
    The points' accuracy is estimated on a seeded sample of at most `MAX_SCORED` of them, and
    the target is sampled at `spacing` m or coarser so that it gives at most `MAX_SCORED`
    samples (a survey's seabed target of 10^4 m^2 would otherwise take 10^6 exact distances);
    every vertex of `mesh` is scored exactly (its colours need them all).
    """
    truth = target if world is None else world
    spacing = max(spacing, float(np.sqrt(target.area / MAX_SCORED)))
    samples = surface_samples(target, spacing, seed)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    seen = covered(points, samples, tolerance, SEEN_POINTS)
    scored = points if len(points) <= MAX_SCORED else points[np.sort(
        np.random.default_rng(seed).choice(len(points), MAX_SCORED, replace=False))]
    raw = accuracy(mesh_distance(truth, scored) if len(scored) else np.zeros(0))
    summary = dict(tolerance_m=tolerance, target_area_m2=float(target.area),
                   seen_area_m2=float(target.area * seen.mean()),
                   accuracy_to="target" if world is None else "world",
                   point_cloud=dict(accuracy_mean_m=raw["mean_m"],
                                    accuracy_median_m=raw["median_m"],
                                    accuracy_p95_m=raw["p95_m"],
                                    completeness=completeness_of_points(points, samples,
                                                                        tolerance),
                                    points=int(len(points)), points_scored=raw["n"]))
    if mesh is None:
        return summary, None
    errors = mesh_distance(truth, np.asarray(mesh.vertices))
    acc = accuracy(errors)
    near = (mesh_distance(mesh, samples) <= tolerance) if len(mesh.faces) else \
        np.zeros(len(samples), bool)
    summary["surface"] = dict(accuracy_mean_m=acc["mean_m"], accuracy_median_m=acc["median_m"],
                              accuracy_p95_m=acc["p95_m"], completeness=float(near.mean()),
                              completeness_seen=float(near[seen].mean()) if seen.any() else
                              0.0, vertices=acc["n"], faces=int(len(mesh.faces)))
    return summary, errors
