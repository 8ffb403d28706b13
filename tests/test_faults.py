"""Faults and the supervisor's safety rules: the `faults:` section, the systems that inject
them, the pure rules, the supervisor detecting and answering each fault from what it is given,
and one short dive whose navigation jump ends in an abort to the surface."""

from __future__ import annotations

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mapping.scan_log import ScanBatch, ScanLog
from drake_auv.mission.config import MissionFileError, load_mission, mission_from_dict, \
    mission_to_dict
from drake_auv.mission.faults import NavigationJump, SonarSilence, ThrusterFailure, silenced
from drake_auv.mission.legs import Leg
from drake_auv.mission.safety import (CAUSES, RESPONSES, SafetyRules, abort_target,
                                      back_off_target, response_reference)
from drake_auv.mission.supervisor import MissionSupervisor
from drake_auv.sonar.returns import SonarReturns


def _returns(t: float, hit: bool, sequence: int = 1) -> SonarReturns:
    ranges = np.array([5.0 if hit else np.nan, np.nan])
    points = np.where(np.isfinite(ranges)[:, None], [[5.0, 0.0, 0.0]] * 2, np.nan)
    return SonarReturns(t, np.zeros(3), np.zeros(2), ranges, np.tile([1.0, 0, 0], (2, 1)),
                        points, points, 20.0, sequence)


def test_faults_section_validates_and_round_trips():
    spec = load_mission("breakwater", overrides=[
        "faults.thruster_failure.start_s=100", "faults.thruster_failure.thruster=heave_bow",
        "faults.sonar_silent.start_s=50", "faults.sonar_silent.sensor=multibeam"])
    assert set(spec.faults.active) == {"thruster_failure", "sonar_silent"}
    assert spec.faults.thruster_failure.thruster == "heave_bow"
    assert mission_from_dict(mission_to_dict(spec), "/", "x") == spec
    assert load_mission("breakwater").faults.active == {}
    for bad, message in (("faults.thruster_failure.thruster=left", "'left' is not allowed"),
                         ("faults.sonar_silent.sensor=camera", "'camera' is not allowed"),
                         ("faults.navigation_jump.error_m=-1", "out of range"),
                         ("faults.sonar_silent.duration_s=0", "out of range"),
                         ("faults.engine.start_s=1", "faults.engine: unknown fault")):
        with pytest.raises(MissionFileError, match=message):
            load_mission("breakwater", overrides=[bad])


def test_fault_systems_inject_from_their_time():
    silence = SonarSilence(10.0, 5.0, 20.0)
    context = silence.CreateDefaultContext()
    for t, silent in ((9.9, False), (10.0, True), (14.9, True), (15.0, False)):
        context.SetTime(t)
        silence.returns_input.FixValue(context, _returns(t, True, 3))
        out = silence.returns_output.Eval(context)
        assert out.hit.any() != silent and out.sequence == 3 and out.time == t
        assert (len(out) == 0) == silent  # silent: no beams at all, not beams without echo
    failure = ThrusterFailure("sway", 20.0)
    context = failure.CreateDefaultContext()
    failure.command_input.FixValue(context, np.arange(1.0, 6.0))
    context.SetTime(19.9)
    assert failure.thrust_output.Eval(context)[4] == 5.0
    context.SetTime(20.0)
    assert list(failure.thrust_output.Eval(context)) == [1, 2, 3, 4, 0]
    jump = NavigationJump(30.0, (3.0, -1.0))
    context = jump.CreateDefaultContext()
    jump.estimated_input.FixValue(context, np.arange(12.0))
    context.SetTime(30.0)
    assert list(jump.estimated_state_output.Eval(context)[:3]) == [3.0, 0.0, 2.0]
    with pytest.raises(ValueError, match="thruster must be one of"):
        ThrusterFailure("left", 0.0)


def test_rules_back_off_away_from_the_map_abort_straight_up_reference_at_speed():
    rules = SafetyRules()
    x = np.zeros(12)
    x[:3] = (10.0, 0.0, -5.0)
    target = back_off_target(rules, x, np.array([[7.0, 0.0, -5.0], [30.0, 0.0, -5.0]]))
    assert np.allclose(target, (15.0, 0.0, -5.0))
    assert back_off_target(rules, x, np.array([[40.0, 0.0, -5.0]])) is None
    assert np.allclose(abort_target(rules, x), (10.0, 0.0, -1.0))
    record = np.array([3, 3, 100.0, 10.0, 0.0, -5.0, 0.5, 10.0, 0.0, -1.0])
    ref = response_reference(rules, record, 110.0)
    assert np.allclose(ref, (10.0, 0.0, -2.0, 0.5, 0.0, 0.0, 0.3, 0.0))
    assert np.allclose(response_reference(rules, record, 200.0)[:3], (10.0, 0.0, -1.0))
    with pytest.raises(ValueError, match="silence_s"):
        SafetyRules(silence_s=0.0)


