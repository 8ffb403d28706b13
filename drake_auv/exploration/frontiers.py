"""Frontiers of the on-line octree and the viewpoints that would look at them. Pure numpy/scipy.

The planner reads the octree (`mapping.OctreeMap`, navigation frame) once per planning step
into a `LabelGrid`: cells of `cell` m (a multiple of the voxel edge) over the region box
widened by a margin, each occupied (any occupied voxel inside it, from the map's cached
occupied voxels), free or unknown (the octree's label at the cell centre). Everything after
that is array work on the grid, so a step costs what the region holds, never the dive's length.

Occupied is not yet seen. The profiler's horizontal sweep and the DVL's four beams map rock
that the multibeam, the sensor whose coverage counts, has not looked at (in boulder seed 1 the
planner believed 99 % covered with 16 % of the boulder unseen: its west side, mapped by the
profiler on the approach, and its top, mapped by the DVL). And a cell is not one surface: the
cell where a boulder's base meets the seabed is seen from above by the seabed's returns long
before its side is. The grid keeps `seen` per cell face (the six of `FACES`): a face is seen
when a multibeam return landed in the cell along a beam within 60 deg of the face's normal
(from the batches since the last step, `multibeam_returns`).

Two kinds of frontier cells, both inside the region box:
- surface: occupied cells next to (6-connected) an unknown cell that touches free water, the
  edge of the seen surface (an occupied cell next to the rock's own unseen interior is not a
  frontier: that unknown touches no free water and no sonar will ever see it), and occupied
  cells on free water none of whose faces on free water a multibeam return has seen;
- boundary: free cells next to an unknown cell, the edge of the known water.

Their view direction (from a viewpoint to the frontier, unit): from the free cells of its
26-neighbourhood towards the occupied ones (surface) or the unknown ones (boundary), the sum of
the offsets to those less the sum of the offsets to the free ones: at the edge of a seen wall
it points into the wall and a little along it, past the edge.
Cells are clustered in blocks of `cluster` m per kind; a cluster's candidate viewpoints sit
`omega` m back from its centroid along the view direction (and that direction turned by
+-`TURN` about z, tilted `TURN` down, so the viewpoint is higher, and made level), moved to
the nearest admissible height when below the floor's clearance or above z = -1 m (the base
of a boulder, seen from no lower than the clearance over the floor), kept if at least
`clearance` m from every occupied cell and `unknown_clearance` m from every unknown one (a
port-looking fan carves known water in thin sheets: a full clearance from unknown water
leaves hardly any viewpoint; the path search prices unknown water, `paths`), inside
the region box widened by `omega`, below z = -1 m and at least `clearance` above the region's
floor (zmin: the operator's bound on the seabed; the map alone cannot be trusted below it,
as beams grazing the seabed return nothing and clear free space through it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from drake_auv.sonar.sensor import BUILT_IN

UNKNOWN, FREE, OCCUPIED = -1, 0, 1
FACES = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
FACE_VIEW = np.cos(np.radians(60.0))  # a return sees a face within 60 deg of its normal
KINDS = ("surface", "boundary")
TURN = np.radians(35.0)  # the side candidates' turn of the view direction about z
MAX_Z = -1.0  # m, viewpoints stay deeper than this
_FACE = ndimage.generate_binary_structure(3, 1)
_OFFSETS = np.stack(np.meshgrid(*(np.arange(-1, 2),) * 3, indexing="ij"), axis=-1).astype(float)


def check_region(region) -> np.ndarray:
    """(6,) region [xmin, ymin, zmin, xmax, ymax, zmax] as floats, min < max on each axis."""
    region = np.asarray(region, dtype=float).reshape(-1)
    if region.shape != (6,) or not np.all(np.isfinite(region)):
        raise ValueError(f"region must be 6 finite numbers [xmin, ymin, zmin, xmax, ymax, "
                         f"zmax] (m), got {region.tolist()}")
    if not np.all(region[:3] < region[3:]):
        raise ValueError(f"region {region.tolist()} has min >= max on an axis; "
                         "allowed: xmin < xmax, ymin < ymax, zmin < zmax")
    return region


@dataclass(frozen=True)
class LabelGrid:
    """Occupancy labels on a regular grid (navigation frame).

    Attributes:
        origin: (3,) corner of cell (0, 0, 0), m. cell: edge, m.
        labels: (nx, ny, nz) int8 of UNKNOWN, FREE, OCCUPIED.
        region: (6,) the region box the frontiers are sought in.
        seen: (nx, ny, nz, 6) bool, the cell faces (`FACES`) a multibeam return has seen
            (None: every face of every occupied cell, for grids built by hand).
    """

    origin: np.ndarray
    cell: float
    labels: np.ndarray
    region: np.ndarray
    seen: np.ndarray | None = None

    @classmethod
    def from_map(cls, octree_map, region, margin: float, cell: float,
                 previous: "LabelGrid | None" = None, rays=None,
                 returns=None) -> "LabelGrid":
        """The grid of `octree_map` (an `OctreeMap`) over `region` widened by `margin` m
        (clipped at the sea surface). With the `previous` grid of the same box and the `rays`
        inserted into the map since it (`scan_rays`), only the cells those rays touch (and
        the previous occupied ones) are read again: no other cell can have changed; the cells
        of the multibeam `returns` since it ((points (m, 3), unit beam directions (m, 3)))
        join the previous grid's `seen` faces (without `returns`, `seen` is None: every
        occupied cell counts as seen)."""
        region = check_region(region)
        lo = np.floor((region[:3] - margin) / cell) * cell
        hi = region[3:] + margin
        hi[2] = min(hi[2], 0.0)
        shape = np.maximum(np.ceil((hi - lo) / cell).astype(int), 1)
        same = (previous is not None and previous.cell == cell
                and previous.labels.shape == tuple(shape) and np.allclose(previous.origin, lo))
        # without a history of returns, what is occupied counts as seen
        seen = None if returns is None else np.zeros((*shape, len(FACES)), bool)
        grid = cls(lo, float(cell), np.empty(shape, np.int8), region, seen)
        if returns is not None:
            if same:
                seen[:] = (previous.seen if previous.seen is not None
                           else (previous.labels == OCCUPIED)[..., None])
            points, directions = returns
            cells, inside = grid.index(points)
            faces = -np.asarray(directions, float)[inside] @ FACES.T > FACE_VIEW  # (m, 6)
            row, face = np.nonzero(faces)
            seen[(*cells[inside][row].T, face)] = True
        if rays is not None and same:
            grid.labels[:] = previous.labels
            flat = np.union1d(grid.touched(*rays),
                              np.flatnonzero(previous.labels == OCCUPIED))
            idx = np.column_stack(np.unravel_index(flat, shape))
        else:
            idx = np.indices(shape).reshape(3, -1).T
        read = octree_map.labels(grid.centres(idx)).astype(np.int8)
        grid.labels[tuple(idx.T)] = np.minimum(read, FREE)  # occupancy from every voxel:
        occupied = octree_map.occupied_points(lo, lo + shape * cell)
        cells, inside = grid.index(occupied)
        grid.labels[tuple(cells[inside].T)] = OCCUPIED
        return grid

    def touched(self, origins, directions, lengths) -> np.ndarray:
        """(k,) flat indices of the cells that rays from `origins` (n, 3) along unit
        `directions` (n, 3) over `lengths` (n,) m pass through, and their 26 neighbours: the
        rays are sampled every half cell, and `scan_rays` keeps beams less than a cell
        apart, so every cell a beam crossed is next to a sampled one."""
        step = 0.5 * self.cell
        seen = np.zeros(self.labels.size, bool)
        for chunk in range(0, len(lengths), 4096):  # bounded memory per block of rays
            o, d, ln = (np.asarray(a[chunk:chunk + 4096], float)
                        for a in (origins, directions, lengths))
            t = np.minimum(np.arange(int(np.ceil(ln.max() / step)) + 1)[None, :] * step,
                           ln[:, None])  # (n, s), the end sampled last
            cells = np.floor((o[:, None, :] + d[:, None, :] * t[..., None] - self.origin)
                             / self.cell).astype(np.int64)
            inside = np.all((cells >= 0) & (cells < self.labels.shape), axis=-1)
            seen[np.ravel_multi_index(tuple(cells[inside].T), self.labels.shape)] = True
        seen = ndimage.binary_dilation(seen.reshape(self.labels.shape),
                                       np.ones((3, 3, 3), bool))
        return np.flatnonzero(seen)

    def index(self, points) -> tuple[np.ndarray, np.ndarray]:
        """((..., 3) cell indices, (...) inside the grid) of `points` (..., 3), m."""
        idx = np.floor((np.asarray(points) - self.origin) / self.cell).astype(np.int64)
        inside = np.all((idx >= 0) & (idx < self.labels.shape), axis=-1)
        return np.where(inside[..., None], idx, 0), inside

    def centres(self, idx) -> np.ndarray:
        return self.origin + (np.asarray(idx) + 0.5) * self.cell

    def in_region(self, points, widen: float = 0.0) -> np.ndarray:
        points = np.asarray(points)
        return np.all((points >= self.region[:3] - widen) & (points <= self.region[3:] + widen),
                      axis=-1)

    def region_mask(self) -> np.ndarray:
        """(nx, ny, nz) cells whose centre lies in the region box."""
        axes = [(self.origin[k] + (np.arange(n) + 0.5) * self.cell >= self.region[k])
                & (self.origin[k] + (np.arange(n) + 0.5) * self.cell <= self.region[k + 3])
                for k, n in enumerate(self.labels.shape)]
        return axes[0][:, None, None] & axes[1][None, :, None] & axes[2][None, None, :]

    def blocked_distance(self) -> np.ndarray:
        """(nx, ny, nz) distance from each cell centre to the nearest occupied or unknown
        cell centre, m (0 in them): unknown water counts as rock for safety."""
        return ndimage.distance_transform_edt(self.labels == FREE) * self.cell


def scan_rays(batches, cell: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origins, directions, lengths) of the beams of `ScanBatch`es as the octree inserted
    them (to the return plus a cell, or to the maximum range without one), thinned so that
    neighbouring kept beams of a fan are at most half a cell apart at its range."""
    if not batches:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    parts = []
    for b in batches:
        d = np.asarray(b.directions, float)
        if len(d) > 2:  # the angle between neighbouring beams of the fan
            gap = float(np.arccos(np.clip(d[0] @ d[1], -1.0, 1.0)))
            d_keep = slice(None, None, max(1, int(0.5 * cell / max(gap * b.max_range, 1e-9))))
        else:
            d_keep = slice(None)
        r = np.asarray(b.ranges, float)[d_keep]
        hit = np.isfinite(r) & (r <= b.max_range)
        parts.append((np.broadcast_to(b.origin, (len(r), 3)), d[d_keep],
                      np.where(hit, r + cell, b.max_range)))
    return tuple(np.concatenate(a) for a in zip(*parts))


