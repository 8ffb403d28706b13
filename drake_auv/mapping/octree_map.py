"""The on-line probabilistic occupancy map: an OctoMap octree fed by sonar returns.

`OctreeMap` wraps `octomap.OcTree` (octomap-python) with the OctoMap defaults of Hornung et
al. (hit 0.7, miss 0.4, clamping 0.12 / 0.97, occupied above 0.5). Returns are inserted with
free-space ray casting: a beam with a return marks its end voxel occupied and the voxels it
crossed free; a beam without a return clears free space up to the sonar's maximum range only.
Frame: the navigation frame (the world as the vehicle believes it), metres.

Insertion is eager (`lazy_eval=False`): OctoMap updates the inner nodes on the way back up
and prunes every subtree whose eight leaves have come to hold the same log-odds (most of them
free water at the clamping threshold, where further misses change nothing), so the tree holds
what the scans distinguish, not every voxel a beam ever crossed. Lazy insertion, which defers
that, never prunes: on the first 1,200 s of `monterey_wall` it held 1.11 M leaves (31 MB)
against 0.70 M (20 MB) here, and the gap widens as beams sweep the same water again, for
about 10 % more work per multibeam ping (docs/benchmarks.md: 0.86 against 0.77 ms). Pruning changes no label or
log-odds: `search` finds the leaf, or the pruned node it was merged into, which carries the
same value, and a pruned node is expanded with that value when a later scan touches it.
Discretised insertion (`discretize`, off by default) is OctoMap's own trade: the endpoints of
a scan are first reduced to one per voxel, and one ray is cast to each such voxel's centre
(`computeDiscreteUpdate`). A voxel is marked occupied by the same scans, but free water is
cleared along rays towards voxel centres, up to half a voxel diagonal off the beams; a
240-beam fan inserts about 25 % faster.

Occupied voxels are found among the candidates, whose labels are cached. A candidate is a
voxel hit and not read as free since: a voxel becomes occupied only by a hit on it (a miss
lowers its log-odds, pruning and clamping change no label), so a candidate read as free leaves
the index (its code, its tile entry, its row, which a later candidate takes) and a later hit
brings it back. The index thus holds the occupied voxels (the map, which grows with the
surveyed surface) and those hit since their last read, not every voxel ever hit: on a long
dive noise and navigation drift spread the returns over many voxels that later beams cross and
clear (at 1,800 s of `monterey_wall`, 68,570 candidates instead of 168,095). Answers come in
row order, not in the order of the hits. A scan can change only the voxels its rays cross, and
the rays of one sonar update lie in a plane through the sensor (a multibeam fan, the
profiler's head plane), so a cached label is read again from the octree only when the voxel
lies within a voxel of the plane of a scan inserted since (and within its reach), tested
tile by tile first; labels older than the last `_SCAN_WINDOW` scans are read again. Scans
whose rays are not coplanar mark their whole reach. A 1 Hz box query thus reads the few voxels
the last second of pings swept, not every voxel in the box.

Distance queries go through a KD-tree of occupied voxel centres that is rebuilt lazily, only
when the map changed since the last build, so the 1 Hz replanner pays for it once per step.
"""

from __future__ import annotations

import math

import numpy as np
import octomap
from scipy.spatial import cKDTree

from drake_auv.mapping.lattice import OFFSET, decode, encode, in_box, in_sorted, unique

_SCAN_WINDOW = 40  # scans remembered for the label cache; older labels are read again
_TILE = 16  # voxels along a tile's edge (the candidates' spatial index)
_LIMIT = 1e9  # m, where an unbounded box is clipped
_LEFT = np.iinfo(np.int64).max  # the revision of a row whose candidate left the index
_MERGE = 4096  # codes added or removed before `_CodeSet` merges them into its bulk
_COMPACT = 4096  # rows filled (at least, and an eighth of the index) before `_compact`


