"""The vehicle in a Drake Diagram: wiring, lawnmower tracking bounds, navigation drift."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from drake_auv.vehicle.control import cross_track_distance, wrap_angle
from drake_auv.vehicle.diagram import add_girona500, build_tracking_diagram
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.planning import PlannedPath

SPEED = 0.5


def lawnmower(length=50.0, spacing=5.0, lanes=5, depth=-10.0, heading=None):
    points = []
    for i in range(lanes):
        xs = (0.0, length) if i % 2 == 0 else (length, 0.0)
        points += [(xs[0], i * spacing, depth), (xs[1], i * spacing, depth)]
    heading = 0.0 if heading is None else heading
    return PlannedPath(np.array(points), heading, (0.0, 0.0, -1.0), "planar")


def fly(path, **kwargs):
    diagram, handles = build_tracking_diagram(path, speed=SPEED, **kwargs)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(handles.end_time + 10.0)
    context = simulator.get_context()
    state = handles.state_log.FindLog(context)
    reference = handles.reference_log.FindLog(context)
    return handles, state.sample_times(), state.data(), reference.data(), diagram, context


def test_add_girona500_names_and_leaves_reference_free():
    builder = DiagramBuilder()
    vehicle = add_girona500(builder)
    names = {s.get_name() for s in (vehicle.dynamics, vehicle.navigation, vehicle.tracker,
                                    vehicle.allocation)}
    assert names == {"dynamics", "navigation", "tracker", "allocation"}
    builder.ExportInput(vehicle.tracker.reference_input, "reference")
    diagram = builder.Build()
    assert diagram.get_input_port(0).get_name() == "reference"
    assert diagram.get_input_port(0).size() == 8


def test_lawnmower_tracking_bounds():
    path = lawnmower()
    handles, t, x, ref, *_ = fly(path.resample(1.0))
    first_lane_end = path.times(SPEED)[1]
    after = t > first_lane_end
    xte = cross_track_distance(x[:3, after].T, path.points)
    rms, peak = np.sqrt(np.mean(xte ** 2)), xte.max()
    assert rms < 0.3 and peak < 1.0, (rms, peak)
    # It flew the whole path: ends at the last sample, at rest.
    np.testing.assert_allclose(x[:3, -1], path.points[-1], atol=0.05)
    assert np.linalg.norm(x[6:9, -1]) < 0.02
    # Roll and pitch stay small (passively stable) while surveying.
    assert np.abs(x[3:5]).max() < np.radians(5)


def test_heading_is_held_independently_of_motion():
    path = lawnmower(lanes=3, heading=np.pi / 2)  # face +y while moving along x
    _, t, x, _, *_ = fly(path.resample(1.0))
    moving = (t > 10.0) & (np.linalg.norm(x[6:9], axis=0) > 0.3)
    assert moving.sum() > 100
    assert np.abs(wrap_angle(x[5, moving] - np.pi / 2)).max() < np.radians(2)
    # Moving along world x while facing +y means mostly sway in the body frame.
    assert np.median(np.abs(x[7, moving])) > 0.4
    xte = cross_track_distance(x[:3, t > path.times(SPEED)[1]].T, path.points)
    assert np.sqrt(np.mean(xte ** 2)) < 0.3


def test_navigation_drift_is_seeded_and_followed():
    path = PlannedPath(np.array([(0.0, 0.0, -10.0), (100.0, 0.0, -10.0)]), 0.0, (0.0, 0.0, -1.0))
    nav = NavigationParams(heading_bias=np.radians(1.0), random_walk=0.02, position_noise=0.05,
                           seed=7)
    runs = [fly(path.resample(1.0), navigation=nav) for _ in range(2)]
    np.testing.assert_array_equal(runs[0][2], runs[1][2])  # same seed, same run
    handles, t, x, _, diagram, context = runs[0]
    nav_system = handles.vehicle.navigation
    drift = nav_system.drift(nav_system.GetMyContextFromRoot(context))
    # The compass bias alone drifts 100 m * sin(1 deg) = 1.75 m across track (to the left);
    # the random walk adds about 0.02 sqrt(100) = 0.2 m.
    assert drift[1] == pytest.approx(100.0 * np.sin(np.radians(1.0)), abs=0.6)
    assert abs(drift[0]) < 0.6
    # The vehicle tracks its *estimate*: the true end point is off by the drift.
    assert np.linalg.norm(x[:2, -1] - path.points[-1, :2]) == pytest.approx(
        np.linalg.norm(drift), abs=0.2)
    other = fly(path.resample(1.0), navigation=NavigationParams(
        heading_bias=np.radians(1.0), random_walk=0.02, position_noise=0.05, seed=8))
    assert not np.array_equal(other[2], runs[0][2])


def test_exported_ports():
    diagram, _ = build_tracking_diagram(lawnmower(lanes=1))
    assert diagram.GetOutputPort("state").size() == 12
    assert diagram.GetOutputPort("estimated_state").size() == 12
    with pytest.raises(ValueError, match="log_period"):
        build_tracking_diagram(lawnmower(lanes=1), log_period=0.0)


def test_heading_step_settles_without_overshoot():
    # A 90 degree heading step held in place: the yaw loop keeps the vehicle's own damping
    # (fed forward on the reference rate), so the lagged thrusters do not make it overshoot.
    from pydrake.systems.primitives import ConstantVectorSource

    builder = DiagramBuilder()
    vehicle = add_girona500(builder)
    step = builder.AddSystem(ConstantVectorSource(np.array([0, 0, 0, np.pi / 2, 0, 0, 0, 0.0])))
    builder.Connect(step.get_output_port(), vehicle.tracker.reference_input)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    context = vehicle.dynamics.GetMyContextFromRoot(simulator.get_context())
    yaw = []
    for t in np.arange(0.5, 20.0, 0.5):
        simulator.AdvanceTo(t)
        yaw.append(vehicle.dynamics.state_output.Eval(context)[5])
    yaw = np.degrees(yaw)
    assert yaw.max() < 92.0  # the earlier law overshot to 118 degrees
    assert abs(yaw[-1] - 90.0) < 0.5
    assert np.argmax(yaw > 85.5) * 0.5 < 7.0  # within 5 % in under 7 s
