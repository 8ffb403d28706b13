"""The `Ocean` system: the water at the vehicle on its `water` port (FixValue, Eval), sampled
once per step, its turbulence in the Context (named discrete-state groups, draws keyed by the
update's index)."""

import copy

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.ocean.current import MeanCurrent, VerticalProfile
from drake_auv.ocean.model import OceanModel
from drake_auv.ocean.spec import ocean_from_raw
from drake_auv.ocean.system import Ocean
from drake_auv.ocean.turbulence import Turbulence
from drake_auv.signals import PORT_SIGNALS, VehicleState, Water


def _state(x=0.0, y=0.0, z=-10.0):
    state = VehicleState.zeros()
    state.x, state.y, state.z = x, y, z
    state.yaw, state.u = 1.0, 0.5  # the vehicle's attitude and speed do not matter
    return state[:]


def _initialized(ocean, state, t=0.0):
    """A context of `ocean` at time `t` with its initialization events run; its simulator."""
    context = ocean.CreateDefaultContext()
    ocean.GetInputPort("state").FixValue(context, state)
    context.SetTime(t)
    simulator = Simulator(ocean, context)
    simulator.Initialize()
    return context, simulator


def test_the_water_port_carries_the_current_at_the_vehicle():
    model = OceanModel(MeanCurrent(0.4, 90.0), VerticalProfile(depth_m=(0.0, 20.0),
                                                               factor=(1.0, 0.5)))
    ocean = Ocean(model)
    context, _ = _initialized(ocean, _state(z=-10.0))
    water = Water(ocean.GetOutputPort("water").Eval(context))
    np.testing.assert_allclose(water.velocity, [0.3, 0.0, 0.0], atol=1e-15)
    np.testing.assert_array_equal(water.acceleration, 0.0)
    assert PORT_SIGNALS["water"] is Water and Water.size() == 6


def test_waves_give_the_model_s_velocity_and_acceleration_at_the_vehicle():
    spec = ocean_from_raw({"current": {"speed_mps": 0.2, "towards_deg": 0},
                           "waves": {"hs_m": 1.5, "tp_s": 7, "depth_m": 30}})
    model = spec.model(np.random.default_rng(3))
    ocean = Ocean(model, period=0.05)
    context, simulator = _initialized(ocean, _state(3.0, -4.0, -2.0), t=12.5)
    water = Water(ocean.GetOutputPort("water").Eval(context))
    velocity, acceleration = model.water(12.5, [[3.0, -4.0, -2.0]])
    np.testing.assert_array_equal(water.velocity, velocity[0])
    np.testing.assert_array_equal(water.acceleration, acceleration[0])
    assert np.any(water.acceleration != 0.0)
    # each step's sample holds the water of the step's own time: what the dynamics read then
    for t in (12.75, 13.0):
        simulator.AdvanceTo(t)
        np.testing.assert_allclose(ocean.GetOutputPort("water").Eval(context), np.concatenate(
            model.water(t, [[3.0, -4.0, -2.0]]), axis=1)[0], rtol=0, atol=1e-12)
    assert not ocean.HasDirectFeedthrough(0, 0)  # a sample: no algebraic loop with the plant


def test_turbulence_lives_in_the_context_and_is_seeded():
    model = OceanModel(MeanCurrent(0.3, 0.0),
                       turbulence=Turbulence(speed_sd_mps=0.05, direction_sd_deg=10.0,
                                             time_constant_s=20.0))
    ocean = Ocean(model, seed=4, turbulence_period=0.1)

    def run(context, seconds):
        ocean.GetInputPort("state").FixValue(context, _state())
        simulator = Simulator(ocean, context)
        simulator.AdvanceTo(seconds)
        return ocean.turbulence(context), Water(ocean.GetOutputPort("water").Eval(context))

    first = ocean.CreateDefaultContext()
    start = ocean.turbulence(first)
    assert np.any(start != 0.0)  # drawn from the stationary law
    twin = copy.deepcopy(first)  # the same seed: the same draws
    a, water_a = run(first, 5.0)
    b, water_b = run(twin, 5.0)
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(water_a[:], water_b[:])
    assert not np.allclose(a, start)
    # the water follows the deviation: speed 0.3 + ds, heading turned by the angle
    assert np.hypot(water_a.vx, water_a.vy) == pytest.approx(0.3 + a[0])
    assert np.arctan2(water_a.vx, water_a.vy) == pytest.approx(a[1])
    other = Ocean(model, seed=5)
    assert not np.allclose(other.turbulence(other.CreateDefaultContext()), start)


def test_still_turbulence_draws_nothing_and_a_period_is_whole_steps():
    ocean = Ocean(OceanModel(MeanCurrent(0.1, 0.0)))
    context, simulator = _initialized(ocean, _state())
    simulator.AdvanceTo(1.0)
    np.testing.assert_array_equal(ocean.turbulence(context), 0.0)
    assert context.get_discrete_state(1).GetAtIndex(0) == 0  # no draw
    turbulent = Ocean(OceanModel(turbulence=Turbulence(speed_sd_mps=0.1)),
                      turbulence_period=0.25)
    context, simulator = _initialized(turbulent, _state())
    simulator.AdvanceTo(1.0)
    assert context.get_discrete_state(1).GetAtIndex(0) == 4  # at 0, 0.25, 0.5, 0.75 s
    with pytest.raises(ValueError, match=r"turbulence_period = 0.12 s is not a whole number of "
                                         r"periods \(0.05 s\)"):
        Ocean(OceanModel(turbulence=Turbulence(speed_sd_mps=0.1)), turbulence_period=0.12)