def multibeam_returns(batches) -> tuple[np.ndarray, np.ndarray]:
    """((m, 3) return points, m; (m, 3) their unit beam directions) of the multibeam's beams
    in `ScanBatch`es."""
    points, directions = [np.zeros((0, 3))], [np.zeros((0, 3))]
    for b in batches or ():
        if b.source == BUILT_IN.index("multibeam"):
            hit = np.isfinite(b.ranges)
            points.append(b.points())
            directions.append(np.asarray(b.directions, float)[hit])
    return np.concatenate(points), np.concatenate(directions)


def face_neighbours(mask: np.ndarray) -> np.ndarray:
    """(nx, ny, nz, 6) whether each cell's face-neighbour across face k (`FACES`) is in
    `mask` (nx, ny, nz) (False beyond the grid)."""
    out = np.zeros((*mask.shape, len(FACES)), bool)
    for k, normal in enumerate(FACES):
        axis = int(np.flatnonzero(normal)[0])
        src, dst = [slice(None)] * 3, [slice(None)] * 3
        src[axis], dst[axis] = ((slice(1, None), slice(None, -1)) if normal[axis] > 0
                                else (slice(None, -1), slice(1, None)))
        out[(*dst, k)] = mask[tuple(src)]
    return out


def _neighbour_sum(mask: np.ndarray) -> np.ndarray:
    """(nx, ny, nz, 3) sum of the offsets (cells) to the 26 neighbours in `mask`."""
    m = mask.astype(float)
    return np.stack([ndimage.correlate(m, _OFFSETS[..., k], mode="constant")
                     for k in range(3)], axis=-1)


