"""One mission Diagram: the supervisor flies every step in one dive, on built-in sites and on
a user's own files, deterministically, and bad mission files get one clear line."""

import base64
import csv
import json
import re

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import InputPortIndex

from drake_auv.cli import main
from drake_auv.mission.config import load_mission
from drake_auv.mission.diagram import build_mission_diagram
from drake_auv.mission.legs import Leg
from drake_auv.mission.report.summary import summarise
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.mission.supervisor import MissionSupervisor
from sites import LOCAL_ORIGIN, write_utm_site

# The boulder mission cut short: the transit, most of the loop of profile following.
SHORT_BOULDER = ["limits.max_time_s=150", "steps.1.follow.loops=0.5"]


@pytest.fixture(scope="module")
def boulder_run():
    spec = load_mission("boulder", overrides=SHORT_BOULDER)
    return run_mission(spec, progress=False)


def test_one_dive_carries_vehicle_navigation_and_map_across_legs(boulder_run):
    result = boulder_run
    names = [p.name for p in result.dive.phases]
    assert names[:2] == ["transit", "follow"]
    follow = next(p for p in result.dive.phases if p.name == "follow")
    assert result.dive.outcomes[0] == "goal" and follow.start_s > 5.0
    # One dive: the vehicle never jumps, the navigation error keeps growing across the legs.
    step = np.linalg.norm(np.diff(result.log.state[:, :3], axis=0), axis=1)
    assert step.max() < 0.2  # 0.1 s samples at <= 1.4 m/s
    error = np.linalg.norm(result.log.estimated[:, :3] - result.log.state[:, :3], axis=1)
    at_follow = np.searchsorted(result.log.times, follow.start_s)
    assert error[at_follow] > 0.05 and error[-1] > error[at_follow]
    # The map is fed from t = 0 by both sonars, the profiler through the following leg.
    sources = {b.source for b in result.mapping.scan_log.batches()}
    assert sources == {0, 1}
    assert len(result.mapping.online_map.map.occupied_points()) > 100
    # Profile following holds its offset once it found the boulder.
    settled = (result.log.times > follow.start_s + 40.0) & (result.log.times < follow.end_s)
    assert np.all(np.abs(result.log.distance[settled] - 3.0) < 1.5)
    assert result.log.clearance.min() > 1.0


def test_unselected_behaviours_do_no_work(boulder_run):
    # No survey leg flew: the replanner never planned; the controller only on its leg.
    assert len(boulder_run.mapping.replanning) == 0
    follow = next(p for p in boulder_run.dive.phases if p.name == "follow")
    during = (boulder_run.log.times >= follow.start_s) & (boulder_run.log.times < follow.end_s)
    valid = boulder_run.log.profile[:, 5] == 1.0
    assert valid[during].any() and not valid[boulder_run.log.times < follow.start_s - 1.0].any()


def test_two_contexts_of_one_diagram_have_their_own_maps():
    spec = load_mission("boulder")
    site = load_site(spec.site, spec.seed)
    diagram, handles = build_mission_diagram(site, spec)
    mapper = handles.mapper
    flown, untouched = diagram.CreateDefaultContext(), diagram.CreateDefaultContext()
    Simulator(diagram, flown).AdvanceTo(3.0)
    fed = mapper.map_output.Eval(mapper.GetMyContextFromRoot(flown))
    assert len(fed.map.occupied_points()) > 0
    other = mapper.GetMyContextFromRoot(untouched)
    assert mapper.scan_log(other).count == 0
    assert len(mapper.map_output.Eval(other).map.occupied_points()) == 0
    # a survey's map clears along a beam without an echo to the sonar's range (OctoMap's way)
    assert fed.map.no_return_clear_m == np.inf
    assert mapper.multibeam_stride == 2 and not fed.map.discretize  # the defaults


def test_the_on_line_maps_insertion_is_set_from_the_mission():
    spec = load_mission("boulder", overrides=["replanner.multibeam_stride=4",
                                              "replanner.discretize=true"])
    _, handles = build_mission_diagram(load_site(spec.site, spec.seed), spec)
    assert handles.mapper.multibeam_stride == 4 and handles.mapper.discretize


