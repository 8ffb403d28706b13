"""Tracking under a current: integral action with anti-windup, and thruster saturation."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.planning import PlannedPath
from drake_auv.vehicle.control import TrackingController, TrackingGains, axis_force_limits
from drake_auv.vehicle.diagram import build_tracking_diagram
from drake_auv.vehicle.model import Girona500Model, Girona500Params, allocate_thrust

LANE = PlannedPath(np.array([(0.0, 0.0, -10.0), (30.0, 0.0, -10.0)]), 0.0, (0.0, 0.0, -1.0))


def _fly_across(current, gains=None):
    """The lane (30 m along x at 0.5 m/s) in a cross current along +y, then 60 s holding its
    end. Returns (times, true states, final wrench, thrust saturation shares)."""
    diagram, handles = build_tracking_diagram(LANE.resample(1.0), speed=0.5, gains=gains,
                                              current=(0.0, current, 0.0))
    simulator = Simulator(diagram)
    simulator.AdvanceTo(handles.end_time + 60.0)
    context = simulator.get_context()
    log = handles.state_log.FindLog(context)
    vehicle = handles.vehicle
    wrench = vehicle.tracker.wrench_output.Eval(vehicle.tracker.GetMyContextFromRoot(context))
    saturation = vehicle.dynamics.thrust_saturation_output.Eval(
        vehicle.dynamics.GetMyContextFromRoot(context))
    return log.sample_times(), log.data(), wrench, saturation


def test_integral_action_rejects_a_steady_cross_current():
    """0.3 m/s across the lane: with the integral the steady error goes to 0 and the wrench
    holding station is the damping at the current's speed, d U^2 = 13.3 N; without it (the
    ablation) the error stays at d U^2 / (M kp) = 9 cm, as the PD's stiffness predicts."""
    params = Girona500Params()
    drag = params.quadratic_damping[1] * 0.3 ** 2
    stiffness = params.mass_matrix()[1, 1] * TrackingGains().kp
    steady = {}
    for ki in (TrackingGains().ki, 0.0):
        t, x, wrench, saturation = _fly_across(0.3, TrackingGains(ki=ki))
        last = t > t[-1] - 20.0
        steady[ki] = np.abs(x[1, last]).mean()
        assert np.all(saturation == 0.0)  # 0.3 m/s is well within the sway thruster
        if ki:
            assert wrench[1] == pytest.approx(-drag, rel=0.01)
    assert steady[TrackingGains().ki] < 0.002
    assert steady[0.0] == pytest.approx(drag / stiffness, rel=0.05)


def test_a_current_beyond_the_thrusters_saturates_them():
    """1.5 m/s across needs d U^2 = 333 N of sway, twice what its one thruster gives: the sway
    thruster is at its limit nearly all the time and the vehicle is swept off."""
    _, x, _, saturation = _fly_across(1.5)
    assert saturation[4] > 0.9 and np.all(saturation[:4] < 0.05)
    assert x[1, -1] > 20.0


def test_anti_windup_clamps_and_freezes_the_integral():
    params = Girona500Params()
    controller = TrackingController(params)
    gains = controller.gains
    # the bound: the integral's acceleration at most the sway axis's (the weaker horizontal)
    sway = axis_force_limits(params)[1] / params.mass_matrix()[1, 1]
    np.testing.assert_allclose(gains.ki * controller.integral_limit[:2], sway)
    state, reference = np.zeros(12), np.zeros(8)
    reference[1] = 0.5  # 0.5 m off: the PD is far from saturating, the integral grows
    _, integral = controller.wrench(reference, state, np.zeros(3), 0.05)
    np.testing.assert_allclose(integral, [0.0, 0.025, 0.0])
    reference[4] = 0.1  # and a velocity error, weighted by kd / kp = 2 s
    _, integral = controller.wrench(reference, state, np.zeros(3), 0.05)
    np.testing.assert_allclose(integral, [0.01, 0.025, 0.0])
    reference[4] = 0.0
    _, integral = controller.wrench(reference, state, np.full(3, 1e3), 0.05)
    np.testing.assert_allclose(integral, controller.integral_limit)  # clamped
    reference[1] = 5.0  # 5 m off: saturated, the integral does not wind up ...
    wrench, integral = controller.wrench(reference, state, np.zeros(3), 0.05)
    assert np.abs(controller.allocation @ wrench).max() > params.max_thrust
    np.testing.assert_array_equal(integral, np.zeros(3))
    # ... but unwinds what it holds against the error
    _, integral = controller.wrench(reference, state, np.array([0.0, -2.0, 0.0]), 0.05)
    np.testing.assert_allclose(integral, [0.0, -2.0 + 0.25, 0.0])


def _carrot(gains, current, seconds=60.0, dt=0.05):
    """The model under the controller with a reference re-anchored on the vehicle every
    period (what profile following does): hold the position, move at 0.3 m/s along x, in a
    head current along -x. Returns the final ground speed, m/s."""
    params = Girona500Params()
    model, controller = Girona500Model(params), TrackingController(params, gains)
    x, integral = np.zeros(17), np.zeros(3)
    water = np.array([-current, 0.0, 0.0, 0.0, 0.0, 0.0])
    for _ in range(int(seconds / dt)):
        reference = np.zeros(8)
        reference[:3], reference[4] = x[:3], 0.3
        wrench, integral = controller.wrench(reference, x[:12], integral, dt)
        thrust = allocate_thrust(controller.allocation, wrench, params.max_thrust)
        x = model.step(x, thrust, dt, water)
    return x[6]


def test_integral_restores_the_speed_of_a_re_anchored_reference():
    """Re-anchored, the position error stays 0: an integral of the position alone would not
    see the 0.3 m/s head current that slows the vehicle; the PD's own command does."""
    assert _carrot(TrackingGains(), 0.3) == pytest.approx(0.3, abs=0.003)
    assert _carrot(TrackingGains(ki=0.0), 0.3) < 0.2
    assert _carrot(TrackingGains(), 0.0) == pytest.approx(0.3, abs=1e-3)