@dataclass(frozen=True)
class Frontiers:
    """Frontier cells: (m, 3) centres, m; (m, 3) unit view directions; (m,) kind index into
    `KINDS`."""

    centres: np.ndarray
    directions: np.ndarray
    kinds: np.ndarray


def frontier_cells(grid: LabelGrid) -> Frontiers:
    """The surface and boundary frontier cells of `grid` inside its region (see the module)."""
    labels = grid.labels
    unknown, free, occupied = labels == UNKNOWN, labels == FREE, labels == OCCUPIED
    open_unknown = unknown & ndimage.binary_dilation(free, _FACE)
    region = grid.region_mask()
    edge = ndimage.binary_dilation(open_unknown, _FACE)
    if grid.seen is not None:  # rock on free water no multibeam return has seen
        on_water = face_neighbours(free)
        edge |= on_water.any(axis=-1) & ~(on_water & grid.seen).any(axis=-1)
    surface = occupied & edge & region
    boundary = free & ndimage.binary_dilation(unknown, _FACE, border_value=1) & region
    towards_free = _neighbour_sum(free)
    towards_rock = _neighbour_sum(occupied) - towards_free
    towards_unknown = _neighbour_sum(unknown) - towards_free
    parts = [(np.argwhere(surface), towards_rock, 0), (np.argwhere(boundary), towards_unknown, 1)]
    centres, directions, kinds = [], [], []
    for idx, field, kind in parts:
        d = field[tuple(idx.T)]
        norm = np.linalg.norm(d, axis=1)
        keep = norm > 1e-9
        centres.append(grid.centres(idx[keep]))
        directions.append(d[keep] / norm[keep, None])
        kinds.append(np.full(int(keep.sum()), kind))
    return Frontiers(np.concatenate(centres).reshape(-1, 3),
                     np.concatenate(directions).reshape(-1, 3), np.concatenate(kinds))


