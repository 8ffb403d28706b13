"""Boustrophedon (Morse) cell decomposition of the effectively planar area, on a raster.

Following Choset's boustrophedon decomposition: a sweep line parallel to the lanes moves across
the free space; a cell boundary falls where the number of free intervals on the line changes
(a split or a merge of the free space around an obstacle). On a raster resampled in the sweep
frame, the sweep line is a column and its free intervals are runs of free cells: a run continues
its cell when it overlaps exactly one run of the previous column, which overlaps only it.
Cells are the nodes of an adjacency graph, ordered by an exhaustive (depth-first) walk; each cell
is covered by parallel lanes spaced by the sensor footprint, traversed back and forth.

Sweep frame: lanes run along a = (cos phi, sin phi) (raster rows, coordinate s), the sweep line
advances along b = (-sin phi, cos phi) (raster columns, coordinate t); world xy = s a + t b.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_auv.terrain.bathymetry import Bathymetry


@dataclass(frozen=True)
class SweepFrame:
    """Raster of the grid resampled in the sweep frame (see the module docstring)."""

    angle: float
    resolution: float
    s0: float
    t0: float
    shape: tuple[int, int]

    @property
    def lane_axis(self) -> np.ndarray:
        return np.array([np.cos(self.angle), np.sin(self.angle)])

    @property
    def advance_axis(self) -> np.ndarray:
        return np.array([-np.sin(self.angle), np.cos(self.angle)])

    def to_world(self, s, t) -> np.ndarray:
        """(N, 2) world xy of sweep-frame coordinates (s along lanes, t across), m."""
        s, t = np.broadcast_arrays(np.asarray(s, float), np.asarray(t, float))
        return s.ravel()[:, None] * self.lane_axis + t.ravel()[:, None] * self.advance_axis

    def row_s(self, rows) -> np.ndarray:
        return self.s0 + self.resolution * np.asarray(rows, dtype=float)

    def col_t(self, cols) -> np.ndarray:
        return self.t0 + self.resolution * np.asarray(cols, dtype=float)


def sweep_raster(bathy: Bathymetry, layers: list[np.ndarray], angle: float,
                 resolution: float | None = None) -> tuple[SweepFrame, list[np.ndarray]]:
    """Resamples grid layers (bool or int, nearest cell) into the sweep frame of `angle` (rad).

    Raster cells outside the grid get 0/False. `resolution` defaults to the smallest cell size.
    """
    h = float(min(bathy.spacing) if resolution is None else resolution)
    xmin, xmax, ymin, ymax = bathy.extent
    corners = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    a = np.array([np.cos(angle), np.sin(angle)])
    b = np.array([-np.sin(angle), np.cos(angle)])
    s, t = corners @ a, corners @ b
    ns = int(np.floor((s.max() - s.min()) / h + 1e-9)) + 1
    nt = int(np.floor((t.max() - t.min()) / h + 1e-9)) + 1
    frame = SweepFrame(float(angle), h, float(s.min()), float(t.min()), (ns, nt))
    ny, nx = bathy.shape
    out = [np.zeros((ns, nt), dtype=layer.dtype) for layer in layers]
    tt = frame.col_t(np.arange(nt))[None, :]
    rows = max(1, (1 << 20) // nt)  # about a million raster cells at a time
    for r0 in range(0, ns, rows):
        ss = frame.row_s(np.arange(r0, min(r0 + rows, ns)))[:, None]
        j = np.rint((ss * a[0] + tt * b[0] - bathy.origin[0]) / bathy.spacing[0]).astype(np.int32)
        i = np.rint((ss * a[1] + tt * b[1] - bathy.origin[1]) / bathy.spacing[1]).astype(np.int32)
        inside = (i >= 0) & (i < ny) & (j >= 0) & (j < nx)
        i, j = i[inside], j[inside]
        for layer, o in zip(layers, out):
            o[r0:r0 + len(ss)][inside] = layer[i, j]
    return frame, out


def column_runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of True along each column of `mask`: (column, first row, one past the last row),
    sorted by column then row."""
    nr, nc = mask.shape
    padded = np.zeros((nc, nr + 2), dtype=np.int8)
    padded[:, 1:-1] = mask.T
    d = np.diff(padded, axis=1)
    cols, lo = np.nonzero(d == 1)
    _, hi = np.nonzero(d == -1)
    return cols, lo, hi


