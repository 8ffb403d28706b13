"""Navigation in a current: the DVL tracks the bottom within its range and the water beyond it,
where dead reckoning drifts with the current it cannot see."""

import numpy as np
import pytest
import trimesh
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource

from drake_auv.geometry.raycast import RayCaster
from drake_auv.signals import NavigationError
from drake_auv.sonar.altimeter import DvlAltimeter
from drake_auv.vehicle.dynamics import Girona500Dynamics
from drake_auv.vehicle.navigation import ERROR_SIZE, NavigationParams, update_error
from drake_auv.vehicle.navigation_system import Navigation

WATER = np.array([0.3, -0.2, 0.0, 0.0, 0.0, 0.0])


def _walk(params, water, lock, seconds=100.0, velocity=(0.5, 0.0)):
    """Updates along a straight line at `velocity` (m/s) for `seconds`."""
    error, state = np.zeros(ERROR_SIZE), np.zeros(12)
    for k in range(round(seconds / params.period) + 1):
        state[:2] = np.multiply(velocity, k * params.period)
        error = update_error(params, error, state, water, lock)
    return NavigationError(error), state


def test_bottom_tracking_ignores_the_water():
    params = NavigationParams(heading_bias=np.radians(1.0), scale_error=0.01,
                              random_walk=0.02, seed=5)
    still, _ = _walk(params, None, True)
    locked, _ = _walk(params, WATER, True)
    np.testing.assert_array_equal(still[:], locked[:])  # bit for bit the model without water
    assert locked.water_tracking == 0.0 and np.all(locked.current_drift == 0.0)


def test_water_tracking_drifts_with_the_current():
    """Through the water the DVL measures dp - v_c dt: the estimate misses what the current
    carried, -v_c t, and the scale and bias act on the displacement through the water."""
    params = NavigationParams(heading_bias=np.radians(1.0), scale_error=0.01, seed=5)
    error, state = _walk(params, WATER, False)
    seconds = 100.0
    np.testing.assert_allclose(error.current_drift, -WATER[:2] * seconds, rtol=1e-9)
    b, k = np.radians(1.0), 1.01
    rot = k * np.array([[np.cos(b), -np.sin(b)], [np.sin(b), np.cos(b)]])
    through_water = state[:2] - WATER[:2] * seconds
    np.testing.assert_allclose(error.drift, rot @ through_water - state[:2], rtol=1e-9)
    assert error.water_tracking == 1.0
    # a vehicle carried by the water at its speed measures no motion at all: drift = -travel
    error, state = _walk(params, WATER, False, velocity=WATER[:2])
    np.testing.assert_allclose(error.drift, -state[:2], atol=1e-9)


def _seabed(depth):
    half = 500.0
    v = np.array([[x, y, depth] for y in (-half, half) for x in (-half, half)])
    return RayCaster(trimesh.Trimesh(v, [[0, 1, 3], [0, 3, 2]], process=False))


@pytest.mark.parametrize("seabed,tracking", [(-40.0, 0.0), (-110.0, 1.0)])
def test_dvl_lock_switches_the_navigation_mode(seabed, tracking):
    """A drifting vehicle 10 m deep: over a seabed 30 m below the DVL tracks the bottom; 100 m
    below (beyond its 80 m) the water, and the estimate lags what the current carried."""
    builder = DiagramBuilder()
    x0 = np.zeros(12)
    x0[2] = -10.0
    plant = builder.AddSystem(Girona500Dynamics(initial_state=x0))
    nav = builder.AddSystem(Navigation(NavigationParams(scale_error=0.01)))
    dvl = builder.AddSystem(DvlAltimeter(_seabed(seabed), noise=False))
    water = builder.AddSystem(ConstantVectorSource(WATER))
    thrust = builder.AddSystem(ConstantVectorSource(np.zeros(5)))
    builder.Connect(thrust.get_output_port(), plant.thrust_input)
    for port in (plant.water_input, nav.water_input):
        builder.Connect(water.get_output_port(), port)
    builder.Connect(plant.state_output, nav.true_state_input)
    builder.Connect(plant.state_output, dvl.true_state_input)
    builder.Connect(nav.estimated_state_output, dvl.estimated_state_input)
    builder.Connect(dvl.bottom_lock_output, nav.bottom_lock_input)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(60.0)
    context = simulator.get_context()
    nav_context = nav.GetMyContextFromRoot(context)
    assert dvl.bottom_lock_output.Eval(dvl.GetMyContextFromRoot(context))[0] == 1.0 - tracking
    assert nav.water_tracking_output.Eval(nav_context)[0] == tracking
    true = plant.state_output.Eval(plant.GetMyContextFromRoot(context))
    estimated = nav.estimated_state_output.Eval(nav_context)
    current_drift = nav.current_drift_output.Eval(nav_context)
    travelled = true[:2] - x0[:2]
    assert np.linalg.norm(travelled) > 10.0  # the current carried it
    if tracking:
        # updates at 0, 0.1, .. 59.9 s; the first measures no displacement
        np.testing.assert_allclose(current_drift, -WATER[:2] * 59.9, rtol=1e-9)
        np.testing.assert_allclose(estimated[:2] - true[:2],
                                   1.01 * (travelled + current_drift) - travelled, atol=0.02)
    else:
        np.testing.assert_array_equal(current_drift, [0.0, 0.0])
        # (the last update was 0.1 s ago: the vehicle has moved 3 cm since)
        np.testing.assert_allclose(estimated[:2] - true[:2], 0.01 * travelled, atol=1e-3)
