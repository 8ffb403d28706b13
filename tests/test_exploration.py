"""On-line view planning, the pure parts: frontiers, viewpoints, gains, the travel field, one
planning step (no Drake)."""

from __future__ import annotations

import numpy as np
import pytest

from drake_auv.exploration.frontiers import (FREE, OCCUPIED, UNKNOWN, LabelGrid,
                                             candidate_viewpoints, cluster_frontiers,
                                             frontier_cells, multibeam_returns, scan_rays)
from drake_auv.exploration.gains import fan_rays, scores, view_gains
from drake_auv.exploration.paths import PathCost, TravelField, plan_path
from drake_auv.exploration.planner import ExploreParameters, plan_view
from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mapping.scan_log import ScanBatch

PORT_TO_PLUS_X = -np.pi / 2  # yaw that turns a port-looking sensor to +x


def wall_grid() -> LabelGrid:
    """10^3 cells of 1 m: free water for x < 5, a seen wall patch at x = 5 (y, z in [2, 8)),
    the rest unknown; the region is the whole grid, placed deep (z from -20 m)."""
    labels = np.full((10, 10, 10), UNKNOWN, np.int8)
    labels[:5] = FREE
    labels[5, 2:8, 2:8] = OCCUPIED
    return LabelGrid(np.array([0.0, 0.0, -20.0]), 1.0, labels,
                     np.array([0.0, 0.0, -20.0, 10.0, 10.0, -10.0]))


def cells_of(grid, centres) -> set:
    return {tuple(i) for i in grid.index(centres)[0].tolist()}


def test_surface_frontier_is_the_edge_of_the_seen_wall():
    grid = wall_grid()
    frontiers = frontier_cells(grid)
    surface = cells_of(grid, frontiers.centres[frontiers.kinds == 0])
    ring = {(5, j, k) for j in range(2, 8) for k in range(2, 8)
            if j in (2, 7) or k in (2, 7)}
    assert surface == ring  # the wall's inside (next to the rock's unseen interior) is not
    boundary = cells_of(grid, frontiers.centres[frontiers.kinds == 1])
    assert (4, 0, 0) in boundary and (4, 9, 5) in boundary  # free next to unknown
    assert (2, 5, 5) not in boundary and (4, 5, 5) not in boundary
    # the view direction at an edge points into the wall (+x) and past the edge (+y)
    edge = np.flatnonzero((frontiers.kinds == 0)
                          & np.all(np.isclose(frontiers.centres, [5.5, 2.5, -14.5]), axis=1))
    d = frontiers.directions[edge[0]]
    assert d[0] > 0.8 and d[1] > 0.1 and abs(d[2]) < 1e-9


def test_rock_no_multibeam_return_has_seen_from_the_water_is_a_surface_frontier():
    """The wall's middle, mapped but its water side (-x face) seen by no multibeam return
    (only the profiler or the DVL mapped it, or returns from above), is still to be looked
    at: a surface frontier."""
    grid = wall_grid()
    seen = np.repeat((grid.labels == OCCUPIED)[..., None], 6, axis=-1)
    seen[5, 4:6, 4:6, 1] = False  # the -x faces (on the water) of four middle cells
    unseen = LabelGrid(grid.origin, grid.cell, grid.labels, grid.region, seen)
    before = cells_of(grid, frontier_cells(grid).centres[frontier_cells(grid).kinds == 0])
    after = cells_of(unseen, frontier_cells(unseen).centres[frontier_cells(unseen).kinds == 0])
    assert after - before == {(5, j, k) for j in (4, 5) for k in (4, 5)}
    seen[5, 4:6, 4:6, 1], seen[5, 4:6, 4:6, 4] = True, False  # +z faces: on rock, not water
    assert cells_of(unseen, frontier_cells(unseen).centres[
        frontier_cells(unseen).kinds == 0]) == before
    # the multibeam returns of a scan mark the faces their beams look at on the next grid
    m = OctreeMap(0.5)
    batches = scanned_wall(m, np.arange(-3.0, 3.0, 0.25))
    region = (-2.0, -6.0, -20.0, 2.0, 6.0, -10.0)
    first = LabelGrid.from_map(m, region, 8.0, 1.0)
    assert first.seen is None  # no history: what is occupied counts as seen
    points, directions = multibeam_returns(batches)
    assert len(points) == len(directions) > 0
    grid = LabelGrid.from_map(m, region, 8.0, 1.0, previous=first, rays=scan_rays([], 1.0),
                              returns=(points, directions))
    cells, inside = grid.index(points)
    level = inside & (np.abs(directions[:, 2]) < 0.5)  # beams within 60 deg of +x
    assert grid.seen[(*cells[level].T, 1)].all() and level.any()  # their -x faces
    fresh = LabelGrid.from_map(m, region, 8.0, 1.0, previous=grid, rays=scan_rays([], 1.0),
                               returns=(points[:1], np.array([[0.0, 0.0, -1.0]])))
    assert fresh.seen[(*grid.index(points[:1])[0][0], 4)]  # a beam from above: the top face
    profiler = [ScanBatch.make(0.0, "profiler", b.origin, b.directions, b.ranges, 20.0)
                for b in batches]
    assert len(multibeam_returns(profiler)[0]) == 0