@dataclass(frozen=True)
class Cell:
    """A boustrophedon cell: one free run per raster column over consecutive columns."""

    index: int
    columns: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    def outline(self, frame: SweepFrame) -> np.ndarray:
        """(K, 2) closed world polygon of the cell's raster footprint."""
        h = frame.resolution
        t = frame.col_t(self.columns)
        t_edges = np.concatenate([[t[0] - h / 2], np.repeat(t[:-1] + h / 2, 2), [t[-1] + h / 2]])
        s_lo = np.repeat(frame.row_s(self.lo) - h / 2, 2)
        s_hi = np.repeat(frame.row_s(self.hi - 1) + h / 2, 2)
        s = np.concatenate([s_lo, s_hi[::-1], s_lo[:1]])
        tt = np.concatenate([t_edges, t_edges[::-1], t_edges[:1]])
        return frame.to_world(s, tt)

    def centroid(self, frame: SweepFrame) -> np.ndarray:
        """World xy of the cell's area centroid, m."""
        w = (self.hi - self.lo).astype(float)
        s = frame.row_s((self.lo + self.hi - 1) / 2.0)
        t = frame.col_t(self.columns)
        return frame.to_world(np.average(s, weights=w), np.average(t, weights=w))[0]

    @property
    def area_cells(self) -> int:
        return int((self.hi - self.lo).sum())


@dataclass(frozen=True)
class Decomposition:
    """Cells of the free space, their adjacency graph and the sweep frame they live in."""

    frame: SweepFrame
    cells: list[Cell]
    edges: np.ndarray  # (E, 2) pairs of adjacent cell indices, i < j
    label_raster: np.ndarray = field(repr=False)  # sweep-frame raster: cell index + 1, 0 = not free

    def adjacency(self) -> list[list[int]]:
        adj = [[] for _ in self.cells]
        for i, j in self.edges:
            adj[i].append(int(j))
            adj[j].append(int(i))
        return adj


def decompose(bathy: Bathymetry, free: np.ndarray, angle: float,
              resolution: float | None = None) -> Decomposition:
    """Boustrophedon decomposition of the `free` cells of `bathy` for lanes along `angle` (rad)."""
    frame, (mask,) = sweep_raster(bathy, [free.astype(bool)], angle, resolution)
    cols, lo, hi = column_runs(mask)
    nc = mask.shape[1]
    n_runs = len(cols)
    if n_runs == 0:
        return Decomposition(frame, [], np.zeros((0, 2), int), np.zeros(mask.shape, np.int32))
    starts = np.searchsorted(cols, np.arange(nc + 2))
    pair_r, pair_s = [], []
    for j in range(nc - 1):
        a0, a1, b0, b1 = starts[j], starts[j + 1], starts[j + 1], starts[j + 2]
        if a1 == a0 or b1 == b0:
            continue
        ov = (lo[a0:a1, None] < hi[None, b0:b1]) & (lo[None, b0:b1] < hi[a0:a1, None])
        r, s = np.nonzero(ov)
        pair_r.append(r + a0)
        pair_s.append(s + b0)
    pair_r = np.concatenate(pair_r) if pair_r else np.zeros(0, int)
    pair_s = np.concatenate(pair_s) if pair_s else np.zeros(0, int)
    outdeg = np.bincount(pair_r, minlength=n_runs)
    indeg = np.bincount(pair_s, minlength=n_runs)
    linked = (outdeg[pair_r] == 1) & (indeg[pair_s] == 1)
    pred = np.full(n_runs, -1)
    pred[pair_s[linked]] = pair_r[linked]
    cell_of = np.empty(n_runs, dtype=int)
    new_cell = pred < 0
    # Runs are in column order, so a linked run's predecessor is labelled before it.
    cell_ids = np.cumsum(new_cell) - 1
    for r in range(n_runs):
        cell_of[r] = cell_ids[r] if new_cell[r] else cell_of[pred[r]]
    n_cells = int(new_cell.sum())
    order = np.argsort(cell_of, kind="stable")
    bounds = np.searchsorted(cell_of[order], np.arange(n_cells + 1))
    cells = [Cell(k, cols[order[bounds[k]:bounds[k + 1]]], lo[order[bounds[k]:bounds[k + 1]]],
                  hi[order[bounds[k]:bounds[k + 1]]]) for k in range(n_cells)]
    e = np.sort(np.column_stack([cell_of[pair_r[~linked]], cell_of[pair_s[~linked]]]), axis=1)
    e = e[e[:, 0] != e[:, 1]]
    edges = np.unique(e, axis=0) if len(e) else np.zeros((0, 2), int)
    label = np.zeros(mask.shape, dtype=np.int32)
    run_len = hi - lo
    rr = np.repeat(lo, run_len) + (np.arange(run_len.sum()) - np.repeat(np.cumsum(run_len) - run_len, run_len))
    label[rr, np.repeat(cols, run_len)] = np.repeat(cell_of + 1, run_len)
    return Decomposition(frame, cells, edges, label)


