"""ProfileFollowingController in Drake: ports, batches, and short closed-loop runs of each mode
(a pool corner in horizontal mode, the ceiling turn inside the C in vertical mode)."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.vehicle.control import wrap_angle
from drake_auv.diagrams.profile_following import build_profile_following_diagram
from drake_auv.geometry.distance import mesh_distance
from drake_auv.perception import FollowingParams
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.returns import SonarReturns
from drake_auv.perception.controller import ProfileFollowingController



def _returns(points, sequence, time=0.0):
    points = np.asarray(points, float)
    n = len(points)
    return SonarReturns(time, np.zeros(3), np.zeros(n), np.linalg.norm(points, axis=1),
                        np.zeros((n, 3)), points, points, 20.0, sequence)


def test_controller_ports_and_each_batch_used_once():
    controller = ProfileFollowingController("horizontal", period=0.1)
    assert controller.returns_input.get_name() == "returns"
    assert controller.state_input.get_name() == "estimated_state"
    assert controller.reference_output.get_name() == "reference"
    assert controller.profile_output.get_name() == "profile"
    context = controller.CreateDefaultContext()
    state = np.zeros(12)
    state[2] = -4.0
    controller.state_input.FixValue(context, state)
    wall = np.column_stack([np.full(40, 2.5), np.linspace(-3, 3, 40), np.full(40, -4.0)])
    controller.returns_input.FixValue(context, _returns(wall, sequence=1))
    simulator = Simulator(controller, context)
    simulator.AdvanceTo(0.35)  # updates at 0, 0.1, 0.2, 0.3 all see the same batch
    follower = controller.follower(context)
    assert len(follower.map) == 40
    profile = controller.profile_output.Eval(context)
    assert profile[0] == pytest.approx(2.5, abs=0.02) and profile[5] == 1.0
    reference = controller.reference_output.Eval(context)
    # it approaches the wall (x) by min(0.5 m, max_correction) and slides along it (+y, right)
    assert reference[0] == pytest.approx(0.5, abs=0.03)
    assert reference[5] > 0 and reference[2] == pytest.approx(-4.0)
    # between updates the reference position moves with its velocity
    t0 = context.get_time()
    context.SetTime(t0 + 0.04)
    later = controller.reference_output.Eval(context)
    assert np.allclose(later[:3] - reference[:3], 0.04 * reference[4:7], atol=1e-12)
    with pytest.raises(ValueError, match="mode"):
        ProfileFollowingController("diagonal")


def _advance(diagram, handles, duration):
    simulator = Simulator(diagram)
    simulator.AdvanceTo(duration)
    context = simulator.get_context()
    log = handles.state_log.FindLog(context)
    return context, log.sample_times(), log.data(), handles.profile_log.FindLog(context).data()


@pytest.mark.parametrize("noise", [None, SonarNoise(spurious_prob=0.1, range_sigma=0.05)],
                         ids=["clean", "spurious"])
def test_pool_corner_in_horizontal_mode(noise):
    scenario = get_scenario("pool")
    start = np.zeros(12)
    start[:3], start[5] = (3.0, -2.0, -4.0), -np.pi / 2  # 2 m from the y = -4 wall, facing it
    params = FollowingParams(offset=2.0, speed=0.3, corner_weight=0.5)
    diagram, handles = build_profile_following_diagram(scenario.world, start, "horizontal",
                                                       params, noise=noise, seed=3)
    _, t, x, profile = _advance(diagram, handles, 22.0)
    # round the (8, -4) corner: now 2 m from the x = 8 wall, facing +x, moving along +y
    assert x[0, -1] == pytest.approx(6.0, abs=0.2)
    assert -1.5 < x[1, -1] < 1.0
    assert abs(wrap_angle(x[5, -1])) < np.radians(10)
    heading = np.column_stack([np.cos(x[5]), np.sin(x[5]), np.zeros(len(t))])
    frontal = handles.caster.cast(x[:3].T, heading, 20.0).ranges
    assert np.nanmax(np.abs(frontal - 2.0)) < 1.0
    assert np.all(np.abs(x[2] + 4.0) < 0.1)  # depth held
    assert np.all(profile[5, t > 4.0] == 1.0)  # seen throughout once the head reached it


def test_ceiling_turn_inside_the_c_in_vertical_mode():
    scenario = get_scenario("c_object")
    start = np.zeros(12)
    start[:3] = (7.0, 0.0, -13.0)  # inside the C, 3 m from its inner wall, facing it
    diagram, handles = build_profile_following_diagram(
        scenario.world, start, "vertical", FollowingParams(offset=2.0, speed=0.3),
        plane_yaw=0.0)
    context, t, x, profile = _advance(diagram, handles, 50.0)
    follower = handles.controller.follower(handles.controller.GetMyContextFromRoot(context))
    assert follower.turns == 1
    assert np.any(profile[6] == 2)  # the turn mode was engaged
    assert abs(wrap_angle(x[5, -1] - np.pi)) < np.radians(10)  # now facing -x
    assert x[2, -1] == pytest.approx(-11.0, abs=0.25)  # 2 m under the ceiling (z = -9)
    assert x[0, -1] < 5.0  # moving along the ceiling towards the opening
    assert mesh_distance(scenario.world, x[:3].T).min() > 1.5


def test_diagram_rejects_bad_options():
    world = get_scenario("pool").world
    start = np.zeros(12)
    with pytest.raises(ValueError, match="mode"):
        build_profile_following_diagram(world, start, "sideways")
    with pytest.raises(ValueError, match="profiler_options"):
        build_profile_following_diagram(world, start, profiler_options={"beams": 3})
    with pytest.raises(ValueError, match="initial_state"):
        build_profile_following_diagram(world, np.zeros(6))
