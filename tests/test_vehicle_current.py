"""The vehicle in moving water: Fossen's relative-velocity model against closed-form physics."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.vehicle.dynamics import Girona500Dynamics
from drake_auv.vehicle.model import Girona500Model, Girona500Params

DT = 0.05


def _drift(model, water_of, seconds, x0=None):
    """Zero thrust for `seconds`; `water_of(t)` -> the 6-vector water at t. Returns the times
    and the 17-states at each step's end."""
    x = np.zeros(17) if x0 is None else x0.copy()
    times, states, previous = [], [], None
    for k in range(round(seconds / DT)):
        water = water_of(k * DT)
        x = model.step(x, np.zeros(5), DT, water, previous)
        previous = water[3:]
        times.append((k + 1) * DT)
        states.append(x)
    return np.array(times), np.array(states)


def test_still_water_is_bit_for_bit_the_model_without_water():
    model, rng = Girona500Model(), np.random.default_rng(4)
    x_none = x_zero = np.concatenate([[1.0, 2.0, -5.0, 0.1, -0.05, 1.0], np.zeros(11)])
    for _ in range(300):
        command = rng.uniform(-200.0, 200.0, 5)
        x_none = model.step(x_none, command, DT)
        x_zero = model.step(x_zero, command, DT, np.zeros(6))
        assert np.array_equal(x_none, x_zero)
    # the LeafSystem: `water` not connected is still water, as a connected zero water
    a, b = Girona500Dynamics(), Girona500Dynamics()
    sims = [Simulator(a), Simulator(b)]
    for system, sim in ((a, sims[0]), (b, sims[1])):
        system.thrust_input.FixValue(sim.get_mutable_context(), [100.0, 80.0, 20.0, 20.0, -30.0])
    b.water_input.FixValue(sims[1].get_mutable_context(), np.zeros(6))
    for sim in sims:
        sim.AdvanceTo(5.0)
    assert np.array_equal(a.state_output.Eval(sims[0].get_context()),
                          b.state_output.Eval(sims[1].get_context()))


def test_step_current_carries_the_vehicle_at_the_quadratic_damping_rate():
    """At rest in a current switched on at t = 0, with zero thrust: only the quadratic damping
    acts on the velocity through the water, per axis (m + m_a) u_r' = -d u_r |u_r|, so
    u_r = c / (1 + k c t) and x = c t - ln(1 + k c t) / k with k = d / (m + m_a), c the
    current's component."""
    params = Girona500Params()
    speed, heading = 0.3, np.radians(30.0)  # flowing towards 30 deg from east, 60 from north
    v_c = speed * np.array([np.cos(heading), np.sin(heading), 0.0])
    t, x = _drift(Girona500Model(params), lambda _: np.concatenate([v_c, np.zeros(3)]), 120.0)
    # no yaw moment in a uniform current (the CG's lag only tilts it, by < 0.3 deg), so the
    # body axes stay the world's
    assert np.abs(x[:, 3:5]).max() < 5e-3 and np.abs(x[:, 5]).max() < 1e-5
    k = params.quadratic_damping[0] / (params.mass + params.added_mass[0])
    for axis in (0, 1):
        c = v_c[axis]
        np.testing.assert_allclose(c - x[:, 6 + axis], c / (1.0 + k * c * t), rtol=0.01)
        np.testing.assert_allclose(x[:, axis], c * t - np.log1p(k * c * t) / k, rtol=0.01,
                                   atol=1e-4)
    # it converges on the current's velocity as 1/t: 3.7 % of it left after 120 s
    assert np.linalg.norm(x[-1, 6:8] - v_c[:2]) < 0.04 * speed


