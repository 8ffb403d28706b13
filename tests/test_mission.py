"""The all-together boulder mission: short runs of the real pipeline (plan, profile following,
replanning), its report and recording, and its determinism."""

import base64
import json
import re

import numpy as np
import pytest

from drake_auv.cli import main
from drake_auv.mission import VEHICLE_RADIUS, MissionConfig, run_mission
from drake_auv.mission_report import angle_stats, summarise

SHORT = dict(follow_loops=0.2, replan_time=80.0)


def test_demo_writes_report_figures_and_recording(tmp_path):
    out = tmp_path / "demo"
    assert main(["demo", "--out", str(out), "--follow-loops", "0.2", "--replan-time", "80",
                 "--quiet"]) == 0
    for name in ("report.md", "report.json", "plan.png", "coverage.png", "distance.png"):
        assert (out / name).stat().st_size > 1000, name
    html = (out / "mission.html").read_text()
    commands = [base64.b64decode(b64) for b64 in re.findall(
        r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html)]
    animation = [c for c in commands if b"set_animation" in c]
    assert len(animation) == 1 and b"/drake_auv/vehicle" in animation[0]
    # Both dives left a trail, and the end-of-mission layers are in the scene.
    assert b"/drake_auv/vehicle_trail/0" in b"".join(commands)
    assert b"/drake_auv/vehicle_trail/1" in b"".join(commands)
    assert any(b"/drake_auv/coverage" in c for c in commands)
    assert any(b"/drake_auv/octree" in c for c in commands)
    summary = json.loads((out / "report.json").read_text())
    r = summary["results"]
    assert r["plan"]["high_slope_regions"] == 1
    assert r["plan"]["length_by_label_m"]["slice"] > 100.0
    assert not r["mission"]["contact"]
    assert r["mission"]["clearance_min_m"] > VEHICLE_RADIUS
    # Navigation drifts (compass bias, DVL scale error): the dive ends with a position error.
    assert 0.1 < r["replan"]["navigation_error_max_m"] < 5.0
    # The profile-following dive has started to image the boulder; the report says so.
    assert 0.02 < r["profile"]["camera_coverage"] < 1.0
    assert "Whole mission" in (out / "report.md").read_text()


def test_same_seed_same_numbers_and_the_seed_matters():
    first = summarise(run_mission(MissionConfig(seed=3, **SHORT), progress=False))["results"]
    again = summarise(run_mission(MissionConfig(seed=3, **SHORT), progress=False))["results"]
    assert json.dumps(first) == json.dumps(again)  # as report.json writes them (NaN too)
    other = summarise(run_mission(MissionConfig(seed=4, **SHORT), progress=False))["results"]
    assert other["plan"] != first["plan"]  # another prior-map error, another plan


def test_profile_following_holds_its_offset_in_the_mission():
    result = run_mission(MissionConfig(follow_loops=0.3, replan_time=5.0), progress=False)
    profile = result.phases[0]
    settled = profile.times > profile.times[0] + 30.0  # after the approach
    assert np.all(np.abs(profile.distance[settled] - 3.0) < 1.5)
    assert profile.clearance.min() > VEHICLE_RADIUS


def test_angle_stats_weight_by_area():
    best = np.radians([10.0, 30.0, np.nan])
    mean, sd = angle_stats(best, np.array([3.0, 1.0, 5.0]))
    assert mean == pytest.approx(15.0) and sd == pytest.approx(np.sqrt(75.0))


@pytest.mark.parametrize("field, value", [("prior_error_m", 6.0), ("omega", 0.0),
                                          ("slice_count", 0), ("follow_depth", 50.0),
                                          ("replan_time", -1.0), ("seed", -1)])
def test_bad_configuration_is_named(field, value):
    with pytest.raises(ValueError, match=field):
        MissionConfig(**{field: value})
