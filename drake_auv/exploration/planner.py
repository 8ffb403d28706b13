"""One step of on-line view planning: frontiers -> candidates -> gains -> choice -> path. Pure.

`plan_view` reads the octree into a `LabelGrid` over the region, finds the frontier clusters
and their admissible viewpoints, scores them (`gains.scores`) and keeps the current target
unless it was reached, became inadmissible, lost its gain, or another candidate outscores it
by `switch_margin_m2`; a new target gets a STOMP path (`paths.plan_path`; a candidate whose
path stays too close to rock is passed over for the next). The step reports `done` when no
candidate would newly see `min_gain_m2` (for `patience` steps in a row). While the region
holds nothing known, the target is the edge of the region widened by Omega nearest the
vehicle (an approach, in a straight line: nothing is known to avoid), and so it is while the
vehicle is outside the planning grid.

Believed coverage: of the surface the map implies inside the region, the share seen, in cell
faces: the faces of occupied cells on free water that a multibeam return has seen, over the
faces of occupied cells on free water or on unknown water that touches free water (surface
not yet seen).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from drake_auv.exploration.frontiers import (FREE, MAX_Z, OCCUPIED, UNKNOWN, LabelGrid,
                                             candidate_viewpoints, check_region,
                                             cluster_frontiers, face_neighbours,
                                             frontier_cells)
from drake_auv.exploration.gains import STRATEGIES, fan_rays, scores, view_gains, view_yaw
from drake_auv.exploration.paths import PathCost, TravelField, path_clear, plan_path
from drake_auv.params import param, validate
from drake_auv.random_streams import child

_FACE = ndimage.generate_binary_structure(3, 1)
VISITED_RADIUS = 3.0  # m, around a reached target where no candidate is chosen again


@dataclass(frozen=True)
class ExploreParameters:
    """Parameters of the view planner (ranges as field metadata, `drake_auv.params`).

    Attributes:
        region: (6,) [xmin, ymin, zmin, xmax, ymax, zmax] where the structure is believed to
            be, navigation frame, m.
        omega: preferred viewing distance, m, > clearance.
        clearance: least distance of a viewpoint to occupied cells, m, > 0.
        unknown_clearance: least distance of a viewpoint to unknown cells, m, in [0,
            clearance] (see `frontiers`).
        strategy: "gain", "nearest" or "random" (`gains.STRATEGIES`).
        min_gain_m2: exploration is done when no viewpoint would newly see this, m^2, >= 0.
        cell_m: planning grid cell, m, in [0.25, 4].
        cluster_m: frontier block edge, m, >= cell_m.
        speed: speed along the paths, m/s, > 0.
        travel_weight: m^2 of gain one second of travel is worth (strategy "gain"), >= 0.
        switch_margin_m2: score a candidate needs above the current target's to replace it.
        arrive_m: a target within this of the vehicle is reached, m, > 0.
        max_range: the multibeam's range, m, > 0.
        mount: the multibeam's mount ("port", "starboard", "down", "forward").
        patience: planning steps in a row without gain that end exploration, >= 1.
        max_candidates: the best this many by straight-line score are gain-scored, >= 1.
    """

    region: tuple = param(kind="vector", names=("xmin", "ymin", "zmin", "xmax", "ymax", "zmax"),
                          unit="m")
    omega: float = param(6.0, low=0.5, high=100.0, unit="m")
    clearance: float = param(3.0, low=0.5, high=20.0, unit="m")
    unknown_clearance: float = param(1.5, low=0.0, high=20.0, unit="m")
    strategy: str = param("gain", kind="choice", choices=STRATEGIES)
    min_gain_m2: float = param(1.0, low=0.0, unit="m^2")
    cell_m: float = param(1.0, low=0.25, high=4.0, unit="m")
    cluster_m: float = param(4.0, low=0.25, unit="m")
    speed: float = param(0.5, low=0.0, low_open=True, high=3.0, unit="m/s")
    travel_weight: float = param(0.5, low=0.0, unit="m^2/s")
    switch_margin_m2: float = param(10.0, low=0.0, unit="m^2")
    arrive_m: float = param(1.5, low=0.0, low_open=True, unit="m")
    max_range: float = param(20.0, low=0.0, low_open=True, unit="m")
    mount: str = param("port", kind="choice", choices=("port", "starboard", "down", "forward"))
    patience: int = param(3, low=1, integer=True)
    max_candidates: int = param(200, low=1, integer=True)

    def __post_init__(self):
        validate(self)
        object.__setattr__(self, "region", tuple(check_region(self.region).tolist()))
        if not self.omega > self.clearance:
            raise ValueError(f"omega ({self.omega} m) must be above the clearance "
                             f"({self.clearance} m): a viewpoint at omega from the surface "
                             "would be inside the clearance")
        if not self.unknown_clearance <= self.clearance:
            raise ValueError(f"unknown_clearance must be in [0, clearance = {self.clearance}] "
                             f"m, got {self.unknown_clearance}")
        if not self.cluster_m >= self.cell_m:
            raise ValueError(f"cluster_m must be >= cell_m ({self.cell_m} m), got "
                             f"{self.cluster_m}")

    @property
    def sensor_azimuth(self) -> float:
        """Azimuth of the multibeam's axis in the body frame, rad."""
        return {"port": np.pi / 2, "starboard": -np.pi / 2}.get(self.mount, 0.0)


