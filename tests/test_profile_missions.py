"""Whole profile-following missions in Drake, checked against the true world: the pool's V
profile in vertical mode (up to its far wall) and a closed loop around the boulder."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.diagrams.profile_following import build_profile_following_diagram
from drake_auv.geometry.distance import mesh_distance
from drake_auv.perception import EstimatorParams, FollowingParams
from drake_auv.scenarios import get_scenario



def _fly(world, start, mode, params, duration, **kwargs):
    diagram, handles = build_profile_following_diagram(world, start, mode, params,
                                                       **kwargs)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(duration)
    log = handles.state_log.FindLog(simulator.get_context())
    return log.sample_times(), log.data()


def test_pool_v_profile_to_the_cliff():
    world = get_scenario("pool").world
    start = np.zeros(12)
    start[:3] = (-6.0, 0.0, -3.0)  # over the shallow end, heading +x along the V
    t, x = _fly(world, start, "vertical", FollowingParams(offset=2.0, min_depth=1.0), 55.0,
                plane_yaw=0.0)
    clearance = mesh_distance(world, x[:3].T)
    assert np.all(np.abs(clearance[t > 10] - 2.0) < 0.3)
    deepest = np.argmin(x[2])
    assert abs(x[0, deepest]) < 1.5 and x[2, deepest] == pytest.approx(-5.0, abs=0.3)  # V apex
    assert x[0, -1] == pytest.approx(6.0, abs=0.2)  # 2 m from the far wall (the cliff) ...
    assert x[2, -1] > -1.5  # ... which it climbed to the depth limit


def test_boulder_closed_loop_without_contact():
    scenario = get_scenario("boulder")
    target = scenario.world.vertices[scenario.world.faces[scenario.target_faces]].reshape(-1, 3)
    centre = target.mean(axis=0)
    start = np.zeros(12)
    start[:3] = (centre[0] - 16.0, centre[1], -34.0)
    params = FollowingParams(offset=3.0, speed=0.5, estimator=EstimatorParams(window=6.0))
    t, x = _fly(scenario.world, start, "horizontal", params, 180.0)
    angle = np.unwrap(np.arctan2(x[1] - centre[1], x[0] - centre[0]))
    assert abs(angle[-1] - angle[0]) > 2 * np.pi  # closed the loop
    clearance = mesh_distance(scenario.world, x[:3].T)
    assert clearance.min() > 2.0  # the vehicle's radius is 1 m
    assert np.abs(clearance[t > 30] - 3.0).mean() < 0.3
    assert np.all(np.abs(x[2] + 34.0) < 0.15)  # constant depth