@dataclass(frozen=True)
class Clusters:
    """Frontier clusters: (k, 3) centroids, m; (k, 3) unit mean view directions; (k,) kinds;
    (k,) cell counts."""

    centroids: np.ndarray
    directions: np.ndarray
    kinds: np.ndarray
    sizes: np.ndarray


def cluster_frontiers(frontiers: Frontiers, size: float, min_cells: int = 2) -> Clusters:
    """Frontier cells grouped per kind in cubic blocks of `size` m (blocks of fewer than
    `min_cells` cells dropped: a lone cell is often one stray return)."""
    if len(frontiers.kinds) == 0:
        return Clusters(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, int), np.zeros(0, int))
    block = np.floor(frontiers.centres / size).astype(np.int64)
    keys = np.column_stack([frontiers.kinds, block])
    _, inverse, sizes = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.reshape(-1)
    k = len(sizes)
    centroids = np.stack([np.bincount(inverse, frontiers.centres[:, i], k) for i in range(3)],
                         axis=1) / sizes[:, None]
    directions = np.stack([np.bincount(inverse, frontiers.directions[:, i], k)
                           for i in range(3)], axis=1)
    norm = np.linalg.norm(directions, axis=1)
    kinds = np.bincount(inverse, frontiers.kinds, k) // sizes
    keep = (sizes >= min_cells) & (norm > 1e-9)
    return Clusters(centroids[keep], directions[keep] / norm[keep, None], kinds[keep].astype(int),
                    sizes[keep])


@dataclass(frozen=True)
class Candidates:
    """Admissible viewpoints: (c, 3) positions, m; (c, 3) unit view directions; (c, 3) the
    frontier centroid each looks at; (c,) index of its cluster."""

    positions: np.ndarray
    directions: np.ndarray
    targets: np.ndarray
    cluster: np.ndarray


def _turned(d: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], d[:, 2]])


def _level(d: np.ndarray) -> np.ndarray:
    """`d` (n, 3) made horizontal (unit; straight down or up stays as it is)."""
    h = np.linalg.norm(d[:, :2], axis=1, keepdims=True)
    return np.where(h > 1e-6, np.column_stack([d[:, :2], np.zeros(len(d))]) / np.maximum(h, 1e-6),
                    d)


def _tilted(d: np.ndarray, angle: float) -> np.ndarray:
    """`d` (n, 3) tilted by `angle` rad towards -z in its vertical plane (unit)."""
    h = np.linalg.norm(d[:, :2], axis=1)
    elevation = np.arctan2(d[:, 2], h) - angle
    heading = np.arctan2(d[:, 1], d[:, 0])
    return np.column_stack([np.cos(elevation) * np.cos(heading),
                            np.cos(elevation) * np.sin(heading), np.sin(elevation)])


def candidate_viewpoints(grid: LabelGrid, clusters: Clusters, omega: float,
                         clearance: float, unknown_clearance: float) -> Candidates:
    """Viewpoints `omega` m back from each cluster along its view direction (turned by
    +-`TURN`, tilted down by `TURN` and made level), moved to the nearest admissible height,
    kept where admissible (see the module)."""
    unknown = ndimage.distance_transform_edt(grid.labels != UNKNOWN) * grid.cell
    d = clusters.directions
    directions = np.concatenate([d, _turned(d, TURN), _turned(d, -TURN), _tilted(d, TURN),
                                 _level(d)])
    targets = np.tile(clusters.centroids, (5, 1))
    cluster = np.tile(np.arange(len(clusters.sizes)), 5)
    positions = targets - omega * directions
    # A view from below the floor (of a base, an undercut) or above MAX_Z is taken from the
    # nearest admissible height instead; its gain, cast from there, says what it still sees.
    positions[:, 2] = np.clip(positions[:, 2], grid.region[2] + clearance, MAX_Z - 1e-6)
    idx, inside = grid.index(positions)
    occupied = grid.centres(np.argwhere(grid.labels == OCCUPIED))
    rock = (cKDTree(occupied).query(positions)[0] if len(occupied)
            else np.full(len(positions), np.inf))
    ok = (inside & (rock >= clearance) & (unknown[tuple(idx.T)] >= unknown_clearance)
          & grid.in_region(positions, omega)
          & (positions[:, 2] < MAX_Z) & (positions[:, 2] >= grid.region[2] + clearance))
    return Candidates(positions[ok], directions[ok], targets[ok], cluster[ok])
