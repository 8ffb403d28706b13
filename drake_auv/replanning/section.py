"""The pieces of the realtime replanning loop (reference, Section 5.5.3), pure numpy/scipy.

At each replanning step, with the vehicle at x (navigation frame):
1. `collect_section`: nominal waypoints w_i, in order from the next unvisited one, while
   |x - w_i| < R and at most K of them;
2. `initial_trajectory`: a polyline from x through them, each moved onto the offset Omega
   from the mapped structure, resampled evenly;
3. `ReplanningCost` + `stomp`: the trajectory optimised against the on-line map;
4. `SectionPlan.next_index`: once part of the trajectory has been flown, the waypoints it
   has passed are marked visited (progress along the plan, not nearness to the waypoints,
   which the vehicle may never approach when the prior map is wrong).
`replan_section` runs 1-3. Names: the on-line map is `octree_map` (the reference's M);
STOMP's smoothing matrix is `StompMatrices.smoothing`.

Choices the reference leaves open (docs/replanning.md): the offset Omega is kept in the
horizontal plane against occupied voxels within a depth band around the trajectory (the slice
plane of a contour path, so the seabed below does not count as the wall to follow), clearance
counts every occupied voxel in 3D; the waypoints (planned on the wrong prior map) are moved
onto the offset before the polyline is built, so the fixed end point is a feasible one; a depth
term keeps the nominal depth.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from scipy.spatial import cKDTree

from drake_auv.planning.polyline import length, resample
from drake_auv.replanning.stomp import StompMatrices, StompParameters, stomp


@dataclass(frozen=True)
class ReplanningParameters:
    """Parameters of the replanning loop.

    Attributes:
        radius: R, waypoints closer than this to the vehicle form the section, m (> 0).
        max_waypoints: K, most waypoints in one section (>= 1).
        omega: offset to keep from the mapped structure, m (> 0).
        clearance: distance to any occupied voxel under which the obstacle cost rises, m (> 0).
        depth_band: half-height of the band of voxels the offset is measured against, m (> 0).
        offset_metric: "horizontal": the offset is the horizontal distance to the band's
            voxels (walls with the seabed closer than Omega below, as at the breakwater);
            "3d": the 3D distance to any voxel, the offset along the surface normal of the
            slicing planner (sloping faces, as on the boulder).
        spacing: distance between trajectory points, m (> 0).
        offset_weight, obstacle_weight, depth_weight: cost weights (>= 0).
        stomp: `StompParameters` (rollouts, iterations, noise, smoothness weight).
    """

    radius: float = 5.0
    max_waypoints: int = 10
    omega: float = 6.0
    clearance: float = 3.0
    depth_band: float = 1.5
    offset_metric: str = "horizontal"
    spacing: float = 0.5
    offset_weight: float = 1.0
    obstacle_weight: float = 50.0
    depth_weight: float = 1.0
    stomp: StompParameters = field(default_factory=lambda: StompParameters(
        num_rollouts=10, max_iterations=40, noise_std=0.5, smoothness_weight=50.0,
        patience=8))

    def __post_init__(self):
        for name in ("radius", "omega", "clearance", "depth_band", "spacing"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be > 0 m, got {value}")
        for name in ("offset_weight", "obstacle_weight", "depth_weight"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be >= 0, got {value}")
        if self.offset_metric not in ("horizontal", "3d"):
            raise ValueError(f"offset_metric must be 'horizontal' or '3d', got "
                             f"{self.offset_metric!r}")
        if int(self.max_waypoints) != self.max_waypoints or self.max_waypoints < 1:
            raise ValueError(f"max_waypoints must be an integer >= 1, got {self.max_waypoints}")


def _check_position(position) -> np.ndarray:
    position = np.asarray(position, dtype=float).reshape(-1)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        raise ValueError(f"position must be a finite 3-vector, got {position}")
    return position


def collect_section(position, waypoints, next_index: int, radius: float,
                    max_waypoints: int) -> np.ndarray:
    """Indices of the section: from `next_index`, in order, while |x - w_i| < R, at most K.

    The next waypoint is always included, even beyond R, so the vehicle keeps progressing
    after a detour; the result is empty only when every waypoint was visited.
    """
    x = _check_position(position)
    waypoints = np.asarray(waypoints, dtype=float)
    if not (radius > 0) or max_waypoints < 1:
        raise ValueError(f"need radius > 0 m and max_waypoints >= 1, got {radius}, "
                         f"{max_waypoints}")
    if not 0 <= next_index:
        raise ValueError(f"next_index must be >= 0, got {next_index}")
    stop = min(len(waypoints), next_index + max_waypoints)
    if next_index >= stop:
        return np.zeros(0, dtype=int)
    near = np.linalg.norm(waypoints[next_index:stop] - x, axis=1) < radius
    count = int(np.argmin(near)) if not near.all() else len(near)
    return np.arange(next_index, next_index + max(count, 1))


def resample_polyline(points, spacing: float) -> np.ndarray:
    """(N, 3) points evenly spaced by at most `spacing` along the polyline, ends kept, N >= 3
    (STOMP needs an interior point)."""
    points = np.asarray(points, dtype=float)
    total = length(points)
    if total <= 1e-9:
        return np.repeat(points[:1], 3, axis=0)
    return resample(points, min(spacing, total / 2.0))


DEPTH_MARGIN = 1.0  # m, how far rollouts may stray from the section's depths (see SliceMap)


def _kdtree(points: np.ndarray) -> cKDTree:
    """KD-tree of voxel centres, built for this use: rebuilt at every step and queried from
    metres away (the offset is ~Omega), where the voxels of a surface are nearly equidistant
    and a default tree visits many small leaves. Large, unbalanced (sliding-midpoint) leaves
    answer the same nearest neighbours 2-4x faster here and build faster."""
    return cKDTree(points, leafsize=64, balanced_tree=False, compact_nodes=False)


class SliceMap:
    """Occupied voxels of the on-line map near a section, queried for the replanning cost.

    Built once per replanning step from the voxels within reach of the section:
    - `band_tree`: for the offset, voxels within `depth_band` of the section's depths in 2D
      (metric "horizontal"), or every voxel in 3D (metric "3d"); `dims` says which;
    - the clearance slab: voxels within `clearance + margin` of the section's depths, the only
      ones that can be nearer than `clearance` to a point of the section (rollouts stay within
      `margin` of its depths: the depth cost holds them). A 2D KD-tree of the slab rules most
      points out (horizontal distance >= clearance), a 3D one measures the rest exactly.
    """

    def __init__(self, occupied: np.ndarray, z_range: tuple[float, float], depth_band: float,
                 clearance: float, margin: float = DEPTH_MARGIN, metric: str = "horizontal"):
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        z = occupied[:, 2]
        if metric == "3d":
            self.dims = 3
            self.band_points = occupied
        else:
            self.dims = 2
            in_band = (z >= z_range[0] - depth_band) & (z <= z_range[1] + depth_band)
            self.band_points = occupied[in_band, :2]
        self.band_tree = _kdtree(self.band_points) if len(self.band_points) else None
        reach = clearance + margin
        slab = occupied[(z >= z_range[0] - reach) & (z <= z_range[1] + reach)]
        self.slab_tree_2d = _kdtree(slab[:, :2]) if len(slab) else None
        self.slab_tree_3d = _kdtree(slab) if len(slab) else None

    def clearance(self, points: np.ndarray, upper_bound: float) -> np.ndarray:
        """3D distance to the nearest occupied voxel centre, inf beyond `upper_bound`, m."""
        flat = points.reshape(-1, 3)
        d = np.full(len(flat), np.inf)
        if self.slab_tree_2d is None:
            return d.reshape(points.shape[:-1])
        d_h, _ = self.slab_tree_2d.query(flat[:, :2], distance_upper_bound=upper_bound)
        near = np.isfinite(d_h)  # the 3D distance is at least the horizontal one
        if near.any():
            d[near], _ = self.slab_tree_3d.query(flat[near], distance_upper_bound=upper_bound)
        return d.reshape(points.shape[:-1])

    def offset(self, points: np.ndarray, upper_bound: float):
        """Distance to, and index of, the nearest voxel of the band (horizontal or 3D), m."""
        if self.band_tree is None:
            shape = points.shape[:-1]
            return np.full(shape, np.inf), np.full(shape, -1)
        d, i = self.band_tree.query(points[..., :self.dims].reshape(-1, self.dims),
                                    distance_upper_bound=upper_bound)
        return d.reshape(points.shape[:-1]), i.reshape(points.shape[:-1])


class ReplanningCost:
    """Per-timestep state cost of STOMP rollouts (K, N, 3) -> (K, N).

    offset_weight * min(|d_h - Omega|, Omega) + obstacle_weight * max(0, clearance - d)^2
    + depth_weight * (z - z_ref)^2, with d_h the horizontal distance to the band's voxels
    (saturated so that an unmapped area pulls nowhere) and d the 3D distance to any voxel.
    """

    def __init__(self, slice_map: SliceMap, z_ref: np.ndarray, params: ReplanningParameters,
                 keep_offset: np.ndarray | None = None):
        self.slice_map = slice_map
        self.z_ref = np.asarray(z_ref, dtype=float)
        self.params = params
        # Per trajectory point: weight of the offset term (0 where the plan does not follow
        # a wall, e.g. a terrain-following lane or a transit).
        self.offset_weight = params.offset_weight * (
            np.ones(len(self.z_ref)) if keep_offset is None
            else np.asarray(keep_offset, dtype=float))

    def __call__(self, trajectories: np.ndarray) -> np.ndarray:
        p = self.params
        # The offset is measured only at the points that keep it (weight > 0): elsewhere it
        # adds nothing, and the nearest-voxel query is the costliest part of the cost.
        offset = np.zeros(trajectories.shape[:-1])
        weighted = self.offset_weight > 0
        if weighted.any():
            d_h, _ = self.slice_map.offset(trajectories[..., weighted, :], 2.0 * p.omega)
            offset[..., weighted] = np.minimum(np.abs(d_h - p.omega), p.omega)
        d = self.slice_map.clearance(trajectories, p.clearance)
        obstacle = np.maximum(0.0, p.clearance - d) ** 2
        depth = (trajectories[..., 2] - self.z_ref) ** 2
        return self.offset_weight * offset + p.obstacle_weight * obstacle + p.depth_weight * depth


def project_to_offset(point, slice_map: SliceMap, omega: float) -> np.ndarray:
    """`point` moved onto the offset `omega` from the nearest band voxel (horizontally, or in
    3D with the "3d" metric).

    Unchanged when no band voxel lies within 2 * omega (nothing mapped there yet).
    """
    point = np.array(point, dtype=float)
    d, i = slice_map.offset(point[None], 2.0 * omega)
    if not np.isfinite(d[0]) or d[0] < 1e-6:
        return point
    q, k = slice_map.band_points[i[0]], slice_map.dims
    point[:k] = q + (point[:k] - q) * (omega / d[0])
    return point


def initial_trajectory(position, section_points, slice_map: SliceMap | None, omega: float,
                       spacing: float, keep_offset=None) -> tuple[np.ndarray, np.ndarray]:
    """Polyline from the vehicle through the section's waypoints, resampled every `spacing`.

    The waypoints were placed on the prior map, which may be wrong by metres: each is first
    moved onto the offset from the on-line map where that map sees structure near it, so the
    polyline does not lead the vehicle back to a wrong waypoint, and the end point (fixed
    during optimisation) is not left inside the clearance margin.

    `keep_offset` (one bool per waypoint, default all True) says which waypoints follow a
    wall at the offset; the others (terrain-following lanes, transits) are not moved.

    Returns the (N, 3) trajectory and, per waypoint, its fraction of the polyline's length.
    """
    x = _check_position(position)
    section_points = np.asarray(section_points, dtype=float).reshape(-1, 3)
    if len(section_points) == 0:
        raise ValueError("a section needs at least one waypoint")
    points = np.vstack([x, section_points])
    keep = np.ones(len(section_points), bool) if keep_offset is None else np.asarray(keep_offset)
    if slice_map is not None:
        for i in np.flatnonzero(keep) + 1:
            points[i] = project_to_offset(points[i], slice_map, omega)
    s = _arclength(points)
    return resample_polyline(points, spacing), s[1:] / max(s[-1], 1e-9)


def _arclength(points: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])


@lru_cache(maxsize=64)
def _matrices(num_points: int) -> StompMatrices:
    return StompMatrices(num_points)


@dataclass(frozen=True)
class SectionPlan:
    """One replanning step's result (navigation frame).

    Attributes:
        indices: the section's waypoint indices.
        initial, trajectory: (N, 3) initial and optimised trajectories, from the vehicle.
        waypoint_arclength: (len(indices),) where each waypoint falls along `trajectory`, m.
        initial_cost, cost, iterations: STOMP's.
        query_time: wall time of the map query (occupied voxels in the section's box), s.
        facing: (N,) yaw of the horizontal direction from each trajectory point to its nearest
            mapped voxel of the depth band, rad; NaN where none lies within 2 Omega.
    """

    indices: np.ndarray
    initial: np.ndarray
    trajectory: np.ndarray
    waypoint_arclength: np.ndarray
    initial_cost: float
    cost: float
    iterations: int
    query_time: float
    facing: np.ndarray

    def next_index(self, travelled: float, capture_radius: float = 0.5) -> int:
        """The first waypoint not passed after flying `travelled` metres of the trajectory.

        A waypoint is passed when the flown distance comes within `capture_radius` of its
        position along the trajectory.
        """
        passed = self.waypoint_arclength <= travelled + capture_radius
        return int(self.indices[passed][-1] + 1) if passed.any() else int(self.indices[0])


def replan_section(position, waypoints, next_index: int, occupied,
                   params: ReplanningParameters = ReplanningParameters(),
                   seed: int = 0, keep_offset=None) -> SectionPlan | None:
    """One replanning step: section, initial trajectory, STOMP against the occupied voxels.

    `occupied` is the on-line map (an `OctreeMap`, queried in the section's box only) or the
    (m, 3) centres of its occupied voxels; only those within reach of the section are used.
    `keep_offset` (one bool per waypoint, default all True) marks the waypoints that follow a
    wall at Omega (slicing contours); elsewhere (lanes, transits) only clearance and depth
    shape the trajectory, and the yaw follows the motion. Returns None when every waypoint
    was visited.
    """
    x = _check_position(position)
    waypoints = np.asarray(waypoints, dtype=float)
    idx = collect_section(x, waypoints, next_index, params.radius, params.max_waypoints)
    if len(idx) == 0:
        return None
    section = waypoints[idx]
    pts = np.vstack([x, section])
    # Within reach: the offset's horizontal range (2 Omega) plus the clearance, and the depths
    # of the offset band and of the clearance slab.
    reach = 2.0 * params.omega + params.clearance
    z_reach = max(params.depth_band, params.clearance + DEPTH_MARGIN)
    if params.offset_metric == "3d":
        z_reach = max(z_reach, 2.0 * params.omega)
    lo = pts.min(axis=0) - [reach, reach, z_reach]
    hi = pts.max(axis=0) + [reach, reach, z_reach]
    start = time.perf_counter()
    if hasattr(occupied, "occupied_points"):
        local = occupied.occupied_points(lo, hi)
    else:
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        local = occupied[np.all((occupied >= lo) & (occupied <= hi), axis=1)]
    query_time = time.perf_counter() - start
    slice_map = SliceMap(local, (pts[:, 2].min(), pts[:, 2].max()), params.depth_band,
                         params.clearance, metric=params.offset_metric)
    keep = (np.ones(len(waypoints), bool) if keep_offset is None
            else np.asarray(keep_offset, dtype=bool))[idx]
    theta0, fraction = initial_trajectory(x, section, slice_map, params.omega, params.spacing,
                                          keep)
    # A trajectory point keeps the offset when the waypoint it leads to does.
    keep_points = keep[np.minimum(np.searchsorted(fraction, np.linspace(0.0, 1.0, len(theta0))),
                                  len(keep) - 1)]
    # The depth to hold: the nominal polyline's before any offset correction (horizontal
    # metric: the slice plane), or the corrected one (3D metric: the offset moves depth too).
    if params.offset_metric == "3d":
        z_ref = theta0[:, 2]
    else:
        z_ref = resample_polyline(pts, params.spacing)
        z_ref = np.interp(np.linspace(0, 1, len(theta0)), np.linspace(0, 1, len(z_ref)),
                          z_ref[:, 2])
    cost = ReplanningCost(slice_map, z_ref, params, keep_points)
    result = stomp(theta0, cost, params.stomp, seed=seed, matrices=_matrices(len(theta0)))
    # Trajectory points are evenly spaced along the polyline, so a waypoint's fraction of it
    # maps to the same fraction of the optimised trajectory's points.
    s_opt = _arclength(result.trajectory)
    at = np.interp(fraction, np.linspace(0.0, 1.0, len(s_opt)), s_opt)
    d_h, nearest = slice_map.offset(result.trajectory, 2.0 * params.omega)
    facing = np.full(len(d_h), np.nan)
    seen = np.isfinite(d_h) & (d_h > 1e-6) & keep_points
    if seen.any():
        to = slice_map.band_points[nearest[seen], :2] - result.trajectory[seen, :2]
        facing[seen] = np.arctan2(to[:, 1], to[:, 0])
    return SectionPlan(idx, theta0, result.trajectory, at, result.initial_cost, result.cost,
                       result.iterations, query_time, facing)
