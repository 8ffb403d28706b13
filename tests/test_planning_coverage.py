"""`plan_coverage` end to end: the caldera acceptance figures, Monterey tiles, flat and steep
terrain, random seabeds (hypothesis), clearance checked against the exact triangle mesh, and
bad input."""

import json

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from drake_auv.formats.geojson import path_to_geojson
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.path import PlannedPath
from drake_auv.scenarios import DATA_DIR as DATA
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.geo import GeoFrame
from drake_auv.terrain.mesh import bathymetry_to_mesh
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.synthetic import caldera_site, random_seabed

MONTEREY = sorted((DATA / "monterey").glob("*.tif"))


def exact_clearance(bathy: Bathymetry, points: np.ndarray, radius: float) -> np.ndarray:
    """Distance from each point to the triangle mesh of the grid, by exact point-triangle
    distances over every triangle whose centroid lies within `radius` in plan view."""
    mesh = bathymetry_to_mesh(bathy)
    tree = cKDTree(mesh.triangles_center[:, :2])
    out = np.empty(len(points))
    for k, p in enumerate(points):
        idx = tree.query_ball_point(p[:2], radius)
        assert idx, "no triangle near the point: the radius is too small"
        tri = mesh.triangles[idx]
        closest = trimesh.triangles.closest_point(tri, np.tile(p, (len(tri), 1)))
        out[k] = np.linalg.norm(closest - p, axis=1).min()
    return out


def check_clearance(plan, omega, n_check=150):
    """Independent check: the samples the planner found closest plus random ones. Samples
    held at the minimum operating depth (water too shallow for Omega) are left out."""
    path = plan.path
    held = path.points[:, 2] >= -plan.parameters.min_depth - 1e-9
    path = path.select(~held)
    d, _ = plan.surface.distance(path.points)
    assert d.min() >= 0.9 * omega
    rng = np.random.default_rng(0)
    pick = np.unique(np.concatenate([np.argsort(d)[:n_check],
                                     rng.choice(len(path), min(n_check, len(path)), replace=False)]))
    radius = 1.5 * omega + 2 * max(plan.bathy.spacing)
    exact = exact_clearance(plan.bathy, path.points[pick], radius)
    assert exact.min() >= 0.9 * omega, f"exact clearance {exact.min():.3f} < 0.9 omega"
    return exact.min()


@pytest.fixture(scope="module")
def caldera_plan():
    return plan_coverage(caldera_site(), CoverageParameters(omega=2.0, aperture_deg=60.0,
                                                            slope_threshold=0.5))


def test_caldera_reproduces_the_table3_comparison(caldera_plan):
    plan = caldera_plan
    m = plan.metrics
    assert plan.labels.n_regions == 1
    assert set(plan.path.labels) <= {"planar", "slice", "transit"}
    assert {"planar", "slice"} <= set(plan.path.labels)
    # Viewing angle: at most 0.6 x the lawnmower's (the reference: 10.8 vs 23.2 deg).
    assert m.total.view_mean_deg <= 0.6 * m.lawnmower.view_mean_deg
    # Down-looking on the planar area the angle is arctan(slope): a few to ~15 degrees.
    assert 5.0 < m.planar.view_mean_deg < 15.0
    assert m.high_slope.view_mean_deg < m.planar.view_mean_deg
    # Length: 0.9 to 1.3 x the lawnmower's (the reference: 1.10).
    assert 0.9 <= m.total.length / m.lawnmower.length <= 1.3
    assert m.total.length == pytest.approx(plan.path.length)
    assert m.high_slope.length + m.planar.length < m.total.length
    assert m.total.coverage >= 0.98 and m.lawnmower.coverage >= 0.98
    assert m.high_slope.coverage >= 0.98 and m.planar.coverage >= 0.98
    assert m.total.min_clearance >= 0.9 * 2.0 and m.lawnmower.min_clearance >= 0.9 * 2.0
    check_clearance(plan, 2.0)