@dataclass(frozen=True)
class Target:
    """A chosen viewpoint: position (3,), yaw (rad), the frontier point it looks at (3,);
    `look_around`: a turn in place (no view reachable: the fan's sweep carves known water)."""

    position: np.ndarray
    yaw: float
    looks_at: np.ndarray
    look_around: bool = False


@dataclass(frozen=True)
class ViewStep:
    """What one planning step decided.

    Attributes:
        target: the viewpoint to fly to (None: none, hold).
        path: (N, 3) a new path to it from the vehicle (None: keep the current one).
        gain_m2: the target's gain (the best candidate's when none is admissible).
        candidates: admissible viewpoints scored.
        frontier_cells: frontier cells found.
        believed_coverage: share of the implied surface seen (see the module), in [0, 1].
        no_gain: True when no candidate would newly see `min_gain_m2` or none has a clear
            path (a turn in place).
        grid: the step's `LabelGrid` (for the next step).
        visited: (v, 3) the targets reached so far, m (for the next step).
        turning: the target is a turn in place.
    """

    target: Target | None
    path: np.ndarray | None
    gain_m2: float
    candidates: int
    frontier_cells: int
    believed_coverage: float
    no_gain: bool
    grid: LabelGrid
    visited: np.ndarray
    turning: bool = False


def believed_coverage(grid: LabelGrid) -> float:
    """Seen over implied surface in the region, counted in cell faces (see the module)."""
    occupied = (grid.labels == OCCUPIED) & grid.region_mask()
    unknown = grid.labels == UNKNOWN
    open_unknown = unknown & ndimage.binary_dilation(grid.labels == FREE, _FACE)
    on_water = face_neighbours(grid.labels == FREE) & occupied[..., None]
    on_unknown = face_neighbours(open_unknown) & occupied[..., None]
    seen = on_water if grid.seen is None else on_water & grid.seen
    total = int(on_water.sum() + on_unknown.sum())
    return int(seen.sum()) / total if total else 0.0


def approach_point(params: ExploreParameters, position) -> np.ndarray:
    """(3,) the point of the region box widened by Omega nearest `position`, below z = -1 m."""
    region = np.asarray(params.region)
    point = np.clip(np.asarray(position, float)[:3], region[:3] - params.omega,
                    region[3:] + params.omega)
    point[2] = min(point[2], MAX_Z - 1.0)
    return point