def test_the_multibeam_is_scored_at_every_ping():
    """The multibeam coverage recorder casts with the multibeam, not at the camera's 2 Hz."""
    spec = load_mission("breakwater")
    _, handles = build_mission_diagram(load_site(spec.site, spec.seed), spec)
    period = handles.multibeam_coverage.GetUniquePeriodicDiscreteUpdateAttribute().period_sec()
    assert period == handles.multibeam.period == 0.1
    assert handles.camera_coverage.GetUniquePeriodicDiscreteUpdateAttribute().period_sec() == 0.5


def test_same_seed_same_numbers_and_the_seed_matters():
    overrides = ["limits.max_time_s=40"]

    def numbers(seed):
        summary = summarise(run_mission(load_mission("breakwater", seed=seed,
                                                     overrides=overrides), progress=False))
        summary.pop("timing")
        return json.dumps(summary)

    first = numbers(3)
    assert numbers(3) == first
    assert numbers(4) != first  # another prior-map error and drift


def test_supervisor_sequences_legs_switches_and_terminates():
    legs = (Leg("transit", 0, "path", "arrive", 100.0, target=(0.0, 0.0, -5.0)),
            Leg("survey", 1, "replan", "finished", 100.0))
    supervisor = MissionSupervisor(legs, {"path": 0, "replan": 1})
    context = supervisor.CreateDefaultContext()
    state = np.zeros(12)
    state[2] = -5.0
    supervisor.state_input.FixValue(context, state)
    supervisor.status_inputs["path"].FixValue(context, [0.0, 0.0, 0.5])  # leg 0's path flying
    supervisor.status_inputs["replan"].FixValue(context, [-1.0, 0.0, 0.0])
    simulator = Simulator(supervisor, context)
    simulator.AdvanceTo(1.9)
    assert supervisor.leg_output.Eval(context).tolist() == [0.0, 0.0]
    assert supervisor.behaviour_output.Eval(context) == InputPortIndex(0)
    supervisor.status_inputs["path"].FixValue(context, [0.0, 1.0, 1.0])  # flown, at 1.9 s
    simulator.AdvanceTo(2.6)
    assert supervisor.leg_output.Eval(context).tolist() == [1.0, 2.0]
    assert supervisor.behaviour_output.Eval(context) == InputPortIndex(1)
    supervisor.status_inputs["replan"].FixValue(context, [1.0, 1.0, 9.0])
    simulator.set_monitor(supervisor.monitor)
    status = simulator.AdvanceTo(50.0)
    assert status.reason() == status.ReturnReason.kReachedTerminationCondition
    assert context.get_time() < 4.0 and supervisor.outcomes(context) == ["goal", "goal"]


def test_a_leg_that_never_arrives_times_out():
    legs = (Leg("transit", 0, "path", "arrive", 3.0, target=(50.0, 0.0, -5.0)),)
    supervisor = MissionSupervisor(legs, {"path": 0})
    context = supervisor.CreateDefaultContext()
    supervisor.state_input.FixValue(context, np.zeros(12))
    supervisor.status_inputs["path"].FixValue(context, [0.0, 1.0, 1.0])
    simulator = Simulator(supervisor, context)
    simulator.set_monitor(supervisor.monitor)
    simulator.AdvanceTo(20.0)
    assert supervisor.outcomes(context) == ["timed out"] and 3.0 <= context.get_time() <= 3.5


def test_a_mission_on_the_users_own_files_in_utm(tmp_path):
    mission = write_utm_site(tmp_path)
    out = tmp_path / "out"
    assert main(["run", str(mission), "-o", str(out), "--quiet", "--no-html"]) == 0
    summary = json.loads((out / "report.json").read_text())
    # the short follow leg sees a third of the target with each sensor (measured: 1/3, 1/3)
    assert summary["coverage"]["multibeam"] > 0.2 and summary["coverage"]["camera"] > 0.2
    assert summary["contact"] is False and summary["min_clearance_m"] > 1.0
    assert {"mean_m", "sd_m", "min_m", "map_mean_m"} <= set(summary["distance_to_target"])
    assert [p["name"] for p in summary["phases"]][:2] == ["transit", "follow"]
    assert all(p["start_s"] <= p["end_s"] for p in summary["phases"])
    with open(out / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0]) == ["t", "x", "y", "z", "roll", "pitch", "yaw", "est_x", "est_y",
                             "est_z", "current_x", "current_y", "current_z"]
    east = np.array([float(r["x"]) for r in rows])
    assert np.all(np.abs(east - LOCAL_ORIGIN[0]) < 100.0)  # back in UTM eastings
    dot = (out / "diagram.dot").read_text()
    assert "mission_supervisor" in dot
    # every vector port labelled with its signal's fields, the logs' inputs too
    assert dot.count(">reference [x y z yaw vx vy vz yaw_rate]<") >= 2
    assert ">leg [index start_s]<" in dot and ">status [leg finished progress]<" in dot
    assert ">data [mode cause start_s x0 y0 z0 yaw0 x1 y1 z1]<" in dot  # the response log


