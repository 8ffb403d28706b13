"""The realtime replanning loop's sections (reference, Section 5.5.3), pure numpy/scipy: the
section bookkeeping and one step's orchestration; the map's distance fields are in
`replanning.fields`, the cost in `replanning.cost`, projection and arc length in
`planning.polyline`.

At each replanning step, with the vehicle at x (navigation frame):
1. `collect_section`: nominal waypoints w_i, in order from the next unvisited one, while
   |x - w_i| < R and at most K of them;
2. `initial_trajectory`: the polyline from x through them (planned on the prior map, which may
   be wrong by metres), resampled evenly;
3. `SliceMap` + `ReplanningCost` + `stomp`: the trajectory, its end free, optimised against
   the on-line map: STOMP alone moves it onto the offset Omega from the mapped structure, clear
   of it, and along the nominal path (`optimizer="none"` flies the initial trajectory);
4. `SectionPlan.next_index` and `passed_index`: the waypoints the flown part of the plan, or
   the vehicle's projection on the nominal path, has passed are marked visited (progress, not
   nearness to the waypoints, which the vehicle may never approach when the prior map is
   wrong).
`replan_section` runs `passed_index` and 1-3. Names: the on-line map is `octree_map` (the
reference's M); STOMP's smoothing matrix is `StompMatrices.smoothing`.

Choices the reference leaves open (docs/replanning.md): the offset Omega is kept in the
horizontal plane against occupied voxels within a depth band around the trajectory (the slice
plane of a contour path, so the seabed below does not count as the wall to follow), measured
on a 2D distance transform of that band; clearance counts every voxel in 3D; only voxels whose
log-odds reach `min_log_odds` count (an outlier hit once does not); a depth term keeps the
nominal depth, a progress term the advance along the nominal path.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from drake_auv.mapping.lattice import in_box
from drake_auv.planning.polyline import Polyline, arc_length, length, project, resample
from drake_auv.replanning.cost import ReplanningCost, inflated_clearance
from drake_auv.replanning.fields import DEPTH_MARGIN, SliceMap, TubeNodes
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.stomp import StompMatrices, stomp

OPTIMIZERS = ("stomp", "none")


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


def passed_index(position, waypoints, next_index: int, window: int,
                 capture_radius: float = 0.5) -> int:
    """`next_index` advanced past the waypoints the vehicle has passed along the nominal path:
    those whose arclength on the polyline w_(next-1) .. w_(next+window) is at most the
    vehicle's projection on it plus `capture_radius` (m). With a wrong prior map the vehicle
    flies parallel to the nominal path, metres from its waypoints, and may never come near
    them: its projection still advances with it. When every waypoint of the window is
    passed the window slides on from the last one, so a vehicle carried more than `window`
    waypoints along (a long replanning period, or a current) leaves none behind it as the
    section's target."""
    x = _check_position(position)
    waypoints = np.asarray(waypoints, dtype=float)
    next_index = int(next_index)
    while next_index < len(waypoints):
        first = max(next_index - 1, 0)
        stop = min(next_index + window + 1, len(waypoints))
        local = waypoints[first:stop]
        if len(local) < 2:
            return next_index
        s_x, _ = project(x[None], local)
        if s_x[0] <= 0.0:  # level with or before the polyline's start: passed only when near
            return next_index + int(np.linalg.norm(x - waypoints[next_index]) <= capture_radius)
        s_w = arc_length(local)[next_index - first:]
        passed = int(np.count_nonzero(s_w <= s_x[0] + capture_radius))
        if next_index + passed < stop:
            return next_index + passed
        next_index = stop  # all passed: the window slides on from its last waypoint
    return next_index


def resample_polyline(points, spacing: float) -> np.ndarray:
    """(N, 3) points evenly spaced by at most `spacing` along the polyline, ends kept, N >= 3
    (STOMP needs an interior point)."""
    points = np.asarray(points, dtype=float)
    total = length(points)
    if total <= 1e-9:
        return np.repeat(points[:1], 3, axis=0)
    return resample(points, min(spacing, total / 2.0))


def initial_trajectory(position, section_points, spacing: float) -> np.ndarray:
    """(N, 3) polyline from the vehicle through the section's waypoints (as planned on the
    prior map), resampled every `spacing` m."""
    x = _check_position(position)
    section_points = np.asarray(section_points, dtype=float).reshape(-1, 3)
    if len(section_points) == 0:
        raise ValueError("a section needs at least one waypoint")
    return resample_polyline(np.vstack([x, section_points]), spacing)