class _CodeSet:
    """A set of int64 voxel codes in sorted arrays, 8 bytes a code (a Python set of them takes
    ~60): the bulk, the codes added since its last merge and those of the bulk since removed,
    the last two at most `_MERGE` each, so adding and removing cost what changes (and one
    pass over the bulk every `_MERGE` codes) and a lookup is three binary searches."""

    def __init__(self):
        none = np.zeros(0, dtype=np.int64)
        self._bulk, self._added, self._removed = none, none, none

    def __len__(self) -> int:
        return len(self._bulk) - len(self._removed) + len(self._added)

    @property
    def nbytes(self) -> int:
        return self._bulk.nbytes + self._added.nbytes + self._removed.nbytes

    def contains(self, codes: np.ndarray) -> np.ndarray:
        """(n,) whether each of `codes` (n,) is in the set."""
        return ((in_sorted(self._bulk, codes) & ~in_sorted(self._removed, codes))
                | in_sorted(self._added, codes))

    def add(self, codes: np.ndarray) -> None:
        """Adds `codes` (unique, none in the set)."""
        back = in_sorted(self._removed, codes)  # removed from the bulk, still there
        if back.any():
            self._removed = self._removed[~in_sorted(np.sort(codes[back]), self._removed)]
        added = np.concatenate([self._added, codes[~back]])
        added.sort(kind="stable")  # two sorted runs (`codes` come sorted): a linear merge
        if len(added) > _MERGE:
            self._bulk = np.insert(self._bulk, np.searchsorted(self._bulk, added), added)
            added = added[:0]
        self._added = added

    def remove(self, codes: np.ndarray) -> None:
        """Removes `codes` (unique, all in the set)."""
        codes = np.sort(codes)
        fresh = in_sorted(self._added, codes)
        if fresh.any():
            self._added = self._added[~in_sorted(codes[fresh], self._added)]
        removed = np.concatenate([self._removed, codes[~fresh]])
        removed.sort(kind="stable")  # two sorted runs: a linear merge
        if len(removed) > _MERGE:  # each a code of the bulk, once
            self._bulk = np.delete(self._bulk, np.searchsorted(self._bulk, removed))
            removed = removed[:0]
        self._removed = removed


def _grown(rows: np.ndarray, size: int) -> np.ndarray:
    """`rows` in a buffer of `size` rows, the new ones unwritten (so not resident until used;
    `np.resize` would fill them with copies)."""
    out = np.empty((size,) + rows.shape[1:], dtype=rows.dtype)
    out[:len(rows)] = rows
    return out


def _log_odds_or_unknown(node) -> float:
    """The log-odds of an `OcTree.search` result, -inf for no node (unknown space)."""
    try:
        return node.getLogOdds()
    except octomap.NullPointerException:
        return -np.inf


def _tile_codes(idx: np.ndarray) -> np.ndarray:
    """Codes of the tiles holding voxels of index `idx` (n, 3)."""
    return encode(np.floor_divide(idx, _TILE))


