"""Replanning loop pieces without Drake: sections, initial trajectory, one STOMP step."""

import numpy as np
import pytest

from drake_auv.replanning.section import (ReplanningParameters, SliceMap, collect_section,
                                           initial_trajectory, replan_section,
                                           resample_polyline)

WAYPOINTS = np.stack([np.zeros(20), np.arange(20.0), np.full(20, -5.0)], axis=1)


def _wall(x=0.0, with_seabed=True):
    """Occupied voxel centres of a wall x = const (y in [-5, 25], z in [-10, 2]) and a seabed."""
    y, z = np.meshgrid(np.arange(-5.0, 25.0, 0.5), np.arange(-10.0, 2.0, 0.5))
    wall = np.stack([np.full(y.size, x), y.ravel(), z.ravel()], axis=1)
    if not with_seabed:
        return wall
    sx, sy = np.meshgrid(np.arange(x, x + 15.0, 0.5), np.arange(-5.0, 25.0, 0.5))
    seabed = np.stack([sx.ravel(), sy.ravel(), np.full(sx.size, -10.0)], axis=1)
    return np.vstack([wall, seabed])


def test_collect_section_takes_waypoints_within_radius_in_order():
    idx = collect_section([0.0, 2.2, -5.0], WAYPOINTS, 3, radius=5.0, max_waypoints=10)
    assert idx.tolist() == [3, 4, 5, 6, 7]  # |x - w_7| = 4.8 < 5, |x - w_8| = 5.8
    idx = collect_section([0.0, 2.2, -5.0], WAYPOINTS, 3, radius=5.0, max_waypoints=2)
    assert idx.tolist() == [3, 4]
    # Stops at the first waypoint out of range even if later ones come back.
    loop = np.array([[0, 0, 0], [1, 0, 0], [9, 0, 0], [1, 1, 0]], dtype=float)
    assert collect_section([0, 0, 0], loop, 0, 5.0, 10).tolist() == [0, 1]


def test_collect_section_always_takes_the_next_waypoint_and_ends_empty():
    idx = collect_section([30.0, 0.0, -5.0], WAYPOINTS, 4, radius=5.0, max_waypoints=10)
    assert idx.tolist() == [4]
    assert len(collect_section([0, 19, -5.0], WAYPOINTS, 20, 5.0, 10)) == 0


def test_collect_section_rejects_bad_input():
    with pytest.raises(ValueError, match="position"):
        collect_section([np.nan, 0, 0], WAYPOINTS, 0, 5.0, 10)
    with pytest.raises(ValueError, match="radius"):
        collect_section([0, 0, 0], WAYPOINTS, 0, 0.0, 10)
    with pytest.raises(ValueError, match="radius"):
        ReplanningParameters(radius=-1.0)
    with pytest.raises(ValueError, match="max_waypoints"):
        ReplanningParameters(max_waypoints=0)


def test_resample_polyline_is_even_and_keeps_ends():
    pts = resample_polyline([[0, 0, 0], [3, 0, 0], [3, 4, 0]], 0.5)
    steps = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    assert np.allclose(pts[[0, -1]], [[0, 0, 0], [3, 4, 0]])
    assert np.allclose(steps, steps[0], atol=1e-9) and steps[0] <= 0.5


def test_initial_trajectory_moves_waypoints_onto_the_offset():
    slice_map = SliceMap(_wall(), (-5.0, -5.0), depth_band=1.5, clearance=3.0)
    x = np.array([3.0, 0.0, -5.0])
    waypoints = np.array([[3.0, 2.0, -5.0], [3.0, 4.0, -5.0]])  # prior map 3 m off
    traj, fraction = initial_trajectory(x, waypoints, slice_map, omega=6.0, spacing=0.5)
    assert np.allclose(traj[0], x)
    assert np.allclose(traj[-1], [6.0, 4.0, -5.0])
    assert np.all(np.diff(fraction) > 0) and fraction[-1] == pytest.approx(1.0)
    # Nothing mapped near: the waypoints stay where they are.
    empty = SliceMap(np.zeros((0, 3)), (-5.0, -5.0), 1.5, 3.0)
    traj, _ = initial_trajectory(x, waypoints, empty, omega=6.0, spacing=0.5)
    assert np.allclose(traj[-1], waypoints[-1])


def test_replan_section_keeps_the_offset_from_a_wall_and_ignores_the_seabed():
    params = ReplanningParameters()
    nominal = WAYPOINTS + [3.0, 0.0, 0.0]  # planned 3 m too close to the wall
    x = np.array([4.5, -1.0, -5.0])
    plan = replan_section(x, nominal, 0, _wall(), params, seed=0)
    assert plan.indices.tolist() == [0, 1, 2, 3]
    traj = plan.trajectory
    assert np.allclose(traj[0], x)
    assert np.all(traj[:, 0] > params.clearance)
    # Past the first 2 m (the vehicle starts 1.5 m too close), the offset Omega is kept.
    far = np.linalg.norm(traj - x, axis=1) > 2.0
    assert np.all(np.abs(traj[far, 0] - params.omega) < 0.4)
    assert np.all(np.abs(traj[:, 2] + 5.0) < 0.3)  # the seabed 5 m below does not pull
    assert plan.cost <= plan.initial_cost
    # The wall (x = 0) lies in -x from every point: facing it is a yaw of pi.
    assert np.allclose(np.abs(np.angle(np.exp(1j * (plan.facing - np.pi)))), 0.0, atol=0.1)
    # Progress along the plan marks waypoints visited.
    assert plan.next_index(0.0, capture_radius=0.1) == 0
    assert plan.next_index(np.inf) == 4


