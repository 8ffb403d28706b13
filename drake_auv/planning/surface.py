"""The terrain as the planners query it: elevation, normals, distance and ray hits on a grid.

Built once per bathymetry (the distance samples lazily, on first distance query) and shared by
the planners and the metrics. No-data cells are filled with the nearest valid elevation for these
geometric queries only, so a path may pass over a hole without NaN; the planners still treat
the holes as no-go for coverage.
"""

from __future__ import annotations

import threading

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from drake_auv.jit import kernel
from drake_auv.planning.nearest_sample import NONE, UNRESOLVED, nearest_samples
from drake_auv.resources import map_chunks, usable_cores
from drake_auv.terrain.bathymetry import Bathymetry

# built once for all threads (the planner builds the route and the lawnmower side by side); a
# module lock, as surfaces are pickled and deep-copied
_BUILDING = threading.Lock()
# the distance queries' ring search gives the points farther than this many rings of samples
# to the KD-tree (a ring search of at most (2 * 24 + 1)^2 samples a point)
MAX_RINGS = 24


def bilinear(grid: np.ndarray, origin, spacing, x, y) -> np.ndarray:
    """Bilinear interpolation of a cell-centred grid at world points (clamped to the grid;
    NaN at a non-finite point), the shape of x and y broadcast (`_bilinear_at` at each)."""
    x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
    out = np.empty(x.shape)
    _bilinear_points(np.asarray(grid, dtype=float), np.asarray(origin, dtype=float),
                     np.asarray(spacing, dtype=float), x.ravel(), y.ravel(), out.reshape(-1))
    return out[()]  # a number for a point, as numpy's arithmetic gives


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
        distance_resolution: largest spacing of the surface samples used for distances, m
            (default: the cell size). A sampled surface overestimates the distance to the
            true surface by at most delta^2 / (2 d), delta being half the diagonal of a
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
        self._samples = None
        self._tree = None
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
    def _distance_samples(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(xs, ys, z): the bilinear surface every `distance_resolution` at most, built once."""
        with _BUILDING:
            if self._samples is None:
                fx = max(1, int(np.ceil(self.spacing[0] / self.distance_resolution)))
                fy = max(1, int(np.ceil(self.spacing[1] / self.distance_resolution)))
                xs, ys, z = self._dense_grid(fx, fy)
                self._samples = xs, ys, np.ascontiguousarray(z)
            return self._samples

    def _kd_tree(self) -> cKDTree:
        """A KD-tree of the distance samples (flat index i * nx + j), built on first need:
        for the points the ring search leaves to it, far from every sample."""
        xs, ys, z = self._distance_samples()
        with _BUILDING:
            if self._tree is None:
                points = np.empty((len(ys), len(xs), 3))  # filled in place
                points[..., 0] = xs
                points[..., 1] = ys[:, None]
                points[..., 2] = z
                self._tree = cKDTree(points.reshape(-1, 3), leafsize=64, balanced_tree=False,
                                     compact_nodes=False)  # half the build time, no slower queries
            return self._tree

    def distance(self, points, upper_bound: float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """(N,) distance from each point to the surface, m, and (N, 3) the nearest surface sample.

        Exact up to the sampling bound of the class docstring; points outside the grid's extent
        get the distance to its nearest edge sample. Points farther than `upper_bound` get inf
        and a NaN nearest sample (a much faster query when only close points matter).
        """
        d, idx = self._query(points, upper_bound)
        xs, ys, z = self._distance_samples()
        found = idx >= 0
        i, j = np.divmod(idx[found], len(xs))
        nearest = np.full((len(d), 3), np.nan)
        nearest[found] = np.column_stack([xs[j], ys[i], z[i, j]])
        return d, nearest

    def _query(self, points, upper_bound: float,
               chunk: int = 65536) -> tuple[np.ndarray, np.ndarray]:
        """`distance`'s distances and the flat indices of the nearest samples (`NONE` where
        none is within `upper_bound`): the ring search of `nearest_sample`, `chunk` points at
        a time on the usable cores, and the KD-tree for the points it leaves."""
        p = np.ascontiguousarray(points, dtype=float).reshape(-1, 3)
        xs, ys, z = self._distance_samples()
        d, idx = np.empty(len(p)), np.empty(len(p), dtype=np.int64)
        map_chunks(lambda s: nearest_samples(xs, ys, z, p[s], float(upper_bound), MAX_RINGS,
                                             d[s], idx[s]), len(p), chunk)
        far = np.flatnonzero(idx == UNRESOLVED)
        if len(far):
            tree = self._kd_tree()
            d[far], i = tree.query(p[far], k=1, distance_upper_bound=upper_bound,
                                   workers=usable_cores())
            idx[far] = np.where(i < tree.n, i, NONE)
        return d, idx

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

    def clearance_stencil(self, omega: float):
        """`safe_elevation_at`'s stencil for `omega`: (zpad, ni, nj, origin, spacing, oi, oj,
        target, block_radius): the clearance samples padded by ni rows and nj columns (float32:
        elevations keep ~0.1 mm, the lift's 1 mm margin covers the rounding), their origin and
        spacing (cx, cy), and the offsets (oi, oj) of the samples within reach of a point."""
        z, origin, (cx, cy), block_radius, target = self._clearance_samples(omega)
        reach = target + block_radius + 0.5 * np.hypot(cx, cy)
        ni, nj = int(np.ceil(reach / cy)), int(np.ceil(reach / cx))
        oi, oj = np.mgrid[-ni:ni + 1, -nj:nj + 1]
        keep = np.hypot(oi * cy, oj * cx) <= reach
        zpad = np.pad(z, ((ni, ni), (nj, nj)), mode="edge").astype(np.float32)
        return (zpad, ni, nj, origin, (float(cx), float(cy)), oi[keep], oj[keep], target,
                block_radius)

    def safe_elevation_at(self, x, y, omega: float, chunk: int = 65536) -> np.ndarray:
        """(N,) lowest elevation at which a point above (x, y) is at least `omega` from the
        surface: the highest point of the hemispheres of radius omega (plus the sampling
        margins) standing on the surface samples around it (`clearance_stencil`,
        `_safe_elevations`); `chunk` points at a time on the usable cores
        (`resources.map_chunks`)."""
        zpad, ni, nj, origin, (cx, cy), oi, oj, target, block_radius = self.clearance_stencil(omega)
        off_x, off_y = (oj * cx).astype(np.float32), (oi * cy).astype(np.float32)
        x = np.ascontiguousarray(x, dtype=float)
        y = np.ascontiguousarray(y, dtype=float)
        out = np.empty(len(x))
        map_chunks(lambda k: _safe_elevations(zpad, ni, nj, origin, cx, cy, oi, oj, off_x, off_y,
                                              np.float32(target ** 2), np.float32(block_radius),
                                              x[k], y[k], out[k]), len(x), chunk)
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
        are marched `chunk` at a time on the usable cores (`resources.map_chunks`), each ray
        stopping at its hit.
        """
        o = np.ascontiguousarray(origins, dtype=float)
        d = np.ascontiguousarray(directions, dtype=float)
        step = float(min(self.spacing) / 3.0 if step is None else step)
        ts = np.arange(0.0, max_range + step, step)
        z = np.ascontiguousarray(self.z, dtype=float)
        xmin, xmax, ymin, ymax = (float(v) for v in self.bathy.extent)
        ranges = np.empty(len(o))
        map_chunks(lambda s: _march(z, self.origin, self.spacing, (xmin, xmax, ymin, ymax), o[s],
                                    d[s], ts, ranges[s]), len(o), chunk)
        hits = o + np.nan_to_num(ranges)[:, None] * d
        return ranges, hits


@kernel
def _bilinear_at(grid, origin, spacing, x, y):
    """`bilinear` at one point."""
    if not (np.isfinite(x) and np.isfinite(y)):
        return np.nan
    ny, nx = grid.shape
    fj = min(max((x - origin[0]) / spacing[0], 0.0), nx - 1.0)
    fi = min(max((y - origin[1]) / spacing[1], 0.0), ny - 1.0)
    j0 = min(int(fj), nx - 2)
    i0 = min(int(fi), ny - 2)
    tj, ti = fj - j0, fi - i0
    return ((1 - ti) * ((1 - tj) * grid[i0, j0] + tj * grid[i0, j0 + 1])
            + ti * ((1 - tj) * grid[i0 + 1, j0] + tj * grid[i0 + 1, j0 + 1]))



@kernel
def _bilinear_points(grid, origin, spacing, x, y, out):
    """`bilinear` at each (x[n], y[n]) into out[n]."""
    for n in range(len(x)):
        out[n] = _bilinear_at(grid, origin, spacing, x[n], y[n])

@kernel
def _march(z, origin, spacing, extent, o, d, ts, ranges):
    """`TerrainSurface.raycast`'s ranges: each ray (origin o[n], direction d[n]) stepped
    through the ranges `ts` until its height over the surface is no longer positive (the range
    then interpolated linearly between the last two steps), it leaves the grid's extent or the
    steps end (NaN). A ray starting on or below the surface gets NaN."""
    xmin, xmax, ymin, ymax = extent
    for n in range(o.shape[0]):
        ranges[n] = np.nan
        ox, oy, oz = o[n, 0], o[n, 1], o[n, 2]
        prev_h = oz - _bilinear_at(z, origin, spacing, ox, oy)
        if not prev_h > 0:
            continue
        prev_t = 0.0
        for k in range(1, len(ts)):
            t = ts[k]
            px, py, pz = ox + t * d[n, 0], oy + t * d[n, 1], oz + t * d[n, 2]
            if not (xmin <= px <= xmax and ymin <= py <= ymax):
                break
            h = pz - _bilinear_at(z, origin, spacing, px, py)
            if h <= 0:
                ranges[n] = prev_t + (t - prev_t) * prev_h / (prev_h - h)
                break
            prev_h, prev_t = h, t


@kernel
def _safe_elevations(zpad, ni, nj, origin, cx, cy, oi, oj, off_x, off_y, target2, block_radius,
                     x, y, out):
    """`TerrainSurface.safe_elevation_at` for each (x[n], y[n]): over the stencil (oi, oj)
    around the nearest clearance sample (`zpad`: the samples padded by ni rows and nj
    columns), the highest of each sample's elevation plus the height of its hemisphere of
    squared radius `target2` (its horizontal distance less `block_radius`), in float32."""
    ny, nx = zpad.shape[0] - 2 * ni, zpad.shape[1] - 2 * nj
    zero = np.float32(0.0)
    for n in range(len(x)):
        fj = (x[n] - origin[0]) / cx
        fi = (y[n] - origin[1]) / cy
        j0 = min(max(int(np.rint(fj)), 0), nx - 1)
        i0 = min(max(int(np.rint(fi)), 0), ny - 1)
        ex = np.float32((fj - j0) * cx)  # the offset from that sample
        ey = np.float32((fi - i0) * cy)
        top = np.float32(-np.inf)
        for m in range(len(oi)):
            r2 = (ex - off_x[m]) * (ex - off_x[m]) + (ey - off_y[m]) * (ey - off_y[m])
            if block_radius > 0:
                r = max(np.sqrt(r2) - block_radius, zero)
                r2 = r * r
            left = target2 - r2
            if left >= 0:
                top = max(top, zpad[i0 + ni + oi[m], j0 + nj + oj[m]] + np.sqrt(left))
        out[n] = top