def test_viewpoints_sit_omega_back_in_free_water():
    grid = wall_grid()
    clusters = cluster_frontiers(frontier_cells(grid), 4.0)
    cands = candidate_viewpoints(grid, clusters, omega=4.0, clearance=2.0,
                                 unknown_clearance=1.0)
    assert len(cands.positions) > 0
    back = cands.targets - cands.positions
    # omega back along the view, or that view's horizontal offset at the nearest admissible
    # height (the floor's clearance, z = -1 m)
    moved = (np.isclose(cands.positions[:, 2], grid.region[2] + 2.0)
             | np.isclose(cands.positions[:, 2], -1.0))
    assert np.allclose(np.linalg.norm(back[~moved], axis=1), 4.0) and (~moved).sum() > 0
    assert np.all(np.linalg.norm(back[moved, :2], axis=1) <= 4.0 + 1e-9)
    idx, inside = grid.index(cands.positions)
    assert inside.all() and np.all(grid.labels[tuple(idx.T)] == FREE)
    # none within the clearance of the wall, none outside the region widened by omega
    wall = grid.centres(np.argwhere(grid.labels == OCCUPIED))
    assert np.linalg.norm(cands.positions[:, None] - wall[None], axis=2).min() >= 2.0 - 1e-9
    assert np.all(cands.positions[:, 2] < -1.0)


def test_gain_facing_unknown_water_beats_facing_known_water():
    labels = np.full((20, 20, 20), FREE, np.int8)
    labels[12:] = UNKNOWN
    grid = LabelGrid(np.array([0.0, 0.0, -30.0]), 1.0, labels,
                     np.array([0.0, 0.0, -30.0, 20.0, 20.0, -10.0]))
    position = np.array([[8.0, 10.0, -20.0]] * 2)
    rays = fan_rays("port", [PORT_TO_PLUS_X, -PORT_TO_PLUS_X])
    gains = view_gains(grid, position, rays, max_range=15.0)
    assert gains[0] > 20.0 and gains[1] == 0.0
    # a wall in front of the unknown hides it
    labels[10] = OCCUPIED
    assert view_gains(grid, position[:1], rays[:1], 15.0)[0] == 0.0


def test_scores_of_the_strategies():
    gains, distance = np.array([10.0, 30.0]), np.array([2.0, 40.0])
    assert np.argmax(scores("gain", gains, distance, 0.5, 0.1, 0)) == 1
    assert np.argmax(scores("gain", gains, distance, 0.5, 1.0, 0)) == 0  # travel too dear
    assert np.argmax(scores("nearest", gains, distance, 0.5, 0.1, 0)) == 0
    a, b = (scores("random", gains, distance, 0.5, 0.1, s) for s in (3, 3))
    assert np.array_equal(a, b)
    with pytest.raises(ValueError, match="strategy must be one of"):
        scores("greedy", gains, distance, 0.5, 0.1, 0)


