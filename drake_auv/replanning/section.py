"""The pieces of the realtime replanning loop (reference, Section 5.5.3), pure numpy/scipy.

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
from scipy import ndimage
from scipy.spatial import cKDTree

from drake_auv.params import nested, param, validate
from drake_auv.planning.polyline import length, resample
from drake_auv.replanning.stomp import StompMatrices, StompParameters, stomp

OPTIMIZERS = ("stomp", "none")


@dataclass(frozen=True)
class ReplanningParameters:
    """Parameters of the replanning loop (cost weights: docs/replanning.md, "Cost"); ranges
    in the fields' `param` metadata, `key`: the mission file's name of a field.

    Attributes:
        radius: R, waypoints closer than this to the vehicle form the section, m.
        max_waypoints: K, most waypoints in one section.
        omega: offset to keep from the mapped structure, m (> 0).
        clearance: distance to any occupied voxel under which the obstacle cost rises, m.
        depth_band: half-height of the band of voxels the offset is measured against, m (> 0).
        offset_metric: "horizontal": the offset is the horizontal distance to the band's
            voxels (walls with the seabed closer than Omega below, as at the breakwater);
            "3d": the 3D distance to any voxel, the offset along the surface normal of the
            slicing planner (sloping faces, as on the boulder).
        spacing: distance between trajectory points, m (> 0).
        margin: how far the optimised trajectory may leave the initial one (the largest
            prior-map plus navigation error the plan assumes), m (> 0); sizes the map query.
        min_log_odds: log-odds a voxel needs to count in the cost (1.5: two hits more than
            the misses, with OctoMap's 0.7 / 0.4 model one hit is 0.85), >= 0.
        huber: |d - Omega| beyond which the offset cost grows linearly, m (> 0).
        offset_weight, obstacle_weight, depth_weight, route_weight, progress_weight,
        terminal_weight, spacing_weight: cost weights (>= 0), per trajectory point.
        stomp: `StompParameters` (rollouts, iterations, noise, smoothness weight).
    """

    radius: float = param(5.0, low=0.5, high=50.0, unit="m", key="R")
    max_waypoints: int = param(10, low=1, high=200, integer=True, key="K")
    omega: float = param(6.0, low=0.0, low_open=True, unit="m")
    clearance: float = param(4.0, low=0.5, high=20.0, unit="m", key="clearance_m")
    depth_band: float = param(1.5, low=0.0, low_open=True, unit="m")
    offset_metric: str = param("horizontal", kind="choice", choices=("horizontal", "3d"))
    spacing: float = param(0.5, low=0.0, low_open=True, unit="m")
    margin: float = param(6.0, low=0.0, low_open=True, unit="m")
    min_log_odds: float = param(1.5, low=0.0)
    huber: float = param(1.0, low=0.0, low_open=True, unit="m")
    offset_weight: float = param(3.0, low=0.0)
    obstacle_weight: float = param(50.0, low=0.0)
    depth_weight: float = param(1.0, low=0.0)
    route_weight: float = param(1.0, low=0.0)
    progress_weight: float = param(0.1, low=0.0)
    terminal_weight: float = param(3.0, low=0.0)
    spacing_weight: float = param(10.0, low=0.0)
    stomp: StompParameters = nested(StompParameters, lambda: StompParameters(
        num_rollouts=10, max_iterations=40, noise_std=0.5, smoothness_weight=50.0,
        patience=8))

    def __post_init__(self):
        validate(self)


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
    them: its projection still advances with it."""
    x = _check_position(position)
    waypoints = np.asarray(waypoints, dtype=float)
    next_index = int(next_index)
    first = max(next_index - 1, 0)
    local = waypoints[first:min(next_index + window + 1, len(waypoints))]
    if len(local) < 2:
        return next_index
    s_x, _ = polyline_progress(x[None], local)
    if s_x[0] <= 0.0:  # level with or before the polyline's start: passed only when near
        return next_index + int(np.linalg.norm(x - waypoints[next_index]) <= capture_radius)
    s_w = _arclength(local)[next_index - first:]
    return next_index + int(np.count_nonzero(s_w <= s_x[0] + capture_radius))


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
    metres away, where the voxels of a surface are nearly equidistant and a default tree
    visits many small leaves. Large, unbalanced (sliding-midpoint) leaves answer the same
    nearest neighbours 2-4x faster here and build faster."""
    return cKDTree(points, leafsize=64, balanced_tree=False, compact_nodes=False)


class _DistanceField2D:
    """Euclidean distance transform (`scipy.ndimage.distance_transform_edt`) of voxel
    columns (m, 2) on the voxel grid over the box [lo, hi] (m), cell centres on the voxel
    centres; distances from the box's voxels to the nearest column, m."""

    def __init__(self, points: np.ndarray, lo: np.ndarray, hi: np.ndarray, resolution: float):
        self.origin = (np.floor(lo / resolution) + 0.5) * resolution  # the first cell's centre
        self.cell = resolution
        shape = np.floor((hi - self.origin) / resolution).astype(int) + 2
        cells = np.round((points - self.origin) / resolution).astype(int)
        cells = cells[np.all((cells >= 0) & (cells < shape), axis=1)]
        free = np.ones(shape, bool)
        free[cells[:, 0], cells[:, 1]] = False
        self.field = (ndimage.distance_transform_edt(free, sampling=resolution) if len(cells)
                      else np.full(shape, np.inf))
        self._last = (np.array(shape) - 1)[:, None]  # the largest cell index per axis

    def _coords(self, points: np.ndarray) -> np.ndarray:
        return ((points[:, :2] - self.origin) / self.cell).T

    def interpolate(self, points: np.ndarray) -> np.ndarray:
        """(n,) bilinear interpolation at `points` (n, >= 2); the box's edge beyond it."""
        return ndimage.map_coordinates(self.field, self._coords(points), order=1,
                                       mode="nearest")

    def lower_bound(self, points: np.ndarray) -> np.ndarray:
        """(n,) at most the distance from `points` (inside the box) to the nearest column:
        the nearest cell's value less half a cell diagonal."""
        idx = np.rint(self._coords(points)).astype(int)
        np.maximum(idx, 0, out=idx)
        np.minimum(idx, self._last, out=idx)
        return self.field[idx[0], idx[1]] - self.cell * np.sqrt(0.5)


@lru_cache(maxsize=8)
def _ball_offsets(radius: float) -> np.ndarray:
    """(m, 3) integer grid offsets within `radius` + sqrt(3) cells of the origin: every
    corner of the cells of points within `radius` cells."""
    reach = radius + np.sqrt(3.0)
    r = int(np.ceil(reach))
    grid = np.arange(-r, r + 1)
    offsets = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), axis=-1).reshape(-1, 3)
    return offsets[np.einsum("ij,ij->i", offsets, offsets) <= reach * reach]