def test_replan_section_is_deterministic_and_none_when_done():
    a = replan_section([4.0, 0.0, -5.0], WAYPOINTS + [3, 0, 0], 0, _wall(), seed=5)
    b = replan_section([4.0, 0.0, -5.0], WAYPOINTS + [3, 0, 0], 0, _wall(), seed=5)
    assert np.array_equal(a.trajectory, b.trajectory)
    assert replan_section([0, 19, -5.0], WAYPOINTS, 20, _wall()) is None


def test_slice_map_clearance_is_the_exact_3d_distance_within_the_bound():
    rng = np.random.default_rng(4)
    occupied = np.vstack([_wall(), rng.uniform([-3, -5, -12], [12, 25, 3], (30, 3))])
    slice_map = SliceMap(occupied, (-5.0, -5.0), depth_band=1.5, clearance=3.0)
    points = rng.uniform([-2, 0, -6], [14, 20, -4], (500, 3))
    exact = np.linalg.norm(points[:, None] - occupied[None], axis=2).min(axis=1)
    got = slice_map.clearance(points, 3.0)
    within = exact < 3.0
    assert within.sum() > 50 and (~within).sum() > 50
    assert np.allclose(got[within], exact[within])
    assert np.all(np.isinf(got[~within]))


def test_only_waypoints_marked_keep_offset_are_moved():
    slice_map = SliceMap(_wall(), (-5.0, -5.0), depth_band=1.5, clearance=3.0)
    x = np.array([3.0, 0.0, -5.0])
    waypoints = np.array([[3.0, 2.0, -5.0], [3.0, 4.0, -5.0]])
    traj, _ = initial_trajectory(x, waypoints, slice_map, omega=6.0, spacing=0.5,
                                 keep_offset=[True, False])
    assert np.allclose(traj[-1], waypoints[-1])  # a lane or transit waypoint is not moved
    assert traj[:, 0].max() == pytest.approx(6.0, abs=0.3)  # the contour one is, to x = 6


def _slope():
    """Occupied voxel centres of a 45 degree face z = -x (x in [-10, 10]), y in [-5, 25]."""
    xs, ys = np.meshgrid(np.arange(-10.0, 10.0, 0.5), np.arange(-5.0, 25.0, 0.5))
    return np.stack([xs.ravel(), ys.ravel(), -xs.ravel()], axis=1)


def test_3d_offset_metric_keeps_omega_along_the_normal_of_a_sloping_face():
    omega = 6.0
    # A contour planned on a prior map 3 m off: 3 m from the face along its normal (1, 0, 1).
    n = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    nominal = np.stack([np.zeros(20), np.arange(20.0), np.zeros(20)], axis=1) + 3.0 * n
    params = ReplanningParameters(omega=omega, offset_metric="3d", radius=8.0)
    x = nominal[0] + [0.0, -1.0, 0.0]
    plan = replan_section(x, nominal, 0, _slope(), params, seed=1)
    end = plan.trajectory[-1]
    # Distance to the plane x + z = 0 is (x + z) / sqrt(2); voxel centres are 0.5 m apart.
    assert (end[0] + end[2]) / np.sqrt(2.0) == pytest.approx(omega, abs=0.3)
    horizontal = replan_section(x, nominal, 0, _slope(),
                                ReplanningParameters(omega=omega, radius=8.0), seed=1)
    assert abs((horizontal.trajectory[-1][0] + horizontal.trajectory[-1][2]) / np.sqrt(2.0)
               - omega) > 0.5  # the horizontal metric misreads a sloping face
    with pytest.raises(ValueError, match="offset_metric"):
        ReplanningParameters(offset_metric="vertical")


def test_offset_is_queried_only_where_it_is_weighted_and_the_cost_is_unchanged():
    from drake_auv.replanning.section import ReplanningCost, ReplanningParameters, SliceMap

    rng = np.random.default_rng(11)
    wall = np.column_stack([rng.uniform(-5, 5, 400), np.full(400, 6.0), rng.uniform(-3, 3, 400)])
    params = ReplanningParameters(omega=5.0, offset_metric="3d")
    slice_map = SliceMap(wall, (-1.0, 1.0), params.depth_band, params.clearance, metric="3d")
    keep = np.array([1, 1, 0, 0, 1, 0, 1, 1], bool)
    cost = ReplanningCost(slice_map, np.zeros(len(keep)), params, keep)
    rollouts = rng.normal(0.0, 2.0, (5, len(keep), 3))
    # The cost term by term, querying every point.
    d, _ = slice_map.offset(rollouts, 2.0 * params.omega)
    expected = (params.offset_weight * keep * np.minimum(np.abs(d - params.omega), params.omega)
                + params.obstacle_weight * np.maximum(
                    0.0, params.clearance - slice_map.clearance(rollouts, params.clearance)) ** 2
                + params.depth_weight * rollouts[..., 2] ** 2)
    assert np.allclose(cost(rollouts), expected, rtol=1e-12, atol=1e-12)
    assert np.allclose(cost(rollouts[0]), expected[0], rtol=1e-12, atol=1e-12)
