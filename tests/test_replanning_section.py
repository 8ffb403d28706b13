"""Replanning loop pieces without Drake: sections, initial trajectory, one STOMP step."""

import numpy as np
import pytest

from drake_auv.mapping.lattice import decode
from drake_auv.replanning.cost import ReplanningCost
from drake_auv.replanning.fields import DEPTH_MARGIN, SliceMap
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import (collect_section, initial_trajectory, passed_index,
                                          replan_section, resample_polyline)

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


def test_initial_trajectory_is_the_polyline_through_the_waypoints():
    x = np.array([3.0, 0.0, -5.0])
    waypoints = np.array([[3.0, 2.0, -5.0], [3.0, 4.0, -5.0]])  # prior map 3 m off
    traj = initial_trajectory(x, waypoints, spacing=0.5)
    assert np.allclose(traj[[0, -1]], [x, waypoints[-1]])
    assert np.allclose(traj[:, 0], 3.0) and len(traj) == 9


def test_passed_index_follows_the_projection_not_the_nearness():
    nominal = WAYPOINTS + [3.0, 0.0, 0.0]
    # 3 m beside the path, level with waypoint 5: waypoints up to 5 are passed.
    assert passed_index([6.0, 5.0, -5.0], nominal, 1, 10) == 6
    assert passed_index([6.0, 5.0, -5.0], nominal, 0, 10) == 6
    # Before the path's start: the first waypoint is passed only when reached.
    assert passed_index([6.0, -2.0, -5.0], nominal, 0, 10) == 0
    assert passed_index([3.2, -0.1, -5.0], nominal, 0, 10) == 1


def test_replan_section_keeps_the_offset_from_a_wall_and_ignores_the_seabed():
    # Planned 3 m too close to the wall: every waypoint, the section's end included, is
    # wrong; STOMP alone (free end, offset on the distance field) moves the trajectory out.
    params = ReplanningParameters()
    nominal = WAYPOINTS + [3.0, 0.0, 0.0]
    x = np.array([4.5, -1.0, -5.0])
    plan = replan_section(x, nominal, 0, _wall(), params, seed=0)
    assert plan.indices.tolist() == [0, 1, 2, 3]
    traj = plan.trajectory
    assert np.allclose(traj[0], x)
    assert np.all(traj[:, 0] > params.clearance)
    # Past the first 2.5 m (the vehicle starts 1.5 m too close), the offset Omega is kept, to
    # the section's (free) end.
    far = np.linalg.norm(traj - x, axis=1) > 2.5
    assert np.all(np.abs(traj[far, 0] - params.omega) < 0.6)
    assert abs(traj[-1, 0] - params.omega) < 0.4 and traj[-1, 1] > 2.5
    assert np.all(np.abs(traj[:, 2] + 5.0) < 0.3)  # the seabed 5 m below does not pull
    assert plan.cost < 0.2 * plan.initial_cost and plan.iterations >= 1
    assert 0 < plan.map_voxels < len(_wall())  # the wall's voxels in the section's box
    # The wall (x = 0) lies in -x from every point: facing it is a yaw of pi.
    assert np.allclose(np.abs(np.angle(np.exp(1j * (plan.facing - np.pi)))), 0.0, atol=0.1)
    # Progress along the plan marks waypoints visited.
    assert plan.next_index(0.0, capture_radius=0.1) == 0
    assert plan.next_index(np.inf) == 4
    # Unoptimised, the same section flies into the offset: the ablation's baseline.
    none = replan_section(x, nominal, 0, _wall(), params, seed=0, optimizer="none")
    assert np.array_equal(none.trajectory, none.initial) and none.iterations == 0
    assert none.trajectory[-1, 0] == pytest.approx(3.0)
    with pytest.raises(ValueError, match="optimizer"):
        replan_section(x, nominal, 0, _wall(), params, optimizer="chomp")


def test_one_outlier_voxel_does_not_repel_the_path_but_a_confirmed_one_does():
    params = ReplanningParameters()
    nominal = WAYPOINTS + [6.0, 0.0, 0.0]  # on the offset
    wall = _wall(with_seabed=False)
    outlier = np.array([[8.0, 4.0, -5.0]])  # 2 m outside the path, within the clearance
    occupied = np.vstack([wall, outlier])
    x = np.array([6.0, 0.0, -5.0])
    hit_once = np.append(np.full(len(wall), 3.5), 0.85)  # OctoMap: one hit is 0.85
    confirmed = np.append(np.full(len(wall), 3.5), 3.5)
    kept = replan_section(x, nominal, 0, occupied, params, seed=2, log_odds=hit_once)
    assert np.all(np.abs(kept.trajectory[:, 0] - params.omega) < 0.25)
    avoided = replan_section(x, nominal, 0, occupied, params, seed=2, log_odds=confirmed)
    assert np.linalg.norm(avoided.trajectory - outlier, axis=1).min() > 2.4
    # Without log-odds every voxel counts.
    assert np.linalg.norm(replan_section(x, nominal, 0, occupied, params, seed=2).trajectory
                          - outlier, axis=1).min() > 2.4