def warm_start(position, previous: np.ndarray, route: Polyline, section_points: np.ndarray,
               waypoint_s: np.ndarray, spacing: float) -> np.ndarray:
    """STOMP's initial trajectory from the last step's optimised one (receding horizon): from
    the vehicle, the part of `previous` (N', 3) ahead of it up to the section's last waypoint
    (by arclength along `route`; `waypoint_s`, m, per waypoint) or to where it turns back
    along the route, then the section's waypoints
    beyond that part's end; resampled every `spacing` m."""
    x = _check_position(position)
    s_x, _ = Polyline(previous).project(x[None])
    ahead = previous[arc_length(previous) > s_x[0] + 0.5 * spacing]
    # Up to the section's end, and up to where it would turn back along the route: the
    # trajectory neither outgrows the section nor carries a fold into the next step.
    progress = route.project(ahead)[0] if len(ahead) else np.zeros(0)
    stop = (progress > waypoint_s[-1] + spacing) | (
        progress < np.maximum.accumulate(progress) - spacing)
    ahead = ahead[np.cumsum(stop) == 0]
    s_end = route.project(ahead[-1:])[0][0] if len(ahead) else 0.0
    extra = section_points[waypoint_s > s_end + spacing]
    return resample_polyline(np.vstack([x, ahead, extra]), spacing)


def _crossing(slice_map: SliceMap, trajectory: np.ndarray) -> np.ndarray:
    """`SliceMap.crossing` of one trajectory (N, 3), its clearance ruling out the segments
    far from every voxel."""
    bound = slice_map.clearance_bound
    return slice_map.crossing(trajectory[None], slice_map.clearance(trajectory[None], bound),
                              bound)[0]


@lru_cache(maxsize=64)
def _matrices(num_points: int) -> StompMatrices:
    return StompMatrices(num_points, free_end=True)