def test_travel_goes_round_rock_and_keeps_clear():
    labels = np.full((30, 30, 12), FREE, np.int8)
    labels[14:16, :24, :] = OCCUPIED  # a wall across x, open for y >= 24
    grid = LabelGrid(np.array([0.0, 0.0, -20.0]), 1.0, labels,
                     np.array([0.0, 0.0, -20.0, 30.0, 30.0, -8.0]))
    cost = PathCost(grid, clearance=2.0)
    assert cost.blocked[5, 5, 5] == 9.0 and cost.blocked[14, 5, 5] == 0.0  # m to the rock
    start, goal = np.array([5.5, 5.5, -14.5]), np.array([25.5, 5.5, -14.5])
    travel = TravelField.build(cost, start)
    assert travel.lengths(goal[None])[0] > 2.0 * np.linalg.norm(goal - start)
    path = plan_path(travel, goal)
    assert path is not None and np.allclose(path[0], start) and np.allclose(path[-1], goal)
    rock, _ = cost.distances(path)
    assert rock.min() >= 1.0
    labels[15, 24:, :] = UNKNOWN  # a sheet of the gap unseen, between known water: crossed
    thin = TravelField.build(PathCost(grid, 2.0), start)
    assert np.isfinite(thin.lengths(goal[None])[0])
    labels[8:22, 24:, :] = UNKNOWN  # unseen water away from any known water: not crossed
    unseen = TravelField.build(PathCost(grid, 2.0), start)
    assert not np.isfinite(unseen.lengths(goal[None])[0])
    labels[8:22, 24:, :] = FREE
    labels[12:15, 24:, :] = UNKNOWN  # unseen water next to known water only: not crossed
    assert not np.isfinite(TravelField.build(PathCost(grid, 2.0), start).lengths(goal[None])[0])
    labels[14:16, 24:, :] = OCCUPIED  # closed: unreachable
    closed = TravelField.build(PathCost(grid, 2.0), start)
    assert not np.isfinite(closed.lengths(goal[None])[0])
    assert plan_path(closed, goal) is None


def scanned_wall(m: OctreeMap, ys) -> list:
    """Port-fan pings from x = -10 along y at `ys` towards a wall x = 0 (y, z in [-4, 4] about
    z = -15), inserted into `m`; returns their batches."""
    batches = []
    for y in ys:
        origin = np.array([-10.0, y, -15.0])
        d = fan_rays("port", [PORT_TO_PLUS_X], beams=121, sweeps=1)[0]
        t = -origin[0] / np.maximum(d[:, 0], 1e-9)
        hit_point = origin + d * t[:, None]
        on_wall = (d[:, 0] > 1e-3) & (np.abs(hit_point[:, 1]) <= 4) & (
            np.abs(hit_point[:, 2] + 15) <= 4) & (t <= 20.0)
        ranges = np.where(on_wall, t, np.nan)
        m.insert_scan(origin, d, ranges, 20.0)
        batches.append(ScanBatch.make(0.0, "multibeam", origin, d, ranges, 20.0))
    return batches


