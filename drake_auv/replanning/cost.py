"""The replanning cost STOMP minimises (reference, Section 5.5.3; weights and why each term:
docs/replanning.md, "Cost"), pure numpy."""

from __future__ import annotations

import numpy as np

from drake_auv.planning.polyline import Polyline
from drake_auv.replanning.fields import SliceMap
from drake_auv.replanning.parameters import ReplanningParameters


def inflated_clearance(params: ReplanningParameters, current: np.ndarray | None) -> float:
    """The largest clearance the obstacle term asks, m: `params.clearance` plus tau times the
    fastest of the forecast `current` (n, 3) (m/s; None: still water). The section gathers
    the map's voxels out to it (`replan_section`) from the same forecast points."""
    if current is None or not len(current):
        return params.clearance
    return params.clearance + params.current_margin_s * float(
        np.linalg.norm(current, axis=1).max())


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
    - crossing: the length (m) of the segment into point i that runs inside a counted voxel
      (`SliceMap.crossing`): a trajectory may not pass through a mapped surface, which the
      clearance alone allows where a structure is known only by its faces (its inside is
      2.5 m from the nearest voxel in a 5 m block);
    - depth: (z_i - z_ref_i)^2, z_ref_i the nominal depth (the route's waypoints', where
      point i of the initial trajectory projects on it; the first waypoint's before it), so
      neither warm starts nor the vehicle's own depth carry a drift from step to step
      (horizontal metric; 3D metric: points without offset only);
    - route (points without offset: lanes, transits): squared distance to the route;
    - progress: max(0, s_ref_i - s_i)^2, s_i the arclength of point i projected on the
      route (the vehicle, the section's waypoints and the next ones) and s_ref_i an even
      advance from the vehicle (0) to `goal` (the section's last waypoint), so lagging
      (hovering) costs;
    - spacing: (|p_i - p_(i-1)| - spacing)^2 (0 at the first point): evenly spaced points, so
      the trajectory neither bunches (hovers) nor folds back on itself;
    - terminal (last point only, times `terminal_weight`): its offset and progress terms
      again, the goal set of the free end.
    With a forecast `current` (N, 3) (world, m/s, the water at the initial trajectory's points)
    and the survey `speed` (m/s), two terms know the sea:
    - effort: |v t_i - c_i|^2 / v^2 (0 at the first point), the squared speed through the
      water the vehicle must make good to fly the step into point i at the survey speed v
      along its direction t_i, over v^2 (1 in still water): a head current costs more;
    - obstacle: the clearance inflated to clearance + tau max(0, c_i . n_i), n_i the unit
      vector to the nearest counted voxel and tau `current_margin_s`: larger on the side the
      current pushes towards; at most the map's `SliceMap.clearance_bound` (the section's
      clearance, from the same forecast), beyond which its voxels are not gathered.
    Without a current both are as in still water, bit for bit (no effort term is added).

    `initial` (N, 3) is the initial trajectory (where its points project on the route sets
    z_ref); `route` (M >= 2, 3) the nominal path from the vehicle's position; `goal` the
    arclength along it (m) that the trajectory's end should reach.
    """

    def __init__(self, slice_map: SliceMap, route: np.ndarray, initial: np.ndarray,
                 params: ReplanningParameters, keep_offset: np.ndarray | None = None,
                 goal: float | None = None, current: np.ndarray | None = None,
                 speed: float = 0.3):
        self.slice_map = slice_map
        self.route = route if isinstance(route, Polyline) else Polyline(route)
        initial = np.asarray(initial, dtype=float)
        knots = np.append(self.route.s0, self.route.length)
        depths = np.append(self.route.a[:, 2], self.route.a[-1, 2] + self.route.ab[-1, 2])
        depths[0] = depths[1]  # the route starts at the vehicle: the nominal depth is ahead
        self.z_ref = np.interp(self.route.arclength(initial), knots, depths)
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
        self._depth_any = bool(depth.any())
        self.current = None if current is None else np.asarray(current, dtype=float)
        if self.current is not None:
            if self.current.shape != (n, 3) or not np.isfinite(self.current).all():
                raise ValueError(f"current must be finite of shape ({n}, 3) m/s, got "
                                 f"{self.current.shape}")
            if not (np.isfinite(speed) and speed > 0):
                raise ValueError(f"speed must be > 0 m/s, got {speed}")
            self._water = self.current[1:] / speed  # c_i / v, the effort's
        self.max_clearance = min(inflated_clearance(params, self.current),
                                 slice_map.clearance_bound)

    def _offset(self, points: np.ndarray) -> np.ndarray:
        """The offset term of `points` (..., 3); 0 where nothing is mapped."""
        d = self.slice_map.offset(points)
        if not self.slice_map.offset_mapped:  # inf everywhere
            return np.zeros(d.shape)
        return _huber(d - self.params.omega, self.params.huber)

    def _terms(self, trajectories: np.ndarray, weighted: bool = False) -> tuple:
        """The terms of `terms`, in its order; None for a term that is 0 everywhere: route
        where every point keeps the offset, obstacle where no point can be within the
        clearance (`SliceMap.within`), and with `weighted` depth where its weights are all 0
        (so the cost skips them: adding an exact 0 changes no sum)."""
        p = self.params
        shape = trajectories.shape[:-1]
        if self._keep_all:  # contours: every point keeps the offset, none follows the route
            offset = self._offset(trajectories)
            s, route = self.route.arclength(trajectories), None
        else:
            offset = np.zeros(shape)
            if self.keep.any():
                offset[..., self.keep] = self._offset(trajectories[..., self.keep, :])
            s, gap = self.route.project(trajectories)
            route = np.where(self.keep, 0.0, gap * gap)
        lag = self.s_ref - s
        np.maximum(lag, 0.0, out=lag)
        step = trajectories[..., 1:, :] - trajectories[..., :-1, :]
        gap = np.einsum("...k,...k->...", step, step)  # in place: (sqrt(gap) - spacing)^2
        np.sqrt(gap, out=gap)
        obstacle, d, bound = None, None, self.max_clearance
        if self.slice_map.within(trajectories, bound):
            if self.current is None:
                d = self.slice_map.clearance(trajectories, bound)
                obstacle = bound - d
            else:
                d, to = self.slice_map.clearance_towards(trajectories, bound)
                push = np.einsum("...k,...k->...", to, self.current)  # m/s towards the voxel
                obstacle = p.clearance + p.current_margin_s * np.maximum(push, 0.0)
                np.minimum(obstacle, bound, out=obstacle)
                obstacle -= d
            np.maximum(obstacle, 0.0, out=obstacle)
            obstacle *= obstacle
        crossing = self.slice_map.crossing(trajectories, bound if d is None else d, bound,
                                           (step, gap))
        spacing = np.empty(shape)
        spacing[..., 0] = 0.0
        effort = None
        if self.current is not None:  # |t_i - c_i / v|^2, t_i the step's unit direction
            relative = step / np.maximum(gap, 1e-9)[..., None] - self._water
            effort = np.zeros(shape)
            effort[..., 1:] = np.einsum("...k,...k->...", relative, relative)
        gap -= p.spacing
        np.square(gap, out=spacing[..., 1:])
        depth = None
        if self._depth_any or not weighted:
            depth = trajectories[..., 2] - self.z_ref
            depth *= depth
        return offset, obstacle, depth, route, lag * lag, spacing, effort, crossing

    def terms(self, trajectories: np.ndarray) -> dict:
        """The unweighted per-point terms (K, N) of `trajectories` (K, N, 3)."""
        terms = dict(zip(("offset", "obstacle", "depth", "route", "progress", "spacing",
                          "effort", "crossing"), self._terms(trajectories)))
        return {k: np.zeros(terms["offset"].shape) if v is None else v
                for k, v in terms.items()}

    def __call__(self, trajectories: np.ndarray) -> np.ndarray:
        p = self.params
        (offset, obstacle, depth, route, progress, spacing, effort,
         crossing) = self._terms(trajectories, True)
        cost = p.offset_weight * offset
        if obstacle is not None:
            cost += p.obstacle_weight * obstacle
        if depth is not None:
            cost += self.depth_weight * depth
        cost += p.progress_weight * progress
        cost += p.spacing_weight * spacing
        if route is not None:
            cost += p.route_weight * route
        if effort is not None:
            cost += p.current_weight * effort
        cost += p.crossing_weight * crossing
        cost[..., -1] += p.terminal_weight * (p.offset_weight * offset[..., -1]
                                              + p.progress_weight * progress[..., -1])
        return cost
