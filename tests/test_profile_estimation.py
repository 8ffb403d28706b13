"""Profile estimator on synthetic scan-plane point sets (no Drake)."""

import numpy as np
import pytest

from drake_auv.perception import EstimatorParams, LocalProfileMap, estimate_profile


def _line(p0, p1, spacing=0.05, noise=0.02, seed=0):
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    n = int(np.linalg.norm(p1 - p0) / spacing) + 1
    t = np.linspace(0, 1, n)[:, None]
    return p0 + t * (p1 - p0) + np.random.default_rng(seed).normal(0, noise, (n, 2))


def test_vertical_wall_distance_normal_orientation():
    # a wall x = 2.5 in front of the vehicle (vertical in the (s, h) plane: y-on-x regression fails)
    est = estimate_profile(_line([2.5, -3], [2.5, 3]), rng=np.random.default_rng(1))
    assert est.distance == pytest.approx(2.5, abs=0.03)
    assert np.allclose(est.normal, [-1, 0], atol=0.02)
    assert abs(abs(est.orientation) - np.pi / 2) < np.radians(1.5)
    assert len(est.segments) == 1


def test_slanted_line_distance_matches_geometry():
    # line through (0, -3) at 30 degrees: distance from the origin is 3 cos(30 deg)
    angle = np.radians(30)
    d = np.array([np.cos(angle), np.sin(angle)])
    pts = _line(np.array([0, -3]) - 4 * d, np.array([0, -3]) + 4 * d, noise=0.01)
    est = estimate_profile(pts)
    assert est.distance == pytest.approx(3 * np.cos(angle), abs=0.03)
    assert est.orientation == pytest.approx(angle, abs=np.radians(1.0))
    expected_normal = np.array([-np.sin(angle), np.cos(angle)])  # from the line to the origin
    assert np.allclose(est.normal, expected_normal, atol=0.02)


def test_concave_corner_gives_two_segments_and_bisector_normal():
    # pool corner: walls x = 2 and y = 2, vehicle at the origin, equidistant from both
    pts = np.vstack([_line([2, -3], [2, 2]), _line([-3, 2], [2, 2], seed=1)])
    est = estimate_profile(pts, rng=np.random.default_rng(2))
    assert len(est.segments) >= 2
    assert est.distance == pytest.approx(2.0, abs=0.05)
    assert np.allclose(est.normal, -np.array([1, 1]) / np.sqrt(2), atol=0.05)
    # 1 m nearer one wall: that wall's normal, the other blended in by exp(-1 m / blend)
    est = estimate_profile(pts - [0.0, -1.0], rng=np.random.default_rng(2))
    assert est.distance == pytest.approx(2.0, abs=0.05)
    expected = np.array([-1.0, -np.exp(-1.0 / EstimatorParams().blend)])
    assert np.allclose(est.normal, expected / np.linalg.norm(expected), atol=0.02)


def test_convex_corner_normal_points_from_the_edge():
    # box corner at (1.5, 1.5), walls going away from the vehicle: nearest point is the edge
    pts = np.vstack([_line([1.5, 1.5], [1.5, 5]), _line([1.5, 1.5], [5, 1.5], seed=1)])
    est = estimate_profile(pts, EstimatorParams(window=8.0))
    assert est.distance == pytest.approx(1.5 * np.sqrt(2), abs=0.06)
    assert np.allclose(est.normal, -np.array([1, 1]) / np.sqrt(2), atol=0.06)


def test_overhang_wall_and_ceiling_in_vertical_plane():
    # (s, h): a wall at s = 2 from h = -4 to h = 1.5, a ceiling at h = 1.5 from s = 2 back to s = -4
    pts = np.vstack([_line([2, -4], [2, 1.5]), _line([-4, 1.5], [2, 1.5], seed=3)])
    est = estimate_profile(pts, EstimatorParams(window=8.0))
    horizontal = [s for s in est.segments if abs(s.direction[1]) < 0.05]
    vertical = [s for s in est.segments if abs(s.direction[0]) < 0.05]
    assert horizontal and vertical
    assert est.distance == pytest.approx(1.5, abs=0.05)
    assert est.normal[1] < -0.9  # the ceiling is the nearest: the normal points down
    assert est.orientation == pytest.approx(0.0, abs=np.radians(1.5))


