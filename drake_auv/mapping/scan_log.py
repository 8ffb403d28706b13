"""The sonar returns a mission has received, as an immutable, persistent log streamed to disk.

`ScanLog` is a singly linked list growing at its head: appending a `ScanBatch` makes a new head
that points to the old one, so each version of the log is a value that never changes and
versions share their past. That is what Drake's abstract state needs: the Context holds the
log, every copy Drake makes of it (two per unrestricted update) is free because an immutable
value is its own copy, and each Context's history is its own. The octree map is a function of
the log (`mapping.mapper`), and so is the recorded point cloud of the dive.

Memory does not grow with the beams: a batch's arrays go, when it is appended, to the log's
`ScanStore`, an append-only temporary file (deleted when the last version of the log goes),
which only the most recent `CACHE_BATCHES` batches also keep in memory (what the mapper reads:
the batches since its last update). Nor with the batches, beyond 8 bytes each: a version holds
its count, its record's offset, the running count of returns and its history, which is the
chain of the versions since the last multiple of `CHUNK_BATCHES` batches (one small object per
batch, at most `CHUNK_BATCHES` of them) and, before that, frozen chunks of `CHUNK_BATCHES`
record offsets (an int64 array each, linked newest first). So the versions older than the
current chunk are no longer objects (176 B a batch when each was: 51 MB for the 290,000
batches of a 4 h dive); what still reaches them is their offsets. A record's offset is unique
in its store (each append writes a new record), so a version is in another's past exactly when
the other's history holds its newest offset at its count: that is how `since` knows a consumer's
version without keeping it. Versions of one log, and so the Contexts cloned from one another,
share its store: a record never changes once written, and each version reaches only its own
records. An empty log has no store; its first append opens one, so a fresh Context shares
nothing with an earlier run. Reading an old batch (an octree rebuilt for a copied Context,
`points.ply`) reads its record back.

A batch's `source` is an index into its log's `sources`, the names of the sensors that feed
it (`sonar.sensor.source_table`: the built-in ones first, so their indices never change).

Frame: the navigation frame (the world as the vehicle believes it), metres, seconds.
"""

from __future__ import annotations

import tempfile
from collections import OrderedDict
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from drake_auv.sonar.sensor import BUILT_IN

CACHE_BATCHES = 64  # the newest batches a store also keeps in memory
CHUNK_BATCHES = 1024  # record offsets frozen into one array of a version's history
# A record: this header, then the directions (n, 3) and ranges (n,) as little-endian float32.
_HEADER = np.dtype([("time", "<f8"), ("source", "<i8"), ("origin", "<f8", (3,)),
                    ("max_range", "<f8"), ("n", "<i8")])


def _frozen(array, dtype) -> np.ndarray:
    out = np.array(array, dtype=dtype)
    out.setflags(write=False)
    return out


@dataclass(frozen=True, eq=False, slots=True)
class ScanBatch:
    """One sensor update: beams from one origin (a multibeam fan, the profiler's pings).

    Attributes:
        time: s. source: index into its log's `sources`. origin: (3,) sensor origin, m.
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
    def make(cls, time, source: int | str, origin, directions, ranges,
             max_range) -> "ScanBatch":
        """The batch, its arrays frozen; `source`: an index, or a `BUILT_IN` source's name."""
        return cls(float(time), BUILT_IN.index(source) if isinstance(source, str) else
                   int(source), _frozen(origin, np.float64),
                   _frozen(directions, np.float32), _frozen(ranges, np.float32),
                   float(max_range))

    def __deepcopy__(self, memo):
        return self  # immutable: frozen fields, read-only arrays

    def points(self) -> np.ndarray:
        """(m, 3) return points of the beams with a return, m."""
        hit = np.isfinite(self.ranges)
        return self.origin + self.directions[hit] * self.ranges[hit, None]


class ScanStore:
    """The append-only file of one log's batches, with its newest `cache` batches in memory.

    Shared, never copied (`__deepcopy__` returns it): records are immutable once written.
    """

    def __init__(self, cache: int = CACHE_BATCHES):
        self._file = tempfile.TemporaryFile(prefix="drake_auv-scans-")
        self._end = 0
        self._cache: OrderedDict[int, ScanBatch] = OrderedDict()
        self._size = int(cache)

    def __deepcopy__(self, memo):
        return self

    @property
    def nbytes(self) -> int:
        """Bytes written to the file."""
        return self._end

    @property
    def cached(self) -> int:
        """How many batches are held in memory (at most `cache`)."""
        return len(self._cache)

    def put(self, batch: ScanBatch) -> int:
        """Writes `batch` at the end of the file; returns its record's offset."""
        header = np.zeros(1, _HEADER)
        header[0] = (batch.time, batch.source, batch.origin, batch.max_range, len(batch.ranges))
        offset = self._end
        self._file.seek(offset)
        self._file.write(header.tobytes())
        self._file.write(np.ascontiguousarray(batch.directions, "<f4").tobytes())
        self._file.write(np.ascontiguousarray(batch.ranges, "<f4").tobytes())
        self._end = self._file.tell()
        self._remember(offset, batch)
        return offset

    def get(self, offset: int, remember: bool = True) -> ScanBatch:
        """The batch recorded at `offset` (from memory when recent); `remember` False: a pass
        over old records that should not evict the recent ones."""
        batch = self._cache.get(offset)
        if batch is not None:
            self._cache.move_to_end(offset)
            return batch
        self._file.seek(offset)
        header = np.frombuffer(self._file.read(_HEADER.itemsize), _HEADER)[0]
        n = int(header["n"])
        directions = np.frombuffer(self._file.read(12 * n), "<f4").reshape(n, 3)
        ranges = np.frombuffer(self._file.read(4 * n), "<f4")
        batch = ScanBatch(float(header["time"]), int(header["source"]),
                          _frozen(header["origin"], np.float64), directions, ranges,
                          float(header["max_range"]))  # frombuffer of bytes: read-only
        if remember:
            self._remember(offset, batch)
        return batch

    def _remember(self, offset: int, batch: ScanBatch) -> None:
        self._cache[offset] = batch
        while len(self._cache) > self._size:
            self._cache.popitem(last=False)


