"""Occluded 3D metrics on the grid's mesh: the batched camera query equals the single one,
occlusion hides what a wall stands in front of, and both slicing sensor models are reported."""

import numpy as np

from drake_auv.geometry.raycast import RayCaster
from drake_auv.geometry.visibility import FaceVisibility
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.metrics3d import evaluate_plan_3d
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh
from drake_auv.terrain.synthetic import random_seabed


def _block():
    yy, xx = np.mgrid[0:80, 0:100] * 1.0
    return Bathymetry(-30.0 + 6.0 * ((np.abs(xx - 50) < 15) & (np.abs(yy - 40) < 10)), (1, 1))


def _seabed_and_cameras(n: int, seed: int):
    """Visibility on a random seabed and n cameras 8 m above it looking down and about."""
    vis = FaceVisibility(RayCaster(bathymetry_to_mesh(random_seabed(5, shape=(30, 40)))))
    rng = np.random.default_rng(seed)
    origins = np.column_stack([rng.uniform(5, 35, n), rng.uniform(5, 25, n), np.full(n, -38.0)])
    return vis, origins, np.column_stack([rng.normal(0, 0.5, (n, 2)), -np.ones(n)])


def test_batched_cameras_equal_single_ones():
    vis, origins, axes = _seabed_and_cameras(20, 0)
    slots, angles, pose = vis.cameras(origins, axes, np.radians(60), 8.0)
    for k in range(20):
        s1, a1 = vis.camera(origins[k], axes[k], np.radians(60), 8.0)
        order = np.argsort(slots[pose == k])
        np.testing.assert_array_equal(np.sort(s1), slots[pose == k][order])
        np.testing.assert_allclose(np.sort(a1), np.sort(angles[pose == k]))


def test_a_wall_occludes_the_floor_behind_it():
    vis = FaceVisibility(RayCaster(bathymetry_to_mesh(_block())))
    slots, _, _ = vis.cameras([[20.0, 40.0, -27.0]], [[1.0, 0.0, 0.0]], np.radians(60), 60.0)
    seen = vis.centroids[slots]
    assert (seen[:, 0] < 35.5).sum() > 50  # the floor before the wall and the wall itself
    assert not (seen[:, 0] > 66).any()  # the floor behind the block is hidden


def test_plan_and_lawnmower_on_a_walled_block():
    plan = plan_coverage(_block(), CoverageParameters(omega=2.0), compute_metrics=False)
    m = evaluate_plan_3d(plan)
    assert list(m) == ["high_slope", "high_slope_fixed_tilt", "planar", "total", "lawnmower",
                       "lawnmower_high_slope"]
    assert m["total"].coverage >= 0.9
    # The slices see the vertical walls better than a down-looking lawnmower does.
    assert m["high_slope"].coverage > m["lawnmower_high_slope"].coverage


def test_both_sensor_models_on_the_caldera_rim():
    from drake_auv.terrain.synthetic import caldera_site

    plan = plan_coverage(caldera_site(cell=1.0), CoverageParameters(omega=2.0),
                         compute_metrics=False)
    m = evaluate_plan_3d(plan)
    assert m["high_slope"].view_mean_deg < 1.0  # along the normal: ~0 by construction
    assert 0.5 < m["high_slope_fixed_tilt"].view_mean_deg < 10.0  # the rim's slope spread
    assert m["total"].view_mean_deg < m["lawnmower"].view_mean_deg
    assert m["total"].coverage >= 0.95 and m["lawnmower_high_slope"].view_mean_deg > 20.0


def test_faces_seen_from_their_side_equal_the_cameras_view():
    vis, origins, axes = _seabed_and_cameras(200, 1)
    slots, _, _ = vis.cameras(origins, axes, np.radians(60), 8.0)
    expected = np.zeros(len(vis.areas), bool)
    expected[slots] = True
    assert 0.2 < expected.mean() < 1.0
    np.testing.assert_array_equal(vis.seen_by(origins, axes, np.radians(60), 8.0, chunk=97),
                                  expected)
    some = np.arange(0, len(expected), 7)
    np.testing.assert_array_equal(vis.seen_by(origins, axes, np.radians(60), 8.0, some),
                                  expected[some])


def test_sampled_coverage_is_near_the_exact_one_within_its_error():
    plan = plan_coverage(_block(), CoverageParameters(omega=2.0), compute_metrics=False)
    exact = evaluate_plan_3d(plan)
    sampled = evaluate_plan_3d(plan, max_faces=2000, exact_faces=0)
    for key, m in exact.items():
        s = sampled[key]
        assert m.coverage_se == 0.0 and (s.view_mean_deg, s.samples) == (m.view_mean_deg,
                                                                         m.samples)
        if "high_slope" in key:  # 200 high-slope faces, all tested: exact
            assert (s.coverage, s.coverage_se) == (m.coverage, 0.0)
        else:  # 2000 of the 15600 other faces
            assert 0 < s.coverage_se < 0.01 and abs(s.coverage - m.coverage) <= 4 * s.coverage_se
