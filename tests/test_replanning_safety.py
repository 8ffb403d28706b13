"""The replanner's safety against a structure the on-line map knows only by its faces, and a
vehicle carried past its waypoints: a section's target is never a waypoint behind the
vehicle; no trajectory, warm start or plan, passes through a mapped surface; the inflated
clearance stays within the map the section gathered; warm starts carry no depth drift."""

import numpy as np
import pytest

from drake_auv.replanning.cost import ReplanningCost
from drake_auv.replanning.fields import SliceMap
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import passed_index, replan_section

LO, HI = np.array([0.0, 0.0, -8.0]), np.array([10.0, 5.0, -2.0])  # the block, m


def _faces(lo=LO, hi=HI, resolution=0.5):
    """Centres of the 0.5 m voxels on the block's faces: what the sonars map, no inside."""
    axes = [np.arange(a, b, resolution) + 0.5 * resolution for a, b in zip(lo, hi)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    edge = np.any((grid - 0.5 * resolution <= lo + 1e-9)
                  | (grid + 0.5 * resolution >= hi - 1e-9), axis=1)
    return grid[edge]


def _through_block(trajectory, lo=LO, hi=HI, step=0.02):
    """Whether any point of the polyline lies inside the block (the true geometry, sampled
    every `step` m: independent of the map's voxels)."""
    a, b = trajectory[:-1], trajectory[1:]
    n = int(np.ceil(np.linalg.norm(b - a, axis=1).max() / step)) + 1
    f = np.linspace(0.0, 1.0, n)[None, :, None]
    samples = (a[:, None] + f * (b - a)[:, None]).reshape(-1, 3)
    return bool(np.any(np.all((samples > lo) & (samples < hi), axis=1)))


def test_a_vehicle_carried_past_more_than_a_window_of_waypoints_leaves_none_behind():
    waypoints = np.stack([np.zeros(20), np.arange(20.0), np.full(20, -5.0)], axis=1)
    x = np.array([1.0, 9.0, -5.0])  # carried from waypoint 3 to beyond waypoint 9
    assert passed_index(x, waypoints, 3, window=2) == 10
    params = ReplanningParameters(max_waypoints=2, radius=5.0)
    plan = replan_section(x, waypoints, 3, np.zeros((0, 3)), params, optimizer="none")
    # The section's waypoints are all ahead of the vehicle along the path (+y).
    assert plan.indices.tolist() == [10, 11]
    assert np.all(waypoints[plan.indices, 1] > x[1])


def test_the_inside_of_a_block_known_by_its_faces_is_priced_as_a_crossing():
    faces = _faces()
    params = ReplanningParameters()
    slice_map = SliceMap(faces, (-5.0, -5.0), params.depth_band, params.clearance)
    y = np.arange(-6.0, 11.01, 0.5)
    through = np.column_stack([np.full(len(y), 5.0), y, np.full(len(y), -5.0)])
    around = through.copy()
    around[:, 0] = -4.5  # 4.5 m west of the block, beyond its faces
    # The middle of the block is 2.5 m from its nearest face: inside the clearance by
    # 1.5 m only, what open water 2.5 m from a wall costs.
    middle = np.array([[5.0, 2.5, -5.0]])
    assert slice_map.clearance(middle, 4.0)[0] == pytest.approx(2.5, abs=0.3)
    crossing = slice_map.crossing(np.stack([through, around]))
    assert crossing[1].sum() == 0.0
    # Two faces crossed, a 0.5 m voxel layer each (y in [0, 0.5] and [4.5, 5]), on the
    # segments into the points at y = 0.5 and 5.
    assert crossing[0].sum() == pytest.approx(1.0)
    assert np.flatnonzero(crossing[0]).tolist() == np.flatnonzero(
        np.isin(y, [0.5, 5.0])).tolist()
    route = np.array([[5.0, -6.0, -5.0], [5.0, 11.0, -5.0]])
    cost = ReplanningCost(slice_map, route, through, params, np.zeros(len(y), bool))
    terms = cost.terms(through[None])
    assert np.array_equal(terms["crossing"][0], crossing[0])
    # The clearance charges the middle of the block less than open water 2 m from a wall;
    # crossing a face into it costs 10^4 x 0.5.
    inside = np.abs(y - 2.5) < 1e-9
    assert terms["obstacle"][0, inside][0] < (params.clearance - 2.0) ** 2
    assert (cost(through[None]) - cost(around[None])).sum() > params.crossing_weight * 0.9


def test_a_warm_start_through_the_block_is_not_flown_and_the_plan_goes_around():
    faces = _faces()
    params = ReplanningParameters(omega=4.0, clearance=3.0)
    x = np.array([2.0, -4.0, -5.0])  # 4 m off the south face
    waypoints = np.column_stack([np.arange(2.0, 9.01, 1.0), np.full(8, -4.0),
                                 np.full(8, -5.0)])
    # Last step's trajectory: a loop north from the vehicle through the block and back,
    # as a warm start grows when the block's faces were not yet mapped.
    t = np.linspace(0.0, 2.0 * np.pi, 40)
    loop = np.column_stack([2.0 + 3.0 * (1.0 - np.cos(t)) / 2.0 + 2.0 * t / np.pi,
                            -4.0 + 6.0 * np.sin(t / 2.0), np.full(len(t), -5.0)])
    assert _through_block(loop)
    for seed in range(3):
        plan = replan_section(x, waypoints, 0, faces, params, seed=seed, previous=loop)
        assert not _through_block(plan.trajectory)
        assert not _through_block(plan.initial)


def test_the_inflated_clearance_is_capped_at_the_sections():
    wall_y = 6.0
    x, z = np.meshgrid(np.arange(-10.0, 20.01, 0.5), np.arange(-3.0, 3.01, 0.5))
    wall = np.column_stack([x.ravel(), np.full(x.size, wall_y), z.ravel()])
    lane = np.column_stack([np.linspace(0.0, 10.0, 21), np.full(21, 3.0), np.zeros(21)])
    params = ReplanningParameters(clearance=4.0, current_margin_s=5.0)
    water = np.tile([0.0, 0.4, 0.0], (len(lane), 1))  # 4 + 5 x 0.4 = 6 m towards the wall
    slice_map = SliceMap(wall, (-1.0, 1.0), params.depth_band, 5.0)  # gathered to 5 m
    cost = ReplanningCost(slice_map, lane[[0, -1]], lane, params, np.zeros(len(lane), bool),
                          current=water)
    assert cost.max_clearance == 5.0
    middle = len(lane) // 2  # 3 m from the wall: (5 - 3)^2, not (6 - 3)^2
    assert cost.terms(lane[None])["obstacle"][0, middle] == pytest.approx(4.0)


def test_the_depth_reference_is_the_nominal_depth_not_the_warm_starts():
    params = ReplanningParameters()
    route = np.array([[0.0, 0.0, -5.0], [10.0, 0.0, -5.0]])
    drifted = np.column_stack([np.linspace(0.0, 10.0, 21), np.zeros(21), np.full(21, -3.0)])
    slice_map = SliceMap(np.zeros((0, 3)), (-5.0, -5.0), params.depth_band, params.clearance)
    cost = ReplanningCost(slice_map, route, drifted, params, np.zeros(21, bool))
    assert np.allclose(cost.z_ref, -5.0)
    assert np.allclose(cost.terms(drifted[None])["depth"], 4.0)