class _TubeField3D:
    """The exact 3D distance to a KD-tree's points at the grid nodes (spacing `cell`, m)
    around a trajectory (N, 3), read by trilinear interpolation: NaN where a point's cell has
    a corner that was not computed (more than `pad` m from every trajectory point).

    STOMP's rollouts stay near the trajectory it starts from, and exact nearest-voxel queries
    from 6-10 m away cost ~3 us a point (1 ms for 11 rollouts of 30 points, 40 times a step
    on the boulder); computing the nodes once and interpolating costs one query per node.
    The distance field is smooth away from the surface, so at 0.5 m nodes the interpolation
    error is millimetres at the offset."""

    def __init__(self, tree: cKDTree, trajectory: np.ndarray, pad: float, cell: float):
        self.cell = cell
        self.origin = np.floor((trajectory.min(axis=0) - pad) / cell) * cell - cell
        self.shape = tuple(np.floor((trajectory.max(axis=0) + pad - self.origin) / cell)
                           .astype(int) + 3)
        centres = np.rint((trajectory - self.origin) / cell).astype(int)
        nodes = (centres[:, None, :] + _ball_offsets(pad / cell)[None]).reshape(-1, 3)
        nodes = nodes[np.all((nodes >= 0) & (nodes < self.shape), axis=1)]
        flat = np.unique(np.ravel_multi_index(nodes.T, self.shape))
        self.field = np.full(self.shape, np.nan)
        node_points = np.column_stack(np.unravel_index(flat, self.shape)) * cell + self.origin
        self.field.flat[flat] = tree.query(node_points)[0]

    def interpolate(self, points: np.ndarray) -> np.ndarray:
        """(n,) trilinear interpolation at `points` (n, 3); NaN outside the computed nodes."""
        return ndimage.map_coordinates(self.field, ((points - self.origin) / self.cell).T,
                                       order=1, mode="constant", cval=np.nan)


