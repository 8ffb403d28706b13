"""The polyline module: arc length, and projection onto a 3D polyline (what the replanner's
progress and route terms and its waypoint bookkeeping read)."""

import numpy as np
import pytest

from drake_auv.planning.path import PlannedPath
from drake_auv.planning.polyline import Polyline, arc_length, length, project, resample

L_SHAPE = np.array([[0.0, 0.0, -5.0], [4.0, 0.0, -5.0], [4.0, 3.0, -5.0]])


def test_arc_length_is_the_cumulative_distance():
    assert np.allclose(arc_length(L_SHAPE), [0.0, 4.0, 7.0])
    assert arc_length(L_SHAPE[:1]).tolist() == [0.0]
    assert length(L_SHAPE) == pytest.approx(7.0)
    path = PlannedPath(L_SHAPE, 0.0, (0, 0, -1))
    assert np.array_equal(path.arc_length(), arc_length(L_SHAPE))
    assert np.allclose(arc_length(resample(L_SHAPE, 0.5)), np.linspace(0.0, 7.0, 15))


def test_project_gives_arclength_and_distance_of_the_nearest_point():
    points = np.array([[2.0, 1.0, -5.0],    # above the first leg: s = 2, 1 m off
                       [5.0, 2.0, -5.0],    # beside the second: s = 4 + 2, 1 m off
                       [-3.0, 0.0, -1.0],   # before the start: clamped to s = 0
                       [4.0, 9.0, -5.0]])   # beyond the end: clamped to s = 7
    s, d = project(points, L_SHAPE)
    assert np.allclose(s, [2.0, 6.0, 0.0, 7.0])
    assert np.allclose(d, [1.0, 1.0, 5.0, 6.0])
    batch = np.stack([points, points + [0.0, 0.0, 0.0]])  # (2, 4, 3) rollouts at once
    s2, d2 = Polyline(L_SHAPE).project(batch)
    assert s2.shape == (2, 4) and np.allclose(s2[1], s) and np.allclose(d2[0], d)
    assert Polyline(L_SHAPE).length == pytest.approx(7.0)
    assert np.array_equal(Polyline(L_SHAPE).arclength(batch), s2)  # the same numbers, no d