def test_progress_past_a_wrong_waypoint_inside_the_offset():
    # One waypoint in the section, on the prior map 3 m too close to the wall; the vehicle
    # already flies at the offset beside it. Hovering costs (progress term); the free end
    # advances along the route at the offset instead of diving to the waypoint.
    params = ReplanningParameters(radius=3.0)
    nominal = WAYPOINTS[::4] + [3.0, 0.0, 0.0]  # waypoints 4 m apart
    x = np.array([6.0, 1.0, -5.0])
    plan = replan_section(x, nominal, 1, _wall(), params, seed=3)
    assert plan.indices.tolist() == [1]
    end = plan.trajectory[-1]
    assert abs(end[0] - params.omega) < 0.4
    assert end[1] > x[1] + 2.5  # advanced along the wall
    slice_map = SliceMap(_wall(), (-5.0, -5.0), params.depth_band, params.clearance)
    route = np.vstack([x, nominal[1:3]])
    advancing = np.linspace(x, x + [0.0, 3.0, 0.0], 7)
    cost = ReplanningCost(slice_map, route, advancing, params, goal=3.0)
    hovering = np.repeat(x[None], 7, axis=0)
    assert cost(hovering[None]).sum() > cost(advancing[None]).sum() + 1.0


def test_offset_is_a_distance_field_that_does_not_saturate():
    y, z = np.meshgrid(np.arange(-4.75, 25.0, 0.5), np.arange(-9.75, 2.0, 0.5))
    wall = np.stack([np.full(y.size, 0.25), y.ravel(), z.ravel()], axis=1)  # voxel centres
    slice_map = SliceMap(wall, (-5.0, -5.0), depth_band=1.5, clearance=3.0)
    points = np.stack([np.linspace(0.6, 14.0, 40), np.full(40, 10.0), np.full(40, -5.0)], 1)
    assert np.allclose(slice_map.offset(points), points[:, 0] - 0.25, atol=0.02)
    empty = SliceMap(np.zeros((0, 3)), (-5.0, -5.0), 1.5, 3.0)
    assert np.all(np.isinf(empty.offset(points)))


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


def test_slice_map_within_rules_a_batch_out_only_when_no_point_is_near():
    """`within`'s one box test of the slab's field is at most every point's own bound, so it
    never rules out a batch with a point inside the clearance (the cost then skips the
    obstacle term)."""
    rng = np.random.default_rng(7)
    slice_map = SliceMap(_wall(), (-5.0, -5.0), depth_band=1.5, clearance=3.0)
    field = slice_map._slab_field
    for _ in range(200):
        centre = rng.uniform([-30, -30, -6], [40, 50, -4])
        batch = centre + rng.normal(0.0, rng.uniform(0.1, 5.0), (11, 12, 3))
        flat = batch.reshape(-1, 3)
        assert field.box_lower_bound(flat) <= field.lower_bound(flat).min() + 1e-12
        near = np.isfinite(slice_map.clearance(batch, 3.0)).any()
        assert slice_map.within(batch, 3.0) or not near
    far = np.stack([np.full(5, 9.0), np.linspace(0, 20, 5), np.full(5, -5.0)], axis=1)
    assert not slice_map.within(far, 3.0)  # 8.75 m from the wall
    assert slice_map.within(np.vstack([far, [[1.0, 10.0, -5.0]]]), 3.0)
    assert not SliceMap(np.zeros((0, 3)), (-5.0, -5.0), 1.5, 3.0).within(far, 3.0)


