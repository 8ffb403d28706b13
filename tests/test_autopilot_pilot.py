"""The autopilot pilot and its DVL: COLA2 and ArduSub semantics, alone and flying the vehicle."""

import numpy as np
import pytest
import trimesh
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, LogVectorOutput

from drake_auv.autopilot.items import FlownMission, LocalLeg
from drake_auv.autopilot.pilot import AutopilotPilot, BehaviourStatus
from drake_auv.autopilot.semantics import item_reached, item_reference, start_record
from drake_auv.geometry.raycast import RayCaster
from drake_auv.sonar.altimeter import DvlAltimeter, DvlParams, measure_altitude
from drake_auv.vehicle.diagram import add_girona500


def slope_world(slope=0.2, depth=-30.0, half=200.0):
    """A plane z = depth + slope * x, 2 * half m wide."""
    xs = np.array([-half, half])
    v = np.array([[x, y, depth + slope * x] for y in xs for x in xs])
    return trimesh.Trimesh(v, [[0, 1, 3], [0, 3, 2]], process=False)


def state(x=0.0, y=0.0, z=-10.0, yaw=0.0):
    s = np.zeros(12)
    s[[0, 1, 2, 5]] = x, y, z, yaw
    return s


def test_dvl_altitude_on_a_slope_and_without_lock():
    caster = RayCaster(slope_world(slope=0.2))
    exact = measure_altitude(caster, DvlParams(), state(x=10.0, z=-10.0))
    # on a plane of slope s the up- and down-slope beams drop h / (1 +- e) with
    # e = s tan(30 deg) cos(45 deg): their mean is h / (1 - e^2), a little above the plane
    e = 0.2 * np.tan(np.radians(30.0)) * np.cos(np.radians(45.0))
    assert exact == pytest.approx(18.0 / (1 - e * e), abs=1e-6)
    strict = DvlParams(min_beams=4)  # all four beams: a 2 % dropout loses lock 8 % of the time
    noisy = [measure_altitude(caster, strict, state(x=10.0), np.random.default_rng(k))
             for k in range(200)]
    finite = np.array([a for a in noisy if np.isfinite(a)])
    assert 0.85 * len(noisy) < len(finite) < len(noisy)
    assert abs(np.median(finite) - exact) < 0.05 and finite.std() > 0.01
    assert np.isnan(measure_altitude(caster, DvlParams(max_range=5.0), state(x=10.0)))


def test_dvl_returns_map_the_seabed_under_the_vehicle():
    """The DVL's four beams, as returns at the estimated pose, put the seabed under the
    vehicle into the octree (what the side-looking sonars graze)."""
    from drake_auv.mapping.mapper import OctreeMapper

    caster = RayCaster(slope_world(slope=0.0, depth=-30.0))
    dvl = DvlAltimeter(caster, noise=False)
    context = dvl.CreateDefaultContext()
    true, estimated = state(z=-10.0), state(x=1.0, z=-10.0)  # navigation 1 m off in x
    dvl.true_state_input.FixValue(context, true)
    dvl.estimated_state_input.FixValue(context, estimated)
    assert len(dvl.returns_output.Eval(context)) == 0  # nothing measured yet
    simulator = Simulator(dvl, context)
    simulator.AdvanceTo(0.1)
    returns = dvl.returns_output.Eval(context)
    assert returns.sequence == 1 and len(returns) == 4
    np.testing.assert_allclose(returns.origin_nav, [1.0, 0.0, -10.0])
    np.testing.assert_allclose(returns.ranges, 20.0 / np.cos(np.radians(30.0)))
    np.testing.assert_allclose(returns.points_nav[:, 2], -30.0, atol=1e-9)
    np.testing.assert_allclose(np.abs(returns.points_nav[:, :2] - [1.0, 0.0]),
                               20.0 * np.tan(np.radians(30.0)) * np.sqrt(0.5), atol=1e-9)
    mapper = OctreeMapper(resolution=0.5)
    mapper_context = mapper.CreateDefaultContext()
    mapper.returns_inputs["dvl"].FixValue(mapper_context, AbstractValue.Make(returns))
    Simulator(mapper, mapper_context).AdvanceTo(0.15)
    assert mapper.scan_log(mapper_context).count == 1  # recorded once
    occupied = mapper.map_output.Eval(mapper_context).map.occupied_points()
    assert len(occupied) == 4 and np.all(np.abs(occupied[:, 2] + 30.0) <= 0.5)


