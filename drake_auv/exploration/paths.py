"""The path to a chosen viewpoint: a grid search, smoothed by STOMP (`replanning.stomp`). Pure.

`TravelField`: Dijkstra (`scipy.sparse.csgraph`) from the vehicle's cell over the 6-connected
cells of the label grid that keep `KEEP` clearances from occupied cells, lie between the
region's floor (zmin plus half the clearance) and z = -1 m and are known free water, unknown
cells between known free water (free on both sides along an axis: the sonar carves known water
in sheets thinner than a cell, sampled with holes) or within `LOCAL_UNKNOWN` clearances of the
vehicle horizontally and a cell vertically (its own unseen surroundings must not forbid every
start; the horizontal profiler scans that layer, nothing scans straight below or above: in seed
0 a descent through unknown water met the boulder's bulge). Other unknown water may be
unseen rock: the edge of the known water next to an unseen face (in the first runs paths along
it led under the boulder's overhang into rock), the inside of a structure whose shell has
holes; it is not crossed. Each metre is priced 1 in known water with the clearance,
`NEAR_FACTOR` in known water closer to rock or unknown, `UNKNOWN_FACTOR` in unknown water. It
gives every candidate's travel length (a candidate it cannot reach is dropped) and the grid
path to one. STOMP alone, from a straight line, cannot find the way round a 20 m boulder; from
the grid path it only smooths. The grid path, resampled every `spacing` m (at most
`MAX_POINTS`), is STOMP's initial trajectory; its interior moves against a cost per point of
    rock_weight * max(0, clearance - d_rock)^2
    + unknown_weight * max(0, clearance - d_blocked)^2
with d_rock the distance to the nearest occupied cell and d_blocked to the nearest occupied or
unknown one (unknown water is treated as rock within the clearance, softly), plus a depth term
that keeps the path below z = -1 m and the clearance above the region's floor (zmin). Fields
are read at the nearest cell; outside the grid the distances are taken as the clearance (no
cost: the grid spans the region widened by Omega and the clearance). The smoothed path (or,
failing it, the grid path) is accepted if it stays on the search's passable cells, keeps
`KEEP` clearances from occupied cell centres and half a clearance above the floor.

A vehicle already nearer rock than `KEEP` clearances (rock seen since it got there, drift, the
seabed guard's lift) may leave: within `ESCAPE` cells of its start a path may cross cells no
nearer rock than the start's own cell (in boulder seed 1 every cell round the vehicle was
within the keep-out, nothing was reachable and exploring stopped at 61 %).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from drake_auv.exploration.frontiers import FREE, MAX_Z, OCCUPIED, UNKNOWN, LabelGrid
from drake_auv.planning.polyline import resample
from drake_auv.replanning.stomp import StompMatrices, StompParameters, stomp

MAX_POINTS = 60
NEAR_FACTOR = 2.0
UNKNOWN_FACTOR = 10.0
KEEP = 1.0  # clearances a path keeps from occupied cell centres (their rock can be 0.87 m nearer)
ESCAPE = 2.0  # cells around a start nearer rock than KEEP where a path may leave it
LOCAL_UNKNOWN = 1.0  # clearances around the vehicle where unknown water may be crossed


@dataclass(frozen=True)
class PathCost:
    """STOMP's state cost on a `LabelGrid` (see the module); fields built once per grid."""

    grid: LabelGrid
    clearance: float
    rock_weight: float = 50.0
    unknown_weight: float = 5.0
    depth_weight: float = 50.0

    def __post_init__(self):
        rock = ndimage.distance_transform_edt(self.grid.labels != OCCUPIED) * self.grid.cell
        object.__setattr__(self, "rock", rock)
        object.__setattr__(self, "blocked", self.grid.blocked_distance())

    def distances(self, points) -> tuple[np.ndarray, np.ndarray]:
        """(d_rock, d_blocked), m, at `points` (..., 3)."""
        idx, inside = self.grid.index(points)
        cells = tuple(np.moveaxis(idx, -1, 0))
        return (np.where(inside, self.rock[cells], self.clearance),
                np.where(inside, self.blocked[cells], self.clearance))

    def __call__(self, trajectories: np.ndarray) -> np.ndarray:
        rock, blocked = self.distances(trajectories)
        z = trajectories[..., 2]
        outside = (np.maximum(0.0, z - MAX_Z)
                   + np.maximum(0.0, self.grid.region[2] + self.clearance - z))
        return (self.rock_weight * np.maximum(0.0, self.clearance - rock) ** 2
                + self.unknown_weight * np.maximum(0.0, self.clearance - blocked) ** 2
                + self.depth_weight * outside ** 2)