class SliceMap:
    """The on-line map near a section, as the fields the replanning cost reads.

    Built once per replanning step from the occupied voxels in the section's box whose
    log-odds reach `min_log_odds` (all of them when no log-odds are given):
    - offset, metric "horizontal": a 2D Euclidean distance transform (`scipy.ndimage`) of the
      voxels within `depth_band` of the section's depths, on the voxel grid over the box,
      read by bilinear interpolation; metric "3d": the exact 3D distance to any voxel (a
      KD-tree: a 3D transform of the box costs 10-30 ms here). inf where none is mapped;
    - clearance: the exact 3D distance to the voxels within `clearance + margin` of the
      section's depths, the only ones that can be nearer than `clearance` to a point of the
      section (rollouts stay within `margin` of its depths: the depth cost holds them); a 2D
      distance transform of that slab rules most points out, a 3D KD-tree measures the rest;
    - `band_points` / `nearest_band`: the band's voxels, for the yaw that faces them.
    """

    def __init__(self, occupied: np.ndarray, z_range: tuple[float, float], depth_band: float,
                 clearance: float, margin: float = DEPTH_MARGIN, metric: str = "horizontal",
                 log_odds: np.ndarray | None = None, min_log_odds: float = 0.0,
                 box: tuple | None = None, resolution: float = 0.5):
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        if log_odds is not None:
            occupied = occupied[np.asarray(log_odds, dtype=float) >= min_log_odds]
        z = occupied[:, 2]
        if metric == "3d":
            self.dims = 3
            self.band_points = occupied
        else:
            self.dims = 2
            in_band = (z >= z_range[0] - depth_band) & (z <= z_range[1] + depth_band)
            self.band_points = occupied[in_band, :2]
        self.band_tree = _kdtree(self.band_points) if len(self.band_points) else None
        if box is None:  # the occupied voxels' box, widened by the reach of the offset
            box = (occupied.min(axis=0) - 15.0, occupied.max(axis=0) + 15.0) if len(
                occupied) else (np.zeros(3), np.zeros(3))
        lo, hi = np.asarray(box[0], dtype=float)[:2], np.asarray(box[1], dtype=float)[:2]
        self._field = (_DistanceField2D(self.band_points, lo, hi, resolution)
                       if self.dims == 2 and len(self.band_points) else None)
        reach = clearance + margin
        slab = occupied[(z >= z_range[0] - reach) & (z <= z_range[1] + reach)]
        # Horizontal distance to the slab: a lower bound of the 3D one that rules most points
        # out before the exact 3D query.
        self._slab_field = _DistanceField2D(slab[:, :2], lo, hi, resolution) if len(
            slab) else None
        self.slab_tree_3d = _kdtree(slab) if len(slab) else None
        self._tube = None
        self.resolution = resolution

    def prepare_tube(self, trajectory: np.ndarray, pad: float) -> None:
        """Metric "3d": precomputes the offset on the grid nodes within `pad` m of
        `trajectory` (N, 3) (`_TubeField3D`); `offset` interpolates there and queries the
        KD-tree exactly elsewhere. No effect for the horizontal metric (already a field)."""
        if self.dims == 3 and self.band_tree is not None:
            self._tube = _TubeField3D(self.band_tree, np.asarray(trajectory, dtype=float),
                                      pad, self.resolution)

    def clearance(self, points: np.ndarray, upper_bound: float) -> np.ndarray:
        """3D distance to the nearest counted voxel centre, inf beyond `upper_bound`, m."""
        flat = points.reshape(-1, 3)
        d = np.full(len(flat), np.inf)
        if self._slab_field is None:
            return d.reshape(points.shape[:-1])
        near = self._slab_field.lower_bound(flat) < upper_bound
        if near.any():
            d[near], _ = self.slab_tree_3d.query(flat[near], distance_upper_bound=upper_bound)
        return d.reshape(points.shape[:-1])

    def offset(self, points: np.ndarray) -> np.ndarray:
        """Distance from `points` (..., 3) to the band's voxels (horizontal or 3D), m; inf
        where the band holds none."""
        shape = points.shape[:-1]
        if self.band_tree is None:
            return np.full(shape, np.inf)
        if self._field is None:
            flat = points.reshape(-1, 3)
            if self._tube is None:
                return self.band_tree.query(flat)[0].reshape(shape)
            d = self._tube.interpolate(flat)
            outside = np.isnan(d)
            if outside.any():
                d[outside] = self.band_tree.query(flat[outside])[0]
            return d.reshape(shape)
        return self._field.interpolate(points.reshape(-1, 3)).reshape(shape)

    def nearest_band(self, points: np.ndarray, upper_bound: float):
        """Distance to, and index in `band_points` of, the nearest band voxel, m (inf, and
        len(band_points), beyond `upper_bound`)."""
        if self.band_tree is None:
            n = len(points)
            return np.full(n, np.inf), np.zeros(n, dtype=int)
        return self.band_tree.query(points[:, :self.dims], distance_upper_bound=upper_bound)