def plan_view(octree_map, position, params: ExploreParameters, current: Target | None,
              seed: int | np.random.SeedSequence = 0, previous: LabelGrid | None = None,
              rays=None, visited=None, yaw: float = 0.0, current_path=None,
              returns=None) -> ViewStep:
    """One planning step from the vehicle at `position` (3,) towards `current` (see the
    module); `seed` (an int or a `SeedSequence`): its child 0 draws the random strategy,
    child 1 STOMP's rollouts; `previous`: the last step's grid (`ViewStep.grid`) and `rays`
    the beams inserted since (`scan_rays`), so only the cells they touched are read again, and `returns` the multibeam's return points
    and beam directions since (`frontiers.multibeam_returns`: the faces it has seen);
    `visited` (v, 3): the targets reached before, m (a candidate within `VISITED_RADIUS` of one is not chosen again: what its view
    promised and did not give, behind rock or below the floor, it will not give later);
    `yaw`: the vehicle's, rad; `current_path` (k, 3): what is left of the path to `current`,
    m (kept only while it stays clear on the new map, `paths.path_clear`)."""
    position = np.asarray(position, float)[:3]
    visited = np.zeros((0, 3)) if visited is None else np.asarray(visited, float)
    if (current is not None and not current.look_around
            and np.linalg.norm(current.position - position) <= params.arrive_m):
        visited = np.vstack([visited, current.position])
    grid = LabelGrid.from_map(octree_map, params.region,
                              params.omega + params.clearance + params.cell_m,
                              params.cell_m, previous, rays, returns)
    cost = PathCost(grid, params.clearance)
    frontiers = frontier_cells(grid)
    surface_mask = np.zeros(grid.labels.shape, bool)
    surface = frontiers.kinds == 0
    surface_mask[tuple(grid.index(frontiers.centres[surface])[0].T)] = True
    coverage = believed_coverage(grid)
    if not (np.any(grid.labels[grid.region_mask()] != UNKNOWN)
            and grid.index(position)[1]):  # approach: straight to the region
        goal = approach_point(params, position)
        looks_at = 0.5 * (np.asarray(params.region[:3]) + params.region[3:])
        yaw = float(view_yaw((looks_at - goal)[None], params.sensor_azimuth)[0])
        target = Target(goal, yaw, looks_at)
        path = None
        if current is None or np.linalg.norm(current.position - goal) > params.arrive_m:
            path = np.vstack([position, goal])
        return ViewStep(target, path, 0.0, 0, 0, coverage, False, grid, visited)
    travel = TravelField.build(cost, position)
    clusters = cluster_frontiers(frontiers, params.cluster_m)
    cands = candidate_viewpoints(grid, clusters, params.omega, params.clearance,
                                 params.unknown_clearance)
    yaws = view_yaw(cands.directions, params.sensor_azimuth)
    # Gain-score only the nearest `max_candidates` the vehicle can reach.
    distance = travel.lengths(cands.positions)
    fresh = np.ones(len(distance), bool)
    if len(visited):
        near = np.linalg.norm(cands.positions[:, None] - visited[None], axis=2)
        fresh = near.min(axis=1) > VISITED_RADIUS
    reachable = np.flatnonzero(np.isfinite(distance) & fresh)
    keep = reachable[np.argsort(distance[reachable], kind="stable")[:params.max_candidates]]
    positions, yaws, looks_at = cands.positions[keep], yaws[keep], cands.targets[keep]
    if current is not None:  # the current target, re-scored on the new map
        positions = np.vstack([positions, current.position])
        yaws = np.append(yaws, current.yaw)
        looks_at = np.vstack([looks_at, current.looks_at])
    rays = fan_rays(params.mount, yaws)
    gains = view_gains(grid, positions, rays, params.max_range, surface_mask)
    lengths = travel.lengths(positions)
    score = scores(params.strategy, gains, np.where(np.isfinite(lengths), lengths, 1e6),
                   params.speed, params.travel_weight, child(seed, 0))
    useful = gains >= max(params.min_gain_m2, 1e-9)
    n = len(keep)
    if current is not None:
        idx, inside = grid.index(current.position)
        reached = np.linalg.norm(current.position - position) <= params.arrive_m
        admissible = bool(inside and cost.blocked[tuple(idx)] >= 0.5 * params.clearance)
        clear = current_path is None or len(current_path) < 2 or path_clear(travel,
                                                                             current_path)
        if not reached and admissible and clear and useful[n] and not (
                useful[:n].any() and score[:n][useful[:n]].max()
                > score[n] + params.switch_margin_m2):
            return ViewStep(current, None, float(gains[n]), n, len(frontiers.kinds),
                            coverage, False, grid, visited)
    order = [k for k in np.argsort(-score[:n], kind="stable") if useful[k]]
    for k in order[:5]:  # the best few whose path is clear
        path = plan_path(travel, positions[k], seed=child(seed, 1))
        if path is not None:
            target = Target(positions[k], float(yaws[k]), looks_at[k])
            return ViewStep(target, path, float(gains[k]), n, len(frontiers.kinds),
                            coverage, False, grid, visited)
    best = float(gains[:n].max()) if n else 0.0
    unreachable = bool(np.any(~np.isfinite(distance) & fresh))
    if order or unreachable or (n == 0 and len(frontiers.kinds)):
        # views exist but no clear path, or frontiers but no admissible view of them (the
        # breakwater's start, its fan along the row: every view of the gaps' faces lay by a
        # neighbouring block, and it stopped 15 s in): turn in place, 120 degrees
        turn = yaw + 2.0 * np.pi / 3.0
        axis = turn + params.sensor_azimuth
        look = position + 10.0 * np.array([np.cos(axis), np.sin(axis), 0.0])
        return ViewStep(Target(position, float(turn), look, True), np.vstack([position] * 2),
                        best, n, len(frontiers.kinds), coverage, True, grid, visited, True)
    return ViewStep(None, None, best, n, len(frontiers.kinds), coverage, True, grid, visited)