@dataclass(frozen=True)
class TravelField:
    """Travel lengths from the vehicle over the grid (see the module).

    Attributes: cost: the `PathCost` (its grid and fields); start: (3,) the vehicle, m;
    length: (nx * ny * nz,) priced travel length to each cell, m (inf: unreachable);
    previous: (nx * ny * nz,) the cell before each on its path (-9999 at the start);
    passable: (nx * ny * nz,) the cells a path may cross; keep: (nx * ny * nz,) the least
    distance to occupied cell centres a path keeps in each cell, m (`KEEP` clearances, or
    the start's own distance round a start nearer rock, `ESCAPE`)."""

    cost: PathCost
    start: np.ndarray
    length: np.ndarray
    previous: np.ndarray
    passable: np.ndarray
    keep: np.ndarray

    @classmethod
    def build(cls, cost: PathCost, start) -> "TravelField":
        grid = cost.grid
        shape, n = grid.labels.shape, grid.labels.size
        start = np.asarray(start, float)[:3]
        z = grid.origin[2] + (np.arange(shape[2]) + 0.5) * grid.cell
        depth_ok = (z >= grid.region[2] + 0.5 * cost.clearance) & (z <= MAX_Z)
        centres = [grid.origin[k] + (np.arange(shape[k]) + 0.5) * grid.cell for k in range(3)]
        near = (((centres[0][:, None, None] - start[0]) ** 2
                 + (centres[1][None, :, None] - start[1]) ** 2
                 <= (LOCAL_UNKNOWN * cost.clearance) ** 2)
                & (np.abs(centres[2][None, None, :] - start[2]) <= grid.cell))
        free = grid.labels == FREE
        between = np.zeros_like(free)
        for axis in range(3):
            pad = [(0, 0)] * 3
            pad[axis] = (1, 1)
            f = np.pad(free, pad)
            lo, hi = (np.take(f, np.arange(k, k + shape[axis]), axis=axis) for k in (0, 2))
            between |= lo & hi
        open_water = free | ((grid.labels == UNKNOWN) & (near | between))
        idx, inside = grid.index(start)
        keep = np.full(shape, KEEP * cost.clearance)
        if inside:  # a start inside the keep-out: the way out, never nearer rock
            lo = np.maximum(idx - int(ESCAPE), 0)
            hi = np.minimum(idx + int(ESCAPE) + 1, shape)
            offsets = np.meshgrid(*(np.arange(a, b) - i for a, b, i in zip(lo, hi, idx)),
                                  indexing="ij")
            near = sum(o ** 2 for o in offsets) <= ESCAPE ** 2
            box = tuple(slice(a, b) for a, b in zip(lo, hi))
            keep[box][near] = min(KEEP * cost.clearance, float(cost.rock[tuple(idx)]))
        passable = (cost.rock >= keep) & depth_ok[None, None, :] & open_water
        factor = np.where(grid.labels == UNKNOWN, UNKNOWN_FACTOR,
                          np.where(cost.blocked >= cost.clearance, 1.0, NEAR_FACTOR))
        first = int(np.ravel_multi_index(tuple(idx), shape)) if inside else -1
        flat_pass, flat_factor = passable.reshape(-1), factor.reshape(-1)
        if first >= 0:
            flat_pass[first] = True
        cells = np.arange(n).reshape(shape)
        rows, cols, weights = [], [], []
        for axis in range(3):
            a = np.take(cells, np.arange(shape[axis] - 1), axis=axis).reshape(-1)
            b = np.take(cells, np.arange(1, shape[axis]), axis=axis).reshape(-1)
            ok = flat_pass[a] & flat_pass[b]
            rows.append(a[ok])
            cols.append(b[ok])
            weights.append(0.5 * grid.cell * (flat_factor[a[ok]] + flat_factor[b[ok]]))
        graph = coo_matrix((np.concatenate(weights), (np.concatenate(rows),
                                                      np.concatenate(cols))), shape=(n, n))
        if first < 0:
            return cls(cost, start, np.full(n, np.inf), np.full(n, -9999), flat_pass,
                       keep.reshape(-1))
        length, previous = dijkstra(graph.tocsr(), directed=False, indices=first,
                                    return_predecessors=True)
        return cls(cost, start, length, previous, flat_pass, keep.reshape(-1))

    def lengths(self, points) -> np.ndarray:
        """(m,) priced travel length to `points` (m, 3), m (inf: unreachable)."""
        idx, inside = self.cost.grid.index(points)
        flat = np.ravel_multi_index(tuple(idx.T), self.cost.grid.labels.shape)
        return np.where(inside, self.length[flat], np.inf)

    def grid_path(self, goal) -> np.ndarray:
        """(N, 3) the start, the cell centres of the search's path, and `goal`, m."""
        grid = self.cost.grid
        idx, _ = grid.index(goal)
        cell = int(np.ravel_multi_index(tuple(idx), grid.labels.shape))
        chain = []
        while cell >= 0:
            chain.append(cell)
            cell = int(self.previous[cell])
        centres = grid.centres(np.column_stack(np.unravel_index(chain[::-1],
                                                                grid.labels.shape)))
        return np.vstack([self.start, centres[1:-1], goal])


