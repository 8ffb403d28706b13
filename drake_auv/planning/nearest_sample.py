"""The nearest sample of a regular height grid to 3D points, by a search in square rings.

The samples are (xs[j], ys[i], z[i, j]). For a point, the search starts at the grid node
nearest to it in plan and visits the rings of nodes at Chebyshev index distance k = 1, 2, ...
Every node of ring k lies at least (k - 1/2) s from the point in plan (s the smaller spacing),
so the search stops at the first ring whose bound is past the best distance found or past the
upper bound. Near a surface the answer is found within a few rings (a point 2 m above a
seabed sampled every 0.5 m: 81 nodes), faster than a KD-tree query on the same samples and
with no tree to build (`benchmarks/bench_jit.py`); the distances are the same numbers. A
point farther than `max_rings` rings from every sample (and within the upper bound) is left
`UNRESOLVED` for the caller's KD-tree, so the work per point is bounded.
"""

from __future__ import annotations

import numpy as np

from drake_auv.jit import kernel

NONE = -1  # no sample within the upper bound
UNRESOLVED = -2  # not decided within max_rings rings (or a non-finite point)


@kernel
def nearest_samples(xs, ys, z, points, upper_bound, max_rings, out_distance, out_index):
    """Fills `out_distance` (m; inf with `NONE`, NaN with `UNRESOLVED`) and `out_index` (the
    nearest sample's flat index i * nx + j, or `NONE` / `UNRESOLVED`) for each of `points`
    (n, 3). `xs` (nx,), `ys` (ny,) increasing and evenly spaced, `z` (ny, nx)."""
    ny, nx = z.shape
    sx = (xs[nx - 1] - xs[0]) / max(nx - 1, 1)
    sy = (ys[ny - 1] - ys[0]) / max(ny - 1, 1)
    spacing = min(sx if nx > 1 else np.inf, sy if ny > 1 else np.inf)
    if not spacing < np.inf:
        spacing = 0.0  # a single sample: the first ring decides
    # a ring's bound in plan, shaded by a millionth of the spacing for the rounding of the
    # nearest node's index
    slack = 1e-6 * spacing
    bound2 = upper_bound * upper_bound
    for n in range(points.shape[0]):
        px, py, pz = points[n, 0], points[n, 1], points[n, 2]
        if not (np.isfinite(px) and np.isfinite(py) and np.isfinite(pz)):
            out_distance[n] = np.nan
            out_index[n] = UNRESOLVED
            continue
        j0 = 0 if nx == 1 else int(min(max(np.rint((px - xs[0]) / sx), 0.0), nx - 1.0))
        i0 = 0 if ny == 1 else int(min(max(np.rint((py - ys[0]) / sy), 0.0), ny - 1.0))
        best, found = bound2, NONE
        k = 0
        while True:
            if k > 0:
                reach = (k - 0.5) * spacing - slack
                if reach >= upper_bound or reach * reach >= best:
                    break
                if i0 - k < 0 and i0 + k >= ny and j0 - k < 0 and j0 + k >= nx:
                    break  # the ring lies wholly outside the grid: every sample was visited
                if k > max_rings:
                    found = UNRESOLVED
                    break
            for i in range(max(i0 - k, 0), min(i0 + k, ny - 1) + 1):
                full_row = i == i0 - k or i == i0 + k
                dy = ys[i] - py
                j = j0 - k
                while j <= j0 + k:
                    if 0 <= j < nx:
                        dx = xs[j] - px
                        dz = z[i, j] - pz
                        d2 = dx * dx + dy * dy + dz * dz
                        if d2 < best:
                            best, found = d2, i * nx + j
                    if k == 0:
                        break
                    j += 1 if full_row else 2 * k
            k += 1
        out_index[n] = found
        if found >= 0:
            out_distance[n] = np.sqrt(best)
        else:
            out_distance[n] = np.inf if found == NONE else np.nan
