"""The `hover` step: station keeping at a point, one step module of the registry."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator

from drake_auv.mission.config import MissionFileError, mission_from_dict
from drake_auv.mission.runner import run_mission
from drake_auv.mission.steps.hover import HoverLeg, station_keeper
from drake_auv.signals import BehaviourStatus, Reference, VehicleState


def _mission(hover: dict, tmp_path):
    return mission_from_dict({"name": "hover", "site": {"scenario": "pool"},
                              "steps": [{"hover": hover}]}, tmp_path, "hover.yaml")


def test_hover_file_rules(tmp_path):
    assert _mission({"duration_s": 10}, tmp_path).steps[0].at == "start"
    assert _mission({"at": [1, 2, -3], "duration_s": 10}, tmp_path).steps[0].at == (1, 2, -3)
    with pytest.raises(MissionFileError, match=r"steps\[0\]\.hover\.at: 'here' is not 3 finite "
                                               r"numbers or 'start'"):
        _mission({"at": "here", "duration_s": 10}, tmp_path)
    with pytest.raises(MissionFileError, match=r"steps\[0\]\.hover\.duration_s"):
        _mission({"duration_s": 0}, tmp_path)


def test_the_station_keeper_holds_the_pose_the_leg_began_at():
    keeper = station_keeper()({1: HoverLeg(None, None, 10.0)})
    context = keeper.CreateDefaultContext()
    x = np.zeros(12)
    x[:3], x[5] = (1.0, 2.0, -3.0), 0.5
    keeper.state_input.FixValue(context, x)
    keeper.leg_input.FixValue(context, [0.0, 0.0])
    simulator = Simulator(keeper, context)
    simulator.AdvanceTo(1.0)  # leg 0 is not its own
    assert BehaviourStatus(keeper.status_output.Eval(context)).leg == -1
    keeper.leg_input.FixValue(context, [1.0, 1.0])
    simulator.AdvanceTo(2.0)
    x[:3] = (5.0, 5.0, -5.0)  # pushed away: the reference stays where the leg began
    keeper.state_input.FixValue(context, x)
    simulator.AdvanceTo(6.0)
    reference = Reference(keeper.reference_output.Eval(context))
    assert reference.position.tolist() == [1.0, 2.0, -3.0] and reference.yaw == 0.5
    assert not reference.rates.any()
    status = BehaviourStatus(keeper.status_output.Eval(context))
    assert status.leg == 1 and status.finished == 0 and status.progress == pytest.approx(0.5)
    simulator.AdvanceTo(11.05)
    assert keeper.status_output.Eval(context).tolist() == [1.0, 1.0, 1.0]


def test_a_hover_mission_holds_the_point_for_its_duration(tmp_path):
    spec = _mission({"at": [-2.0, 1.0, -3.0], "heading_deg": 90.0, "duration_s": 15.0},
                    tmp_path)
    result = run_mission(spec, progress=False)
    assert [leg.behaviour for leg in result.plan.legs] == ["path", "hover"]
    assert result.dive.outcomes == ["goal", "goal"] and result.dive.completed
    hovering = result.log.leg_at == 1
    held = result.log.times[hovering]
    assert held[-1] - held[0] == pytest.approx(15.0, abs=0.6)
    estimated = VehicleState(result.log.estimated[hovering])
    error = np.linalg.norm(estimated.position - [-2.0, 1.0, -3.0], axis=1)
    assert error.max() < 0.5, error.max()  # arrived within 1.5 m, then holding
    assert np.abs(np.angle(np.exp(1j * (estimated.yaw - np.pi / 2)))).max() < 0.1


def test_a_hover_point_inside_the_world_or_above_the_surface_is_refused(tmp_path):
    from drake_auv.mission.plan import plan_mission
    from drake_auv.mission.site import load_site

    for at, problem in (([-2.0, 1.0, -300.0], "inside the world"), ([-2.0, 1.0, 2.0], "above")):
        spec = mission_from_dict({"name": "hover", "site": {"scenario": "pool"}, "steps": [
            {"hover": {"duration_s": 5}}, {"hover": {"at": at, "duration_s": 5}}]},
            tmp_path, "hover.yaml")
        with pytest.raises(MissionFileError, match=r"steps\[1\]\.hover\.at: the point held: .*"
                                                   + problem):
            plan_mission(spec, load_site(spec.site, spec.seed))