def test_caldera_path_samples_are_dense_and_oriented(caldera_plan):
    path = caldera_plan.path
    assert path.segment_lengths().max() <= 2.0  # transits and lanes sampled finely
    planar = path.labels == "planar"
    np.testing.assert_allclose(path.sensor_dir[planar], np.tile([0, 0, -1.0], (planar.sum(), 1)))
    sl = path.labels == "slice"
    # On the rim the sensor looks into the wall and the vehicle faces it.
    assert np.all(path.sensor_dir[sl, 2] < -0.7)
    facing = np.arctan2(path.sensor_dir[sl, 1], path.sensor_dir[sl, 0])
    np.testing.assert_allclose(np.angle(np.exp(1j * (path.heading[sl] - facing))), 0, atol=1e-9)
    # Lane spacing from the footprint: 2 * 2 * tan(30 deg) * 0.9 = 2.078 m.
    assert caldera_plan.lane_spacing == pytest.approx(2.0784609690826525)
    # The planar lanes fly at about Omega above the terrain (more where slopes push them out).
    alt = path.points[planar, 2] - caldera_plan.surface.elevation(*path.points[planar, :2].T)
    assert np.median(alt) == pytest.approx(2.0, abs=0.15) and alt.min() >= 2.0 - 1e-6


def test_polygon_roi_oblique_to_the_lanes():
    # Edges nearly parallel to the sweep rasterise as staircases: their teeth become tiny
    # Morse cells, which get no lanes of their own; coverage must not suffer.
    roi = [(20.0, 5.0), (95.0, 30.0), (80.0, 240.0), (3.0, 200.0)]
    plan = plan_coverage(caldera_site(), CoverageParameters(omega=2.0), roi=roi)
    m = plan.metrics
    visited = [k for kind, k in plan.visit_order if kind == "cell"]
    assert len(visited) < len(plan.cells.cells)
    assert m.total.coverage >= 0.98 and m.lawnmower.coverage >= 0.98
    assert 0.9 <= m.total.length / m.lawnmower.length <= 1.3
    assert plan.path.length_by_label()["transit"] < 0.1 * m.total.length
    assert m.total.min_clearance >= 1.8


def test_flat_terrain_gives_a_planar_only_plan():
    bathy = Bathymetry(np.full((81, 61), -30.0), (0.5, 0.5))
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0))
    assert plan.labels.n_regions == 0 and "slice" not in set(plan.path.labels)
    assert len(plan.cells.cells) == 1 and plan.metrics.total.coverage >= 0.99
    assert plan.metrics.total.view_mean_deg == pytest.approx(0.0, abs=1e-6)


def test_sweep_angle_parameter_sets_the_lane_direction():
    bathy = Bathymetry(np.full((61, 41), -30.0), (0.5, 0.5))
    for angle, axis in ((0.0, 0), (90.0, 1)):
        plan = plan_coverage(bathy, CoverageParameters(omega=2.0, sweep_angle_deg=angle),
                             compute_metrics=False)
        step = np.abs(np.diff(plan.path.points[:, :2], axis=0))
        along = step[:, axis].sum() / step.sum()
        assert along > 0.85, (angle, along)
        assert plan.parameters.sweep_angle_deg == pytest.approx(angle)


def test_fixed_tilt_sensor_on_the_caldera_rim(caldera_plan):
    plan = plan_coverage(caldera_site(), CoverageParameters(omega=2.0, slice_sensor="fixed-tilt"))
    sl = plan.path.labels == "slice"
    tilt = np.arcsin(-plan.path.sensor_dir[sl, 2])
    assert np.ptp(tilt) < 1e-9  # one tilt for the region
    slope = plan.labels.slope[plan.labels.high]
    assert tilt[0] == pytest.approx(np.pi / 2 - np.arctan(np.median(slope)))
    m = plan.metrics
    # Off the normal by the rim's slope variation only, so still far below the lawnmower's.
    assert caldera_plan.metrics.high_slope.view_mean_deg < m.high_slope.view_mean_deg < 5.0
    assert m.total.view_mean_deg <= 0.6 * m.lawnmower.view_mean_deg
    assert m.high_slope.coverage >= 0.98 and m.total.min_clearance >= 1.8