def test_only_points_marked_keep_offset_keep_it_the_others_follow_the_route():
    nominal = WAYPOINTS + [4.5, 0.0, 0.0]  # 1.5 m inside the offset, outside the clearance
    x = np.array([4.5, 0.0, -5.0])
    params = ReplanningParameters()
    wall = _wall()
    contour = replan_section(x, nominal, 0, wall, params, seed=4)
    transit = replan_section(x, nominal, 0, wall, params, seed=4,
                             keep_offset=np.zeros(len(nominal), bool))
    assert abs(contour.trajectory[-1, 0] - params.omega) < 0.4
    assert np.all(np.abs(transit.trajectory[:, 0] - 4.5) < 0.3)
    assert np.all(np.isnan(transit.facing))  # the yaw follows the motion there


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


def test_cost_is_the_weighted_sum_of_its_terms_with_the_terminal_goal_on_the_last_point():
    rng = np.random.default_rng(11)
    wall = np.column_stack([rng.uniform(-5, 5, 400), np.full(400, 6.0), rng.uniform(-3, 3, 400)])
    params = ReplanningParameters(omega=5.0, offset_metric="3d")
    slice_map = SliceMap(wall, (-1.0, 1.0), params.depth_band, params.clearance, metric="3d")
    keep = np.array([1, 1, 0, 0, 1, 0, 1, 1], bool)
    initial = np.column_stack([np.linspace(-3, 3, 8), np.zeros(8), np.zeros(8)])
    cost = ReplanningCost(slice_map, initial[[0, -1]], initial, params, keep)
    rollouts = initial + rng.normal(0.0, 1.0, (5, len(keep), 3))
    t = cost.terms(rollouts)
    d = np.linalg.norm(rollouts[..., None, :] - wall, axis=-1).min(axis=-1)
    assert np.allclose(t["offset"][..., keep], np.where(np.abs(d - 5.0) <= 1.0, (d - 5.0) ** 2,
                                                        2.0 * np.abs(d - 5.0) - 1.0)[..., keep])
    assert np.all(t["offset"][..., ~keep] == 0) and np.all(t["route"][..., keep] == 0)
    expected = (params.offset_weight * t["offset"] + params.obstacle_weight * t["obstacle"]
                + params.depth_weight * ~keep * t["depth"] + params.route_weight * t["route"]
                + params.progress_weight * t["progress"] + params.spacing_weight * t["spacing"])
    gaps = np.linalg.norm(np.diff(rollouts, axis=1), axis=-1)
    assert np.allclose(t["spacing"][:, 1:], (gaps - params.spacing) ** 2)
    assert np.all(t["spacing"][:, 0] == 0)
    expected[..., -1] += params.terminal_weight * (params.offset_weight * t["offset"][..., -1]
                                                   + params.progress_weight
                                                   * t["progress"][..., -1])
    assert np.allclose(cost(rollouts), expected, rtol=1e-12, atol=1e-12)



def test_a_band_off_the_box_grid_maps_no_offset_and_costs_none():
    """Horizontal metric: band voxels outside the box's grid give an offset of inf everywhere
    (`offset_mapped` False) and an offset term of 0, as where nothing is mapped at all."""
    params = ReplanningParameters(omega=3.0)  # 5 m from the wall in reach: a cost
    wall = np.column_stack([np.linspace(-5, 5, 50), np.full(50, 40.0), np.zeros(50)])
    box = (np.array([-10.0, -10.0, -5.0]), np.array([10.0, 10.0, 5.0]))
    initial = np.column_stack([np.linspace(-3, 3, 8), np.zeros(8), np.zeros(8)])
    for voxels, mapped in ((wall, False), (wall - [0.0, 35.0, 0.0], True)):
        slice_map = SliceMap(voxels, (-1.0, 1.0), params.depth_band, params.clearance, box=box)
        assert slice_map.offset_mapped == mapped
        cost = ReplanningCost(slice_map, initial[[0, -1]], initial, params)
        offset = cost.terms(initial[None])["offset"]
        assert np.all(offset == 0) != mapped
        assert np.all(np.isinf(slice_map.offset(initial))) != mapped