def sliver_cells(dec: Decomposition, min_area: float) -> set[int]:
    """Cells smaller than `min_area` (m^2) that touch a larger cell.

    A boundary nearly parallel to the sweep line rasterises as a staircase, and every tooth
    becomes a Morse cell of a few raster cells. They get no lanes of their own: they lie within
    a raster cell or two of the larger cell's lanes, whose footprints reach them.
    """
    area = np.array([c.area_cells for c in dec.cells]) * dec.frame.resolution ** 2
    small = area < min_area
    out = set()
    for i, j in dec.edges:
        if small[i] and not small[j]:
            out.add(int(i))
        if small[j] and not small[i]:
            out.add(int(j))
    return out


def lane_count(bathy: Bathymetry, free: np.ndarray, angle: float, lane_spacing: float) -> float:
    """Estimated number of lanes (so of turns) to sweep `free` with lanes along `angle`:
    free runs per sweep column, summed, times columns per lane. Uses a raster at the lane
    spacing (one column per lane)."""
    frame, (mask,) = sweep_raster(bathy, [free.astype(bool)], angle,
                                  max(min(bathy.spacing), lane_spacing))
    cols, _, _ = column_runs(mask)
    return len(cols) * frame.resolution / lane_spacing


def best_sweep_angle(bathy: Bathymetry, free: np.ndarray, lane_spacing: float,
                     n_candidates: int = 12) -> float:
    """The lane direction in [0, pi) (rad, `n_candidates` evenly spaced) with the fewest lanes."""
    angles = np.arange(n_candidates) * np.pi / n_candidates
    counts = [lane_count(bathy, free, a, lane_spacing) for a in angles]
    return float(angles[int(np.argmin(counts))])


def exhaustive_walk(adjacency: list[list[int]], positions: np.ndarray, start: int = 0) -> list[int]:
    """Order in which a depth-first walk of the graph first visits its nodes.

    From each node the walk goes to the nearest unvisited neighbour (by `positions`), backs up
    when none is left, and jumps to the nearest unvisited node when a connected component is
    exhausted, so every node is visited once.
    """
    n = len(adjacency)
    if n == 0:
        return []
    visited = np.zeros(n, dtype=bool)
    order = []
    stack = [start]
    visited[start] = True
    order.append(start)
    while len(order) < n:
        if not stack:
            rest = np.flatnonzero(~visited)
            here = positions[order[-1]]
            nxt = int(rest[np.argmin(np.linalg.norm(positions[rest] - here, axis=1))])
            visited[nxt] = True
            order.append(nxt)
            stack.append(nxt)
            continue
        node = stack[-1]
        todo = [k for k in adjacency[node] if not visited[k]]
        if not todo:
            stack.pop()
            continue
        nxt = min(todo, key=lambda k: float(np.linalg.norm(positions[k] - positions[node])))
        visited[nxt] = True
        order.append(nxt)
        stack.append(nxt)
    return order


def cell_lanes(cell: Cell, frame: SweepFrame, lane_spacing: float) -> np.ndarray:
    """(n, 3) lanes of a cell as rows (t, s_start, s_end): n = ceil(width / lane_spacing) lanes
    evenly spread across the cell, each spanning the cell's extent over its own strip, m."""
    h = frame.resolution
    c0 = int(cell.columns[0])
    width = len(cell.columns) * h
    n = max(1, int(np.ceil(width / lane_spacing - 1e-9)))
    edges = np.linspace(0, len(cell.columns), n + 1)
    lanes = np.empty((n, 3))
    for k in range(n):
        a = int(np.floor(edges[k] + 1e-9))
        b = max(a + 1, int(np.ceil(edges[k + 1] - 1e-9)))
        lanes[k, 0] = frame.col_t(c0 - 0.5) + (k + 0.5) * width / n
        lanes[k, 1] = frame.row_s(cell.lo[a:b].min())
        lanes[k, 2] = frame.row_s(cell.hi[a:b].max() - 1)
    return lanes


def boustrophedon_waypoints(lanes: np.ndarray, frame: SweepFrame, start_xy=None) -> np.ndarray:
    """(2 n, 2) world xy of the lane ends in back-and-forth order, starting at the corner of
    the cell nearest to `start_xy` (first lane first, upward, when None)."""
    best = None
    for reverse_lanes in (False, True):
        ln = lanes[::-1] if reverse_lanes else lanes
        for first_up in (True, False):
            up = np.arange(len(ln)) % 2 == (0 if first_up else 1)
            s_a = np.where(up, ln[:, 1], ln[:, 2])
            s_b = np.where(up, ln[:, 2], ln[:, 1])
            s = np.column_stack([s_a, s_b]).ravel()
            t = np.repeat(ln[:, 0], 2)
            xy = frame.to_world(s, t)
            cost = 0.0 if start_xy is None else float(np.linalg.norm(xy[0] - start_xy))
            if best is None or cost < best[0] - 1e-9:
                best = (cost, xy)
            if start_xy is None:
                return best[1]
    return best[1]
