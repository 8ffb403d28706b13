"""The terrain as the planners query it: elevation, normals, distance and ray hits on a grid.

Built once per bathymetry (the KD-tree lazily, on first distance query) and shared by the
planners and the metrics. No-data cells are filled with the nearest valid elevation for these
geometric queries only, so a path may pass over a hole without NaN; the planners still treat
the holes as no-go for coverage.
"""

from __future__ import annotations

import threading

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from drake_auv.resources import map_chunks, usable_cores
from drake_auv.terrain.bathymetry import Bathymetry

# built once for all threads (the planner builds the route and the lawnmower side by side); a
# module lock, as surfaces are pickled and deep-copied
_BUILDING = threading.Lock()


def bilinear(grid: np.ndarray, origin, spacing, x, y) -> np.ndarray:
    """Bilinear interpolation of a cell-centred grid at world points (clamped to the grid)."""
    ny, nx = grid.shape
    fj = np.clip((np.asarray(x, dtype=float) - origin[0]) / spacing[0], 0, nx - 1)
    fi = np.clip((np.asarray(y, dtype=float) - origin[1]) / spacing[1], 0, ny - 1)
    j0 = np.minimum(fj.astype(int), nx - 2)
    i0 = np.minimum(fi.astype(int), ny - 2)
    tj, ti = fj - j0, fi - i0
    g00, g01 = grid[i0, j0], grid[i0, j0 + 1]
    g10, g11 = grid[i0 + 1, j0], grid[i0 + 1, j0 + 1]
    return (1 - ti) * ((1 - tj) * g00 + tj * g01) + ti * ((1 - tj) * g10 + tj * g11)


def _upsample(a: np.ndarray, factor: int, axis: int) -> np.ndarray:
    """Linear interpolation of `a` at every 1/factor of a sample along `axis` (ends kept)."""
    if factor == 1:
        return a
    n = a.shape[axis]
    pos = np.arange((n - 1) * factor + 1) / factor
    i0 = np.minimum(pos.astype(int), n - 2)
    shape = [1] * a.ndim
    shape[axis] = -1
    t = (pos - i0).astype(a.dtype).reshape(shape)
    a0 = np.take(a, i0, axis=axis)
    return a0 + t * (np.take(a, i0 + 1, axis=axis) - a0)


