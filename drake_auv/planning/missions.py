"""Waypoints of a `PlannedPath`, the start of the vehicle missions: the COLA2 mission XML
(`formats.cola2`, sections chosen under COLA2's semantics) and the QGroundControl `.plan`
(`formats.qgc`, ArduSub), both in WGS 84.

Waypoints: the path's samples thinned per labelled run by Douglas-Peucker in 3D (x, y and the
coordinate the vehicle holds: altitude above the seabed on terrain-following lanes, elevation
elsewhere), so every dropped sample lies within `tolerance` (m) of the waypoint polyline and
every waypoint is a path sample. A waypoint takes the label of the segment that arrives at it.
Vertical reference per waypoint: altitude above the seabed on "planar" and "lawnmower" lanes
(the DVL holds the offset over planar terrain), depth on slicing contours and transits (planned
3D lines whose altitude varies).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.jit import kernel
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.surface import TerrainSurface

ALTITUDE_LABELS = ("planar", "lawnmower")


def douglas_peucker(points: np.ndarray, tolerance: float, piece: int | None = None) -> np.ndarray:
    """Indices of the samples of a polyline (any dimension) kept by Douglas-Peucker: every
    dropped sample lies within `tolerance` of the kept polyline; the ends are kept.

    `piece`: thin consecutive pieces of at most `piece` samples on their own (each piece's
    ends kept too): the same guarantee, a few more vertices, and time about linear in the
    length, where one pass over a long zigzag of lanes splits off a lane per level (time the
    length times the lanes)."""
    points = np.ascontiguousarray(points, dtype=float)
    n = len(points)
    keep = np.zeros(n, dtype=bool)
    if n:
        ends = (np.append(np.arange(0, n - 1, piece - 1), n - 1)
                if piece is not None and n > piece else np.array([0, n - 1]))
        _thin(points, ends, tolerance * tolerance, keep)
    return np.flatnonzero(keep)


@kernel
def _thin(points, ends, tolerance2, keep):
    """Marks in `keep` the samples Douglas-Peucker keeps in each piece ends[k]..ends[k + 1]
    (their ends included): a sample splits its piece where its distance to the chord is the
    largest (the first such) and over the tolerance."""
    dims = points.shape[1]
    stack = np.empty((64, 2), dtype=np.int64)
    chord, unit = np.empty(dims), np.empty(dims)  # a piece's chord, and over its square
    for piece in range(len(ends) - 1):
        keep[ends[piece]] = True
        keep[ends[piece + 1]] = True
        stack[0, 0], stack[0, 1] = ends[piece], ends[piece + 1]
        top = 1
        while top:
            top -= 1
            a, b = stack[top, 0], stack[top, 1]
            if b <= a + 1:
                continue
            seg2 = 0.0
            for k in range(dims):
                chord[k] = points[b, k] - points[a, k]
                seg2 += chord[k] * chord[k]
            project = seg2 > 1e-18
            for k in range(dims):
                unit[k] = chord[k] / seg2 if project else 0.0
            worst, split = -1.0, -1
            for i in range(a + 1, b):
                t = 0.0
                if project:
                    for k in range(dims):
                        t += (points[i, k] - points[a, k]) * unit[k]
                    t = min(max(t, 0.0), 1.0)
                d2 = 0.0
                for k in range(dims):
                    e = (points[i, k] - points[a, k]) - t * chord[k]
                    d2 += e * e
                if d2 > worst:
                    worst, split = d2, i
            if worst > tolerance2:
                keep[split] = True
                if top + 2 > len(stack):
                    stack = np.concatenate((stack, np.empty_like(stack)))
                stack[top, 0], stack[top, 1] = a, split
                stack[top + 1, 0], stack[top + 1, 1] = split, b
                top += 2


@dataclass(frozen=True)
class Waypoints:
    """Mission waypoints taken from a path (world frame, z up, m).

    Attributes:
        index: (K,) index of each waypoint's sample in the path.
        points: (K, 3) positions.
        altitude: (K,) height above the seabed below, m.
        heading: (K,) yaw of the body x axis, rad (world frame, from +x counter-clockwise).
        labels: (K,) label of the segment arriving at each waypoint (the first: its own).
        use_altitude: (K,) True where the vehicle holds altitude (lanes), else depth.
    """

    index: np.ndarray
    points: np.ndarray
    altitude: np.ndarray
    heading: np.ndarray
    labels: np.ndarray
    use_altitude: np.ndarray

    def __len__(self) -> int:
        return len(self.index)


def mission_waypoints(path: PlannedPath, surface: TerrainSurface, tolerance: float = 0.05,
                      altitude_labels: tuple[str, ...] = ALTITUDE_LABELS) -> Waypoints:
    """Waypoints of `path` (see the module docstring); `tolerance` in m, > 0; the vehicle holds
    altitude on the runs labelled one of `altitude_labels` (() : depth everywhere)."""
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"waypoint tolerance must be > 0 m, got {tolerance}")
    pts = path.points
    altitude = pts[:, 2] - surface.elevation(pts[:, 0], pts[:, 1])
    labels = path.labels
    use_alt = np.isin(labels.astype(str), list(altitude_labels))
    breaks = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    starts = np.concatenate([[0], breaks])
    ends = np.concatenate([breaks, [len(path)]])
    kept = [np.array([0])]
    for a, b in zip(starts, ends):
        lo = max(a - 1, 0)  # a run's segments start at the previous run's last sample
        held = np.column_stack([pts[lo:b, :2], np.where(use_alt[a], altitude[lo:b],
                                                        pts[lo:b, 2])])
        kept.append(lo + douglas_peucker(held, tolerance))
    idx = np.unique(np.concatenate(kept))
    return Waypoints(idx, pts[idx], altitude[idx], path.heading[idx], labels[idx], use_alt[idx])


