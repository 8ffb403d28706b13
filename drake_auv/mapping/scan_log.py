"""The sonar returns a mission has received, as an immutable, persistent log.

`ScanLog` is a singly linked list growing at its head: appending a `ScanBatch` makes a new head
that points to the old one, so each version of the log is a value that never changes and
versions share their past. That is what Drake's abstract state needs: the Context holds the
log, every copy Drake makes of it (two per unrestricted update) is free because an immutable
value is its own copy, and each Context's history is its own. The octree map is a function of
the log (`mapping.mapper`), and so is the recorded point cloud of the dive.

Frame: the navigation frame (the world as the vehicle believes it), metres, seconds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SOURCES = ("multibeam", "profiler")


def _frozen(array, dtype) -> np.ndarray:
    out = np.array(array, dtype=dtype)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False)
class ScanBatch:
    """One sensor update: beams from one origin (a multibeam fan, the profiler's pings).

    Attributes:
        time: s. source: index into `SOURCES`. origin: (3,) sensor origin, m.
        directions: (n, 3) unit beam directions (float32). ranges: (n,) m, NaN: no return.
        max_range: m (beams without a return clear free space up to it).
    """

    time: float
    source: int
    origin: np.ndarray
    directions: np.ndarray
    ranges: np.ndarray
    max_range: float

    @classmethod
    def make(cls, time, source: str, origin, directions, ranges, max_range) -> "ScanBatch":
        return cls(float(time), SOURCES.index(source), _frozen(origin, np.float64),
                   _frozen(directions, np.float32), _frozen(ranges, np.float32),
                   float(max_range))

    def __deepcopy__(self, memo):
        return self  # immutable: frozen fields, read-only arrays

    def points(self) -> np.ndarray:
        """(m, 3) return points of the beams with a return, m."""
        hit = np.isfinite(self.ranges)
        return self.origin + self.directions[hit] * self.ranges[hit, None]


@dataclass(frozen=True, eq=False)
class ScanLog:
    """A version of the log: `count` batches, the newest `batch`, the older ones in `parent`."""

    count: int = 0
    batch: ScanBatch | None = None
    parent: "ScanLog | None" = None

    def __deepcopy__(self, memo):
        return self  # immutable, and so are the versions it points to

    def append(self, batch: ScanBatch) -> "ScanLog":
        return ScanLog(self.count + 1, batch, self)

    def since(self, older: "ScanLog | None") -> list[ScanBatch] | None:
        """The batches appended after version `older`, oldest first; None when `older` is not
        a version of this log's past (then a consumer must start again from the empty log)."""
        older_count = 0 if older is None else older.count
        node, out = self, []
        while node.count > older_count:
            out.append(node.batch)
            node = node.parent
        if older is not None and older.count > 0 and node is not older:
            return None
        out.reverse()
        return out

    def batches(self) -> list[ScanBatch]:
        """Every batch, oldest first."""
        return self.since(None)