def test_cola2_holds_the_final_target_from_the_section_start():
    section = LocalLeg("section", (100.0, 0.0), "depth", 20.0, start=(0.0, 0.0),
                       start_z=-5.0, speed=0.5)
    x = state(x=10.0, y=2.0, z=-5.0)
    record = start_record("cola2", (section,), 0, 0.0, x, np.nan)
    ref = item_reference("cola2", section, record, x, np.nan, 0.5)
    assert ref[2] == -20.0  # the final depth at once, not interpolated
    np.testing.assert_allclose(ref[[0, 1]], [10.0, 0.0])  # the foot on the line
    np.testing.assert_allclose(ref[4:7], [0.5, 0.0, 0.0])  # along the line at the speed
    ref3d = item_reference("cola2", section, record, x, np.nan, 0.5, heave_in_3d=True)
    assert ref3d[2] == pytest.approx(-5.0 - 0.1 * 15.0) and ref3d[6] < 0
    altitude = LocalLeg("section", (100.0, 0.0), "altitude", 8.0, start=(0.0, 0.0))
    assert item_reference("cola2", altitude, record, x, -33.0, 0.5)[2] == -25.0
    # no bottom lock: no_altitude_goes_up
    assert item_reference("cola2", altitude, record, x, np.nan, 0.5)[2] > x[2]
    assert not item_reached("cola2", section, record, x, np.nan)
    assert item_reached("cola2", section, record, state(x=99.5, z=-5.0), np.nan)  # xy only


def test_ardusub_interpolates_along_straight_3d_legs():
    legs = (LocalLeg("waypoint", (0.0, 0.0), "depth", 5.0, tolerance=1.0),
            LocalLeg("waypoint", (100.0, 0.0), "depth", 25.0, tolerance=1.0),
            LocalLeg("waypoint", (200.0, 0.0), "altitude", 10.0, tolerance=1.0),
            LocalLeg("waypoint", (300.0, 0.0), "altitude", 4.0, tolerance=1.0))
    x = state(x=25.0, z=-10.0)
    second = start_record("ardusub", legs, 1, 0.0, x, -40.0)
    assert item_reference("ardusub", legs[1], second, x, -40.0, 0.5)[2] == pytest.approx(-10.0)
    # depth 25 m -> altitude 10 m: the altitude measured where the leg began, then the target
    x = state(x=150.0, z=-25.0)
    third = start_record("ardusub", legs, 2, 0.0, x, -40.0)
    assert item_reference("ardusub", legs[2], third, x, -40.0, 0.5)[2] == pytest.approx(
        -40.0 + 0.5 * (15.0 + 10.0))
    fourth = start_record("ardusub", legs, 3, 0.0, state(x=200.0, z=-30.0), -40.0)
    x = state(x=250.0, z=-30.0)
    assert item_reference("ardusub", legs[3], fourth, x, -42.0, 0.5)[2] == pytest.approx(-35.0)
    # reached in 3D: within the radius horizontally but 5 m off in altitude is not reached
    assert not item_reached("ardusub", legs[3], fourth, state(x=299.8, z=-33.0), -42.0)
    assert item_reached("ardusub", legs[3], fourth, state(x=299.8, z=-37.8), -42.0)


