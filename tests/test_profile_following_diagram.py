"""ProfileFollowingController in Drake: ports, batches, and short closed-loop runs of each mode
(a pool corner in horizontal mode, the ceiling turn inside the C in vertical mode) in a small
diagram of the vehicle, the profiler and the controller alone."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput

from drake_auv.geometry.distance import mesh_distance
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mission.config import MissionFileError, load_mission
from drake_auv.following import FollowingParams
from drake_auv.following.controller import FollowConfig, ProfileFollowingController
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.profiler import FOLLOWING_SETUP, PencilBeamProfiler
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.control import wrap_angle
from drake_auv.vehicle.diagram import add_girona500

WARMUP = 360.0 / FOLLOWING_SETUP["step_deg"] / FOLLOWING_SETUP["ping_rate"]  # one head turn


def _returns(points, sequence, time=0.0):
    points = np.asarray(points, float)
    n = len(points)
    return SonarReturns(time, np.zeros(3), np.zeros(n), np.linalg.norm(points, axis=1),
                        np.zeros((n, 3)), points, points, 20.0, sequence)


def test_controller_ports_and_each_batch_used_once():
    controller = ProfileFollowingController(FollowConfig("horizontal"), period=0.1)
    assert controller.returns_input.get_name() == "returns"
    assert controller.state_input.get_name() == "estimated_state"
    assert controller.leg_input.get_name() == "leg"
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
    # a leg it does not fly leaves it idle: the reference holds the estimated pose
    controller.leg_input.FixValue(context, [1.0, 0.0])
    assert np.allclose(controller.reference_output.Eval(context), [0, 0, -4, 0, 0, 0, 0, 0])


def _follow(world, start, config: FollowConfig, duration: float, noise=None, seed=0):
    """Flies `config` from `start` for `duration` s with the vehicle, the profiler (scanning
    the mode's plane) and the controller; returns (controller, its context, t, x, profile)."""
    builder = DiagramBuilder()
    vehicle = add_girona500(builder, initial_state=start)
    profiler = builder.AddSystem(PencilBeamProfiler(
        RayCaster(world), scan_plane=config.mode, noise=noise, seed=seed, **FOLLOWING_SETUP))
    controller = builder.AddSystem(ProfileFollowingController(config, profiler.period, seed))
    estimated = vehicle.navigation.estimated_state_output
    builder.Connect(vehicle.dynamics.state_output, profiler.true_state_input)
    builder.Connect(estimated, profiler.estimated_state_input)
    builder.Connect(profiler.returns_output, controller.returns_input)
    builder.Connect(estimated, controller.state_input)
    builder.Connect(controller.reference_output, vehicle.tracker.reference_input)
    state_log = LogVectorOutput(vehicle.dynamics.state_output, builder, 0.1)
    profile_log = LogVectorOutput(controller.profile_output, builder, 0.1)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(duration)
    context = simulator.get_context()
    log = state_log.FindLog(context)
    return (controller, controller.GetMyContextFromRoot(context), log.sample_times(), log.data(),
            profile_log.FindLog(context).data())


@pytest.mark.parametrize("noise", [None, SonarNoise(spurious_prob=0.1, range_sigma=0.05)],
                         ids=["clean", "spurious"])
def test_pool_corner_in_horizontal_mode(noise):
    world = get_scenario("pool").world
    start = np.zeros(12)
    start[:3], start[5] = (3.0, -2.0, -4.0), -np.pi / 2  # 2 m from the y = -4 wall, facing it
    params = FollowingParams(offset=2.0, speed=0.3, corner_weight=0.5, warmup=WARMUP)
    _, _, t, x, profile = _follow(world, start, FollowConfig("horizontal", params), 22.0,
                                  noise=noise, seed=3)
    # round the (8, -4) corner: now 2 m from the x = 8 wall, facing +x, moving along +y
    assert x[0, -1] == pytest.approx(6.0, abs=0.2)
    assert -1.5 < x[1, -1] < 1.0
    assert abs(wrap_angle(x[5, -1])) < np.radians(10)
    heading = np.column_stack([np.cos(x[5]), np.sin(x[5]), np.zeros(len(t))])
    frontal = RayCaster(world).cast(x[:3].T, heading, 20.0).ranges
    assert np.nanmax(np.abs(frontal - 2.0)) < 1.0
    assert np.all(np.abs(x[2] + 4.0) < 0.1)  # depth held
    assert np.all(profile[5, t > 4.0] == 1.0)  # seen throughout once the head reached it


def test_ceiling_turn_inside_the_c_in_vertical_mode():
    world = get_scenario("c_object").world
    start = np.zeros(12)
    start[:3] = (7.0, 0.0, -13.0)  # inside the C, 3 m from its inner wall, facing it
    config = FollowConfig("vertical", FollowingParams(offset=2.0, speed=0.3, warmup=WARMUP),
                          plane_yaw=0.0)
    controller, context, t, x, profile = _follow(world, start, config, 50.0)
    assert controller.follower(context).turns == 1
    assert np.any(profile[6] == 2)  # the turn mode was engaged
    assert abs(wrap_angle(x[5, -1] - np.pi)) < np.radians(10)  # now facing -x
    assert x[2, -1] == pytest.approx(-11.0, abs=0.25)  # 2 m under the ceiling (z = -9)
    assert x[0, -1] < 5.0  # moving along the ceiling towards the opening
    assert mesh_distance(world, x[:3].T).min() > 1.5


def test_bad_options_are_rejected():
    with pytest.raises(ValueError, match="mode"):
        FollowConfig("diagonal")
    with pytest.raises(ValueError, match="period"):
        ProfileFollowingController(FollowConfig(), period=0.0)
    with pytest.raises(ValueError, match="at least one leg"):
        ProfileFollowingController({})
    with pytest.raises(ValueError, match="scan_plane"):
        PencilBeamProfiler(get_scenario("pool").world, scan_plane="sideways")
    with pytest.raises(ValueError, match="step_deg"):
        PencilBeamProfiler(get_scenario("pool").world, step_deg=0.0)
    with pytest.raises(ValueError, match="initial_state"):
        add_girona500(DiagramBuilder(), initial_state=np.zeros(6))
    with pytest.raises(MissionFileError, match=r"steps\[0\]\.follow\.mode.*horizontal"):
        load_mission("pool", overrides=["steps.0.follow.mode=sideways"])
    with pytest.raises(MissionFileError, match=r"steps\[1\]\.follow.*needs an end"):
        load_mission("pool", overrides=["steps.1.follow.distance_m=null",
                                        "steps.1.follow.end_depth_m=null"])