class Polyline:
    """A polyline (M >= 2, 3) prepared for projections: `project(points)` gives the arclength
    (m) of the nearest point on it to each of `points` (..., 3), and the distance to it (m)."""

    def __init__(self, points: np.ndarray):
        points = np.asarray(points, dtype=float)
        self.a, self.ab = points[:-1], np.diff(points, axis=0)
        self.seg_sq = np.maximum(np.einsum("mk,mk->m", self.ab, self.ab), 1e-12)
        self.seg_len = np.sqrt(self.seg_sq)
        self.s0 = np.concatenate([[0.0], np.cumsum(self.seg_len)])[:-1]
        self.length = float(self.seg_len.sum())
        self.a_ab = np.einsum("mk,mk->m", self.a, self.ab)
        self.a_sq = np.einsum("mk,mk->m", self.a, self.a)
        self._ab_a = np.vstack([self.ab, -2.0 * self.a]).T  # (3, 2m): p.ab and -2 p.a at once

    def project(self, points: np.ndarray):
        flat = points.reshape(-1, 3)
        # |p - a - t ab|^2 = |p|^2 - 2 p.a + |a|^2 - 2 t (p - a).ab + t^2 |ab|^2 from one
        # (n, 3) x (3, 2m) product (the segments' a and ab are fixed); |p|^2 is the same for
        # every segment, so it is added after the nearest segment is chosen.
        m = len(self.a)
        products = flat @ self._ab_a
        u = products[:, :m] - self.a_ab  # (p - a).ab
        t = u / self.seg_sq
        np.minimum(t, 1.0, out=t)
        np.maximum(t, 0.0, out=t)
        gap = products[:, m:] + self.a_sq + t * (t * self.seg_sq - 2.0 * u)
        best = np.argmin(gap, axis=1)
        rows = np.arange(len(best))
        s = self.s0[best] + t[rows, best] * self.seg_len[best]
        gap_sq = gap[rows, best] + np.einsum("nk,nk->n", flat, flat)
        return (s.reshape(points.shape[:-1]),
                np.sqrt(np.maximum(gap_sq, 0.0)).reshape(points.shape[:-1]))


def polyline_progress(points: np.ndarray, polyline: np.ndarray):
    """Arclength along `polyline` (M >= 2, 3) of the nearest point to each of `points`
    (..., 3), and the distance to it, m."""
    return Polyline(polyline).project(np.asarray(points, dtype=float))


def _huber(x: np.ndarray, delta: float) -> np.ndarray:
    """x^2 within delta, 2 delta |x| - delta^2 beyond (same value and slope at delta)."""
    a = np.abs(x)
    return np.where(a <= delta, a * a, 2.0 * delta * a - delta * delta)


