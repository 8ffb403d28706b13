"""The on-line map near a replanning section as distance fields (pure numpy/scipy).

`SliceMap` is what the replanning cost reads: the offset to the structure (a 2D distance
transform of a depth band, or the exact 3D distance with a precomputed tube of grid nodes)
and the 3D clearance to every counted voxel, built once per replanning step from the octree's
voxels in the section's box.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from drake_auv.mapping.lattice import decode, encode, in_box, in_sorted, unique

DEPTH_MARGIN = 1.0  # m, how far rollouts may stray from the section's depths (see SliceMap)
SWEEP_SAMPLES = 4  # samples per voxel edge along a segment in `SliceMap.crossing`


def _kdtree(points: np.ndarray) -> cKDTree:
    """KD-tree of voxel centres, built for this use: rebuilt at every step and queried from
    metres away, where the voxels of a surface are nearly equidistant and a default tree
    visits many small leaves. Large, unbalanced (sliding-midpoint) leaves answer the same
    nearest neighbours 2-4x faster here and build faster."""
    return cKDTree(points, leafsize=64, balanced_tree=False, compact_nodes=False)


class _DistanceField2D:
    """Euclidean distance transform (`scipy.ndimage.distance_transform_edt`) of voxel
    columns (m, 2) on the voxel grid over the box [lo, hi] (m), cell centres on the voxel
    centres; distances from the box's voxels to the nearest column, m."""

    def __init__(self, points: np.ndarray, lo: np.ndarray, hi: np.ndarray, resolution: float):
        self.origin = (np.floor(lo / resolution) + 0.5) * resolution  # the first cell's centre
        self.cell = resolution
        shape = np.floor((hi - self.origin) / resolution).astype(int) + 2
        cells = np.round((points - self.origin) / resolution).astype(int)
        i, j = cells[:, 0], cells[:, 1]  # column by column: 6x `np.all(..., axis=1)` here
        cells = np.compress((i >= 0) & (i < shape[0]) & (j >= 0) & (j < shape[1]), cells, axis=0)
        free = np.ones(shape, bool)
        free[cells[:, 0], cells[:, 1]] = False
        self.empty = len(cells) == 0  # no column in the box: inf everywhere
        self.field = (np.full(shape, np.inf) if self.empty
                      else ndimage.distance_transform_edt(free, sampling=resolution))
        self._last = (np.array(shape) - 1)[:, None]  # the largest cell index per axis

    def _coords(self, points: np.ndarray) -> np.ndarray:
        return ((points[:, :2] - self.origin) / self.cell).T

    def interpolate(self, points: np.ndarray) -> np.ndarray:
        """(n,) bilinear interpolation at `points` (n, >= 2); the box's edge beyond it."""
        return ndimage.map_coordinates(self.field, self._coords(points), order=1,
                                       mode="nearest")

    def box_lower_bound(self, points: np.ndarray) -> float:
        """At most `lower_bound` of every one of `points` (n >= 1, >= 2): the least value of
        the cells nearest to their bounding box (an index is monotonic in its coordinate), so
        one slice stands for n reads when the batch is far from every column."""
        xy = np.ascontiguousarray(points[:, :2].T)  # rows reduce 1.6x faster than columns
        (x0, y0), (x1, y1) = xy.min(axis=1).tolist(), xy.max(axis=1).tolist()
        (ox, oy), cell, (nx, ny) = self.origin.tolist(), self.cell, self._last[:, 0].tolist()
        # round() is rint's half-to-even, on the same float64 operations as `_coords`.
        i0, i1 = (min(max(round((v - ox) / cell), 0), nx) for v in (x0, x1))
        j0, j1 = (min(max(round((v - oy) / cell), 0), ny) for v in (y0, y1))
        return float(self.field[i0:i1 + 1, j0:j1 + 1].min()) - cell * math.sqrt(0.5)

    def lower_bound(self, points: np.ndarray) -> np.ndarray:
        """(n,) at most the distance from `points` (inside the box) to the nearest column:
        the nearest cell's value less half a cell diagonal."""
        idx = np.rint(self._coords(points)).astype(int)
        np.maximum(idx, 0, out=idx)
        np.minimum(idx, self._last, out=idx)
        return self.field[idx[0], idx[1]] - self.cell * np.sqrt(0.5)


