"""Slicing contours, surface queries (distance, clearance, rays) and viewing-angle geometry."""

import numpy as np
import pytest

from drake_auv.planning.metrics import coverage_mask, viewing_angles
from drake_auv.planning.slicing import (fixed_depression, order_contours, sensor_axes,
                                        slice_levels, slice_region)
from drake_auv.planning.surface import TerrainSurface
from drake_auv.terrain.bathymetry import Bathymetry

S = 0.7  # slope of the test plane z = S x


def _plane(spacing=0.5, scale=1.0):
    x = np.arange(0, 40.0 * scale + spacing / 2, spacing)
    y = np.arange(0, 30.0 * scale + spacing / 2, spacing)
    xx, _ = np.meshgrid(x, y)
    return Bathymetry(-60.0 + S * xx, (spacing, spacing))


def test_distance_to_a_plane_is_the_perpendicular_distance():
    surface = TerrainSurface(_plane(), distance_resolution=0.25)
    rng = np.random.default_rng(3)
    p = np.column_stack([rng.uniform(10, 30, 200), rng.uniform(10, 20, 200), np.zeros(200)])
    h = rng.uniform(1.0, 4.0, 200)
    p[:, 2] = -60.0 + S * p[:, 0] + h  # h above the plane, vertically
    d, _ = surface.distance(p)
    true = h / np.sqrt(1 + S ** 2)
    # Sampled surface: overestimates by at most delta^2 / (2 d), delta = half the sample
    # diagonal measured on the surface.
    delta = 0.5 * np.hypot(0.25, 0.25) * np.hypot(1.0, S)
    assert np.all(d >= true - 1e-9) and np.all(d <= true + delta ** 2 / (2 * true) + 1e-9)


@pytest.mark.parametrize("spacing, omega", [(0.5, 2.0), (0.25, 2.0), (1.0, 1.0), (2.0, 20.0)])
def test_enforce_clearance_lifts_just_enough(spacing, omega):
    scale = max(1.0, omega / 2.0)  # keep the points a few omega from the grid's edges
    surface = TerrainSurface(_plane(spacing, scale))
    rng = np.random.default_rng(1)
    p = np.column_stack([rng.uniform(15, 25, 300) * scale, rng.uniform(12, 18, 300) * scale,
                         np.zeros(300)])
    p[:, 2] = -60.0 + S * p[:, 0] + rng.uniform(0.0, 3.0 * omega, 300)
    out = surface.enforce_clearance(p, omega)
    n = np.array([-S, 0.0, 1.0]) / np.hypot(S, 1.0)
    d_true = (out - np.array([0.0, 0.0, -60.0])) @ n  # distance to the plane
    assert d_true.min() >= omega - 1e-9
    moved = np.any(out != p, axis=1)
    np.testing.assert_array_equal(out[:, :2], p[:, :2])  # only lifted
    # Conservative but not wasteful: a lifted point ends within 25 % of omega of the bound.
    assert d_true[moved].max() <= 1.25 * omega


def test_raycast_hits_the_plane():
    surface = TerrainSurface(_plane())
    o = np.array([[20.0, 15.0, -60.0 + S * 20 + 3.0]])
    r, hit = surface.raycast(o, np.array([[0.0, 0.0, -1.0]]), 10.0)
    assert r[0] == pytest.approx(3.0, abs=1e-6)
    r, _ = surface.raycast(o, np.array([[0.0, 0.0, 1.0]]), 10.0)
    assert np.isnan(r[0])


def _rough(seed=2):
    rng = np.random.default_rng(seed)
    x = np.arange(0.0, 40.0, 1.0)
    xx, yy = np.meshgrid(x, x[:30])
    z = -50.0 + 4.0 * np.sin(xx / 3.0) * np.cos(yy / 4.0) + rng.normal(0, 0.3, xx.shape)
    return TerrainSurface(Bathymetry(z, (1.0, 1.0), origin=(5.0, -3.0)))


