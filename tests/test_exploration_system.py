"""The ViewPlanner system, the explore step in mission files and at the command line, and a
short explore dive on the boulder in the one mission Diagram."""

from __future__ import annotations

import copy
import numpy as np
import pytest
import yaml
from pydrake.systems.analysis import Simulator

from drake_auv.cli import main
from drake_auv.exploration.planner import ExploreParameters
from drake_auv.exploration.view_planner import ViewPlanner
from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mapping.scan_log import ScanLog
from drake_auv.mission.config import MissionFileError, load_mission, mission_from_dict
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.steps.explore import NO_RETURN_CLEAR_M
from drake_auv.mission.site import load_site

from test_exploration import scanned_wall  # noqa: E402  (tests/ is on sys.path)


def wall_map() -> OnlineMap:
    """The octree of a log of port-fan pings at a wall x = 0 (see `scanned_wall`)."""
    from drake_auv.mapping.octree_map import OctreeMap

    log = ScanLog()
    for batch in scanned_wall(OctreeMap(0.5), np.arange(-3.0, 3.0, 0.25)):
        log = log.append(batch)
    online = OnlineMap(0.5)
    online.catch_up(log)
    return online


def planner_context(leg: float):
    params = ExploreParameters(region=(-2.0, -8.0, -22.0, 3.0, 8.0, -8.0), min_gain_m2=2.0)
    planner = ViewPlanner({0: params}, period=2.0, seed=0)
    context = planner.CreateDefaultContext()
    x = np.zeros(12)
    x[:3] = (-10.0, 0.0, -15.0)
    planner.GetInputPort("estimated_state").FixValue(context, x)
    planner.GetInputPort("leg").FixValue(context, [leg, 0.0])
    planner.GetInputPort("map").FixValue(context, wall_map())
    simulator = Simulator(planner, context)
    simulator.Initialize()
    return planner, simulator, x


def test_view_planner_flies_towards_a_view_of_the_wall():
    planner, simulator, x = planner_context(0.0)
    context = simulator.get_context()
    leg, finished, viewpoints = planner.GetOutputPort("status").Eval(context)
    assert (leg, finished, viewpoints) == (0.0, 0.0, 1.0)
    target = planner.view(context).target
    assert target is not None
    start = planner.GetOutputPort("reference").Eval(context)
    assert np.allclose(start[:3], x[:3], atol=1e-6) and np.linalg.norm(start[4:7]) > 0.1
    simulator.AdvanceTo(1.9)  # before the next planning step: along the same path
    later = planner.GetOutputPort("reference").Eval(context)
    assert (np.linalg.norm(later[:3] - target.position)
            < np.linalg.norm(start[:3] - target.position))
    step = planner.GetOutputPort("step").Eval(context)
    assert step[2] >= 2.0 and 0.0 < step[5] < 1.0  # gain, believed coverage


def test_the_reference_keeps_the_guard_above_the_dvl_seabed():
    """The seabed guard: however the path descends, the reference stays GUARD clearances above
    the DVL's seabed (and its vertical rate is not downwards there); no lock, no guard."""
    from drake_auv.exploration.view_planner import GUARD

    planner, simulator, x = planner_context(0.0)
    context = simulator.get_context()
    free = planner.GetOutputPort("reference").Eval(context).copy()
    seabed = free[2] - 0.5  # a seabed just under the reference
    planner.GetInputPort("seabed_elevation").FixValue(context, [seabed])
    guarded = planner.GetOutputPort("reference").Eval(context)
    assert guarded[2] == pytest.approx(seabed + GUARD * 3.0) and guarded[6] >= 0.0
    np.testing.assert_array_equal(np.delete(guarded, [2, 6]), np.delete(free, [2, 6]))
    planner.GetInputPort("seabed_elevation").FixValue(context, [np.nan])
    np.testing.assert_array_equal(planner.GetOutputPort("reference").Eval(context), free)