def _supervisor(behaviour="replan"):
    legs = (Leg("survey", 0, behaviour, "finished", 1000.0),)
    builder = DiagramBuilder()
    sup = builder.AddSystem(MissionSupervisor(
        legs, {"path": 0, "follow": 1, "replan": 2, "response": 3}, 0.5,
        sensors=("multibeam", "profiler")))
    diagram = builder.Build()
    simulator = Simulator(diagram)
    root = simulator.get_mutable_context()
    context = sup.GetMyMutableContextFromRoot(root)
    x = np.zeros(12)
    x[:3] = (0.0, 0.0, -5.0)
    sup.state_input.FixValue(context, x)
    sup.status_inputs["replan"].FixValue(context, [0.0, 0.0, 0.0])
    sup.reference_input.FixValue(context, np.r_[x[:3], 0.0, np.zeros(4)])
    sup.map_input.FixValue(context, OnlineMap(0.5))
    for name in ("multibeam", "profiler"):
        sup.returns_inputs[name].FixValue(context, _returns(0.0, True))
    return sup, simulator, context, x


def _mode(sup, context) -> tuple[str, int]:
    record = sup.response_output.Eval(context)
    return RESPONSES[int(record[0])], sup.behaviour_output.Eval(context)


def test_supervisor_holds_on_a_silent_sonar_and_resumes_when_it_returns():
    sup, simulator, context, _ = _supervisor("replan")
    sup.returns_inputs["multibeam"].FixValue(context, _returns(3.0, True, 2))
    simulator.AdvanceTo(3.2)
    assert _mode(sup, context) == ("none", 2)
    sup.returns_inputs["multibeam"].FixValue(context, silenced(_returns(3.5, True, 3)))
    simulator.AdvanceTo(7.9)
    assert _mode(sup, context)[0] == "none"  # silent for 4.5 s at the last check: not yet
    simulator.AdvanceTo(8.1)
    assert _mode(sup, context) == ("hold", 3)
    sup.returns_inputs["multibeam"].FixValue(context, _returns(9.0, True, 4))
    simulator.AdvanceTo(9.1)
    assert _mode(sup, context) == ("none", 2)
    # Beams without an echo (open water beside a side-looking fan) are data, not silence.
    for k, t in enumerate(np.arange(9.5, 20.0, 0.5)):
        sup.returns_inputs["multibeam"].FixValue(context, _returns(t, False, 5 + k))
        simulator.AdvanceTo(t + 0.1)
    assert _mode(sup, context) == ("none", 2)


def test_supervisor_aborts_on_a_jump_and_ends_the_dive_at_the_surface():
    sup, simulator, context, x = _supervisor()
    simulator.AdvanceTo(2.0)
    x[0] += 2.0  # more than jump_m in one period
    sup.state_input.FixValue(context, x)
    simulator.AdvanceTo(2.6)
    assert _mode(sup, context) == ("abort", 3)
    started = sup.response_output.Eval(context)[2]
    rise = 0.3 * (2.6 - started)  # at SafetyRules.speed from where it began
    assert np.allclose(sup.response_reference_output.Eval(context)[:3], (2.0, 0.0, -5 + rise))
    x[2] = -1.2
    sup.state_input.FixValue(context, x)
    simulator.AdvanceTo(3.1)
    assert sup.outcomes(context) == ["aborted"]
    assert sup.monitor(simulator.get_context()).message() == "mission complete"


def test_supervisor_backs_off_from_the_map_when_tracking_fails():
    sup, simulator, context, x = _supervisor()
    online = OnlineMap(0.5)  # one return 3 m behind the vehicle (-x)
    online.catch_up(ScanLog().append(ScanBatch.make(0.0, "multibeam", (0.0, 0.0, -5.0),
                                                    [[-1.0, 0.0, 0.0]], [3.0], 20.0)))
    sup.map_input.FixValue(context, online)
    sup.reference_input.FixValue(context, np.r_[3.0, 0.0, -5.0, 0.0, np.zeros(4)])
    simulator.AdvanceTo(4.9)
    assert _mode(sup, context)[0] == "none"  # error since t = 0, for < tracking_s
    simulator.AdvanceTo(5.1)
    record = sup.response_output.Eval(context)
    assert _mode(sup, context)[0] == "back_off"
    assert record[7] > 4.0 and abs(record[8]) < 0.5  # away (+x) from the voxel at x = -3


