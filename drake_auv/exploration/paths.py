"""The path to a chosen viewpoint: STOMP (`replanning.stomp`) in the label grid. Pure.

The initial path is the straight line from the vehicle to the viewpoint, points every
`spacing` m (at most `MAX_POINTS`); STOMP moves its interior against a cost per point of
    rock_weight * max(0, clearance - d_rock)^2 + unknown_weight * max(0, clearance - d_blocked)^2
with d_rock the distance to the nearest occupied cell and d_blocked to the nearest occupied or
unknown one (unknown water is treated as rock within the clearance, softly: the vehicle's own
unseen surroundings must not forbid every start), plus a depth term that keeps the path
below z = -1 m and the clearance above the region's floor (zmin). A path is accepted if no
point comes closer than half the clearance to an occupied cell or to the floor. Fields are read at the nearest cell; outside the grid the distances are
taken as the clearance (no cost: the grid spans the region widened by Omega and the clearance).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import ndimage

from drake_auv.exploration.frontiers import MAX_Z, OCCUPIED, LabelGrid
from drake_auv.replanning.stomp import StompMatrices, StompParameters, stomp

MAX_POINTS = 60


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


@lru_cache(maxsize=64)
def _matrices(num_points: int) -> StompMatrices:
    return StompMatrices(num_points)


def plan_path(start, goal, cost: PathCost, spacing: float = 1.0,
              params: StompParameters = StompParameters(num_rollouts=10, max_iterations=30,
                                                        noise_std=1.0),
              seed: int = 0) -> np.ndarray | None:
    """(N, 3) path from `start` to `goal` (m) optimised by STOMP against `cost`, or None when
    it still comes within half the clearance of an occupied cell."""
    start, goal = np.asarray(start, float)[:3], np.asarray(goal, float)[:3]
    n = int(np.clip(np.ceil(np.linalg.norm(goal - start) / spacing) + 1, 3, MAX_POINTS))
    initial = start + np.linspace(0.0, 1.0, n)[:, None] * (goal - start)
    path = stomp(initial, cost, params, seed=seed, matrices=_matrices(n)).trajectory
    rock, _ = cost.distances(path[1:])
    clear = np.all(rock >= 0.5 * cost.clearance) and np.all(
        path[1:, 2] >= cost.grid.region[2] + 0.5 * cost.clearance)
    return path if clear else None