def test_a_current_that_builds_up_carries_the_vehicle_within_one_percent():
    """A neutrally buoyant vehicle in a current spun up over 20 s (its acceleration given) is
    carried by the Froude-Krylov force and the added mass: within 1 % of the current's velocity
    throughout, and displaced by the current's own integral."""
    speed, ramp = 0.5, 20.0
    direction = np.array([0.6, -0.8, 0.0])

    def water_of(time):
        rate = speed / ramp if time < ramp else 0.0
        return np.concatenate([min(time / ramp, 1.0) * speed * direction, rate * direction])

    t, x = _drift(Girona500Model(), water_of, 60.0)
    current = np.array([water_of(s)[:3] for s in t])
    ground = np.linalg.norm(x[:, 6:9], axis=1)
    assert np.all(np.abs(ground - np.linalg.norm(current, axis=1)) <= 0.01 * speed)
    assert abs(ground[-1] - speed) < 0.01 * speed
    travelled = speed * (t[-1] - ramp / 2.0) * direction
    np.testing.assert_allclose(x[-1, :3], travelled, atol=0.01 * np.linalg.norm(travelled))


@pytest.mark.parametrize("buoyancy_ratio", [1.0, 1.2])
def test_oscillating_current_gives_the_froude_krylov_response(buoyancy_ratio):
    """A wave-like oscillating current v_c = U sin(w t) along x, no horizontal damping, CG at
    the CB: (m + m_a) u' = (rho V + m_a) a_c, so u = (rho V + m_a) / (m + m_a) v_c in phase
    (1 for a neutrally buoyant vehicle, 1.133 for one 20 % buoyant)."""
    params = Girona500Params(centre_of_gravity=(0.0, 0.0, 0.0), buoyancy_ratio=buoyancy_ratio,
                             quadratic_damping=(0.0, 0.0, 148.0, 180.0, 180.0, 180.0))
    amplitude, omega = 0.4, 2.0 * np.pi / 8.0  # an 8 s swell's orbital velocity

    def water_of(time):
        return np.array([amplitude * np.sin(omega * time), 0.0, 0.0,
                         amplitude * omega * np.cos(omega * time), 0.0, 0.0])

    t, x = _drift(Girona500Model(params), water_of, 80.0)
    gain = (buoyancy_ratio * params.mass + params.added_mass[0]) / (params.mass
                                                                   + params.added_mass[0])
    # (the first step, with no earlier acceleration to extrapolate from, leaves an offset of
    # the jerk's dt^2 / 2: 0.3 mm/s)
    np.testing.assert_allclose(x[:, 6], gain * amplitude * np.sin(omega * t), atol=5e-4)
    assert np.abs(x[:, 1]).max() < 1e-9 and np.abs(x[:, 3:6]).max() < 1e-9


def test_damping_acts_on_the_velocity_through_the_water():
    """At rest in a 0.3 m/s current the only force is the damping on the relative velocity:
    d U^2 = 13.3 N towards the current's direction, so holding station costs that thrust."""
    params = Girona500Params(centre_of_gravity=(0.0, 0.0, 0.0))
    model = Girona500Model(params)
    water = np.array([0.0, 0.3, 0.0, 0.0, 0.0, 0.0])
    force = params.mass_matrix() @ model.derivative(np.zeros(17), np.zeros(5), water)[6:12]
    np.testing.assert_allclose(force, [0.0, params.quadratic_damping[1] * 0.09, 0, 0, 0, 0],
                               atol=1e-9)


def test_dynamics_system_feels_the_water_and_measures_saturation():
    plant = Girona500Dynamics(time_step=DT)
    simulator = Simulator(plant)
    context = simulator.get_mutable_context()
    limit = plant.params.max_thrust
    command = np.array([2.0 * limit, limit, 20.0, -limit, 0.0])
    water = np.array([0.2, -0.1, 0.0, 0.01, 0.02, 0.0])
    plant.thrust_input.FixValue(context, command)
    plant.water_input.FixValue(context, water)
    np.testing.assert_array_equal(plant.thrust_saturation_output.Eval(context), np.zeros(5))
    simulator.AdvanceTo(2.0)
    model, x, previous = Girona500Model(), np.zeros(17), None
    for _ in range(40):
        x = model.step(x, command, DT, water, previous)
        previous = water[3:]
    np.testing.assert_allclose(plant.state_output.Eval(context), x[:12], atol=1e-12)
    # the first, second and fourth commands are at (or beyond) the limit all the time
    np.testing.assert_allclose(plant.thrust_saturation_output.Eval(context), [1, 1, 0, 1, 0])