@lru_cache(maxsize=8)
def _ball_offsets(radius: float) -> np.ndarray:
    """(m, 3) integer grid offsets within `radius` + sqrt(3) cells of the origin: every
    corner of the cells of points within `radius` cells."""
    reach = radius + np.sqrt(3.0)
    r = int(np.ceil(reach))
    grid = np.arange(-r, r + 1)
    offsets = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), axis=-1).reshape(-1, 3)
    return offsets[np.einsum("ij,ij->i", offsets, offsets) <= reach * reach]


def _voxel_codes(points: np.ndarray, resolution: float):
    """The codes (m,) of voxel centres `points` (m, 3) of `resolution` m, and the same sorted;
    (None, None) when the points are not distinct voxel centres (codes would not name them)."""
    idx = np.floor(points / resolution)
    if not (len(points) and np.array_equal((idx + 0.5) * resolution, points)):
        return None, None
    codes = encode(idx)
    voxels = np.sort(codes)  # the sort alone: 0.7x an argsort here
    if np.any(voxels[1:] == voxels[:-1]):  # two points in one voxel
        return None, None
    return codes, voxels


@dataclass(frozen=True)
class TubeNodes:
    """One step's exact offsets at its tube's grid nodes, kept so that the next step
    computes only what changed (`_TubeField3D`): the codes of the voxels they were measured
    to (sorted), of the nodes (sorted; node g lies at g * `cell`), each node's distance (m)
    and the code of its nearest voxel. Never modified; holds one tube's nodes, not the
    dive's."""

    cell: float
    resolution: float
    voxels: np.ndarray
    nodes: np.ndarray
    distance: np.ndarray
    nearest: np.ndarray


class _TubeField3D:
    """The exact 3D distance to `points` (m, 3) (voxel centres, `tree` their KD-tree) at the
    grid nodes (spacing `cell`, m) around a trajectory (N, 3), read by trilinear
    interpolation: NaN where a point's cell has a corner that was not computed (more than
    `pad` m from every trajectory point).

    STOMP's rollouts stay near the trajectory it starts from, and exact nearest-voxel queries
    from 6-10 m away cost ~3 us a point (1 ms for 11 rollouts of 30 points, 40 times a step
    on the boulder); computing the nodes once and interpolating costs one query per node.
    The distance field is smooth away from the surface, so at 0.5 m nodes the interpolation
    error is millimetres at the offset.

    With `reuse`, the last step's `TubeNodes`, a node it measured keeps its distance unless
    its nearest voxel is gone, lowered to the distance of a voxel added since when that one
    is nearer; only the other nodes query `tree`. The distances are the ones a full query
    gives (the same pairs, the same arithmetic), at a fraction of its cost: consecutive steps
    share most of their nodes and voxels. `nodes` is this step's `TubeNodes` (None when the
    points are not distinct voxel centres of `resolution`, whose codes would not name them).
    """

    def __init__(self, tree: cKDTree, points: np.ndarray, trajectory: np.ndarray, pad: float,
                 cell: float, resolution: float, reuse: TubeNodes | None = None):
        self.cell = cell
        first = np.floor((trajectory.min(axis=0) - pad) / cell) - 1.0
        self.origin = first * cell
        self.shape = tuple(np.floor((trajectory.max(axis=0) + pad - self.origin) / cell)
                           .astype(int) + 3)
        centres = np.rint((trajectory - self.origin) / cell).astype(int)
        nodes = (centres[:, None, :] + _ball_offsets(pad / cell)[None]).reshape(-1, 3)
        nodes = np.compress(in_box(nodes, (0, 0, 0), np.subtract(self.shape, 1)), nodes, axis=0)
        computed = np.zeros(int(np.prod(self.shape)), bool)  # a mask: 20x np.unique here
        computed[np.ravel_multi_index(nodes.T, self.shape)] = True
        flat = np.flatnonzero(computed)
        lattice = np.column_stack(np.unravel_index(flat, self.shape)) + first.astype(np.int64)
        node_points = lattice * cell
        codes, voxels = _voxel_codes(points, resolution)
        distance = np.empty(len(flat))
        nearest = np.empty(len(flat), dtype=np.int64)
        node_codes = encode(lattice)  # sorted: flat is, and the codes keep its order
        fresh = np.ones(len(flat), bool)
        if (reuse is not None and codes is not None and reuse.cell == cell
                and reuse.resolution == resolution and len(reuse.nodes)):
            at = np.minimum(np.searchsorted(reuse.nodes, node_codes), len(reuse.nodes) - 1)
            kept = (reuse.nodes[at] == node_codes) & in_sorted(voxels, reuse.nearest[at])
            distance[kept], nearest[kept] = reuse.distance[at[kept]], reuse.nearest[at[kept]]
            # The voxels added since, from their sorted codes (sorted queries: 4x faster),
            # at their centres: the points themselves (`_voxel_codes` checked that).
            added = voxels[~in_sorted(reuse.voxels, voxels)]
            if len(added) and kept.any():
                d, i = cKDTree((decode(added) + 0.5) * resolution).query(node_points[kept])
                lower = d < distance[kept]
                rows = np.flatnonzero(kept)[lower]
                distance[rows], nearest[rows] = d[lower], added[i[lower]]
            fresh = ~kept
        if fresh.any():
            distance[fresh], i = tree.query(node_points[fresh])
            if codes is not None:
                nearest[fresh] = codes[i]
        self.field = np.full(self.shape, np.nan)
        self.field.flat[flat] = distance
        self.nodes = None if codes is None else TubeNodes(cell, resolution, voxels,
                                                          node_codes, distance, nearest)

    def interpolate(self, points: np.ndarray) -> np.ndarray:
        """(n,) trilinear interpolation at `points` (n, 3); NaN outside the computed nodes."""
        return ndimage.map_coordinates(self.field, ((points - self.origin) / self.cell).T,
                                       order=1, mode="constant", cval=np.nan)