def test_a_vehicle_nearer_rock_than_the_keep_out_finds_its_way_out():
    labels = np.full((30, 30, 12), FREE, np.int8)
    labels[14:16, :, :] = OCCUPIED  # a wall across x
    grid = LabelGrid(np.array([0.0, 0.0, -20.0]), 1.0, labels,
                     np.array([0.0, 0.0, -20.0, 30.0, 30.0, -8.0]))
    cost = PathCost(grid, clearance=3.0)  # keep-out: 3 m from rock cell centres (KEEP)
    start, goal = np.array([13.6, 15.5, -14.5]), np.array([5.5, 15.5, -14.5])
    assert cost.distances(start)[0] == 1.0  # the vehicle's cell is 1 m from the wall
    travel = TravelField.build(cost, start)
    path = plan_path(travel, goal)
    assert path is not None and np.isfinite(travel.lengths(goal[None])[0])
    rock, _ = cost.distances(path[1:])
    assert rock.min() >= 1.0  # never nearer than it started
    assert np.all(rock[np.linalg.norm(path[1:] - start, axis=1) > 3.0] >= 3.0)
    # no way out that does not come nearer: stays unreachable
    labels[:, :, :] = OCCUPIED
    labels[13, 15, 5] = FREE
    shut = TravelField.build(PathCost(grid, 3.0), start)
    assert not np.isfinite(shut.lengths(goal[None])[0])


def test_label_grid_refreshed_by_the_new_rays_equals_a_full_read():
    m = OctreeMap(0.5)
    scanned_wall(m, np.arange(-3.0, 0.0, 0.25))
    region = (-2.0, -6.0, -20.0, 2.0, 6.0, -10.0)
    first = LabelGrid.from_map(m, region, 8.0, 1.0)
    assert np.any(first.labels == OCCUPIED) and np.any(first.labels == FREE)
    batches = scanned_wall(m, np.arange(0.0, 3.0, 0.25))
    again = LabelGrid.from_map(m, region, 8.0, 1.0, previous=first,
                               rays=scan_rays(batches, 1.0))
    full = LabelGrid.from_map(m, region, 8.0, 1.0)
    assert np.array_equal(again.labels, full.labels)
    assert not np.array_equal(first.labels, full.labels)


def test_plan_view_chooses_a_reachable_view_of_the_wall():
    m = OctreeMap(0.5)
    scanned_wall(m, np.arange(-3.0, 3.0, 0.25))
    params = ExploreParameters(region=(-2.0, -8.0, -22.0, 3.0, 8.0, -8.0), omega=6.0,
                               clearance=3.0, min_gain_m2=2.0)
    position = np.array([-10.0, 0.0, -15.0])
    step = plan_view(m, position, params, None, seed=0)
    assert step.target is not None and step.gain_m2 >= 2.0 and not step.no_gain
    assert np.allclose(step.path[0], position) and np.allclose(step.path[-1],
                                                                step.target.position)
    assert np.linalg.norm(m.occupied_points()[:, None] - step.path[None], axis=2).min() > 1.4
    assert 0.0 < step.believed_coverage < 1.0
    # the same map and target a step later: kept, no new path
    kept = plan_view(m, position, params, step.target, seed=1, previous=step.grid)
    assert kept.target is step.target and kept.path is None
    # frontiers, but no view left to take (every one within 3 m of a view already reached):
    # a turn in place, which sweeps the fan over what else is there, not the end
    visited = np.stack(np.meshgrid(np.arange(-16.0, 12.0, 2.0), np.arange(-16.0, 16.0, 2.0),
                                   np.arange(-24.0, -4.0, 2.0)), axis=-1).reshape(-1, 3)
    turn = plan_view(m, position, params, None, seed=0, visited=visited)
    assert turn.frontier_cells > 0 and turn.candidates == 0
    assert turn.turning and turn.target.look_around and turn.no_gain


def test_explore_parameters_name_what_is_wrong():
    with pytest.raises(ValueError, match=r"omega \(3.0 m\) must be above the clearance"):
        ExploreParameters(region=(0, 0, -10, 1, 1, -5), omega=3.0, clearance=3.0)
    with pytest.raises(ValueError, match="min >= max"):
        ExploreParameters(region=(0, 0, -5, 1, 1, -10))
    with pytest.raises(ValueError, match="ExploreParameters.strategy = .best. is not allowed"):
        ExploreParameters(region=(0, 0, -10, 1, 1, -5), strategy="best")
    with pytest.raises(ValueError, match=r"ExploreParameters.cell_m = 9 is out of range"):
        ExploreParameters(region=(0, 0, -10, 1, 1, -5), cell_m=9)
