"""The single-contour nominal path (breakwater mission) on synthetic priors."""

import numpy as np
import pytest

from drake_auv.planning.contour import nominal_contour
from drake_auv.terrain.bathymetry import Bathymetry


def _blocks(xmin: float, xmax: float, half_width: float = 2.5, cell: float = 0.5) -> Bathymetry:
    """A flat seabed at -10 m with a solid x in [xmin, xmax], |y| <= half_width, to +2 m."""
    x = np.arange(-60.0, 20.0 + cell / 2, cell)
    y = np.arange(-20.0, 20.0 + cell / 2, cell)
    gx, gy = np.meshgrid(x, y)
    solid = (gx >= xmin) & (gx <= xmax) & (np.abs(gy) <= half_width)
    return Bathymetry(np.where(solid, 2.0, -10.0), (cell, cell), (x[0], y[0]))


def _distance_to_box(points, xmin, xmax, half_width):
    dx = np.maximum.reduce([xmin - points[:, 0], points[:, 0] - xmax, np.zeros(len(points))])
    dy = np.maximum(np.abs(points[:, 1]) - half_width, 0.0)
    return np.hypot(dx, dy)


def test_closed_contour_keeps_omega_counter_clockwise():
    path = nominal_contour(_blocks(-5.0, 5.0), depth=5.0, omega=4.0, spacing=0.5)
    assert np.all(path.points[:, 2] == -5.0) and set(path.labels) == {"slice"}
    d = _distance_to_box(path.points, -5.25, 5.25, 2.75)  # the cells' faces
    np.testing.assert_allclose(d, 4.0, atol=0.35)
    assert np.max(np.linalg.norm(np.diff(path.points, axis=0), axis=1)) <= 0.5 + 1e-9
    # counter-clockwise seen from above, the sensor (to port) towards the structure
    x, y = path.points[:, 0], path.points[:, 1]
    assert np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0
    inward = -path.points[:, :2] / np.linalg.norm(path.points[:, :2], axis=1, keepdims=True)
    assert np.mean(np.sum(path.sensor_dir[:, :2] * inward, axis=1) > 0) > 0.9


def test_end_arc_around_the_last_block():
    prior = _blocks(-50.0, 2.5)  # a long row ending at x = 2.5 (+ half a cell)
    start = (0.0, -14.0, -5.0)
    path = nominal_contour(prior, 5.0, 6.0, end_width=5.0, start=start, overrun=7.0)
    np.testing.assert_array_equal(path.points[0], start)
    arc = path.points[1:]
    assert arc[:, 0].min() >= 2.75 - 12.0 - 1.0  # only the end's 5 m plus the 7 m overrun
    assert arc[:, 0].max() == pytest.approx(2.75 + 6.0, abs=0.5)
    assert arc[0, 1] < 0 < arc[-1, 1]  # south side first: counter-clockwise, structure to port
    np.testing.assert_allclose(_distance_to_box(arc, -50.25, 2.75, 2.75), 6.0, atol=0.35)
    west = nominal_contour(prior, 5.0, 6.0, end_width=5.0, end_heading=np.pi)
    assert west.points[:, 0].max() <= -50.25 + 12.0 + 1.0


def test_bad_inputs():
    prior = _blocks(-5.0, 5.0)
    with pytest.raises(ValueError, match="no structure above 5"):
        nominal_contour(prior.with_z(np.full(prior.shape, -10.0)), 5.0, 4.0)
    with pytest.raises(ValueError, match="no contour at 4"):  # the seabed is above 12 m too
        nominal_contour(prior, 12.0, 4.0)
    with pytest.raises(ValueError, match="omega must be > 0"):
        nominal_contour(prior, 5.0, 0.0)
    with pytest.raises(ValueError, match="end_width"):
        nominal_contour(prior, 5.0, 4.0, end_width=-1.0)
    with pytest.raises(ValueError, match="at 30.0 m from the structure leaves the prior map"):
        nominal_contour(prior, 5.0, 30.0)
