"""Each vehicle LeafSystem as a thin adapter: ports, and outputs that match the pure model."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.vehicle.control import TrackingController, TrackingGains, cross_track_distance
from drake_auv.vehicle.navigation import NavigationParams, estimate, update_error, ERROR_SIZE
from drake_auv.vehicle.dynamics import Girona500Dynamics
from drake_auv.vehicle.navigation_system import Navigation
from drake_auv.vehicle.thrusters import ThrusterAllocation
from drake_auv.vehicle.tracker import TrajectoryTracker
from drake_auv.vehicle.model import WRENCH_ROWS, Girona500Model, Girona500Params


def test_dynamics_system_steps_the_model():
    x0 = np.zeros(12)
    x0[:3] = [1.0, 2.0, -5.0]
    plant = Girona500Dynamics(time_step=0.05, initial_state=x0)
    assert plant.thrust_input.get_name() == "thrust" and plant.state_output.size() == 12
    simulator = Simulator(plant)
    context = simulator.get_mutable_context()
    command = np.array([100.0, 80.0, 20.0, 20.0, -30.0])
    plant.thrust_input.FixValue(context, command)
    simulator.AdvanceTo(2.0)
    model, x = Girona500Model(), np.concatenate([x0, np.zeros(5)])
    for _ in range(40):
        x = model.step(x, command, 0.05)
    np.testing.assert_allclose(plant.state_output.Eval(context), x[:12], atol=1e-12)
    pose = plant.pose_output.Eval(context)
    np.testing.assert_allclose(pose.translation(), x[:3], atol=1e-12)
    with pytest.raises(ValueError, match="time_step"):
        Girona500Dynamics(time_step=1.0)
    with pytest.raises(ValueError, match="initial_state"):
        Girona500Dynamics(initial_state=[0.0, np.nan])


def test_allocation_system_matches_configuration_matrix():
    alloc = ThrusterAllocation()
    context = alloc.CreateDefaultContext()
    wrench = np.array([60.0, -20.0, 35.0, 5.0])
    alloc.wrench_input.FixValue(context, wrench)
    thrust = alloc.thrust_output.Eval(context)
    B4 = Girona500Params().thruster_configuration_matrix()[list(WRENCH_ROWS)]
    np.testing.assert_allclose(B4 @ thrust, wrench, atol=1e-9)


def test_exact_navigation_passes_the_state_through():
    nav = Navigation()
    context = nav.CreateDefaultContext()
    state = np.arange(12.0) * 0.1
    nav.true_state_input.FixValue(context, state)
    np.testing.assert_array_equal(nav.estimated_state_output.Eval(context), state)


def test_navigation_error_model_is_seeded_and_linear_in_distance():
    params = NavigationParams(heading_bias=np.radians(2.0), scale_error=0.01, seed=3)
    error = np.zeros(ERROR_SIZE)
    state = np.zeros(12)
    for x in np.linspace(0.0, 200.0, 401):
        state[0] = x
        error = update_error(params, error, state)
    # Compass bias and scale factor only: drift = ((1 + s) Rz(b) - I) dp exactly.
    b = np.radians(2.0)
    np.testing.assert_allclose(error[:2], [200 * (1.01 * np.cos(b) - 1), 200 * 1.01 * np.sin(b)],
                               atol=1e-9)
    est = estimate(params, error, state)
    assert est[5] == pytest.approx(b)
    noisy = NavigationParams(random_walk=0.05, position_noise=0.1, seed=3)
    a = update_error(noisy, update_error(noisy, np.zeros(ERROR_SIZE), state), state + 1)
    b2 = update_error(noisy, update_error(noisy, np.zeros(ERROR_SIZE), state), state + 1)
    np.testing.assert_array_equal(a, b2)
    assert np.all(a[2:4] != 0)


@pytest.mark.parametrize("field,value", [("heading_bias", 2.0), ("position_noise", -0.1),
                                         ("period", 0.0), ("random_walk", float("nan")),
                                         ("seed", -1)])
def test_navigation_params_out_of_range(field, value):
    with pytest.raises(ValueError, match=field):
        NavigationParams(**{field: value})


def test_tracker_gains_validated_and_buoyancy_compensated():
    with pytest.raises(ValueError, match="kd"):
        TrackingGains(kd=-1.0)
    with pytest.raises(ValueError, match="ki"):
        TrackingGains(kp=0.1, kd=0.1, ki=0.5)
    params = Girona500Params(buoyancy_ratio=1.02)
    wrench, _ = TrackingController(params).wrench(np.zeros(8), np.zeros(12), np.zeros(3), 0.05)
    np.testing.assert_allclose(wrench, [0, 0, -0.02 * params.weight, 0], atol=1e-9)
    tracker = TrajectoryTracker(params)
    assert [tracker.get_input_port(i).get_name() for i in range(2)] == ["reference", "state"]


def test_cross_track_distance():
    polyline = np.array([[0.0, 0, 0], [10, 0, 0], [10, 5, 0]])
    points = np.array([[5.0, 1, 0], [12, 2, 0], [-3, 4, 0], [10, 7, 0]])
    np.testing.assert_allclose(cross_track_distance(points, polyline), [1, 2, 5, 2])