def test_elevation_is_bilinear_clamped_and_nan_off_the_numbers():
    """`bilinear` (compiled, one point at a time) against the interpolation written out."""
    surface = _rough(4)
    rng = np.random.default_rng(9)
    x, y = rng.uniform(-5, 50, (20, 7)), rng.uniform(-8, 35, (20, 7))
    z = surface.elevation(x, y)
    fx = np.clip((x - surface.origin[0]) / surface.spacing[0], 0, surface.z.shape[1] - 1)
    fy = np.clip((y - surface.origin[1]) / surface.spacing[1], 0, surface.z.shape[0] - 1)
    j, i = np.minimum(fx.astype(int), surface.z.shape[1] - 2), np.minimum(
        fy.astype(int), surface.z.shape[0] - 2)
    tx, ty = fx - j, fy - i
    g = surface.z
    want = ((1 - ty) * ((1 - tx) * g[i, j] + tx * g[i, j + 1])
            + ty * ((1 - tx) * g[i + 1, j] + tx * g[i + 1, j + 1]))
    assert z.shape == (20, 7)
    np.testing.assert_array_equal(z, want)
    assert isinstance(surface.elevation(10.0, 5.0), float)
    assert np.isnan(surface.elevation(np.nan, 5.0)) and np.isnan(surface.elevation(10.0, np.inf))


def test_raycast_marches_each_ray_to_its_first_crossing():
    """The compiled march against the algorithm written out ray by ray: step by step along
    the ray until the height over the bilinear surface is no longer positive (the range
    interpolated between the last two steps), NaN when it leaves the grid first."""
    surface = _rough()
    rng = np.random.default_rng(7)
    n = 300
    o = np.column_stack([rng.uniform(0, 50, n), rng.uniform(-8, 32, n),
                         rng.uniform(-52, -40, n)])
    d = rng.normal(size=(n, 3)) - [0.0, 0.0, 1.0]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    step, max_range = 1.0 / 3.0, 12.0
    ranges, hits = surface.raycast(o, d, max_range)
    xmin, xmax, ymin, ymax = surface.bathy.extent
    want = np.full(n, np.nan)
    for k in range(n):
        prev_t, prev_h = 0.0, o[k, 2] - surface.elevation(o[k, 0], o[k, 1])
        for t in np.arange(0.0, max_range + step, step)[1:] if prev_h > 0 else ():
            p = o[k] + t * d[k]
            if not (xmin <= p[0] <= xmax and ymin <= p[1] <= ymax):
                break
            h = p[2] - surface.elevation(p[0], p[1])
            if h <= 0:
                want[k] = prev_t + (t - prev_t) * prev_h / (prev_h - h)
                break
            prev_t, prev_h = t, h
    assert 30 < np.isfinite(want).sum() < n
    np.testing.assert_array_equal(ranges, want)
    np.testing.assert_array_equal(hits[np.isnan(ranges)], o[np.isnan(ranges)])


@pytest.mark.parametrize("aperture_deg, sensor_range", [(60.0, 6.0), (150.0, 4.0)])
def test_coverage_mask_is_every_cell_in_some_samples_cone(aperture_deg, sensor_range):
    """The compiled stencil test against every cell of the grid tested from every sample."""
    surface = _rough(3)
    rng = np.random.default_rng(8)
    n = 40
    x, y = rng.uniform(5, 45, n), rng.uniform(-3, 27, n)
    p = np.column_stack([x, y, surface.elevation(x, y) + rng.uniform(1, 4, n)])
    axis = rng.normal(size=(n, 3)) * [0.5, 0.5, 1.0] - [0.0, 0.0, 2.0]
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    seen = coverage_mask(surface, p, axis, aperture_deg, sensor_range)
    ny, nx = surface.z.shape
    jj, ii = np.meshgrid(np.arange(nx), np.arange(ny))
    cells = np.column_stack([surface.origin[0] + jj.ravel() * surface.spacing[0],
                             surface.origin[1] + ii.ravel() * surface.spacing[1],
                             surface.z.ravel()])
    v = cells[None, :, :] - p[:, None, :]
    dist = np.linalg.norm(v, axis=2)
    cos = np.einsum("ncd,nd->nc", v, axis) / np.maximum(dist, 1e-12)
    want = ((dist <= sensor_range) & (cos >= np.cos(np.radians(aperture_deg) / 2))).any(axis=0)
    assert 0 < want.sum() < want.size
    # equal but for cells on the cone's edge to the last bits
    assert (seen.ravel() != want).sum() <= 2