@pytest.mark.parametrize("speed, response", [(0.3, "none"), (0.05, "back_off")])
def test_a_step_the_vehicle_closes_is_not_a_fault(speed, response):
    """The reference steps 9 m down at t = 0 (a COLA2 section's depth, held from its start):
    closed at 0.3 m/s the error stays above 2 m for 20 s without a response; closed at
    0.05 m/s (a failed heave thruster) it is a tracking error after 5 s."""
    sup, simulator, context, x = _supervisor()
    online = OnlineMap(0.5)  # one return 3 m west of the vehicle: room to back off
    online.catch_up(ScanLog().append(ScanBatch.make(0.0, "multibeam", (0.0, 0.0, -5.0),
                                                    [[-1.0, 0.0, 0.0]], [3.0], 20.0)))
    sup.map_input.FixValue(context, online)
    sup.reference_input.FixValue(context, np.r_[0.0, 0.0, -14.0, 0.0, np.zeros(4)])
    for k, t in enumerate(np.arange(0.5, 20.01, 0.5)):
        x[2] = -5.0 - speed * t
        sup.state_input.FixValue(context, x)
        sup.returns_inputs["multibeam"].FixValue(context, _returns(t, True, 2 + k))
        simulator.AdvanceTo(t + 0.1)
        if _mode(sup, context)[0] != "none":
            break
    assert _mode(sup, context)[0] == response
    assert np.linalg.norm(x[:3] - (0.0, 0.0, -14.0)) > 2.0
    if response != "none":
        assert 5.0 <= t <= 5.6


@pytest.mark.parametrize("vx, vy, commanded, response", [
    (0.3, 0.0, 0.3, "none"), (0.3, 0.0, 0.0, "none"), (0.1, 0.0, 0.3, "none"),
    (0.3, 1.5, 0.3, "abort"), (-1.0, 0.0, 0.3, "abort")])
def test_a_reference_that_starts_again_from_a_swept_vehicle_is_a_fault(vx, vy, commanded,
                                                                       response):
    """The reference starts again 1 m ahead (+x) of the vehicle every period (a replanner's
    sections, a profile follower's or an autopilot's reference), commanding `commanded` m/s
    along +x: its error never passes 2 m. Flying along x the vehicle does what it is told, by
    the reference's velocity or its position ahead, or more slowly (accelerating); carried
    sideways at 1.5 m/s or backwards at 1 m/s (a current beyond the thrusters) it moves 5 m
    or more in a window that the reference did not command: a tracking fault after two such
    windows (one is a transient), answered by an abort (the map is empty)."""
    sup, simulator, context, x = _supervisor()
    for k, t in enumerate(np.arange(0.0, 20.01, 0.5)):
        x[0], x[1] = vx * t, vy * t
        sup.state_input.FixValue(context, x)
        sup.reference_input.FixValue(context, np.r_[x[0] + 1.0, x[1], -5.0, 0.0,
                                                    commanded, 0.0, 0.0, 0.0])
        sup.returns_inputs["multibeam"].FixValue(context, _returns(t, True, 2 + k))
        simulator.AdvanceTo(t + 0.1)
        if _mode(sup, context)[0] != "none":
            break
    assert _mode(sup, context)[0] == response
    if response != "none":
        assert t == 2 * SafetyRules().tracking_s
        assert CAUSES[int(sup.response_output.Eval(context)[1])] == "tracking_error"


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # no survey samples: null statistics
def test_a_current_the_thrusters_cannot_hold_is_a_tracking_fault():
    """2.5 m/s onto the breakwater (the thrusters hold 1.02 m/s across the hull and 1.44 m/s
    along it, docs/vehicle.md) sweeps the vehicle towards the blocks while the replanner's
    sections start again from it once a second: the supervisor backs off after two tracking
    windows. In the mission's own sea (0.3 m/s onshore, tide, turbulence, swell) the whole
    dive flies without a response."""
    from drake_auv.mission.report.summary import summarise
    from drake_auv.mission.runner import run_mission

    swept = run_mission(load_mission("breakwater_current", overrides=[
        "ocean.current.speed_mps=2.5", "limits.max_time_s=15"]), progress=False)
    first = summarise(swept)["responses"][0]
    assert first["cause"] == "tracking_error" and first["response"] == "back_off"
    assert first["start_s"] <= 2 * SafetyRules().tracking_s
    calm = run_mission(load_mission("breakwater_current"), progress=False)
    summary = summarise(calm)
    assert summary["responses"] == [] and not summary["mission"]["aborted"]
    assert calm.dive.completed


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # no survey samples: null statistics
def test_a_navigation_jump_in_a_dive_ends_it_with_an_abort():
    from drake_auv.mission.report.summary import summarise
    from drake_auv.mission.runner import run_mission

    spec = load_mission("breakwater", overrides=[
        "limits.max_time_s=60", "faults.navigation_jump.time_s=10",
        "faults.navigation_jump.error_m=3"])
    result = run_mission(spec, progress=False)
    summary = summarise(result)
    assert summary["responses"][0] == dict(response="abort", cause="navigation_jump",
                                           start_s=10.0, end_s=None)
    assert summary["mission"]["aborted"] and result.dive.completed
    assert summary["faults"]["navigation_jump"]["error_m"] == 3.0
    assert result.log.state[-1, 2] > -1.5  # at the surface