def test_outliers_do_not_move_the_estimate():
    rng = np.random.default_rng(7)
    wall = _line([2.0, -3], [2.0, 3])
    spurious = rng.uniform(-5, 5, (60, 2))  # 60 random returns against ~120 wall returns
    clean = estimate_profile(wall, rng=np.random.default_rng(3))
    noisy = estimate_profile(np.vstack([wall, spurious]), rng=np.random.default_rng(3))
    assert noisy.distance == pytest.approx(clean.distance, abs=0.03)
    assert np.allclose(noisy.normal, clean.normal, atol=0.02)
    # spurious returns nearer than the wall would bias a nearest-point estimator: not this one
    near = rng.uniform(-0.8, 0.8, (15, 2))
    est = estimate_profile(np.vstack([wall, near]), rng=np.random.default_rng(3))
    assert est.distance == pytest.approx(2.0, abs=0.05)


def test_sector_excludes_points_behind():
    front = _line([2, -3], [2, 3])
    behind = _line([-1, -3], [-1, 3], seed=2)
    est = estimate_profile(np.vstack([front, behind]), EstimatorParams(sector=np.radians(80)),
                           look_direction=[1, 0])
    assert est.distance == pytest.approx(2.0, abs=0.05)
    assert estimate_profile(np.vstack([front, behind])).distance == pytest.approx(1.0, abs=0.05)


def test_no_profile_and_bad_input():
    assert estimate_profile(np.empty((0, 2))) is None
    assert estimate_profile(np.random.default_rng(0).uniform(-5, 5, (30, 2))) is None
    assert estimate_profile(np.full((20, 2), np.nan)) is None
    with pytest.raises(ValueError, match="sector"):
        EstimatorParams(sector=4.0)
    with pytest.raises(ValueError, match="inlier_tolerance"):
        EstimatorParams(inlier_tolerance=-1)
    with pytest.raises(ValueError, match="look_direction"):
        estimate_profile(_line([2, -3], [2, 3]), look_direction=[0, 0])


def test_deterministic_with_seed():
    pts = np.vstack([_line([2, -3], [2, 2]), _line([-3, 2], [2, 2], seed=1),
                     np.random.default_rng(5).uniform(-5, 5, (40, 2))])
    a = estimate_profile(pts, rng=np.random.default_rng(11))
    b = estimate_profile(pts, rng=np.random.default_rng(11))
    assert a.distance == b.distance and np.array_equal(a.normal, b.normal)


def test_local_map_forgets_by_age_and_count_and_slices():
    m = LocalProfileMap(max_age=5.0, max_points=10)
    m.add([[1, 0, -4], [np.nan] * 3, [0, 3, -4.2]], time=0.0)
    assert len(m) == 2
    m.add([[2, 0, -9]], time=4.0)
    assert len(m) == 3
    m.add(np.empty((0, 3)), time=5.5)  # the first two are now 5.5 s old
    assert len(m) == 1
    m.add(np.tile([[5.0, 0, -4]], (12, 1)), time=6.0)
    assert len(m) == 10
    m = LocalProfileMap()
    m.add([[1, 0, -4], [0, 3, -4.2], [3, 3, -6]], time=0.0)
    xy = m.horizontal_slice([0, 0, -4], band=0.5)
    assert np.allclose(xy, [[1, 0], [0, 3]])
    sh = m.vertical_slice([0, 0, -4], direction_yaw=np.pi / 2, band=0.5)
    assert np.allclose(sh, [[3, -0.2]])
    with pytest.raises(ValueError, match="max_age"):
        LocalProfileMap(max_age=0)
    with pytest.raises(ValueError, match="position"):
        m.horizontal_slice([0, np.nan, 0])