def fly(mission: FlownMission, world, start, t_end):
    builder = DiagramBuilder()
    vehicle = add_girona500(builder, initial_state=start)
    caster = RayCaster(world)
    dvl = builder.AddSystem(DvlAltimeter(caster, seed=3))
    pilot = builder.AddSystem(AutopilotPilot(mission))
    leg = builder.AddSystem(ConstantVectorSource([0.0, 0.0]))
    builder.Connect(vehicle.dynamics.state_output, dvl.true_state_input)
    builder.Connect(vehicle.navigation.estimated_state_output, dvl.estimated_state_input)
    builder.Connect(vehicle.navigation.estimated_state_output, pilot.state_input)
    builder.Connect(dvl.seabed_output, pilot.seabed_input)
    builder.Connect(leg.get_output_port(), pilot.leg_input)
    builder.Connect(pilot.reference_output, vehicle.tracker.reference_input)
    log = LogVectorOutput(vehicle.dynamics.state_output, builder, 0.5)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(t_end)
    context = simulator.get_context()
    status = BehaviourStatus(pilot.status_output.Eval(pilot.GetMyContextFromRoot(context)))
    return log.FindLog(context).data().T, status


@pytest.mark.parametrize("autopilot", ["cola2", "ardusub"])
def test_terrain_following_over_a_slope(autopilot):
    """Altitude legs over a 0.2 slope: the vehicle follows the DVL's seabed 6 m above it,
    and flies every item to the end."""
    world = slope_world(slope=0.2)
    kind = "section" if autopilot == "cola2" else "waypoint"
    legs = (LocalLeg("goto" if autopilot == "cola2" else "waypoint", (0.0, 0.0), "altitude",
                     6.0, speed=0.5, tolerance=1.0),
            LocalLeg(kind, (40.0, 0.0), "altitude", 6.0, start=(0.0, 0.0) if kind == "section"
                     else None, speed=0.5, tolerance=1.0))
    states, status = fly(FlownMission(autopilot, legs), world, state(x=-5.0, z=-25.0), 160.0)
    assert status.finished == 1 and status.progress == 1
    seabed = -30.0 + 0.2 * states[:, 0]
    along = states[:, 0] > 5.0
    altitude = states[along, 2] - seabed[along]
    assert abs(np.median(altitude) - 6.0) < 0.5 and altitude.min() > 4.5, altitude
    assert np.abs(states[along, 1]).max() < 0.5  # on the line


def test_the_pilot_serves_only_its_leg():
    legs = (LocalLeg("goto", (10.0, 0.0), "depth", 10.0),)
    pilot = AutopilotPilot({2: FlownMission("cola2", legs)})
    context = pilot.CreateDefaultContext()
    pilot.state_input.FixValue(context, state(x=3.0, z=-4.0))
    pilot.seabed_input.FixValue(context, [np.nan])
    pilot.leg_input.FixValue(context, [1.0, 0.0])
    simulator = Simulator(pilot, context)
    simulator.AdvanceTo(0.25)
    assert BehaviourStatus(pilot.status_output.Eval(context)).leg == -1  # leg 1 is not its own
    np.testing.assert_allclose(pilot.reference_output.Eval(context)[:3], [3.0, 0.0, -4.0])
    pilot.leg_input.FixValue(context, [2.0, 0.25])
    simulator.AdvanceTo(0.5)
    assert BehaviourStatus(pilot.status_output.Eval(context)).leg == 2
    assert pilot.reference_output.Eval(context)[2] == -10.0


def test_dvl_ranges_within_the_blanking_distance_are_no_measurement():
    """A beam 0.3 m from the seabed: with noise its range could be negative (the mapper
    refuses those); within the blanking distance it is no measurement, never a range < 0."""
    from drake_auv.sonar.altimeter import measure_ranges

    caster = RayCaster(slope_world(slope=0.0, depth=-10.3))
    params = DvlParams(range_sigma_m=0.5)
    ranges = np.array([measure_ranges(caster, params, state(z=-10.0), np.random.default_rng(k))
                       for k in range(50)])
    assert np.all(np.isnan(ranges) | (ranges >= params.blanking_m))
    far = measure_ranges(caster, DvlParams(blanking_m=0.0), state(z=-10.0))
    np.testing.assert_allclose(far, 0.3 / np.cos(np.radians(30.0)))
