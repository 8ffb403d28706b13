"""The gain of a viewpoint: the surface it would newly see, and the score against travel. Pure.

From a viewpoint the planner casts the multibeam's fan (`sonar.beams`: the mount's fan
plane, `fan_angles`), turned about z by `sweep` offsets (a fan sees a strip as the vehicle
turns and moves, not a line), through the `LabelGrid` by sampling each ray every half cell
up to the sonar's range (a vectorised voxel traversal). A ray stops at the first occupied
cell. It newly sees the cell where it enters unknown water inside the region (the surface
there is not yet known; counting one cell per ray and not every unknown cell it crosses is a
surface measure, not a volume one) or, failing that, the surface frontier cell it stops on.
The gain is the number of distinct such cells times the cell's face, m^2.

Score (`strategy` "gain"): gain - `travel_weight` * travel time (the travel length of the
grid search, `paths.TravelField`, over the speed, s); "nearest": minus the travel length;
"random": a seeded uniform draw.
"""

from __future__ import annotations

import numpy as np

from drake_auv.exploration.frontiers import OCCUPIED, UNKNOWN, LabelGrid
from drake_auv.sonar.beams import MOUNT_ROTATIONS, fan_angles

STRATEGIES = ("gain", "nearest", "random")


def view_yaw(directions, sensor_azimuth: float) -> np.ndarray:
    """(c,) yaw, rad, that turns a sensor at `sensor_azimuth` (body frame, rad) to the
    horizontal part of each view direction (c, 3)."""
    d = np.asarray(directions)
    return np.arctan2(d[:, 1], d[:, 0]) - sensor_azimuth


def fan_rays(mount: str, yaws, fan_deg: float = 120.0, beams: int = 13,
             sweep_deg: float = 30.0, sweeps: int = 5) -> np.ndarray:
    """(c, r, 3) unit rays in the world frame of the multibeam fan on `mount` at each of the
    `yaws` (c,), level vehicle, the fan turned by `sweeps` offsets over +-`sweep_deg`."""
    angles = fan_angles(beams, np.radians(fan_deg))
    if len(np.atleast_1d(yaws)) == 0:
        return np.zeros((0, beams * max(sweeps, 1), 3))
    body = MOUNT_ROTATIONS[mount] @ np.stack([np.cos(angles), np.sin(angles),
                                              np.zeros_like(angles)])  # (3, beams)
    offsets = np.radians(np.linspace(-sweep_deg, sweep_deg, sweeps)) if sweeps > 1 else [0.0]
    yaw = (np.asarray(yaws, dtype=float)[:, None] + np.asarray(offsets)[None, :]).ravel()
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]  # level vehicle: R_WB = Rz(yaw)
    rays = np.stack([c * body[0] - s * body[1], s * body[0] + c * body[1],
                     np.broadcast_to(body[2], c.shape[:1] + body[2].shape)], axis=-1)
    return rays.reshape(len(np.atleast_1d(yaws)), -1, 3)  # (c, s * beams, 3)


def view_gains(grid: LabelGrid, positions, rays, max_range: float,
               frontier_mask: np.ndarray | None = None) -> np.ndarray:
    """(c,) surface, m^2, each viewpoint (c, 3) would newly see along its rays (c, r, 3)
    (see the module). `frontier_mask`: (nx, ny, nz) surface frontier cells (None: none)."""
    positions = np.asarray(positions, dtype=float)
    c, r = rays.shape[:2]
    if c == 0:
        return np.zeros(0)
    step = 0.5 * grid.cell
    t = (np.arange(int(np.ceil(max_range / step))) + 0.5) * step
    points = positions[:, None, None, :] + rays[:, :, None, :] * t[None, None, :, None]
    idx, inside = grid.index(points)  # (c, r, s, 3), (c, r, s)
    cells = np.ravel_multi_index(tuple(np.moveaxis(idx, -1, 0)), grid.labels.shape)
    labels = np.where(inside, grid.labels.reshape(-1)[cells], 0)
    occupied = labels == OCCUPIED
    before = np.cumsum(occupied, axis=2) == 0  # samples before the first occupied one
    entering = ((labels == UNKNOWN) & inside & before
                & grid.region_mask().reshape(-1)[cells])
    first = np.argmax(entering, axis=2)  # (c, r)
    has = entering.any(axis=2)
    picked = np.take_along_axis(cells, first[..., None], axis=2)[..., 0]
    if frontier_mask is not None:
        stop = np.argmax(occupied, axis=2)
        hit_cell = np.take_along_axis(cells, stop[..., None], axis=2)[..., 0]
        hits = occupied.any(axis=2) & frontier_mask.reshape(-1)[hit_cell] & ~has
        picked = np.where(has, picked, hit_cell)
        has = has | hits
    owner = np.broadcast_to(np.arange(c)[:, None], (c, r))[has]
    pairs = np.unique(owner * grid.labels.size + picked[has])
    return np.bincount(pairs // grid.labels.size, minlength=c) * grid.cell ** 2


def scores(strategy: str, gains: np.ndarray, distance: np.ndarray, speed: float,
           travel_weight: float, seed: int | np.random.SeedSequence) -> np.ndarray:
    """(c,) ranking score of each candidate from its gain (m^2) and travel length (m),
    larger is better (see the module)."""
    if strategy not in STRATEGIES:
        raise ValueError(f"strategy must be one of {STRATEGIES}, got {strategy!r}")
    if strategy == "gain":
        return gains - travel_weight * distance / speed
    if strategy == "nearest":
        return -distance
    return np.random.default_rng(seed).uniform(size=len(distance))