@lru_cache(maxsize=64)
def _matrices(num_points: int) -> StompMatrices:
    return StompMatrices(num_points)


def plan_path(travel: TravelField, goal, spacing: float = 1.0,
              params: StompParameters = StompParameters(num_rollouts=10, max_iterations=30,
                                                        noise_std=0.5),
              seed: int | np.random.SeedSequence = 0) -> np.ndarray | None:
    """(N, 3) path from the vehicle to `goal` (m): the grid search's, smoothed by STOMP
    against its cost; None when the goal is unreachable or the path (smoothed or not) comes
    within `KEEP` clearances of an occupied cell centre or half a clearance of the floor, or
    leaves the passable cells."""
    goal = np.asarray(goal, float)[:3]
    if not np.isfinite(travel.lengths(goal[None])[0]):
        return None
    initial = resample(travel.grid_path(goal), spacing)
    if len(initial) > MAX_POINTS:
        initial = resample(initial, spacing * len(initial) / (MAX_POINTS - 1))
    if len(initial) < 3:
        initial = travel.start + np.linspace(0.0, 1.0, 3)[:, None] * (goal - travel.start)
    smoothed = stomp(initial, travel.cost, params, seed=seed,
                     matrices=_matrices(len(initial))).trajectory
    for path in (smoothed, initial):
        if path_clear(travel, path):
            return path
    return None


def path_clear(travel: TravelField, path) -> bool:
    """Whether `path` (N, 3) after its first point stays on the passable cells (its last
    point excepted), keeps `KEEP` clearances from occupied cell centres (`travel.keep`: less
    on the way out of a start nearer rock) and half a clearance above the floor."""
    cost, path = travel.cost, np.asarray(path, float)
    rock, _ = cost.distances(path[1:])
    shape = cost.grid.labels.shape
    idx, inside = cost.grid.index(path[1:-1])
    crossed = travel.passable[np.ravel_multi_index(tuple(idx.T), shape)]
    cells, within = cost.grid.index(path[1:])
    keep = np.where(within, travel.keep[np.ravel_multi_index(tuple(cells.T), shape)],
                    KEEP * cost.clearance)
    return bool(np.all(crossed & inside) and np.all(rock >= keep - 1e-9)
                and np.all(path[1:, 2] >= cost.grid.region[2] + 0.5 * cost.clearance))