def test_view_planner_idles_on_another_leg():
    planner, simulator, x = planner_context(1.0)
    context = simulator.get_context()
    assert planner.GetOutputPort("status").Eval(context)[0] == -1.0
    assert planner.view(context).target is None
    reference = planner.GetOutputPort("reference").Eval(context)
    assert np.allclose(reference[:3], x[:3]) and np.allclose(reference[4:], 0.0)


def explore_mission(**explore) -> dict:
    body = dict(region=[-13.0, -11.0, -40.5, 16.0, 11.0, -26.0], omega=6.0, clearance_m=3.0)
    body.update(explore)
    return dict(name="explore_test", site=dict(scenario="boulder"), steps=[{"explore": body}])


def test_omega_below_the_clearance_is_one_line():
    with pytest.raises(MissionFileError) as err:
        mission_from_dict(explore_mission(omega=2.0), ".", "m.yaml")
    assert str(err.value).startswith("m.yaml: steps[0].explore.omega: 2 m is not above "
                                     "clearance_m 3 m")
    with pytest.raises(MissionFileError, match=r"steps\[0\].explore.strategy: 'best'"):
        mission_from_dict(explore_mission(strategy="best"), ".", "m.yaml")


@pytest.mark.parametrize("region, what", [
    ([100.0, 100.0, -40.0, 120.0, 120.0, -20.0], "holds no part of the world"),
    ([-20.0, -20.0, -43.0, 20.0, 20.0, -40.8], "holds no water the vehicle can reach"),
    ([-2.0, -2.0, -36.0, 2.0, 2.0, -32.0], "holds no water the vehicle can reach"),
])
def test_regions_the_vehicle_cannot_explore(region, what):
    spec = mission_from_dict(explore_mission(region=region), ".", "m.yaml")
    with pytest.raises(MissionFileError,
                       match=r"explore_test: steps\[0\].explore.region: .*" + what):
        plan_mission(spec, load_site(spec.site, 0))


def test_bad_explore_step_exits_2_at_the_command_line(tmp_path, capsys):
    path = tmp_path / "below.yaml"
    path.write_text(yaml.safe_dump(explore_mission(
        region=[-20.0, -20.0, -60.0, 20.0, 20.0, -45.0])))
    code = main(["run", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0 and "steps[0].explore.region" in err, err


def test_explore_dive_gains_coverage_without_contact():
    from drake_auv.mission.report.summary import summarise
    from drake_auv.mission.runner import run_mission

    spec = load_mission("boulder_explore", overrides=["limits.max_time_s=60"])
    assert spec.site.prior is None
    result = run_mission(spec, progress=False)
    summary = summarise(result)
    assert summary["coverage"]["multibeam"] > 0.1
    assert not summary["contact"] and summary["min_clearance_m"] > 1.5
    exploration = summary["exploration"]
    assert exploration["viewpoints"] >= 3 and exploration["strategy"] == "gain"
    assert 0.0 < exploration["believed_coverage"] < 1.0 and exploration["stopped"] == "time"
    # the DVL's beams reach the map: the seabed under the vehicle is in the scan log
    log = result.mapping.scan_log
    dvl = [b for b in log.batches() if b.source == log.sources.index("dvl")]
    assert len(dvl) > 100 and all(len(b.ranges) == 4 for b in dvl)
    # explore's map (and its copies) clears along a beam without an echo only 12 m
    assert spec.steps[0].no_return_clear_m == NO_RETURN_CLEAR_M == 12.0
    assert result.mapping.online_map.map.no_return_clear_m == NO_RETURN_CLEAR_M
    assert copy.deepcopy(result.mapping.online_map).map.no_return_clear_m == NO_RETURN_CLEAR_M


def test_explore_leg_ends_when_the_planner_says_finished():
    from drake_auv.mission.legs import Leg, goal_reached

    leg = Leg("explore", 0, "explore", "finished", 1800.0)
    args = (leg, 2, 10.0, np.zeros(12), np.zeros(4))
    assert not goal_reached(*args, np.array([2.0, 0.0, 5.0]))
    assert not goal_reached(*args, np.array([1.0, 1.0, 5.0]))  # another leg's
    assert goal_reached(*args, np.array([2.0, 1.0, 5.0]))