def test_slices_of_a_plane_are_straight_offset_lines_looking_square_on():
    bathy = _plane()
    surface = TerrainSurface(bathy)
    region = np.ones(bathy.shape, dtype=bool)
    slope = np.full(bathy.shape, S)
    footprint = 2.0
    levels = slice_levels(surface, region, slope, footprint)
    dz = footprint * S / np.hypot(1, S)  # footprint measured along the wall
    np.testing.assert_allclose(np.diff(levels), dz)
    assert levels[0] >= bathy.z.min() and levels[-1] <= bathy.z.max()
    per_level = slice_region(surface, region, 1, levels, omega=2.0, sample_spacing=0.5,
                             min_length=2.0)
    assert all(len(p) == 1 for p in per_level)
    n = np.array([-S, 0.0, 1.0]) / np.hypot(S, 1.0)
    for pieces in per_level:
        c = pieces[0]
        x_level = (c.level + 60.0) / S
        np.testing.assert_allclose(c.surface[:, 0], x_level, atol=1e-6)
        np.testing.assert_allclose(c.path - c.surface, np.tile(2.0 * n, (len(c.path), 1)), atol=1e-6)
        np.testing.assert_allclose(c.sensor_dir, np.tile(-n, (len(c.path), 1)), atol=1e-9)
        assert np.all(np.diff(c.path[:, 1]) <= 0.5 + 1e-9)
    ordered = order_contours(per_level, start_xyz=per_level[0][0].path[-1])
    assert [c.level for c in ordered] == sorted(c.level for c in ordered)
    # Boustrophedon along the levels: each contour starts where the previous one ended.
    for a, b in zip(ordered[:-1], ordered[1:]):
        assert abs(a.path[-1, 1] - b.path[0, 1]) < 1.0
    ang = np.degrees(viewing_angles(surface, ordered[3].path, ordered[3].sensor_dir, 4.0))
    assert np.nanmax(ang) < 0.5
    # The down-looking view of the same wall sees it at arctan(S).
    down = np.tile([0.0, 0.0, -1.0], (len(ordered[3].path), 1))
    np.testing.assert_allclose(viewing_angles(surface, ordered[3].path, down, 10.0),
                               np.arctan(S), atol=1e-6)


def test_a_cone_slices_into_closed_loops():
    yy, xx = np.mgrid[0:81, 0:81] * 0.5
    r = np.hypot(xx - 20.0, yy - 20.0)
    bathy = Bathymetry(-60.0 + 0.8 * r, (0.5, 0.5))  # a pit, walls of slope 0.8
    surface = TerrainSurface(bathy)
    region = (r > 3) & (r < 15)
    levels = slice_levels(surface, region, np.full(bathy.shape, 0.8), 2.0)
    per_level = slice_region(surface, region, 1, levels, 2.0, 0.5, 2.0)
    loops = [c for p in per_level for c in p]
    assert loops and all(c.closed for c in loops)
    for c in loops:
        rad = np.hypot(c.surface[:, 0] - 20.0, c.surface[:, 1] - 20.0)
        np.testing.assert_allclose(rad, (c.level + 60.0) / 0.8, atol=0.05)
        # Offset into the pit's open water: the path circles inside the contour.
        assert np.all(np.hypot(c.path[:, 0] - 20.0, c.path[:, 1] - 20.0) < rad)


def test_fixed_tilt_sensor_sees_a_plane_at_the_slope_mismatch():
    bathy = _plane()
    surface = TerrainSurface(bathy)
    region = np.ones(bathy.shape, dtype=bool)
    levels = slice_levels(surface, region, np.full(bathy.shape, S), 2.0)[2:4]
    # Tilt matched to the plane: the axis is the inward normal again.
    matched = fixed_depression(np.full(10, S))
    assert matched == pytest.approx(np.pi / 2 - np.arctan(S))
    n = surface.normal(np.array([20.0]), np.array([15.0]))
    np.testing.assert_allclose(sensor_axes(n, matched), -n, atol=1e-12)
    # Tilt matched to a slope of 0.5: seen at arctan(0.7) - arctan(0.5) off the normal, and
    # from Omega back along the axis.
    c = slice_region(surface, region, 1, levels, 2.0, 0.5, 2.0,
                     depression=fixed_depression(np.array([0.5])))[0][0]
    ang = viewing_angles(surface, c.path, c.sensor_dir, 6.0)
    np.testing.assert_allclose(ang, np.arctan(S) - np.arctan(0.5), atol=1e-3)
    np.testing.assert_allclose(np.linalg.norm(c.path - c.surface, axis=1), 2.0)
    assert np.all(c.sensor_dir[:, 0] > 0)  # facing the wall, which rises towards +x