@dataclass(frozen=True)
class SectionPlan:
    """One replanning step's result (navigation frame).

    Attributes:
        indices: the section's waypoint indices.
        initial, trajectory: (N, 3) initial and optimised trajectories, from the vehicle.
        waypoint_arclength: (len(indices),) where each waypoint falls along `trajectory`, m.
        initial_cost, cost, iterations: STOMP's (iterations 0 with optimizer "none").
        query_time: wall time of the map query (voxels and their log-odds in the box), s.
        map_voxels: the occupied voxels the query gave (before the log-odds threshold).
        facing: (N,) yaw of the horizontal direction from each trajectory point to its nearest
            mapped voxel of the depth band, rad; NaN where none lies within 2 Omega.
        tube: the offsets at the tube's nodes (`fields.TubeNodes`), for the next step's
            `replan_section(tube=...)`; None without a 3D tube.
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
    map_voxels: int
    tube: TubeNodes | None = None

    def next_index(self, travelled: float, capture_radius: float = 0.5) -> int:
        """The first waypoint not passed after flying `travelled` metres of the trajectory.

        A waypoint is passed when the flown distance comes within `capture_radius` of its
        position along the trajectory.
        """
        passed = self.waypoint_arclength <= travelled + capture_radius
        return int(self.indices[passed][-1] + 1) if passed.any() else int(self.indices[0])


def replan_section(position, waypoints, next_index: int, occupied,
                   params: ReplanningParameters = ReplanningParameters(),
                   seed: int | np.random.SeedSequence = 0, keep_offset=None,
                   optimizer: str = "stomp",
                   log_odds=None, previous=None,
                   tube: TubeNodes | None = None, current=None,
                   speed: float = 0.3) -> SectionPlan | None:
    """One replanning step: section, initial trajectory, STOMP against the on-line map.

    `occupied` is the on-line map (an `OctreeMap`, queried in the section's box only, with
    each voxel's log-odds) or the (m, 3) centres of its occupied voxels, with their
    `log_odds` (m,) (None: all count); only those within reach of the section are used.
    `keep_offset` (one bool per waypoint, default all True) marks the waypoints that follow a
    wall at Omega (slicing contours); elsewhere (lanes, transits) clearance, depth and the
    nominal route shape the trajectory, and the yaw follows the motion. `optimizer` "none"
    returns the initial trajectory (the polyline through the section's waypoints)
    unoptimised; with "stomp", `previous` (the last step's optimised trajectory, (N', 3))
    warm-starts STOMP (`warm_start`), and `tube` (the last step's `SectionPlan.tube`) spares
    the offsets at the tube's nodes that the map's changes since left as they were (the same
    numbers, `fields._TubeField3D`). `current` (positions (n, 3) -> (n, 3), world, m/s:
    the forecast water at the step's time, None: still water) with the survey `speed` (m/s)
    gives the cost its current terms (`ReplanningCost`). Returns None when every waypoint
    was visited.
    """
    if optimizer not in OPTIMIZERS:
        raise ValueError(f"optimizer must be one of {OPTIMIZERS}, got {optimizer!r}")
    x = _check_position(position)
    waypoints = np.asarray(waypoints, dtype=float)
    next_index = passed_index(x, waypoints, next_index, params.max_waypoints)
    idx = collect_section(x, waypoints, next_index, params.radius, params.max_waypoints)
    if len(idx) == 0:
        return None
    section = waypoints[idx]
    pts = np.vstack([x, section])
    keep = (np.ones(len(waypoints), bool) if keep_offset is None
            else np.asarray(keep_offset, dtype=bool))[idx]
    # The path of the progress and route terms: from the vehicle through the section and on
    # through the next 3 waypoints, so that the section's end is not the end of progress.
    route = Polyline(np.vstack([x, waypoints[int(idx[0]):min(int(idx[-1]) + 4,
                                                            len(waypoints))]]))
    waypoint_s = np.append(route.s0, route.length)[1:len(idx) + 1]
    # STOMP's seeds: the straight one through the section's waypoints, and the last step's
    # trajectory (`warm_start`), which must not pass through a mapped surface (below).
    seeds = [initial_trajectory(x, section, params.spacing)]
    if optimizer == "stomp" and previous is not None and len(previous) >= 2:
        seeds.append(warm_start(x, np.asarray(previous, dtype=float), route, section,
                                waypoint_s, params.spacing))
    # The forecast at the seeds' points: the cost's current, and the clearance it inflates
    # to, out to which the map is gathered (the same numbers: `inflated_clearance`).
    water = None if current is None else np.asarray(current(np.vstack(seeds)), dtype=float)
    clearance = inflated_clearance(params, water)
    # Within reach: where the trajectory may go (the points plus the margin), plus the
    # offset's range (Omega + 1 m) or the clearance, and the depths of the offset band and
    # of the clearance slab. A section without offset (lanes, transits) needs only the
    # clearance: on the boulder's lanes the offset's reach took in the seabed below.
    if keep.any():
        reach = params.margin + max(params.omega + 1.0, clearance)
        z_reach = max(params.depth_band, clearance + DEPTH_MARGIN)
        if params.offset_metric == "3d":
            z_reach = max(z_reach, reach)
    else:
        reach, z_reach = params.margin + clearance, clearance + DEPTH_MARGIN
    extent = np.vstack([pts, *seeds])
    lo = extent.min(axis=0) - [reach, reach, z_reach]
    hi = extent.max(axis=0) + [reach, reach, z_reach]
    start = time.perf_counter()
    resolution = 0.5
    if hasattr(occupied, "occupied_points"):
        local, log_odds = occupied.occupied_points(lo, hi, log_odds=True)
        resolution = occupied.resolution
    else:
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        inside = in_box(occupied, lo, hi)
        local = occupied[inside]
        if log_odds is not None:
            log_odds = np.asarray(log_odds, dtype=float)[inside]
    query_time = time.perf_counter() - start
    slice_map = SliceMap(local, (pts[:, 2].min(), pts[:, 2].max()), params.depth_band,
                         clearance, metric=params.offset_metric, log_odds=log_odds,
                         min_log_odds=params.min_log_odds, box=(lo, hi),
                         resolution=resolution)
    # A warm start through a mapped surface (the map has grown since it was planned: a loop
    # through a structure whose faces are now seen) is dropped for the straight seed.
    first = 0 if len(seeds) == 1 or _crossing(slice_map, seeds[1]).any() else 1
    theta0 = seeds[first]
    if water is not None:
        water = water[len(seeds[0]):] if first else water[:len(seeds[0])]

    def keeps(points):  # a trajectory point keeps the offset when the waypoint it leads to does
        return keep[np.minimum(np.searchsorted(waypoint_s, route.project(points)[0]),
                               len(keep) - 1)]

    keep_points = keeps(theta0)
    cost = ReplanningCost(slice_map, route, theta0, params, keep_points,
                          goal=float(waypoint_s[-1]), current=water, speed=speed)
    nodes = None
    if optimizer == "stomp":
        if keep_points.any():  # the rollouts' reach: twice the largest per-point noise
            nodes = slice_map.prepare_tube(theta0[keep_points],
                                           2.0 * float(np.max(params.stomp.noise_std)), tube)
        result = stomp(theta0, cost, params.stomp, seed=seed, matrices=_matrices(len(theta0)),
                       free_end=True)
        trajectory, initial_cost = result.trajectory, result.initial_cost
        final_cost, iterations = result.cost, result.iterations
        # Never through a mapped surface: when STOMP found no way around one (a seed
        # through the structure), the plan stops short of it and the next step replans.
        inside = _crossing(slice_map, trajectory)
        if inside.any():
            trajectory = trajectory[:int(np.argmax(inside > 0))]
            if len(trajectory) < 3:
                trajectory = resample_polyline(trajectory, params.spacing)
            keep_points = keeps(trajectory)
    else:
        trajectory, iterations = theta0, 0
        initial_cost = final_cost = float(cost(theta0[None]).sum())
    # A waypoint is passed where the trajectory's progress along the route reaches it (the
    # trajectory need not come near it: the prior map may have put it inside the structure).
    progress = np.maximum.accumulate(route.project(trajectory)[0])
    s_opt = arc_length(trajectory)
    at = np.interp(waypoint_s, progress, s_opt, right=np.inf)
    d_h, nearest = slice_map.nearest_band(trajectory, 2.0 * params.omega)
    facing = np.full(len(d_h), np.nan)
    seen = np.isfinite(d_h) & (d_h > 1e-6) & keep_points
    if seen.any():
        to = slice_map.band_points[nearest[seen], :2] - trajectory[seen, :2]
        facing[seen] = np.arctan2(to[:, 1], to[:, 0])
    return SectionPlan(idx, theta0, trajectory, at, initial_cost, final_cost, iterations,
                       query_time, facing, len(local), nodes)