class SliceMap:
    """The on-line map near a section, as the fields the replanning cost reads.

    Built once per replanning step from the occupied voxels in the section's box whose
    log-odds reach `min_log_odds` (all of them when no log-odds are given):
    - offset, metric "horizontal": a 2D Euclidean distance transform (`scipy.ndimage`) of the
      voxels within `depth_band` of the section's depths, on the voxel grid over the box,
      read by bilinear interpolation; metric "3d": the exact 3D distance to any voxel (a
      KD-tree: a 3D transform of the box costs 10-30 ms here). inf where none is mapped;
    - clearance: the exact 3D distance to the voxels within `clearance + margin` of the
      section's depths, the only ones that can be nearer than `clearance` to a point of the
      section (rollouts stay within `margin` of its depths: the depth cost holds them); a 2D
      distance transform of that slab rules most points out, a 3D KD-tree measures the rest;
    - `band_points` / `nearest_band`: the band's voxels, for the yaw that faces them;
    - crossing: how much of each segment between consecutive trajectory points runs inside a
      counted voxel of the box. The sonars map a structure's faces, not its inside, so the
      middle of a 5 m block is 2.5 m from the nearest voxel and the clearance alone prices it
      like open water near a wall; a path into it must cross a face, which this sees.
    `clearance_bound` is the clearance it was built for: the largest the cost may ask.
    """

    def __init__(self, occupied: np.ndarray, z_range: tuple[float, float], depth_band: float,
                 clearance: float, margin: float = DEPTH_MARGIN, metric: str = "horizontal",
                 log_odds: np.ndarray | None = None, min_log_odds: float = 0.0,
                 box: tuple | None = None, resolution: float = 0.5):
        occupied = np.asarray(occupied, dtype=float).reshape(-1, 3)
        if log_odds is not None:  # `compress` selects rows 2x faster than a boolean index
            occupied = np.compress(np.asarray(log_odds, dtype=float) >= min_log_odds,
                                   occupied, axis=0)
        self.resolution = resolution
        self.clearance_bound = float(clearance)
        self._voxels = unique(encode(np.floor(occupied / resolution)))
        # The slab's depths: a point's `clearance` is exact up to its depth's distance to
        # their edge (and to `clearance_bound`).
        self._slab_z = (z_range[0] - clearance - margin, z_range[1] + clearance + margin)
        z = occupied[:, 2]
        if metric == "3d":
            self.dims = 3
            self.band_points = occupied
        else:
            self.dims = 2
            in_band = (z >= z_range[0] - depth_band) & (z <= z_range[1] + depth_band)
            self.band_points = occupied[in_band, :2]
        self.band_tree = _kdtree(self.band_points) if len(self.band_points) else None
        if box is None:  # the occupied voxels' box, widened by the reach of the offset
            box = (occupied.min(axis=0) - 15.0, occupied.max(axis=0) + 15.0) if len(
                occupied) else (np.zeros(3), np.zeros(3))
        lo, hi = np.asarray(box[0], dtype=float)[:2], np.asarray(box[1], dtype=float)[:2]
        self._field = (_DistanceField2D(self.band_points, lo, hi, resolution)
                       if self.dims == 2 and len(self.band_points) else None)
        reach = clearance + margin
        slab = np.compress((z >= z_range[0] - reach) & (z <= z_range[1] + reach), occupied,
                           axis=0)
        # Horizontal distance to the slab: a lower bound of the 3D one that rules most points
        # out before the exact 3D query.
        self._slab_field = _DistanceField2D(slab[:, :2], lo, hi, resolution) if len(
            slab) else None
        self.slab_tree_3d = _kdtree(slab) if len(slab) else None
        self._tube = None
        # The offset is finite everywhere (a band voxel in reach: the 3D tree's, or a column
        # on the 2D field's grid) or inf everywhere.
        self.offset_mapped = self.band_tree is not None and (
            self._field is None or not self._field.empty)

    def prepare_tube(self, trajectory: np.ndarray, pad: float,
                     reuse: TubeNodes | None = None) -> TubeNodes | None:
        """Metric "3d": precomputes the offset on the grid nodes within `pad` m of
        `trajectory` (N, 3) (`_TubeField3D`, from the last step's `reuse`); `offset`
        interpolates there and queries the KD-tree exactly elsewhere. Returns the nodes for
        the next step (None: no tube, or for the horizontal metric, already a field)."""
        if self.dims == 3 and self.band_tree is not None:
            self._tube = _TubeField3D(self.band_tree, self.band_points,
                                      np.asarray(trajectory, dtype=float), pad,
                                      self.resolution, self.resolution, reuse)
            return self._tube.nodes
        return None

    def within(self, points: np.ndarray, upper_bound: float) -> bool:
        """False when no point of `points` (..., 3) can lie within `upper_bound` m of a
        counted voxel (one test of their bounding box on the slab's field); True may be a
        false alarm."""
        return self._slab_field is not None and points.size > 0 and (
            self._slab_field.box_lower_bound(points.reshape(-1, 3)) < upper_bound)

    def clearance(self, points: np.ndarray, upper_bound: float) -> np.ndarray:
        """3D distance to the nearest counted voxel centre, inf beyond `upper_bound`, m."""
        flat = points.reshape(-1, 3)
        d = np.full(len(flat), np.inf)
        if not self.within(flat, upper_bound):
            return d.reshape(points.shape[:-1])
        near = self._slab_field.lower_bound(flat) < upper_bound
        if near.any():
            d[near], _ = self.slab_tree_3d.query(flat[near], distance_upper_bound=upper_bound)
        return d.reshape(points.shape[:-1])

    def clearance_towards(self, points: np.ndarray, upper_bound: float):
        """`clearance` (..., ) and the unit vectors (..., 3) from each point to its nearest
        counted voxel centre (0 beyond `upper_bound`, or on a centre)."""
        flat = points.reshape(-1, 3)
        d, to = np.full(len(flat), np.inf), np.zeros(flat.shape)
        if self.within(flat, upper_bound):
            near = np.flatnonzero(self._slab_field.lower_bound(flat) < upper_bound)
            dist, index = self.slab_tree_3d.query(flat[near], distance_upper_bound=upper_bound)
            d[near] = dist
            found = np.isfinite(dist) & (dist > 0.0)
            near, dist, index = near[found], dist[found], index[found]
            to[near] = (self.slab_tree_3d.data[index] - flat[near]) / dist[:, None]
        return d.reshape(points.shape[:-1]), to.reshape(points.shape)

    def crossing(self, trajectories: np.ndarray, clearance: np.ndarray | float = 0.0,
                 bound: float = np.inf, segments: tuple | None = None) -> np.ndarray:
        """(..., N) the length (m) of the segment from point i - 1 to point i of each of
        `trajectories` (..., N, 3) inside counted voxels (0 at i = 0), sampled every
        1/`SWEEP_SAMPLES` of a voxel edge; the first point's own voxel does not count (the
        vehicle is there: a voxel of noise, or drift, must not wall it in).

        `clearance` (..., N), the points' `clearance` up to `bound` (inf beyond), or a lower
        bound of them all (`bound` where `within` found no point within it; 0: unknown,
        every segment sampled), rules out the segments that cannot reach a voxel: every point of a segment of length L lies within L/2 of one end, and a
        voxel's points within half its diagonal of its centre, so a segment is sampled only
        when an end lies within L/2 + that of a counted voxel centre (or where `clearance`
        may not be exact that near: beyond `bound`, or closer to the edge of the slab's
        depths, beyond which are voxels it does not hold). `segments`: the
        trajectories' steps (..., N - 1, 3) and their lengths (..., N - 1), when known."""
        shape = trajectories.shape
        out = np.zeros(shape[:-1])
        if not len(self._voxels) or shape[-2] < 2:
            return out
        flat = trajectories.reshape(-1, shape[-2], 3)
        if segments is None:
            step = np.diff(flat, axis=1)
            length = np.sqrt(np.einsum("...k,...k->...", step, step))
        else:
            step, length = segments[0].reshape(flat.shape[0], -1, 3), segments[1].reshape(
                flat.shape[0], -1)
        half_diagonal = 0.5 * math.sqrt(3.0) * self.resolution
        longest = 0.5 * float(length.max()) + half_diagonal
        z = flat[..., 2]
        # No segment reaches a voxel (the common case): a few reductions.
        inside_slab = False
        if longest < bound and float(np.min(clearance)) > longest:
            inside_slab = bool(z.min() - self._slab_z[0] > longest
                               and self._slab_z[1] - z.max() > longest)
            if inside_slab:
                return out
        d = np.broadcast_to(clearance, shape[:-1]).reshape(len(flat), -1)
        reach = 0.5 * length + half_diagonal
        candidate = (np.minimum(d[:, :-1], d[:, 1:]) <= reach) | (reach >= bound)
        if not inside_slab:
            edge = np.minimum(z - self._slab_z[0], self._slab_z[1] - z)
            candidate |= reach >= np.minimum(edge[:, :-1], edge[:, 1:])
        k, i = np.nonzero(candidate)
        if not len(k):
            return out
        m = max(1, math.ceil(SWEEP_SAMPLES * float(length[k, i].max()) / self.resolution))
        f = (np.arange(m) + 0.5) / m
        samples = flat[k, i][:, None, :] + f[None, :, None] * step[k, i][:, None, :]
        codes = encode(np.floor(samples.reshape(-1, 3) / self.resolution)).reshape(-1, m)
        start = encode(np.floor(flat[:, 0] / self.resolution))[k]
        hit = in_sorted(self._voxels, codes.ravel()).reshape(codes.shape)
        hit &= codes != start[:, None]
        out.reshape(len(flat), -1)[k, i + 1] = hit.sum(axis=1) * length[k, i] / m
        return out

    def offset(self, points: np.ndarray) -> np.ndarray:
        """Distance from `points` (..., 3) to the band's voxels (horizontal or 3D), m; inf
        where the band holds none."""
        shape = points.shape[:-1]
        if self.band_tree is None:
            return np.full(shape, np.inf)
        if self._field is None:
            flat = points.reshape(-1, 3)
            if self._tube is None:
                return self.band_tree.query(flat)[0].reshape(shape)
            d = self._tube.interpolate(flat)
            outside = np.isnan(d)
            if outside.any():
                d[outside] = self.band_tree.query(flat[outside])[0]
            return d.reshape(shape)
        return self._field.interpolate(points.reshape(-1, 3)).reshape(shape)

    def nearest_band(self, points: np.ndarray, upper_bound: float):
        """Distance to, and index in `band_points` of, the nearest band voxel, m (inf, and
        len(band_points), beyond `upper_bound`)."""
        if self.band_tree is None:
            n = len(points)
            return np.full(n, np.inf), np.zeros(n, dtype=int)
        return self.band_tree.query(points[:, :self.dims], distance_upper_bound=upper_bound)
