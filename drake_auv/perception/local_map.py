"""Local map of profiler returns for profile following: a time window of recent return points.

The map stores return points in the navigation frame (where the profiler placed them with the
estimated pose) with their ping time, and forgets them by age and by count, so that old returns
(and the navigation drift accumulated since) do not smear the estimate. Queries express the
points in a 2D frame centred on the vehicle:

- horizontal plane: (x, y) world-aligned offsets of the points within a depth band around the
  vehicle (horizontal profile following, circumnavigation at constant depth);
- vertical plane: (s, h) with s along a fixed horizontal direction e and h = z offset, for the
  points within a lateral band around the vertical plane through the vehicle along e.

Why a window of points rather than a log-odds grid: the estimator fits lines to points
(RANSAC + total least squares), which needs the points themselves; the forgetting a grid gets
by decaying log-odds is here a maximum age, and isolated spurious returns are rejected by the
estimator's density filter and RANSAC instead of by evidence accumulation.
"""

from __future__ import annotations

import numpy as np


class LocalProfileMap:
    """A window of recent profiler returns in the navigation frame.

    Args:
        max_age: returns older than this many seconds are forgotten, s (> 0).
        max_points: at most this many returns are kept, the newest win (>= 10).

    Its arrays are replaced, never modified in place, so a shallow copy is an independent map.
    """

    def __init__(self, max_age: float = 20.0, max_points: int = 4000):
        if not (np.isfinite(max_age) and max_age > 0):
            raise ValueError(f"LocalProfileMap max_age must be a finite number > 0 s, got {max_age}")
        if int(max_points) != max_points or max_points < 10:
            raise ValueError(f"LocalProfileMap max_points must be an integer >= 10, got {max_points}")
        self.max_age = float(max_age)
        self.max_points = int(max_points)
        self._points = np.empty((0, 3))
        self._times = np.empty(0)

    def __len__(self) -> int:
        return len(self._points)

    @property
    def points(self) -> np.ndarray:
        """(n, 3) stored return points, navigation frame, m (read-only view)."""
        view = self._points.view()
        view.setflags(write=False)
        return view

    def add(self, points_nav, time: float) -> None:
        """Adds the return points of one update (NaN rows, i.e. beams without return, are
        skipped) and forgets what is older than `max_age` before `time`."""
        points = np.asarray(points_nav, dtype=float).reshape(-1, 3)
        if not np.isfinite(time):
            raise ValueError(f"LocalProfileMap.add time must be finite, got {time}")
        points = points[np.all(np.isfinite(points), axis=1)]
        if len(points):
            self._points = np.vstack([self._points, points])
            self._times = np.concatenate([self._times, np.full(len(points), float(time))])
        self.forget(time)

    def forget(self, time: float) -> None:
        """Drops the returns older than `max_age` at `time` and keeps at most `max_points`."""
        keep = self._times >= time - self.max_age
        if np.count_nonzero(keep) > self.max_points:
            keep &= np.arange(len(keep)) >= len(keep) - self.max_points
        if not np.all(keep):
            self._points = self._points[keep]
            self._times = self._times[keep]

    def horizontal_slice(self, position, band: float = 0.5) -> np.ndarray:
        """(m, 2) world-aligned (x, y) offsets from `position` of the points whose depth is
        within `band` metres of the vehicle's."""
        position = _check_position(position)
        if not band > 0:
            raise ValueError(f"horizontal_slice band must be > 0 m, got {band}")
        rel = self._points - position
        return rel[np.abs(rel[:, 2]) <= band, :2]

    def vertical_slice(self, position, direction_yaw: float, band: float = 0.5) -> np.ndarray:
        """(m, 2) (s, h) coordinates of the points within `band` metres of the vertical plane
        through `position` along yaw `direction_yaw`: s along (cos, sin, 0) of that yaw, h up."""
        position = _check_position(position)
        if not band > 0:
            raise ValueError(f"vertical_slice band must be > 0 m, got {band}")
        e = np.array([np.cos(direction_yaw), np.sin(direction_yaw)])
        rel = self._points - position
        s = rel[:, :2] @ e
        lateral = rel[:, 0] * -e[1] + rel[:, 1] * e[0]
        keep = np.abs(lateral) <= band
        return np.column_stack([s[keep], rel[keep, 2]])


def _check_position(position) -> np.ndarray:
    position = np.asarray(position, dtype=float)
    if position.shape != (3,) or not np.all(np.isfinite(position)):
        raise ValueError(f"position must be a finite 3-vector, got {position!r}")
    return position