def test_steep_everywhere_gives_a_slicing_only_plan():
    yy, xx = np.mgrid[0:61, 0:81] * 0.5
    bathy = Bathymetry(-60.0 + 0.8 * xx + 0.1 * yy, (0.5, 0.5))
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0))
    assert plan.labels.n_regions == 1 and plan.labels.high.all()
    assert "planar" not in set(plan.path.labels) and len(plan.cells.cells) == 0
    assert plan.metrics.total.coverage >= 0.95
    assert plan.metrics.high_slope.view_mean_deg < 1.0
    check_clearance(plan, 2.0, n_check=60)


def test_slice_spacing_override_gives_two_contours_two_metres_apart():
    # A 4 m high wall of slope 1 between flat ground, Omega = 10 m as at l'Amarrador.
    x = np.arange(0, 80.5, 0.5)
    z1 = np.clip(x - 38.0, 0.0, 4.0) - 40.0
    bathy = Bathymetry(np.tile(z1, (81, 1)), (0.5, 0.5))
    plan = plan_coverage(bathy, CoverageParameters(omega=10.0, slice_spacing=2.0),
                         compute_metrics=False)
    levels = sorted({c.level for c in plan.contours})
    assert len(levels) == 2 and levels[1] - levels[0] == pytest.approx(2.0)


def test_slice_count_fixes_the_number_of_contours_centred_on_the_wall():
    # A 12 m high wall: six planes at 2 m spacing, or exactly two when slice_count = 2.
    x = np.arange(0, 80.5, 0.5)
    z1 = np.clip(x - 34.0, 0.0, 12.0) - 40.0
    bathy = Bathymetry(np.tile(z1, (81, 1)), (0.5, 0.5))
    all_levels = sorted({c.level for c in plan_coverage(
        bathy, CoverageParameters(omega=10.0, slice_spacing=2.0), compute_metrics=False).contours})
    two = sorted({c.level for c in plan_coverage(
        bathy, CoverageParameters(omega=10.0, slice_spacing=2.0, slice_count=2),
        compute_metrics=False).contours})
    assert len(all_levels) >= 5
    assert len(two) == 2 and two[1] - two[0] == pytest.approx(2.0)
    assert np.mean(two) == pytest.approx(np.mean(all_levels), abs=0.5)
    with pytest.raises(ValueError, match="slice_count"):
        CoverageParameters(omega=10.0, slice_count=0)


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2 ** 31 - 1), relief=st.floats(0.0, 15.0),
       smoothness=st.floats(4.0, 10.0), omega=st.floats(1.5, 3.0), hole=st.booleans())
def test_random_seabeds_are_covered_safely(seed, relief, smoothness, omega, hole):
    bathy = random_seabed(seed, (40, 56), 1.0, relief, smoothness)
    if hole:  # a no-data patch somewhere inside
        rng = np.random.default_rng(seed)
        i, j = rng.integers(5, 25), rng.integers(5, 40)
        z = bathy.z.copy()
        z[i:i + rng.integers(3, 10), j:j + rng.integers(3, 10)] = np.nan
        bathy = Bathymetry(z, bathy.spacing)
    plan = plan_coverage(bathy, CoverageParameters(omega=omega))
    m = plan.metrics
    assert m.total.min_clearance >= 0.9 * omega
    assert m.total.coverage >= 0.95
    assert np.all(np.isfinite(plan.path.points))