@pytest.mark.parametrize("change, message", [
    (lambda raw: raw.update(colour="red"), "colour"),
    (lambda raw: raw["steps"].insert(0, {"survey": {"replanning": True}}), "steps"),
    (lambda raw: raw["steps"].append({"follow": {"mode": "horizontal", "offset": -1.0,
                                                  "depth": 15.0}}), "offset"),
    (lambda raw: raw["steps"].append({"follow": {"mode": "horizontal", "offset": 2.0,
                                                  "depth": 45.0}}), "seabed"),
    (lambda raw: raw["site"].update(world="missing.ply"), "missing.ply"),
])
def test_bad_mission_files_exit_with_one_line(tmp_path, capsys, change, message):
    import yaml

    mission = write_utm_site(tmp_path)
    raw = yaml.safe_load(mission.read_text())
    change(raw)
    mission.write_text(yaml.safe_dump(raw))
    assert main(["run", str(mission), "-o", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and "Traceback" not in err


def test_demo_writes_every_output(tmp_path):
    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--quiet", "--set", "limits.max_time_s=30"]) == 0
    for name in ("report.md", "report.json", "plan.png", "coverage.png", "distance.png",
                 "trajectory.csv", "diagram.dot", "mission.html"):
        assert (out / name).stat().st_size > 500, name
    html = (out / "mission.html").read_text()
    commands = b"".join(base64.b64decode(b64) for b64 in re.findall(
        r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html))
    for layer in (b"/drake_auv/world", b"/drake_auv/nominal_path", b"/drake_auv/vehicle",
                  b"/drake_auv/vehicle_trail/0", b"/drake_auv/octree", b"/drake_auv/coverage",
                  b"set_animation"):
        assert layer in commands, layer
    assert b"/Cameras/default" in commands and b"set_target" in commands  # framed
    files = listed_files((out / "report.md").read_text())
    assert {"plan.png", "mission.html", "trajectory.csv"} <= set(files)
    assert all((out / name).stat().st_size > 0 for name in files)
    t = json.loads((out / "report.json").read_text())["timing"]  # end to end, the HTML too
    assert 0 < t["reconstruction_s"] < t["outputs_s"] and t["setup_s"] > 0
    assert t["total_s"] == pytest.approx(t["setup_s"] + t["simulation_s"] + t["outputs_s"],
                                         abs=2e-4)
    assert t["simulation_s"] == t["wall_s"] and 100 < t["peak_rss_mb"] < 24 * 1024


def test_a_dive_stopped_before_its_survey_still_reports(tmp_path):
    # 10 s: the breakwater's transit only, no survey or follow sample to score (the prior
    # unshifted, so the transit's length does not hang on the seed's prior-map draw)
    result = run_mission(load_mission("breakwater", overrides=["limits.max_time_s=10",
                                                               "site.prior_error_m=0"]),
                         progress=False)
    summary = summarise(result)
    assert summary["distance_to_target"]["mean_m"] is None
    assert not summary["mission"]["completed"] and summary["phases"][0]["name"] == "transit"
    from drake_auv.mission.report.markdown import report_markdown

    text = report_markdown(summary)  # what does not apply is left out, not "n/a"
    assert "n/a" not in text and "survey samples" not in text and "viewing angle" not in text
    assert f"minimum over the dive {summary['distance_to_target']['min_m']:.2f} m" in text


def listed_files(report_md: str) -> list[str]:
    line = next(x for x in report_md.splitlines() if x.startswith("Files: "))
    return re.findall(r"`([^`]+)`", line)
