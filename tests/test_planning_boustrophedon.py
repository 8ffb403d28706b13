"""Boustrophedon decomposition, adjacency graph, exhaustive walk and lanes."""

import numpy as np
import pytest

from drake_auv.planning.boustrophedon import (best_sweep_angle, boustrophedon_waypoints,
                                              cell_lanes, column_runs, decompose, exhaustive_walk)
from drake_auv.terrain.bathymetry import Bathymetry


def _square_with_hole():
    """40 m x 40 m at 1 m cells with a 10 m x 10 m obstacle in the middle."""
    bathy = Bathymetry(np.zeros((41, 41)) - 20.0, (1.0, 1.0))
    free = np.ones(bathy.shape, dtype=bool)
    free[15:26, 15:26] = False
    return bathy, free


def test_column_runs():
    mask = np.array([[1, 0], [1, 1], [0, 1], [1, 1]], dtype=bool)
    cols, lo, hi = column_runs(mask)
    np.testing.assert_array_equal(cols, [0, 0, 1])
    np.testing.assert_array_equal(lo, [0, 3, 1])
    np.testing.assert_array_equal(hi, [2, 4, 4])


def test_obstacle_splits_free_space_into_four_cells():
    bathy, free = _square_with_hole()
    dec = decompose(bathy, free, angle=np.pi / 2)  # lanes along y, the sweep moves along x
    assert len(dec.cells) == 4
    sizes = sorted(c.area_cells for c in dec.cells)
    # Left and right of the obstacle: 15 x 41 each; below and above it: 11 x 15 each.
    assert sizes == [165, 165, 615, 615]
    degree = np.bincount(dec.edges.ravel(), minlength=4)
    assert sorted(degree.tolist()) == [2, 2, 2, 2]  # a cycle: left-below-right-above
    assert sum(c.area_cells for c in dec.cells) == free.sum()
    order = exhaustive_walk(dec.adjacency(), np.array([c.centroid(dec.frame) for c in dec.cells]))
    assert sorted(order) == [0, 1, 2, 3]
    for a, b in zip(order[:-1], order[1:]):  # on a cycle every step is along an edge
        assert (min(a, b), max(a, b)) in {tuple(e) for e in dec.edges.tolist()}


def test_free_space_without_obstacle_is_one_cell_at_any_angle():
    bathy = Bathymetry(np.zeros((21, 31)), (1.0, 1.0))
    for angle in np.radians([0.0, 30.0, 90.0, 135.0]):
        dec = decompose(bathy, np.ones(bathy.shape, bool), angle)
        assert len(dec.cells) == 1 and len(dec.edges) == 0


def test_walk_visits_disconnected_components():
    adjacency = [[1], [0], [3], [2], []]
    positions = np.array([[0, 0], [1, 0], [10, 0], [11, 0], [5, 0]], dtype=float)
    order = exhaustive_walk(adjacency, positions, 0)
    assert sorted(order) == [0, 1, 2, 3, 4] and order[:2] == [0, 1]


def test_lanes_are_spaced_by_at_most_the_lane_spacing_and_span_the_cell():
    bathy = Bathymetry(np.zeros((21, 41)), (0.5, 0.5))  # 20 m x 10 m
    dec = decompose(bathy, np.ones(bathy.shape, bool), angle=0.0)  # lanes along x
    lanes = cell_lanes(dec.cells[0], dec.frame, 2.0)
    width = 10.5  # 21 raster columns of 0.5 m
    assert len(lanes) == int(np.ceil(width / 2.0))
    assert np.all(np.diff(lanes[:, 0]) <= 2.0 + 1e-9)
    np.testing.assert_allclose(lanes[:, 1:], np.tile([0.0, 20.0], (len(lanes), 1)))
    wp = boustrophedon_waypoints(lanes, dec.frame, start_xy=np.array([20.0, 10.0]))
    np.testing.assert_allclose(wp[0], [20.0, lanes[-1, 0]])  # nearest corner first
    # Back and forth: consecutive lanes in opposite directions.
    d = np.diff(wp[:, 0])[::2]
    assert np.all(d[:-1] * d[1:] < 0)


def test_best_sweep_angle_runs_lanes_along_the_long_side():
    bathy = Bathymetry(np.zeros((201, 41)), (0.5, 0.5))  # 20 m wide, 100 m long in y
    angle = best_sweep_angle(bathy, np.ones(bathy.shape, bool), 2.0)
    assert angle == pytest.approx(np.pi / 2)
    bathy = Bathymetry(np.zeros((41, 201)), (0.5, 0.5))
    assert best_sweep_angle(bathy, np.ones(bathy.shape, bool), 2.0) == pytest.approx(0.0)