class TerrainSurface:
    """Geometric queries on a bathymetric surface (world frame, z up, metres).

    Args:
        bathy: the grid.
        distance_resolution: largest spacing of the surface samples in the KD-tree used for
            distances, m (default: the cell size). A sampled surface overestimates the distance
            to the true surface by at most delta^2 / (2 d), delta being half the diagonal of a
            sample cell measured on the surface (plan-view diagonal times sqrt(1 + S_max^2)).
    """

    def __init__(self, bathy: Bathymetry, distance_resolution: float | None = None):
        self.bathy = bathy
        self.origin = np.asarray(bathy.origin, dtype=float)
        self.spacing = np.asarray(bathy.spacing, dtype=float)
        valid = bathy.valid
        z = bathy.z
        if not valid.all():
            _, (ii, jj) = ndimage.distance_transform_edt(~valid, sampling=bathy.spacing[::-1],
                                                         return_indices=True)
            z = z[ii, jj]
        self.z = z
        self.valid = valid
        gy, gx = np.gradient(z, bathy.spacing[1], bathy.spacing[0])
        self.gx, self.gy = gx, gy
        self.distance_resolution = (float(max(bathy.spacing)) if distance_resolution is None
                                    else float(distance_resolution))
        if not self.distance_resolution > 0:
            raise ValueError(f"distance_resolution must be > 0 m, got {distance_resolution}")
        self._tree = None
        self._tree_points = None
        self._safe = {}

    # -- pointwise queries -------------------------------------------------------------------
    def elevation(self, x, y) -> np.ndarray:
        """Elevation at world (x, y), m (bilinear, holes filled)."""
        return bilinear(self.z, self.origin, self.spacing, x, y)

    def gradient(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """(dz/dx, dz/dy) at world (x, y), bilinear in the grid's central differences."""
        return (bilinear(self.gx, self.origin, self.spacing, x, y),
                bilinear(self.gy, self.origin, self.spacing, x, y))

    def normal(self, x, y) -> np.ndarray:
        """(N, 3) upward unit surface normal (out of the seabed, into the water)."""
        gx, gy = self.gradient(x, y)
        n = np.column_stack([-np.ravel(gx), -np.ravel(gy), np.ones(np.size(gx))])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def inside(self, x, y) -> np.ndarray:
        """True where (x, y) lies on the grid's extent."""
        xmin, xmax, ymin, ymax = self.bathy.extent
        return (x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax)

    # -- distance ------------------------------------------------------------------------------
    def _build_tree(self):
        fx = max(1, int(np.ceil(self.spacing[0] / self.distance_resolution)))
        fy = max(1, int(np.ceil(self.spacing[1] / self.distance_resolution)))
        xs, ys, zz = self._dense_grid(fx, fy)
        points = np.empty((len(ys), len(xs), 3))  # filled in place: no grid-sized temporaries
        points[..., 0] = xs
        points[..., 1] = ys[:, None]
        points[..., 2] = zz
        self._tree_points = points.reshape(-1, 3)
        self._tree = cKDTree(self._tree_points, leafsize=64, balanced_tree=False,
                             compact_nodes=False)  # half the build time, no slower queries

    def distance(self, points, upper_bound: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """(N,) distance from each point to the surface, m, and (N, 3) the nearest surface sample.

        Exact up to the sampling bound of the class docstring; points outside the grid's extent
        get the distance to its nearest edge sample. Points farther than `upper_bound` get inf
        and a NaN nearest sample (a much faster query when only close points matter).
        """
        d, idx = self._query(points, upper_bound)
        found = idx < len(self._tree_points)
        nearest = np.full((len(d), 3), np.nan)
        nearest[found] = self._tree_points[idx[found]]
        return d, nearest

    def _query(self, points, upper_bound: float) -> tuple[np.ndarray, np.ndarray]:
        """`distance`'s distances and the indices of the nearest samples (the tree's size
        where none is within `upper_bound`), on the usable cores."""
        with _BUILDING:
            if self._tree is None:
                self._build_tree()
        return self._tree.query(np.asarray(points, dtype=float), k=1,
                                distance_upper_bound=upper_bound, workers=usable_cores())

    def signed_distance(self, points, upper_bound: float = np.inf) -> np.ndarray:
        """(N,) `distance` signed: negative below the surface (on the grid's extent: inside the
        ground) and above the sea surface (z > 0) at most -z, m. Points farther than
        `upper_bound` above it get inf; those below it their exact distance."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        d, _ = self._query(p, upper_bound)
        below = self.inside(p[:, 0], p[:, 1]) & (p[:, 2] < self.elevation(p[:, 0], p[:, 1]))
        if below.any():
            d[below] = -self._query(p[below], np.inf)[0]
        return np.minimum(d, np.where(p[:, 2] > 0.0, -p[:, 2], np.inf))

    def clamp_to_grid(self, points: np.ndarray, copy: bool = True) -> np.ndarray:
        """Points with x, y clamped to the grid's extent (cell centres): the path stays over
        the mapped seabed. With `copy` False a float array is clamped in place."""
        xmin, xmax, ymin, ymax = self.bathy.extent
        out = np.array(points, dtype=float, copy=copy or None)
        out[:, 0] = np.clip(out[:, 0], xmin, xmax)
        out[:, 1] = np.clip(out[:, 1], ymin, ymax)
        return out

    def _dense_grid(self, factor_x: int, factor_y: int, dtype=float):
        """The bilinear surface sampled `factor` times finer than the grid: (xs, ys, z), z of
        `dtype` (bilinear is separable: linear along x, then along y)."""
        ny, nx = self.z.shape
        xs = self.origin[0] + self.spacing[0] * np.linspace(0, nx - 1, (nx - 1) * factor_x + 1)
        ys = self.origin[1] + self.spacing[1] * np.linspace(0, ny - 1, (ny - 1) * factor_y + 1)
        z = _upsample(_upsample(self.z.astype(dtype, copy=False), factor_x, 1), factor_y, 0)
        return xs, ys, z

    def _clearance_samples(self, omega: float):
        """Surface samples about every omega / 4 for clearance: bilinear refinement of a coarse
        grid or block maxima (at block centres) of a fine one. Returns (z, origin, spacing,
        block_radius, target): `block_radius` bounds how far a block's own samples lie from
        its centre, `target` adds the sampled-versus-true surface margin to omega. Cached."""
        with _BUILDING:
            key = float(omega)
            if key not in self._safe:
                self._safe[key] = self._build_clearance_samples(key)
            return self._safe[key]

    def _build_clearance_samples(self, omega: float):
        h = omega / 4.0
        dx, dy = self.spacing
        ux, uy = max(1, int(np.ceil(dx / h))), max(1, int(np.ceil(dy / h)))
        _, _, z = self._dense_grid(ux, uy, np.float32)
        sx, sy = dx / ux, dy / uy
        f = max(1, int(np.floor(h / max(sx, sy))))
        if f > 1:
            pad = ((0, (-z.shape[0]) % f), (0, (-z.shape[1]) % f))
            zp = np.pad(z, pad, mode="edge")
            z = zp.reshape(zp.shape[0] // f, f, zp.shape[1] // f, f).max(axis=(1, 3))
        stretch = np.sqrt(1.0 + float(np.max(self.gx ** 2 + self.gy ** 2)))
        target = float(np.hypot(omega, 0.5 * np.hypot(sx, sy) * stretch))
        origin = self.origin + 0.5 * (f - 1) * np.array([sx, sy])
        block_radius = 0.5 * np.hypot((f - 1) * sx, (f - 1) * sy)
        return z, origin, np.array([f * sx, f * sy]), block_radius, target

    def safe_elevation_at(self, x, y, omega: float, chunk: int = 8192) -> np.ndarray:
        """(N,) lowest elevation at which a point above (x, y) is at least `omega` from the
        surface: the highest point of the hemispheres of radius omega (plus the sampling
        margins) standing on the surface samples around it; `chunk` points at a time on the
        usable cores (`resources.map_chunks`)."""
        z, origin, (cx, cy), block_radius, target = self._clearance_samples(omega)
        reach = target + block_radius + 0.5 * np.hypot(cx, cy)
        ni, nj = int(np.ceil(reach / cy)), int(np.ceil(reach / cx))
        oi, oj = np.mgrid[-ni:ni + 1, -nj:nj + 1]
        keep = np.hypot(oi * cy, oj * cx) <= reach
        oi, oj = oi[keep], oj[keep]
        # float32 inside the stencil (halves the memory traffic; elevations keep ~0.1 mm), with
        # the margin below covering its rounding.
        zpad = np.pad(z, ((ni, ni), (nj, nj)), mode="edge").astype(np.float32)
        flat_offsets = (oi * zpad.shape[1] + oj)[None, :]
        off_x, off_y = (oj * cx).astype(np.float32)[None, :], (oi * cy).astype(np.float32)[None, :]
        t2 = np.float32(target ** 2)
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        out = np.empty(len(x))
        ny, nx = z.shape

        def fill(k: slice) -> None:
            fj = (x[k] - origin[0]) / cx
            fi = (y[k] - origin[1]) / cy
            j0 = np.clip(np.rint(fj).astype(int), 0, nx - 1)
            i0 = np.clip(np.rint(fi).astype(int), 0, ny - 1)
            ex = ((fj - j0) * cx).astype(np.float32)[:, None]  # offset from the nearest node
            ey = ((fi - i0) * cy).astype(np.float32)[:, None]
            r2 = (ex - off_x) ** 2 + (ey - off_y) ** 2
            if block_radius > 0:
                r2 = np.maximum(np.sqrt(r2) - np.float32(block_radius), np.float32(0.0)) ** 2
            left = t2 - r2
            height = np.where(left >= 0, np.sqrt(np.maximum(left, np.float32(0.0))), -np.inf)
            base = ((i0 + ni) * zpad.shape[1] + (j0 + nj))[:, None]
            out[k] = (np.take(zpad, base + flat_offsets) + height).max(axis=1)

        map_chunks(fill, len(x), chunk)
        return out + 1e-3  # 1 mm over the float32 rounding

    def enforce_clearance(self, points: np.ndarray, omega: float, copy: bool = True) -> np.ndarray:
        """Points kept over the grid (x, y clamped to its extent) and lifted vertically where
        needed to be at least `omega` from the surface (`safe_elevation_at`); in place with
        `copy` False."""
        points = self.clamp_to_grid(points, copy)
        points[:, 2] = np.maximum(points[:, 2],
                                  self.safe_elevation_at(points[:, 0], points[:, 1], omega))
        return points

    # -- rays ----------------------------------------------------------------------------------
    def raycast(self, origins, directions, max_range: float, step: float | None = None,
                chunk: int = 262144):
        """First intersection of rays with the height field, by marching and linear refinement.

        Returns (N,) ranges (NaN where a ray leaves the grid or goes beyond `max_range` without
        a hit) and (N, 3) hit points. `step` defaults to a third of the smallest cell. The rays
        are marched `chunk` at a time on the usable cores (`resources.map_chunks`).
        """
        o = np.asarray(origins, dtype=float)
        d = np.asarray(directions, dtype=float)
        step = float(min(self.spacing) / 3.0 if step is None else step)
        ranges = np.concatenate([np.zeros(0)] + map_chunks(
            lambda s: self._march(o[s], d[s], max_range, step), len(o), chunk))
        hits = o + np.nan_to_num(ranges)[:, None] * d
        return ranges, hits

    def _march(self, o: np.ndarray, d: np.ndarray, max_range: float, step: float) -> np.ndarray:
        """`raycast`'s ranges for one chunk of rays."""
        ts = np.arange(0.0, max_range + step, step)
        ranges = np.full(len(o), np.nan)
        prev_h = o[:, 2] - self.elevation(o[:, 0], o[:, 1])
        prev_t = np.zeros(len(o))
        alive = prev_h > 0
        for t in ts[1:]:
            idx = np.flatnonzero(alive)
            if idx.size == 0:
                break
            p = o[idx] + t * d[idx]
            h = p[:, 2] - self.elevation(p[:, 0], p[:, 1])
            out = ~self.inside(p[:, 0], p[:, 1])
            hit = (h <= 0) & ~out
            if hit.any():
                hi = idx[hit]
                h0, h1 = prev_h[hi], h[hit]
                ranges[hi] = prev_t[hi] + (t - prev_t[hi]) * h0 / (h0 - h1)
                alive[hi] = False
            alive[idx[out & ~hit]] = False
            prev_h[idx] = h
            prev_t[idx] = t
        return ranges
