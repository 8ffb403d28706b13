"""The compiled kernels (`drake_auv.jit`) against the numpy and scipy code they replaced, on
the plan of a 1 km x 1 km site at 1 m (1 M cells; `bench_plan_scale.site`):

- the clearance lift's stencil (`TerrainSurface.safe_elevation_at`, every sample of the path
  and the lawnmower) against the numpy stencil;
- the clearance of the path and the lawnmower (`TerrainSurface._query`, the ring search of
  `planning.nearest_sample`) against a KD-tree of the same surface samples, built and queried;
- the GeoJSON route's Douglas-Peucker (`missions.douglas_peucker`) against the numpy loop;
- the viewing angles' ray march (`TerrainSurface.raycast`) against the numpy march;
- the grid coverage mask (`metrics.coverage_mask`) against the numpy stencil.

Each pair runs in this process, one after the other, and must give the same numbers (checked);
wall and CPU seconds (all threads) of each, and the reference's over the kernel's. Then the
kernels' one-time cost, each in a fresh process with an empty cache (`NUMBA_CACHE_DIR`):
importing and compiling them, and, the second time, importing and loading them from the cache.

    .venv/bin/python benchmarks/bench_jit.py [--site-cells 1000]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
from _reference import machine  # noqa: E402
from bench_plan_scale import site  # noqa: E402
from drake_auv.formats.geojson import ROUTE_PIECE, ROUTE_TOLERANCE  # noqa: E402
from drake_auv.planning.coverage_plan import plan_coverage  # noqa: E402
from drake_auv.planning.metrics import coverage_mask  # noqa: E402
from drake_auv.planning.missions import douglas_peucker  # noqa: E402
from drake_auv.planning.surface import TerrainSurface  # noqa: E402
from drake_auv.resources import map_chunks, usable_cores  # noqa: E402

FIRST_CALLS = """
import time
t0 = time.perf_counter()
import numpy as np
from drake_auv.planning import metrics, missions, nearest_sample, surface
from drake_auv.terrain.bathymetry import Bathymetry
t1 = time.perf_counter()
xs, z, p = np.arange(3.0), np.zeros((3, 3)), np.ones((2, 3))
nearest_sample.nearest_samples(xs, xs, z, p, 8.0, 24, np.empty(2), np.empty(2, np.int64))
missions.douglas_peucker(p, 0.1)
s = surface.TerrainSurface(Bathymetry(z, (1.0, 1.0)))
s.raycast(p, -p, 2.0)
s.safe_elevation_at(p[:, 0], p[:, 1], 2.0)
metrics.coverage_mask(s, p, -p, 60.0, 2.0)
print(t1 - t0, time.perf_counter() - t1)
"""


# -- the replaced code, the reference ----------------------------------------------------------
def kd_query(surface: TerrainSurface, points, upper_bound):
    xs, ys, z = surface._distance_samples()
    samples = np.empty((len(ys), len(xs), 3))
    samples[..., 0], samples[..., 1], samples[..., 2] = xs, ys[:, None], z
    tree = cKDTree(samples.reshape(-1, 3), leafsize=64, balanced_tree=False, compact_nodes=False)
    return tree.query(points, k=1, distance_upper_bound=upper_bound, workers=usable_cores())[0]


def numpy_safe_elevation(surface, x, y, omega, chunk=8192):
    zpad, ni, nj, origin, (cx, cy), oi, oj, target, block_radius = surface.clearance_stencil(omega)
    flat_offsets = (oi * zpad.shape[1] + oj)[None, :]
    off_x, off_y = (oj * cx).astype(np.float32)[None, :], (oi * cy).astype(np.float32)[None, :]
    t2 = np.float32(target ** 2)
    ny, nx = zpad.shape[0] - 2 * ni, zpad.shape[1] - 2 * nj
    out = np.empty(len(x))

    def fill(k):
        fj, fi = (x[k] - origin[0]) / cx, (y[k] - origin[1]) / cy
        j0 = np.clip(np.rint(fj).astype(int), 0, nx - 1)
        i0 = np.clip(np.rint(fi).astype(int), 0, ny - 1)
        ex = ((fj - j0) * cx).astype(np.float32)[:, None]
        ey = ((fi - i0) * cy).astype(np.float32)[:, None]
        r2 = (ex - off_x) ** 2 + (ey - off_y) ** 2
        if block_radius > 0:
            r2 = np.maximum(np.sqrt(r2) - np.float32(block_radius), np.float32(0.0)) ** 2
        left = t2 - r2
        height = np.where(left >= 0, np.sqrt(np.maximum(left, np.float32(0.0))), -np.inf)
        base = ((i0 + ni) * zpad.shape[1] + (j0 + nj))[:, None]
        out[k] = (np.take(zpad, base + flat_offsets) + height).max(axis=1)

    map_chunks(fill, len(x), chunk)
    return out + 1e-3


def numpy_douglas_peucker(points, tolerance, piece=None):
    n = len(points)
    if piece is not None and n > piece:
        ends = np.append(np.arange(0, n - 1, piece - 1), n - 1)
        return np.unique(np.concatenate([a + numpy_douglas_peucker(points[a:b + 1], tolerance)
                                         for a, b in zip(ends[:-1], ends[1:])]))
    keep = np.zeros(n, dtype=bool)
    keep[[0, n - 1]] = True
    cols = [np.ascontiguousarray(points[:, k]) for k in range(points.shape[1])]
    stack = [(0, n - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        v = [c[a + 1:b] - c[a] for c in cols]
        seg = [c[b] - c[a] for c in cols]
        seg2 = sum(s * s for s in seg)
        t = np.zeros(b - a - 1)
        if seg2 > 1e-18:
            for vk, sk in zip(v, seg):
                t += vk * (sk / seg2)
            np.clip(t, 0.0, 1.0, out=t)
        d2 = np.zeros(b - a - 1)
        for vk, sk in zip(v, seg):
            e = vk - t * sk
            d2 += e * e
        k = int(np.argmax(d2))
        if d2[k] > tolerance * tolerance:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return np.flatnonzero(keep)


def numpy_march(surface, o, d, max_range, chunk=262144):
    step = min(surface.spacing) / 3.0
    ts = np.arange(0.0, max_range + step, step)

    def march(s):
        oo, dd = o[s], d[s]
        ranges = np.full(len(oo), np.nan)
        prev_h = oo[:, 2] - surface.elevation(oo[:, 0], oo[:, 1])
        prev_t = np.zeros(len(oo))
        alive = prev_h > 0
        for t in ts[1:]:
            idx = np.flatnonzero(alive)
            if idx.size == 0:
                break
            p = oo[idx] + t * dd[idx]
            h = p[:, 2] - surface.elevation(p[:, 0], p[:, 1])
            out = ~surface.inside(p[:, 0], p[:, 1])
            hit = (h <= 0) & ~out
            hi = idx[hit]
            ranges[hi] = prev_t[hi] + (t - prev_t[hi]) * prev_h[hi] / (prev_h[hi] - h[hit])
            alive[hi] = False
            alive[idx[out & ~hit]] = False
            prev_h[idx], prev_t[idx] = h, t
        return ranges

    return np.concatenate(map_chunks(march, len(o), chunk))


def numpy_coverage_mask(surface, points, sensor_dir, aperture_deg, sensor_range, chunk=16384):
    bathy = surface.bathy
    ny, nx = bathy.shape
    dx, dy = bathy.spacing
    half = np.radians(aperture_deg) / 2.0
    cos_half = np.cos(half)
    rho, centre_offset = ((sensor_range / (2.0 * np.cos(half)),) * 2 if half < np.pi / 3
                          else (sensor_range, 0.0))
    ri, rj = int(np.ceil(rho / dy)), int(np.ceil(rho / dx))
    oi, oj = np.mgrid[-ri:ri + 1, -rj:rj + 1]
    keep = (oi * dy) ** 2 + (oj * dx) ** 2 <= (rho + 0.5 * np.hypot(dx, dy)) ** 2
    oi, oj = oi[keep], oj[keep]
    seen = np.zeros(ny * nx, dtype=bool)

    def mark(k):
        p, d = points[k], sensor_dir[k]
        c = p[:, :2] + centre_offset * d[:, :2]
        ii = np.rint((c[:, 1] - bathy.origin[1]) / dy).astype(int)[:, None] + oi[None, :]
        jj = np.rint((c[:, 0] - bathy.origin[0]) / dx).astype(int)[:, None] + oj[None, :]
        ok = (ii >= 0) & (ii < ny) & (jj >= 0) & (jj < nx)
        ii, jj = np.clip(ii, 0, ny - 1), np.clip(jj, 0, nx - 1)
        vx = bathy.origin[0] + jj * dx - p[:, 0:1]
        vy = bathy.origin[1] + ii * dy - p[:, 1:2]
        vz = surface.z[ii, jj] - p[:, 2:3]
        dist2 = vx * vx + vy * vy + vz * vz
        along = vx * d[:, 0:1] + vy * d[:, 1:2] + vz * d[:, 2:3]
        inside = (ok & (dist2 <= sensor_range ** 2) & (along > 0)
                  & (along * along >= cos_half ** 2 * dist2))
        seen[(ii * nx + jj)[inside]] = True

    map_chunks(mark, len(points), chunk)
    return seen.reshape(ny, nx)


# -- the run -------------------------------------------------------------------------------------
def timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def first_calls(cache: str) -> tuple[float, float]:
    done = subprocess.run([sys.executable, "-c", FIRST_CALLS], capture_output=True, text=True,
                          check=True, env={**os.environ, "NUMBA_CACHE_DIR": cache})
    imports, calls = done.stdout.split()
    return float(imports), float(calls)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--site-cells", type=int, default=1000,
                        help="the site's cells along a side (1 m each; default 1000)")
    args = parser.parse_args()
    print(machine())
    plan = plan_coverage(site(args.site_cells), compute_metrics=False)
    p = plan.parameters
    print(f"site {args.site_cells} x {args.site_cells} at 1 m: path {len(plan.path)} samples, "
          f"lawnmower {len(plan.lawnmower)}")
    surface = plan.surface
    surface._distance_samples()  # the samples the searches share, built before either
    surface._clearance_samples(p.omega)
    points = np.concatenate([plan.path.points, plan.lawnmower.points])
    imaging = plan.path.labels != "transit"
    o, d = plan.path.points[imaging], plan.path.sensor_dir[imaging]
    cases = [
        ("clearance lift (path and lawnmower)",
         lambda: numpy_safe_elevation(surface, points[:, 0], points[:, 1], p.omega),
         lambda: surface.safe_elevation_at(points[:, 0], points[:, 1], p.omega)),
        ("clearance (path and lawnmower)", lambda: kd_query(surface, points, 4 * p.omega),
         lambda: surface._query(points, 4 * p.omega)[0]),
        ("GeoJSON route thinning", lambda: numpy_douglas_peucker(
            plan.path.points[:, :2], ROUTE_TOLERANCE, ROUTE_PIECE),
         lambda: douglas_peucker(plan.path.points[:, :2], ROUTE_TOLERANCE, ROUTE_PIECE)),
        ("viewing angles' ray march", lambda: numpy_march(surface, o, d, p.sensor_range),
         lambda: surface.raycast(o, d, p.sensor_range)[0]),
        ("grid coverage mask", lambda: numpy_coverage_mask(surface, o, d, p.aperture_deg,
                                                           p.sensor_range),
         lambda: coverage_mask(surface, o, d, p.aperture_deg, p.sensor_range)),
    ]
    print("| step | reference: wall / CPU (s) | kernel: wall / CPU (s) | reference over kernel "
          "(wall, CPU) | same result |")
    print("| --- | ---: | ---: | ---: | :---: |")
    for name, reference, compiled in cases:
        compiled()  # loaded (or compiled) before it is timed
        want, w0, c0 = timed(reference)
        got, w1, c1 = timed(compiled)
        same = np.array_equal(want, got, equal_nan=True)
        print(f"| {name} | {w0:.2f} / {c0:.2f} | {w1:.2f} / {c1:.2f} | {w0 / w1:.1f}, "
              f"{c0 / c1:.1f} | {'yes' if same else 'NO'} |")
        if not same:
            raise SystemExit(f"{name}: the kernel's result differs from the reference's")
    with tempfile.TemporaryDirectory() as cache:
        compile_import, compile_calls = first_calls(cache)
        load_import, load_calls = first_calls(cache)
    print(f"\nfirst use in a fresh process: imports {compile_import:.2f} s, then the kernels' "
          f"first calls {compile_calls:.2f} s with an empty cache (compiling) and "
          f"{load_calls:.2f} s from the cache (imports {load_import:.2f} s)")


if __name__ == "__main__":
    main()
