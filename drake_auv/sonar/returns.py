"""`SonarReturns`: what a sonar system outputs, the returns of the pings of its last update."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SonarReturns:
    """Returns of n beams, placed with the estimated (navigation) state. Immutable: the
    arrays are made read-only (views are copied first), so Drake's state copies share them.
    (`scan`'s returns derive their points on first read: see `of_scan`.)

    Attributes:
        time: time of the update, s.
        origin_nav: (3,) sensor origin in the navigation frame, m.
        angles: (n,) beam angles in the scan plane of the sensor, rad.
        ranges: (n,) measured range, m; NaN where a beam had no return.
        directions_nav: (n, 3) unit beam directions in the navigation frame.
        points_nav: (n, 3) return points in the navigation frame, m (NaN rows: no return).
        points_body: (n, 3) return points in the body frame, m (NaN rows: no return).
        max_range: the sensor's maximum range, m (a beam without return saw free space to it).
        sequence: update counter, 0 before the first update, +1 at each update, so consumers
            can tell new data from old.
    """

    time: float
    origin_nav: np.ndarray
    angles: np.ndarray
    ranges: np.ndarray
    directions_nav: np.ndarray
    points_nav: np.ndarray
    points_body: np.ndarray
    max_range: float
    sequence: int = 0

    def __post_init__(self):
        for name in ("origin_nav", "angles", "ranges", "directions_nav", "points_nav",
                     "points_body"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.flags.writeable and value.base is not None:
                value = value.copy()  # a view: do not freeze someone else's array
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __deepcopy__(self, memo):
        # Immutable (frozen, read-only arrays): Drake's state copies can share it.
        return self

    @classmethod
    def of_scan(cls, time: float, origin_nav, angles, ranges, directions_nav, max_range: float,
                sequence: int, mount_position, directions_body, position_nav,
                rotation_nav) -> "SonarReturns":
        """The returns of one `scan`, from float64 arrays that are already read-only and
        shared with no one who may write them (the per-field conversions are skipped).
        `points_body` (mount_position + range * directions_body) and `points_nav`
        (position_nav + rotation_nav @ points_body) are derived on first read: most
        consumers (the mapper, the multibeam's) read only the ranges and directions."""
        returns = object.__new__(cls)
        for name, value in (("time", time), ("origin_nav", origin_nav), ("angles", angles),
                            ("ranges", ranges), ("directions_nav", directions_nav),
                            ("max_range", max_range), ("sequence", sequence),
                            ("_frame", (mount_position, directions_body, position_nav,
                                        rotation_nav))):
            object.__setattr__(returns, name, value)
        return returns

    def __getattr__(self, name):
        # Only reached for attributes not set yet: the points of `of_scan` returns.
        frame = self.__dict__.get("_frame") if name in ("points_body", "points_nav") else None
        if frame is None:
            raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")
        mount_position, d_b, p_nb, r_nb = frame
        points_body = mount_position + self.ranges[:, None] * d_b
        points_nav = p_nb + points_body @ r_nb.T
        for key, value in (("points_body", points_body), ("points_nav", points_nav)):
            value.setflags(write=False)
            object.__setattr__(self, key, value)  # the same values for everyone sharing it
        return self.__dict__[name]

    @classmethod
    def empty(cls, max_range: float) -> "SonarReturns":
        """No beams yet (the value before the first update)."""
        return cls(0.0, np.zeros(3), np.zeros(0), np.zeros(0), np.zeros((0, 3)),
                   np.zeros((0, 3)), np.zeros((0, 3)), float(max_range), 0)

    def __len__(self) -> int:
        return len(self.ranges)

    @property
    def hit(self) -> np.ndarray:
        """(n,) True where a beam returned."""
        return np.isfinite(self.ranges)