class ReplanningCost:
    """Per-timestep state cost of STOMP rollouts (K, N, 3) -> (K, N), the sum of `terms`.

    Per point i (weights in `ReplanningParameters`; docs/replanning.md says why each):
    - offset (points that keep it): huber(d_i - Omega), d the `SliceMap.offset` field;
      0 where nothing is mapped;
    - obstacle: max(0, clearance - c_i)^2, c the 3D distance to the counted voxels;
    - depth: (z_i - z_ref_i)^2 (horizontal metric; 3D metric: points without offset only);
    - route (points without offset: lanes, transits): squared distance to the route;
    - progress: max(0, s_ref_i - s_i)^2, s_i the arclength of point i projected on the
      route (the vehicle, the section's waypoints and the next ones) and s_ref_i an even
      advance from the vehicle (0) to `goal` (the section's last waypoint), so lagging
      (hovering) costs;
    - spacing: (|p_i - p_(i-1)| - spacing)^2 (0 at the first point): evenly spaced points, so
      the trajectory neither bunches (hovers) nor folds back on itself;
    - terminal (last point only, times `terminal_weight`): its offset and progress terms
      again, the goal set of the free end.

    `initial` (N, 3) is the initial trajectory (its depths are z_ref); `route` (M >= 2, 3)
    the nominal path from the vehicle's position; `goal` the arclength along it (m) that the
    trajectory's end should reach.
    """

    def __init__(self, slice_map: SliceMap, route: np.ndarray, initial: np.ndarray,
                 params: ReplanningParameters, keep_offset: np.ndarray | None = None,
                 goal: float | None = None):
        self.slice_map = slice_map
        self.route = route if isinstance(route, Polyline) else Polyline(route)
        initial = np.asarray(initial, dtype=float)
        self.z_ref = initial[:, 2]
        self.params = params
        n = len(self.z_ref)
        self.keep = (np.ones(n, bool) if keep_offset is None
                     else np.asarray(keep_offset, dtype=bool))
        self._keep_all = bool(self.keep.all())
        self.s_ref = np.linspace(0.0, self.route.length if goal is None else goal, n)
        depth = np.full(n, params.depth_weight)
        if params.offset_metric == "3d":
            depth[self.keep] = 0.0  # the offset along the normal sets the depth there
        self.depth_weight = depth

    def terms(self, trajectories: np.ndarray) -> dict:
        """The unweighted per-point terms (K, N) of `trajectories` (K, N, 3)."""
        p = self.params
        shape = trajectories.shape[:-1]
        if self._keep_all:  # contours: every point keeps the offset, none follows the route
            d = self.slice_map.offset(trajectories)
            offset = np.where(np.isfinite(d), _huber(d - p.omega, p.huber), 0.0)
        else:
            offset = np.zeros(shape)
            if self.keep.any():
                d = self.slice_map.offset(trajectories[..., self.keep, :])
                offset[..., self.keep] = np.where(np.isfinite(d), _huber(d - p.omega, p.huber),
                                                  0.0)
        c = self.slice_map.clearance(trajectories, p.clearance)
        s, gap = self.route.project(trajectories)
        route = np.zeros(shape) if self._keep_all else np.where(self.keep, 0.0, gap * gap)
        lag = self.s_ref - s
        np.maximum(lag, 0.0, out=lag)
        obstacle = p.clearance - c
        np.maximum(obstacle, 0.0, out=obstacle)
        step = trajectories[..., 1:, :] - trajectories[..., :-1, :]
        spacing = np.empty(shape)
        spacing[..., 0] = 0.0
        spacing[..., 1:] = (np.sqrt(np.einsum("...k,...k->...", step, step)) - p.spacing) ** 2
        depth = trajectories[..., 2] - self.z_ref
        return dict(offset=offset, obstacle=obstacle * obstacle, depth=depth * depth,
                    route=route, progress=lag * lag, spacing=spacing)

    def __call__(self, trajectories: np.ndarray) -> np.ndarray:
        p, t = self.params, self.terms(trajectories)
        cost = (p.offset_weight * t["offset"] + p.obstacle_weight * t["obstacle"]
                + self.depth_weight * t["depth"] + p.progress_weight * t["progress"]
                + p.spacing_weight * t["spacing"])
        if not self._keep_all:
            cost += p.route_weight * t["route"]
        cost[..., -1] += p.terminal_weight * (p.offset_weight * t["offset"][..., -1]
                                              + p.progress_weight * t["progress"][..., -1])
        return cost


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
    ahead = previous[_arclength(previous) > s_x[0] + 0.5 * spacing]
    # Up to the section's end, and up to where it would turn back along the route: the
    # trajectory neither outgrows the section nor carries a fold into the next step.
    progress = route.project(ahead)[0] if len(ahead) else np.zeros(0)
    stop = (progress > waypoint_s[-1] + spacing) | (
        progress < np.maximum.accumulate(progress) - spacing)
    ahead = ahead[np.cumsum(stop) == 0]
    s_end = route.project(ahead[-1:])[0][0] if len(ahead) else 0.0
    extra = section_points[waypoint_s > s_end + spacing]
    return resample_polyline(np.vstack([x, ahead, extra]), spacing)