@dataclass(frozen=True, eq=False, slots=True)
class _Batches:
    """Some consecutive batches of a log, oldest first, read from its store when asked
    (`batches()`, what `reconstruction.pointcloud.from_scan_log` reads); `sources`: the log's."""

    store: ScanStore
    offsets: list
    sources: tuple

    def batches(self) -> list[ScanBatch]:
        return [self.store.get(offset, remember=False) for offset in self.offsets]


@dataclass(frozen=True, eq=False, slots=True)
class _Chunk:
    """`CHUNK_BATCHES` consecutive record offsets of a log's history (read-only int64), the
    older ones in `parent`; `count`: the batches up to and including this chunk's last."""

    offsets: np.ndarray
    parent: "_Chunk | None"
    count: int


@dataclass(frozen=True, eq=False, slots=True)
class ScanLog:
    """A version of the log: `count` batches, the newest in `store` at `offset`; `returns`: the
    beams with a return (finite range) of all `count` batches. Its history: `parent`, the
    previous version while it lies in the current chunk (None at a multiple of
    `CHUNK_BATCHES`), and `chunk`, the frozen offsets of the batches before that. `sources`:
    the names a batch's `source` indexes (every version of a log has its first's)."""

    count: int = 0
    parent: "ScanLog | None" = None
    store: ScanStore | None = None
    offset: int = -1
    returns: int = 0
    chunk: _Chunk | None = None
    sources: tuple = BUILT_IN

    def __deepcopy__(self, memo):
        return self  # immutable, and so are the versions it points to

    @property
    def batch(self) -> ScanBatch | None:
        """The newest batch (None for the empty log)."""
        return None if self.count == 0 else self.store.get(self.offset)

    def append(self, batch: ScanBatch) -> "ScanLog":
        store = self.store if self.store is not None else ScanStore()
        offset = store.put(batch)
        returns = self.returns + int(np.count_nonzero(np.isfinite(batch.ranges)))
        count = self.count + 1
        if count % CHUNK_BATCHES:
            return ScanLog(count, self, store, offset, returns, self.chunk, self.sources)
        # The chunk is full: its offsets become one array, and its versions can go.
        node, tail = self, [offset]
        while node.count > count - CHUNK_BATCHES:
            tail.append(node.offset)
            node = node.parent
        return ScanLog(count, None, store, offset, returns,
                       _Chunk(_frozen(tail[::-1], np.int64), self.chunk, count), self.sources)

    def _offsets_since(self, older: "ScanLog | None") -> list[int] | None:
        """The offsets of the batches after version `older`, oldest first (None when `older`
        is not in this version's past: another store, or another newest offset at its count).
        Walks only the versions and chunks after `older`."""
        low = 0 if older is None else older.count
        if low > self.count or (low > 0 and older.store is not self.store):
            return None
        node, tail = self, []
        while node.count > low and node.parent is not None:
            tail.append(node.offset)
            node = node.parent
        parts, before = [], node.offset  # `before`: the offset of batch `low` - 1
        if node.count > low:  # a chunk boundary: the rest lies in the chunks
            chunk = node.chunk
            while chunk is not None and chunk.count > low:
                first = chunk.count - len(chunk.offsets)
                parts.append(chunk.offsets[max(low - first, 0):])
                if first < low:
                    before = int(chunk.offsets[low - first - 1])
                    break
                chunk = chunk.parent
            else:
                before = int(chunk.offsets[-1]) if chunk is not None else -1
        if low > 0 and before != older.offset:
            return None
        return np.concatenate(parts[::-1]).tolist() + tail[::-1] if parts else tail[::-1]

    def since(self, older: "ScanLog | None") -> list[ScanBatch] | None:
        """The batches appended after version `older`, oldest first; None when `older` is not
        a version of this log's past (then a consumer must start again from the empty log)."""
        offsets = self._offsets_since(older)
        return None if offsets is None else [self.store.get(o) for o in offsets]

    def batches(self) -> list[ScanBatch]:
        """Every batch, oldest first (all in memory: for short logs; see `chunks`)."""
        return self.since(None)

    def chunks(self, size: int = 500) -> Iterator[_Batches]:
        """The batches, oldest first, `size` at a time, each group read from the store only
        when its `batches()` is called: a whole dive in bounded memory."""
        offsets = self._offsets_since(None)
        for start in range(0, len(offsets), size):
            yield _Batches(self.store, offsets[start:start + size], self.sources)

    def iter_batches(self) -> Iterator[ScanBatch]:
        """Every batch, oldest first, read one at a time."""
        for chunk in self.chunks():
            yield from chunk.batches()