class OctreeMap:
    """Probabilistic octree of the structure around the vehicle, in the navigation frame.

    Args:
        resolution: voxel edge, m, in (0.01, 10].
        prob_hit, prob_miss: sensor model probabilities (0.7, 0.4 in OctoMap).
        clamp_min, clamp_max: occupancy clamping thresholds (0.12, 0.97 in OctoMap).
        no_return_clear_m: how far a beam without an echo clears free water, m, > 0 (inf:
            to the sonar's range, OctoMap's way). No echo is not proof of water: a dropout,
            a weak or grazing echo off rock, and a beam cleared to 20 m carves free water
            through the rock behind (boulder seed 2: a path into a wall facing it, the map
            free there 1,356 s in).
        discretize: insert with OctoMap's discretised update, one ray per endpoint voxel
            (see the module), faster for dense fans; off: every beam is cast.
    """

    def __init__(self, resolution: float = 0.5, prob_hit: float = 0.7, prob_miss: float = 0.4,
                 clamp_min: float = 0.12, clamp_max: float = 0.97,
                 no_return_clear_m: float = np.inf, discretize: bool = False):
        if not (np.isfinite(resolution) and 0.01 < resolution <= 10.0):
            raise ValueError(f"resolution must be in (0.01, 10] m, got {resolution}")
        if not no_return_clear_m > 0:
            raise ValueError(f"no_return_clear_m must be > 0 m (inf: the sonar's range), got "
                             f"{no_return_clear_m}")
        self.no_return_clear_m = float(no_return_clear_m)
        self.discretize = bool(discretize)
        if not 0.5 < prob_hit < 1.0:
            raise ValueError(f"prob_hit must be in (0.5, 1), got {prob_hit}")
        if not 0.0 < prob_miss < 0.5:
            raise ValueError(f"prob_miss must be in (0, 0.5), got {prob_miss}")
        if not 0.0 < clamp_min < 0.5 < clamp_max < 1.0:
            raise ValueError(f"need 0 < clamp_min < 0.5 < clamp_max < 1, got "
                             f"{clamp_min}, {clamp_max}")
        self.resolution = float(resolution)
        self.tree = octomap.OcTree(self.resolution)
        self.tree.setProbHit(prob_hit)
        self.tree.setProbMiss(prob_miss)
        self.tree.setClampingThresMin(clamp_min)
        self.tree.setClampingThresMax(clamp_max)
        self.clear()

    def clear(self) -> None:
        """Forgets everything: the whole map becomes unknown."""
        self.tree.clear()
        self._candidates = _CodeSet()  # codes of the candidates: a superset of the occupied
        # The candidates as rows of arrays (the first `_count` rows of a buffer that grows by a
        # quarter, so adding costs what is added and memory grows in small steps; rows left by
        # candidates read as free, in `_vacant`, are taken first): centres, cached label and
        # the revision at which it was read from the octree (-1: never; `_LEFT`: a vacant
        # row). `_tiles`: per tile of `_TILE` voxels a side, the rows of its candidates, so a
        # box query visits only the box's tiles.
        self._count = 0
        self._vacant: list[np.ndarray] = []
        self._placed = 0  # rows filled since the last `_compact`
        self._centres = np.zeros((0, 3))
        self._label = np.zeros(0, dtype=bool)
        self._checked = np.zeros(0, dtype=np.int64)
        self._log_odds = np.zeros(0)  # read with the label (used for the occupied)
        self._tiles: dict[int, np.ndarray] = {}
        self._new_codes: list[np.ndarray] = []  # hit, not yet in the arrays
        # The scans as rows (revision, origin, plane normal, plane tolerance and reach, m) of
        # a buffer of twice `_SCAN_WINDOW`, the last `_SCAN_WINDOW` kept when it fills.
        self._scan_rows = np.zeros((2 * _SCAN_WINDOW, 9))
        self._num_scan_rows = 0
        self._occupied = np.zeros((0, 3))
        self._kdtree: cKDTree | None = None
        self._dirty = False
        self.revision = 0
        self.num_scans = 0

    def insert_scan(self, origin, directions, ranges, max_range: float) -> None:
        """Inserts one scan from `origin` (3,) along unit `directions` (n, 3).

        `ranges` (n,) are metres, NaN (or beyond `max_range`) where a beam had no return;
        such beams clear free space up to `max_range` and mark nothing occupied.
        """
        origin = np.asarray(origin, dtype=float).reshape(-1)
        directions = np.asarray(directions, dtype=float)
        ranges = np.asarray(ranges, dtype=float).reshape(-1)
        if origin.shape != (3,) or not all(map(math.isfinite, origin.tolist())):
            raise ValueError(f"scan origin must be a finite 3-vector, got {origin}")
        if directions.ndim != 2 or directions.shape[1] != 3 or len(directions) != len(ranges):
            raise ValueError(f"directions must be (n, 3) matching ranges (n,), got "
                             f"{directions.shape} and {ranges.shape}")
        if not (math.isfinite(max_range) and max_range > 0):
            raise ValueError(f"max_range must be > 0 m, got {max_range}")
        if (ranges < 0).any():
            raise ValueError("ranges must be >= 0 m or NaN for no return")
        finite = np.isfinite(directions)
        if not finite.all():  # beams without a direction go (the rows test only then)
            valid = finite.all(axis=1)
            directions, ranges = directions[valid], ranges[valid]
        if len(ranges) == 0:
            return
        hit = np.isfinite(ranges) & (ranges <= max_range)
        # OctoMap truncates beams longer than maxrange and then only clears free space along
        # them: placing no-return endpoints beyond max_range is its documented way to clear.
        clear = min(float(max_range), self.no_return_clear_m)
        length = np.where(hit, ranges, clear + 2.0 * self.resolution)
        endpoints = origin + directions * length[:, None]
        # OctoMap truncates at one maxrange per cloud: beams without an echo cleared less go
        # in a cloud of their own (a voxel one of them crosses and another beam of the scan
        # hits is then updated by both, not the hit's alone)
        clouds = ([(hit, float(max_range)), (~hit, clear)] if clear < max_range
                  else [(slice(None), float(max_range))])
        for beams, reach in clouds:
            cloud = endpoints[beams]
            if len(cloud):
                self.tree.insertPointCloud(cloud, origin, maxrange=reach, lazy_eval=False,
                                           discretize=self.discretize)
        if np.any(hit):
            # OctoMap keys single-precision points (floor(float(p) / resolution)): keyed in
            # float64, an end on a voxel face (a flat seabed at z = -30 m) lands one voxel off.
            idx = np.floor(endpoints[hit].astype(np.float32).astype(float)
                           * (1.0 / self.resolution))
            codes = unique(encode(idx))
            new = codes[~self._candidates.contains(codes)]
            if len(new):
                self._candidates.add(new)
                self._new_codes.append(new)
        self._dirty = True
        self.revision += 1
        self.num_scans += 1
        self._record_swept(origin, directions, np.minimum(length, max_range))

    def _record_swept(self, origin, directions, lengths) -> None:
        """Remembers where the scan just inserted may have changed labels: the voxels crossed
        by its rays, whose centres lie within half a voxel diagonal of a ray (one voxel here,
        for margin), so within that of the rays' best-fit plane through `origin` widened by
        the rays' largest departure from it."""
        # A fan's outer rays span its plane; otherwise the direction of least spread.
        (ax, ay, az), (bx, by, bz) = directions[0].tolist(), directions[-1].tolist()
        normal = np.array([ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx])
        norm = math.sqrt(normal @ normal)
        normal = (normal / norm if norm > 1e-3
                  else np.linalg.eigh(directions.T @ directions)[1][:, 0])
        reach = float(lengths.max()) + self.resolution
        tolerance = self.resolution + reach * float(np.abs(directions @ normal).max())
        if self._num_scan_rows == len(self._scan_rows):
            self._scan_rows[:_SCAN_WINDOW - 1] = self._scan_rows[-(_SCAN_WINDOW - 1):]
            self._num_scan_rows = _SCAN_WINDOW - 1
        row = self._scan_rows[self._num_scan_rows]
        row[0], row[1:4], row[4:7], row[7], row[8] = self.revision, origin, normal, tolerance, reach
        self._num_scan_rows += 1

    @property
    def _scans(self) -> np.ndarray:
        """(<= `_SCAN_WINDOW`, 9) the last scans' rows, oldest first (a view)."""
        n = self._num_scan_rows
        return self._scan_rows[max(n - _SCAN_WINDOW, 0):n]

    def _materialise(self) -> None:
        """Moves the newly hit codes into the candidate arrays (labels unread) and tiles,
        into vacant rows first."""
        if not self._new_codes:
            return
        codes = np.concatenate(self._new_codes)
        self._new_codes = []
        taken, need = [], len(codes)
        while need and self._vacant:
            last = self._vacant.pop()
            if len(last) > need:
                self._vacant.append(last[need:])
                last = last[:need]
            taken.append(last)
            need -= len(last)
        start, stop = self._count, self._count + need
        rows = np.concatenate(taken + [np.arange(start, stop)])
        if stop > len(self._label):
            size = max(stop, len(self._label) + len(self._label) // 4, 1024)
            self._centres, self._label, self._checked, self._log_odds = (
                _grown(a, size) for a in (self._centres, self._label, self._checked,
                                          self._log_odds))
        idx = decode(codes)
        self._centres[rows] = (idx + 0.5) * self.resolution
        self._label[rows] = False
        self._checked[rows] = -1
        self._count = stop
        tiles = _tile_codes(idx)
        order = np.argsort(tiles, kind="stable")
        keys, first = np.unique(tiles[order], return_index=True)
        for key, part in zip(keys.tolist(), np.split(rows[order], first[1:])):
            old = self._tiles.get(key)
            self._tiles[key] = part if old is None else np.concatenate([old, part])
        self._placed += len(rows)
        if self._placed > max(_COMPACT, self._count // 8):
            self._compact()

    def _compact(self) -> None:
        """Renumbers the candidates' rows tile by tile (tiles in code order, each tile's in
        its order), so a box query reads its tiles' rows from contiguous memory rather than
        from rows strewn over the buffers by arrival and reuse (on a long dive a cache miss
        per candidate); the vacant rows go. Answers keep their order: a box query lists its
        tiles' rows tile by tile, each tile's in its order, which this keeps."""
        keys = sorted(self._tiles)
        parts = [self._tiles[k] for k in keys]
        live = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int64)
        for a in (self._centres, self._label, self._checked, self._log_odds):
            a[:len(live)] = a[live]
        stops = np.cumsum([len(part) for part in parts])
        renumbered = {k: np.arange(stop - len(part), stop)
                      for k, part, stop in zip(keys, parts, stops.tolist())}
        # in the dict's own order, which a box of more tiles than the map lists them in
        self._tiles = {k: renumbered[k] for k in self._tiles}
        self._count, self._vacant, self._placed = len(live), [], 0

    def _box_index(self, lo: np.ndarray, hi: np.ndarray):
        """Indices of the candidates inside the box [lo, hi] (m), found through the tiles the
        box overlaps (or, for a box of more tiles than the map holds, through every tile);
        with the codes of those tiles and each candidate's position among them."""
        edge = _TILE * self.resolution
        t0 = np.floor(np.maximum(lo, -_LIMIT) / edge).astype(np.int64)
        t1 = np.floor(np.minimum(hi, _LIMIT) / edge).astype(np.int64)
        none = np.zeros(0, dtype=np.int64)
        if np.any(t1 < t0) or not self._tiles:
            return none, (none, none)
        tiles = self._tiles
        if np.prod((t1 - t0 + 1).astype(float)) > len(tiles):
            keys = list(tiles)
        else:
            # `encode`'s fields do not overlap: a tile's code is the sum of its axes' codes.
            x, y, z = (np.arange(a, b + 1, dtype=np.int64) + OFFSET for a, b in zip(t0, t1))
            codes = (x[:, None, None] << 42) + (y[None, :, None] << 21) + z[None, None, :]
            keys = [k for k in codes.ravel().tolist() if k in tiles]
        if not keys:
            return none, (none, none)
        parts = [tiles[k] for k in keys]
        index = np.concatenate(parts)
        tile_of = np.repeat(np.arange(len(parts)), [len(p) for p in parts])
        # `take` gathers rows 3x faster than fancy indexing (numpy 2)
        inside = in_box(np.take(self._centres, index, axis=0), lo, hi)
        return index[inside], (np.array(keys, dtype=np.int64), tile_of[inside])

    def _read_labels(self, index: np.ndarray, tiles=None) -> None:
        """Brings the cached labels of candidates `index` up to the current revision, reading
        from the octree only those a scan since their last read may have changed. `tiles`:
        the (codes, position of each candidate's among them) `_box_index` gives, or None."""
        is_stale = self._checked[index] < self.revision
        stale = index[is_stale]
        if len(stale) == 0:
            return
        if tiles is None:
            keys, tile_of = np.unique(_tile_codes(
                np.floor(self._centres[stale] * (1.0 / self.resolution))), return_inverse=True)
        else:
            keys, tile_of = tiles[0], tiles[1][is_stale]
        checked = self._checked[stale]
        scans = self._scans
        # Read before the oldest remembered scan (or never): read again.
        swept = checked < scans[0, 0] - 1 if len(scans) else np.ones(len(stale), bool)
        test = np.flatnonzero(~swept)
        if len(test):
            # Most were read at the last query and need only the scans since; the rest
            # (entering the box) are tested against every scan since their own read.
            latest = checked[test] == checked[test].max()
            for group in (test[latest], test[~latest]):
                if len(group):
                    swept[group] = self._swept(stale[group], checked[group], scans, keys,
                                               tile_of[group])
        read = stale[swept]
        if len(read):
            log_odds = self._read_log_odds(np.take(self._centres, read, axis=0))
            self._log_odds[read] = log_odds
            self._label[read] = log_odds >= self.tree.getOccupancyThresLog()
        self._checked[stale] = self.revision
        if len(read):
            self._leave(read[~self._label[read]])

    def _read_log_odds(self, centres: np.ndarray) -> np.ndarray:
        """(n,) the log-odds of the voxels at `centres` (n, 3), -inf where unknown: one
        `search` a voxel (its label follows, as in OctoMap's `isNodeOccupied`: at or above
        the occupancy threshold), half what `getLabels` and a second `search` for the
        occupied ones took; rows as lists, which octomap-python indexes faster."""
        search, points = self.tree.search, centres.tolist()
        try:
            return np.fromiter((search(p).getLogOdds() for p in points), dtype=float,
                               count=len(points))
        except octomap.NullPointerException:  # a voxel never updated (not a candidate's)
            return np.array([_log_odds_or_unknown(search(p)) for p in points], dtype=float)

    def _leave(self, rows: np.ndarray) -> None:
        """Takes the candidates of `rows`, read as free, out of the index: their codes, their
        tiles' entries; the rows become vacant (never stale, never occupied)."""
        if len(rows) == 0:
            return
        centres = np.take(self._centres, rows, axis=0)
        idx = np.floor(centres * (1.0 / self.resolution)).astype(np.int64)
        self._candidates.remove(encode(idx))
        self._checked[rows] = _LEFT
        self._vacant.append(rows)
        for key in unique(_tile_codes(idx)).tolist():
            part = self._tiles[key]
            part = part[self._checked[part] != _LEFT]
            if len(part):
                self._tiles[key] = part
            else:
                del self._tiles[key]

    def _swept(self, rows: np.ndarray, checked: np.ndarray, scans: np.ndarray,
               keys: np.ndarray, tile_of: np.ndarray) -> np.ndarray:
        """(m,) True where the centre of candidate `rows` (m,) lies in the plane slab and the
        reach of a scan (rows of `_scans`) inserted after its label was read (`checked`);
        `keys` are tile codes and `tile_of` (m,) the position of each one's tile among them.

        Tiles first: a scan can sweep a voxel only if its slab and its sphere meet the
        voxel's tile (the tile's box widened by the slab's projection of it), so each voxel
        is tested only against the scans that reach its tile, and a voxel of a tile no scan
        reaches (most of a query's box: one second of pings sweeps a strip) not at all."""
        scans = scans[scans[:, 0] > checked.min()]
        out = np.zeros(len(rows), bool)
        if len(scans) == 0:
            return out
        origins, normals = scans[:, 1:4], scans[:, 4:7]
        tolerance, reach = scans[:, 7], scans[:, 8]
        offsets = np.einsum("sk,sk->s", origins, normals)
        edge = _TILE * self.resolution
        half = 0.5 * edge * (1.0 + 1e-9)
        middle = (decode(keys) + 0.5) * edge  # (T, 3) tile centres
        gap = np.maximum(np.abs(middle[:, None, :] - origins[None]) - half, 0.0)  # (T, S, 3)
        reaches = np.einsum("tsk,tsk->ts", gap, gap) <= reach ** 2
        along = np.abs(middle @ normals.T - offsets)
        reaches &= along <= tolerance + half * np.abs(normals).sum(axis=1)
        test = np.flatnonzero(reaches.any(axis=1)[tile_of])  # in a tile some scan reaches
        pairs = reaches[tile_of[test]] & (scans[:, 0] > checked[test, None])  # (m', S)
        some = pairs.any(axis=1)
        test, pairs = test[some], pairs[some]
        origin_sq = np.einsum("sk,sk->s", origins, origins)
        for chunk in range(0, len(test), 8192):  # (8192, S) blocks bound the memory
            part = slice(chunk, chunk + 8192)
            c = np.take(self._centres, rows[test[part]], axis=0)
            plane = np.abs(c @ normals.T - offsets) <= tolerance
            dist_sq = np.einsum("mk,mk->m", c, c)[:, None] - 2.0 * (c @ origins.T) + origin_sq
            out[test[part]] = (plane & (dist_sq <= reach ** 2) & pairs[part]).any(axis=1)
        return out

    def insert_returns(self, returns) -> None:
        """Inserts a `drake_auv.sonar.SonarReturns` (navigation frame)."""
        if returns is None or len(np.atleast_1d(returns.ranges)) == 0:
            return
        self.insert_scan(returns.origin_nav, returns.directions_nav, returns.ranges,
                         returns.max_range)

    def _refresh(self) -> None:
        if not self._dirty:
            return
        self._materialise()
        self._read_labels(np.arange(self._count))
        self._occupied = self._centres[:self._count][self._label[:self._count]]
        self._kdtree = cKDTree(self._occupied) if len(self._occupied) else None
        self._dirty = False

    def occupied_points(self, lo=None, hi=None, log_odds: bool = False):
        """(m, 3) centres of the occupied voxels (finest resolution), m; with `log_odds`, also
        their (m,) log-odds.

        With a box (`lo`, `hi`: (3,) corners, m), only the voxels inside it, found through the
        tiles the box overlaps, and only those are brought up to date (of them, only the ones
        recent scans swept are read from the octree): a local query (the replanner's) costs
        what the box holds, not what the whole map holds.
        """
        if lo is None and hi is None and not log_odds:
            self._refresh()
            return self._occupied
        lo = np.full(3, -np.inf) if lo is None else np.asarray(lo, dtype=float)
        hi = np.full(3, np.inf) if hi is None else np.asarray(hi, dtype=float)
        self._materialise()
        inside, tiles = self._box_index(lo, hi)
        self._read_labels(inside, tiles)
        occupied = inside[self._label[inside]]
        if log_odds:
            return np.take(self._centres, occupied, axis=0), self._log_odds[occupied]
        return np.take(self._centres, occupied, axis=0)

    def candidates(self) -> tuple[np.ndarray, np.ndarray]:
        """The voxels hit since their label was last read as free (a superset of the occupied
        ones), by row: their centres (n, 3), m, and whether each one's label was never read
        from the octree (n,) (a box query reads only the voxels in its box)."""
        self._materialise()
        checked = self._checked[:self._count]
        live = checked != _LEFT
        return self._centres[:self._count][live], checked[live] == -1

    @property
    def kdtree(self) -> cKDTree | None:
        """KD-tree of the occupied voxel centres (None while nothing is occupied)."""
        self._refresh()
        return self._kdtree

    def distance(self, points, upper_bound: float = np.inf) -> np.ndarray:
        """Distance from `points` (..., 3) to the nearest occupied voxel centre, m.

        inf where no occupied voxel lies within `upper_bound` (or the map holds none).
        """
        points = np.asarray(points, dtype=float)
        if points.shape[-1] != 3:
            raise ValueError(f"points must have shape (..., 3), got {points.shape}")
        tree = self.kdtree
        if tree is None:
            return np.full(points.shape[:-1], np.inf)
        d, _ = tree.query(points.reshape(-1, 3), distance_upper_bound=upper_bound)
        return d.reshape(points.shape[:-1])

    def memory(self) -> dict:
        """The map's memory, MB: the OctoMap tree's own (`memoryUsage`, its leaves counted)
        and the candidates' index (its arrays and codes, its tiles estimated); the
        candidates now in the index."""
        index = (self._centres.nbytes + self._label.nbytes + self._checked.nbytes
                 + self._log_odds.nbytes
                 + sum(t.nbytes + 100 for t in self._tiles.values())
                 + self._candidates.nbytes)
        return dict(resolution_m=self.resolution, leaves=int(self.tree.getNumLeafNodes()),
                    octree_mb=self.tree.memoryUsage() / 2**20, candidates=len(self._candidates),
                    index_mb=index / 2**20)

    def labels(self, points) -> np.ndarray:
        """(n,) per point: 1 occupied, 0 free, -1 unknown."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        return np.asarray(self.tree.getLabels(points))

    def write(self, filename) -> None:
        """Saves the octree in OctoMap's binary format (.bt), readable by octovis."""
        if not self.tree.writeBinary(str(filename).encode()):
            raise ValueError(f"could not write octree to {filename}")