def _arclength(points: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1))])


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
                   seed: int = 0, keep_offset=None, optimizer: str = "stomp",
                   log_odds=None, previous=None) -> SectionPlan | None:
    """One replanning step: section, initial trajectory, STOMP against the on-line map.

    `occupied` is the on-line map (an `OctreeMap`, queried in the section's box only, with
    each voxel's log-odds) or the (m, 3) centres of its occupied voxels, with their
    `log_odds` (m,) (None: all count); only those within reach of the section are used.
    `keep_offset` (one bool per waypoint, default all True) marks the waypoints that follow a
    wall at Omega (slicing contours); elsewhere (lanes, transits) clearance, depth and the
    nominal route shape the trajectory, and the yaw follows the motion. `optimizer` "none"
    returns the initial trajectory (the polyline through the section's waypoints)
    unoptimised; with "stomp", `previous` (the last step's optimised trajectory, (N', 3))
    warm-starts STOMP (`warm_start`). Returns None when every waypoint was visited.
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
    # Within reach: where the trajectory may go (the points plus the margin), plus the
    # offset's range (Omega + 1 m) or the clearance, and the depths of the offset band and
    # of the clearance slab. A section without offset (lanes, transits) needs only the
    # clearance: on the boulder's lanes the offset's reach took in the seabed below.
    if keep.any():
        reach = params.margin + max(params.omega + 1.0, params.clearance)
        z_reach = max(params.depth_band, params.clearance + DEPTH_MARGIN)
        if params.offset_metric == "3d":
            z_reach = max(z_reach, reach)
    else:
        reach, z_reach = params.margin + params.clearance, params.clearance + DEPTH_MARGIN
    lo = pts.min(axis=0) - [reach, reach, z_reach]
    hi = pts.max(axis=0) + [reach, reach, z_reach]
    start = time.perf_counter()
    resolution = 0.5
    if hasattr(occupied, "occupied_points"):
        local, log_odds = occupied.occupied_points(lo, hi, log_odds=True)
        resolution = occupied.resolution
    else:
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        inside = np.all((occupied >= lo) & (occupied <= hi), axis=1)
        local = occupied[inside]
        if log_odds is not None:
            log_odds = np.asarray(log_odds, dtype=float)[inside]
    query_time = time.perf_counter() - start
    slice_map = SliceMap(local, (pts[:, 2].min(), pts[:, 2].max()), params.depth_band,
                         params.clearance, metric=params.offset_metric, log_odds=log_odds,
                         min_log_odds=params.min_log_odds, box=(lo, hi),
                         resolution=resolution)
    # The path of the progress and route terms: from the vehicle through the section and on
    # through the next 3 waypoints, so that the section's end is not the end of progress.
    route = Polyline(np.vstack([x, waypoints[int(idx[0]):min(int(idx[-1]) + 4,
                                                            len(waypoints))]]))
    waypoint_s = np.append(route.s0, route.length)[1:len(idx) + 1]
    if optimizer == "stomp" and previous is not None and len(previous) >= 2:
        theta0 = warm_start(x, np.asarray(previous, dtype=float), route, section, waypoint_s,
                            params.spacing)
    else:
        theta0 = initial_trajectory(x, section, params.spacing)
    # A trajectory point keeps the offset when the waypoint it leads to does.
    keep_points = keep[np.minimum(np.searchsorted(waypoint_s, route.project(theta0)[0]),
                                  len(keep) - 1)]
    cost = ReplanningCost(slice_map, route, theta0, params, keep_points,
                          goal=float(waypoint_s[-1]))
    if optimizer == "stomp":
        if keep_points.any():  # the rollouts' reach: twice the largest per-point noise
            slice_map.prepare_tube(theta0[keep_points],
                                   2.0 * float(np.max(params.stomp.noise_std)))
        result = stomp(theta0, cost, params.stomp, seed=seed, matrices=_matrices(len(theta0)),
                       free_end=True)
        trajectory, initial_cost = result.trajectory, result.initial_cost
        final_cost, iterations = result.cost, result.iterations
    else:
        trajectory, iterations = theta0, 0
        initial_cost = final_cost = float(cost(theta0[None]).sum())
    # A waypoint is passed where the trajectory's progress along the route reaches it (the
    # trajectory need not come near it: the prior map may have put it inside the structure).
    progress = np.maximum.accumulate(route.project(trajectory)[0])
    s_opt = _arclength(trajectory)
    at = np.interp(waypoint_s, progress, s_opt, right=np.inf)
    d_h, nearest = slice_map.nearest_band(trajectory, 2.0 * params.omega)
    facing = np.full(len(d_h), np.nan)
    seen = np.isfinite(d_h) & (d_h > 1e-6) & keep_points
    if seen.any():
        to = slice_map.band_points[nearest[seen], :2] - trajectory[seen, :2]
        facing[seen] = np.arctan2(to[:, 1], to[:, 0])
    return SectionPlan(idx, theta0, trajectory, at, initial_cost, final_cost, iterations,
                       query_time, facing)