def test_3d_offset_near_the_trajectory_is_interpolated_and_exact_elsewhere():
    """Metric "3d": after `prepare_tube` the offset within the tube is the trilinear read of
    exact node distances (within 2 cm of the KD-tree's at 5-8 m from a curved face), and
    beyond the tube exactly the KD-tree's."""
    rng = np.random.default_rng(3)
    u = rng.normal(size=(4000, 3))
    sphere = 5.0 * u / np.linalg.norm(u, axis=1, keepdims=True)  # voxels of a 5 m boulder
    slice_map = SliceMap(sphere, (-12.0, 12.0), 1.5, 3.0, DEPTH_MARGIN, metric="3d")
    a = np.linspace(0.0, 1.5, 20)
    trajectory = np.column_stack([11.0 * np.cos(a), 11.0 * np.sin(a), np.zeros(20)])
    exact = slice_map.offset(trajectory + 0.0)
    slice_map.prepare_tube(trajectory, pad=1.0)

    class Counting:  # the KD-tree, counting the points queried after the tube was built
        def __init__(self, tree):
            self.tree, self.points = tree, 0

        def query(self, x, *args, **kwargs):
            self.points += len(x)
            return self.tree.query(x, *args, **kwargs)

    tree = slice_map.band_tree = Counting(slice_map.band_tree)
    near = trajectory[None] + rng.uniform(-0.5, 0.5, (8, 20, 3))
    d = slice_map.offset(near)
    assert tree.points == 0  # all read from the tube's nodes
    assert np.abs(d.ravel() - tree.tree.query(near.reshape(-1, 3))[0]).max() < 0.02
    np.testing.assert_allclose(slice_map.offset(trajectory), exact, atol=0.02)
    far = trajectory + [0.0, 0.0, 4.0]  # 4 m above the tube: no computed node
    tree.points = 0
    np.testing.assert_array_equal(slice_map.offset(far), tree.tree.query(far)[0])
    assert tree.points == len(far)


class _CountingTree:
    """A KD-tree counting the points queried."""

    def __init__(self, tree):
        self.tree, self.points = tree, 0

    def query(self, x, *args, **kwargs):
        self.points += len(x)
        return self.tree.query(x, *args, **kwargs)


def test_the_tube_reuses_the_last_steps_node_offsets_and_gives_a_full_querys_numbers():
    """`prepare_tube(reuse=...)` after the map changed (voxels gone, the nearest of many
    nodes among them; voxels added, nearer than some nodes' nearest) and the trajectory moved
    on: the same node offsets as a tube built afresh, bit for bit, each at the distance of the
    voxel it names, for fewer queries of the band's KD-tree than the nodes."""
    rng = np.random.default_rng(11)
    u = rng.normal(size=(6000, 3))
    idx = np.unique(np.floor(5.0 * u / np.linalg.norm(u, axis=1, keepdims=True) / 0.5), axis=0)
    voxels = (idx + 0.5) * 0.5  # centres of 0.5 m voxels of a 5 m boulder
    a = np.linspace(0.0, 1.5, 20)
    arc = np.column_stack([11.0 * np.cos(a), 11.0 * np.sin(a), np.zeros(20)])

    def tube(points, trajectory, reuse=None):
        slice_map = SliceMap(points, (-12.0, 12.0), 1.5, 3.0, metric="3d", resolution=0.5)
        slice_map.band_tree = tree = _CountingTree(slice_map.band_tree)
        return slice_map.prepare_tube(trajectory, pad=1.0, reuse=reuse), tree.points

    last, _ = tube(voxels, arc)
    gone = np.linalg.norm(voxels - [5.5, 2.0, 0.0], axis=1) < 2.0  # the face nearest the arc
    bump = voxels[gone & (voxels[:, 0] > 3.5)] * 1.1  # pushed out: nearer than before
    bump = (np.floor(bump / 0.5) + 0.5) * 0.5
    hole = np.linalg.norm(voxels - [1.1, 4.9, 0.0], axis=1) < 1.2  # gone, not replaced
    changed = np.unique(np.vstack([voxels[~gone & ~hole], bump]), axis=0)
    moved = arc[2:] + [0.2, 0.0, 0.1]
    reused, queried = tube(changed, moved, reuse=last)
    fresh, fresh_queries = tube(changed, moved)
    np.testing.assert_array_equal(reused.nodes, fresh.nodes)
    np.testing.assert_array_equal(reused.distance, fresh.distance)
    np.testing.assert_array_equal(reused.voxels, fresh.voxels)
    at = (decode(reused.nearest) + 0.5) * 0.5  # each node's nearest voxel centre
    np.testing.assert_allclose(np.linalg.norm(decode(reused.nodes) * 0.5 - at, axis=1),
                               reused.distance, rtol=1e-12)
    assert fresh_queries == len(fresh.nodes) and 0 < queried < 0.6 * fresh_queries
    _, mine, theirs = np.intersect1d(reused.nodes, last.nodes, return_indices=True)
    change = reused.distance[mine] - last.distance[theirs]
    assert (change < -0.05).any() and (change > 0.05).any()  # both changes were exercised
    assert tube(np.vstack([voxels, voxels[:1]]), arc)[0] is None  # a point twice: no codes