@pytest.mark.parametrize("tile", MONTEREY, ids=lambda p: p.name[12:40])
def test_monterey_tiles(tile):
    bathy = read_bathymetry(tile)
    plan = plan_coverage(bathy, CoverageParameters(omega=20.0, aperture_deg=60.0,
                                                   slope_threshold=0.5))
    assert plan.metrics.total.coverage >= 0.95
    check_clearance(plan, 20.0, n_check=40)
    assert plan.path.points[:, 2].max() <= -1.0 and plan.lawnmower.points[:, 2].max() <= -1.0
    gj = json.loads(json.dumps(path_to_geojson(plan.path, GeoFrame(plan.bathy))))
    (route,) = gj["features"]  # no vehicle files: the route alone
    coords = np.array(route["geometry"]["coordinates"])
    import rasterio
    from pyproj import Transformer

    with rasterio.open(tile) as ds:
        b = ds.bounds
    lon, lat = Transformer.from_crs("EPSG:3857", "EPSG:4326", always_xy=True).transform(
        [b.left, b.right], [b.bottom, b.top])
    # The Y scale is positive, so rasterio's "bottom" is the northern edge: compare sorted.
    x0, x1 = sorted(lon)
    y0, y1 = sorted(lat)
    assert np.all((coords[:, 0] >= x0) & (coords[:, 0] <= x1))
    assert np.all((coords[:, 1] >= y0) & (coords[:, 1] <= y1))
    assert route["properties"]["depth_min"] >= 1.0


@pytest.mark.parametrize("kwargs, match", [
    (dict(omega=0.0), "omega"), (dict(omega=-2.0), "omega"), (dict(omega=np.nan), "omega"),
    (dict(aperture_deg=0.0), "aperture_deg"), (dict(aperture_deg=180.0), "aperture_deg"),
    (dict(overlap=1.0), "overlap"), (dict(slope_threshold=0.0), "slope_threshold"),
    (dict(slope_threshold=-0.5), "slope_threshold"), (dict(slice_spacing=0.0), "slice_spacing"),
    (dict(sweep_angle_deg=np.inf), "sweep_angle_deg"), (dict(slice_sensor="up"), "slice_sensor"),
    (dict(sensor_range=0.0), "sensor_range"), (dict(sample_spacing=-1.0), "sample_spacing"),
    (dict(order="3"), "order"), (dict(min_depth=-1.0), "min_depth")])
def test_bad_parameters_are_named(kwargs, match):
    with pytest.raises(ValueError, match=f"CoverageParameters.{match} = "):
        CoverageParameters(**kwargs)


def test_bad_grids_and_no_data_roi():
    with pytest.raises(ValueError, match="outside the grid"):
        plan_coverage(random_seabed(0, (20, 20), 1.0, 2.0, 4.0),
                      roi=(1000.0, 1000.0, 1100.0, 1100.0))
    with pytest.raises(ValueError, match="at least 3 x 3"):
        plan_coverage(Bathymetry(np.zeros((2, 10))))
    z = np.full((20, 20), -10.0)
    z[:8, :8] = np.nan
    with pytest.raises(ValueError, match="only no-data"):
        plan_coverage(Bathymetry(z), roi=(0.0, 0.0, 5.0, 5.0))
    with pytest.raises(FileNotFoundError):
        read_bathymetry("/nonexistent/bathymetry.tif")


def test_no_data_holes_are_no_go_for_coverage_but_do_not_break_the_plan():
    bathy = random_seabed(5, (60, 60), 1.0, 3.0, 6.0)
    z = bathy.z.copy()
    z[25:35, 25:35] = np.nan
    plan = plan_coverage(Bathymetry(z), CoverageParameters(omega=2.0))
    assert plan.metrics.total.coverage >= 0.95
    assert len(plan.cells.cells) >= 4  # the hole is an obstacle of the decomposition
    assert np.all(np.isfinite(plan.path.points))


def test_lawnmower_is_a_path_over_the_whole_roi(caldera_plan):
    lawn = caldera_plan.lawnmower
    assert isinstance(lawn, PlannedPath) and set(lawn.labels) <= {"lawnmower", "transit"}
    xy = lawn.points[:, :2]
    assert xy[:, 0].min() < 1.5 and xy[:, 0].max() > 98.5
    assert xy[:, 1].min() < 1.5 and xy[:, 1].max() > 248.5
