"""The ring search for the nearest grid sample (`planning.nearest_sample`) against scipy's
KD-tree on the same samples, and `TerrainSurface`'s distance queries built on it."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from drake_auv.planning.nearest_sample import NONE, UNRESOLVED, nearest_samples
from drake_auv.planning.surface import TerrainSurface
from drake_auv.terrain.bathymetry import Bathymetry


def _grid(rng, nx=60, ny=45, sx=0.5, sy=0.75, relief=4.0):
    xs = 100.0 + sx * np.arange(nx)
    ys = -20.0 + sy * np.arange(ny)
    z = -30.0 + relief * np.cumsum(rng.normal(size=(ny, nx)), axis=1) / np.sqrt(nx)
    return xs, ys, np.ascontiguousarray(z)


def _kd(xs, ys, z):
    pts = np.column_stack([np.tile(xs, len(ys)), np.repeat(ys, len(xs)), z.ravel()])
    return cKDTree(pts)


def _search(xs, ys, z, p, bound, rings):
    d, i = np.empty(len(p)), np.empty(len(p), dtype=np.int64)
    nearest_samples(xs, ys, z, np.ascontiguousarray(p, dtype=float), bound, rings, d, i)
    return d, i


@pytest.mark.parametrize("bound", [np.inf, 3.0])
def test_the_ring_search_finds_the_kd_trees_nearest_sample(bound):
    rng = np.random.default_rng(4)
    xs, ys, z = _grid(rng)
    # near the surface, inside and outside the grid's extent, above and below it
    p = np.column_stack([rng.uniform(95, 135, 3000), rng.uniform(-25, 18, 3000),
                         rng.uniform(-40, -20, 3000)])
    d, i = _search(xs, ys, z, p, bound, 1000)
    dk, ik = _kd(xs, ys, z).query(p, distance_upper_bound=bound)
    np.testing.assert_array_equal(d, dk)  # the same samples, the same arithmetic
    found = np.isfinite(dk)
    np.testing.assert_array_equal(i[found], ik[found])
    assert np.all(i[~found] == NONE) and (bound == np.inf or (~found).any())


def test_a_point_beyond_the_rings_is_left_to_the_caller():
    rng = np.random.default_rng(5)
    xs, ys, z = _grid(rng)
    p = np.array([[115.0, 0.0, z.max() + 40.0],  # 40 m above: over 3 rings of 0.5 m
                  [xs[30], ys[27], z[27, 30] + 0.2],  # just over a sample: the first ring
                  [np.nan, 0.0, -30.0]])
    d, i = _search(xs, ys, z, p, np.inf, 3)
    assert list(i[[0, 2]]) == [UNRESOLVED, UNRESOLVED] and np.isnan(d[[0, 2]]).all()
    assert i[1] >= 0 and d[1] <= 0.2 + 1e-12


def test_surface_distances_equal_the_kd_trees_near_and_far():
    """Points within the rings are answered by the ring search, the others by the KD-tree
    fallback: both the exact nearest sample."""
    rng = np.random.default_rng(6)
    x = np.arange(0.0, 30.0, 1.0)
    xx, yy = np.meshgrid(x, x)
    bathy = Bathymetry(-40.0 + 3.0 * np.sin(xx / 4.0) * np.cos(yy / 5.0), (1.0, 1.0))
    surface = TerrainSurface(bathy, distance_resolution=0.5)
    p = np.column_stack([rng.uniform(-5, 35, 2000), rng.uniform(-5, 35, 2000),
                         rng.uniform(-45, 0, 2000)])  # up to ~40 m from the surface
    d, nearest = surface.distance(p)
    xs, ys, z = surface._distance_samples()
    dk, ik = _kd(xs, ys, z).query(p)
    np.testing.assert_array_equal(d, dk)
    np.testing.assert_array_equal(nearest, _kd(xs, ys, z).data[ik])
    assert surface._tree is not None  # the far points needed the fallback
    d8, n8 = surface.distance(p, upper_bound=8.0)
    far = dk >= 8.0
    assert np.isinf(d8[far]).all() and np.isnan(n8[far]).all()
    np.testing.assert_array_equal(d8[~far], dk[~far])
