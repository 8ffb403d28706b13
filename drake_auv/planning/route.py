"""Assembling a `PlannedPath` from coverage pieces: terrain-following legs, transits, clearance,
the water column.

A transit is the straight line between two pieces, lifted where needed to at least Omega above
the terrain below it; after assembly every sample is kept over the grid and lifted where it is
closer than Omega to the surface (3D distance, not just altitude:
`TerrainSurface.enforce_clearance`). Samples are at most `sample_spacing` apart, so the clearance
holds along the segments to within that spacing. No sample lies above the ceiling (world z = -the
minimum operating depth): where the water is too shallow for Omega the path runs at it.
"""

from __future__ import annotations

import numpy as np

from drake_auv.planning.path import PlannedPath
from drake_auv.planning.polyline import arc_length, densify, motion_heading
from drake_auv.planning.surface import TerrainSurface

DOWN = np.array([0.0, 0.0, -1.0])


class RouteBuilder:
    """Accumulates labelled pieces in order, then builds one `PlannedPath`."""

    def __init__(self, surface: TerrainSurface, omega: float, sample_spacing: float,
                 ceiling: float = 0.0, nogo=None):
        self.surface = surface
        self.omega = float(omega)
        self.ds = float(sample_spacing)
        self.ceiling = float(ceiling)
        self.nogo = nogo  # a `planning.nogo.NoGo`, or None
        self.unreachable = 0  # pieces dropped because no detour around the no-go zones reached them
        self._points, self._sensor, self._labels, self._facing = [], [], [], []

    @property
    def position(self) -> np.ndarray | None:
        return self._points[-1][-1] if self._points else None

    def _add(self, points, sensor, label, facing):
        """Appends a piece, joined by a transit; with no-go zones only its runs of samples
        outside the forbidden set, each joined by a transit around the zones."""
        if len(points) == 0:
            return
        if self.nogo is None:
            if self.add_transit(points[0]):
                self._append(points, sensor, label, facing)
            return
        ok = np.concatenate([[False], ~self.nogo.inside(points[:, :2]), [False]])
        starts = np.flatnonzero(ok[1:] & ~ok[:-1])
        ends = np.flatnonzero(~ok[1:] & ok[:-1])
        for a, b in zip(starts, ends):
            if self.add_transit(points[a]):
                self._append(points[a:b], sensor[a:b], label, facing[a:b])
            else:
                self.unreachable += 1

    def _append(self, points, sensor, label, facing):
        if self._points and np.allclose(points[0], self._points[-1][-1]):
            points, sensor, facing = points[1:], sensor[1:], facing[1:]
            if len(points) == 0:
                return
        self._points.append(points)
        self._sensor.append(sensor)
        self._labels.append((label, len(points)))
        self._facing.append(facing)

    def add_terrain_following(self, xy_waypoints: np.ndarray, label: str) -> None:
        """Straight legs through `xy_waypoints` at altitude Omega, sensor down, heading along
        the motion. Joined to the previous piece by a transit."""
        xy = densify(np.asarray(xy_waypoints, float), self.ds)
        z = self.surface.elevation(xy[:, 0], xy[:, 1]) + self.omega
        pts = np.column_stack([xy, z])
        self._add(pts, np.tile(DOWN, (len(pts), 1)), label, np.full(len(pts), np.nan))

    def add_oriented(self, points: np.ndarray, sensor_dir: np.ndarray, label: str) -> None:
        """Samples with their own sensor axes; the heading faces the sensor's horizontal part
        (the motion direction where the sensor looks straight down)."""
        points = np.asarray(points, float)
        sensor_dir = np.asarray(sensor_dir, float)
        horiz = np.linalg.norm(sensor_dir[:, :2], axis=1)
        facing = np.where(horiz > 1e-3, np.arctan2(sensor_dir[:, 1], sensor_dir[:, 0]), np.nan)
        self._add(points, sensor_dir, label, facing)

    def add_transit(self, target: np.ndarray) -> bool:
        """Line from the current position to `target` (around the no-go zones, through the
        detour's corners, z linear in the distance along it), never lower than Omega above
        the terrain below it; sensor down. False when no detour reaches `target`."""
        if self.position is None:
            return True
        a, b = self.position, np.asarray(target, float)
        if np.linalg.norm(b - a) <= 1e-9:
            return True
        if self.nogo is None:
            corners = np.vstack([a, b])
        else:
            xy = self.nogo.detour(a[:2], b[:2])
            if xy is None:
                return False
            arc = arc_length(xy)
            z = a[2] + (b[2] - a[2]) * arc / max(arc[-1], 1e-12)
            corners = np.column_stack([xy, z])
        line = densify(corners, self.ds)[1:-1]
        if len(line) == 0:
            return True
        floor = self.surface.elevation(line[:, 0], line[:, 1]) + self.omega
        line[:, 2] = np.maximum(line[:, 2], floor)
        self._append(line, np.tile(DOWN, (len(line), 1)), "transit", np.full(len(line), np.nan))
        return True

    def build(self, enforce_clearance: bool = True) -> PlannedPath:
        """The assembled path; every sample at least Omega from the terrain if asked, and
        none above `ceiling` (the minimum operating depth, world z, m), which wins where the
        two conflict (water shallower than Omega plus the minimum depth). Consumes the
        pieces (their memory is released before the path is built)."""
        if not self._points:
            raise ValueError("the route is empty: nothing to cover")
        # Each list is dropped as soon as it is joined, so the peak holds one copy plus one field.
        points = np.vstack(self._points)
        self._points = []
        sensor = np.vstack(self._sensor)
        self._sensor = []
        names, counts = zip(*self._labels)
        labels = np.repeat(np.array(names, dtype=object), counts)
        self._labels = []
        facing = np.concatenate(self._facing)
        self._facing = []
        if enforce_clearance:
            points = self.surface.enforce_clearance(points, self.omega, copy=False)
        points[:, 2] = np.minimum(points[:, 2], self.ceiling)
        heading = np.where(np.isnan(facing), motion_heading(points), facing)
        return PlannedPath.adopt(points, heading, sensor, labels)
