"""Reconstruction speed: 100k recorded returns to a screened-Poisson mesh at depth 9.

The cloud: the breakwater scenario's target block scanned by ray casting from sensor origins on
a ring 6 m off its walls at 5 m depth (vertical 120 degree fans), the first 100k returns inside
the block's box grown by 1 m (walls and a seabed ring), with their origins. Timed, interleaved,
median of RUNS: the whole `reconstruct` (Hoppe normals with k = 200 oriented by the origins,
Poisson at depth 9, 5 % trimming) and, as the reference measured in the same run on the same
machine, the normal estimation alone; their ratio is the figure to compare across machines
(the machine is shared, so process CPU time is printed beside the wall time).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from drake_auv.geometry.raycast import RayCaster
from drake_auv.reconstruction.pointcloud import PointCloud
from drake_auv.reconstruction.surface import estimate_normals, reconstruct
from drake_auv.scenarios import get_scenario

NUM_POINTS = 100_000
DEPTH = 9
RUNS = 3


def scanned_block(num_points: int = NUM_POINTS, seed: int = 0) -> PointCloud:
    """`num_points` ray-cast returns on and around the breakwater's target block."""
    scenario = get_scenario("breakwater")
    caster, rng = RayCaster(scenario.world), np.random.default_rng(seed)
    target = scenario.world.submesh([np.flatnonzero(scenario.target_faces)], append=True)
    lo, hi = target.bounds
    centre = 0.5 * (lo + hi)
    parts, count = [], 0
    while count < num_points:
        angle = rng.uniform(-np.pi / 2, np.pi / 2)  # the block's free (east) half
        origin = np.array([centre[0] + 8.5 * np.cos(angle), centre[1] + 8.5 * np.sin(angle),
                           -5.0])
        look = centre[:2] - origin[:2] + rng.normal(0.0, 1.0, 2)
        heading = np.arctan2(look[1], look[0])
        elevation = np.linspace(-np.pi / 3, np.pi / 3, 240)
        directions = np.column_stack([np.cos(elevation) * np.cos(heading),
                                      np.cos(elevation) * np.sin(heading), np.sin(elevation)])
        hits = caster.cast(origin, directions, 20.0)
        inside = np.isfinite(hits.ranges)
        inside[inside] = np.all((hits.points[inside] >= lo - 1.0)
                                & (hits.points[inside] <= hi + 1.0), axis=1)
        points = hits.points[inside]
        parts.append((points, np.broadcast_to(origin, points.shape)))
        count += len(points)
    points, origins = (np.concatenate(p)[:num_points] for p in zip(*parts))
    return PointCloud(points, origins.copy(), np.zeros(len(points)),
                      np.zeros(len(points), np.uint8))


def timed(fn) -> tuple[float, float, object]:
    """(wall s, process CPU s, result) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - wall, time.process_time() - cpu, out


def main() -> None:
    cloud = scanned_block()
    walls, cpus, normal_walls = [], [], []
    for _ in range(RUNS):
        w, _, _ = timed(lambda: estimate_normals(cloud.points, cloud.origins, k=200))
        normal_walls.append(w)
        w, c, surface = timed(lambda: reconstruct(cloud, depth=DEPTH, progress=False))
        walls.append(w)
        cpus.append(c)
    wall, reference = statistics.median(walls), statistics.median(normal_walls)
    print(f"{len(cloud)} points -> {len(surface.mesh.vertices)} vertices, "
          f"{len(surface.mesh.faces)} faces at depth {DEPTH}")
    print(f"reconstruct: {wall:.2f} s wall (median of {RUNS}; runs "
          + ", ".join(f"{w:.2f}" for w in walls) + f"), {statistics.median(cpus):.2f} s CPU")
    print(f"reference, normals alone (k = 200): {reference:.2f} s wall; "
          f"ratio reconstruct / normals = {wall / reference:.2f}")


if __name__ == "__main__":
    main()
