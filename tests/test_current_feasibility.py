"""A plan in a current: thrust and ground speed per lane and contour from the vehicle's damping
and thrust limits, warnings, durations at ground speed, lanes aligned with the current."""

import numpy as np
import pytest

from drake_auv.planning.path import PlannedPath
from drake_auv.vehicle.control import axis_force_limits
from drake_auv.vehicle.current_feasibility import (PlanCurrent, aligned_sweep_angle,
                                                   current_markdown, current_report,
                                                   parse_current, thrust_share)
from drake_auv.vehicle.model import Girona500Params


def _two_lanes(n=41, length=20.0):
    """East along y = 0 facing east, then north along x = length facing north; 0.5 m apart."""
    east = np.column_stack([np.linspace(0, length, n), np.zeros(n), np.full(n, -5.0)])
    north = np.column_stack([np.full(n, length), np.linspace(0, length, n), np.full(n, -5.0)])
    points = np.vstack([east, north[1:]])
    heading = np.concatenate([np.zeros(n), np.full(n - 1, np.pi / 2)])
    return PlannedPath(points, heading, (0.0, 0.0, -1.0),
                np.array(["planar"] * len(points), dtype=object))


def test_the_thrust_share_is_the_damping_over_the_axis_limit():
    p = Girona500Params()
    limits = axis_force_limits(p)
    east = np.array([[1.0, 0.0, 0.0]])
    # Holding station (ground speed 0) in a 0.5 m/s current from the side (towards north):
    # sway holds d U^2 = 148 x 0.25 = 37 N of its 153.8 N.
    share, force = thrust_share(east, np.zeros(1), 0.0, np.array([0.0, 0.5]), p)
    assert force[0] == pytest.approx([0.0, -37.0, 0.0])
    assert share[0] == pytest.approx(37.0 / limits[1])
    # 0.5 m/s east into a 0.3 m/s head current: 0.8 m/s through the water, surge.
    share, force = thrust_share(east, np.zeros(1), 0.5, np.array([-0.3, 0.0]), p)
    assert force[0, 0] == pytest.approx(148.0 * 0.64) and share[0] == pytest.approx(
        148.0 * 0.64 / limits[0])
    # The sway limit: sqrt(153.8 / 148) = 1.02 m/s across is the most held.
    across = np.sqrt(limits[1] / 148.0)
    assert thrust_share(east, np.zeros(1), 0.0, np.array([0.0, across * 0.999]), p)[0] < 1.0
    assert thrust_share(east, np.zeros(1), 0.0, np.array([0.0, across * 1.001]), p)[0] > 1.0


def test_still_water_flies_every_lane_as_planned():
    path = _two_lanes()
    report = current_report(path, PlanCurrent(), 0.5)
    assert [p["kind"] for p in report["pieces"]] == ["lane", "lane"]
    assert [p["length_m"] for p in report["pieces"]] == [20.0, 20.0]
    assert all(p["ground_speed_mps"] == 0.5 and p["flyable"] for p in report["pieces"])
    assert report["warnings"] == []
    assert report["duration_s"] == report["duration_planned_s"] == pytest.approx(
        path.times(0.5)[-1], abs=0.05)


def test_a_head_current_slows_a_lane_and_a_cross_current_beyond_sway_forbids_it():
    path = _two_lanes()
    # 1.2 m/s towards west: lane 1 (east) into it needs 148 x 1.7^2 = 428 N of surge's 308;
    # lane 2 (north) has it across: 148 x 1.44 = 213 N of sway's 154, even at rest.
    report = current_report(path, PlanCurrent(1.2, 270.0), 0.5)
    lane1, lane2 = report["pieces"]
    assert lane1["current_along_mps"] == pytest.approx(-1.2)
    assert lane2["current_across_mps"] == pytest.approx(1.2)  # towards west: to port
    assert lane1["limiting_axis"] == "surge" and lane1["axis_force_n"] == pytest.approx(427.7)
    expected = np.sqrt(axis_force_limits(Girona500Params())[0] / 148.0) - 1.2
    assert expected - 0.005 <= lane1["ground_speed_mps"] <= expected  # the grid's 5 mm steps
    assert lane2["limiting_axis"] == "sway" and not lane2["flyable"]
    assert report["duration_s"] is None
    assert len(report["warnings"]) == 2
    assert "flies at 0.24 m/s" in report["warnings"][0]
    assert report["warnings"][1].startswith("lane 2 (20 m) cannot be flown")


def test_the_tidal_envelope_takes_the_worst_end_and_the_duration_grows_at_ground_speed():
    path = _two_lanes()
    # 0.9 m/s towards west +- 0.3: lane 1 at 1.2 m/s of head current at the worst end.
    report = current_report(path, PlanCurrent(0.9, 270.0, 0.3), 0.5)
    lane1 = report["pieces"][0]
    assert lane1["ground_speed_mps"] == 0.5 and lane1["thrust_share"] < 1.0
    assert lane1["thrust_share_worst"] > 1.0 and 0.2 < lane1["ground_speed_worst_mps"] < 0.25
    assert report["duration_worst_s"] is None  # lane 2 at 1.2 m/s across
    flyable = current_report(path, PlanCurrent(0.9, 270.0, 0.1), 0.5)
    assert flyable["duration_worst_s"] > flyable["duration_s"] == pytest.approx(
        flyable["duration_planned_s"])
    assert any("at the tide's worst flies at" in w for w in flyable["warnings"])
    text = current_markdown(flyable)
    assert "| lane 1 | 20 |" in text and "tide +- 0.1 m/s" in text


def test_contours_and_transits_are_pieces_of_their_own():
    path = _two_lanes()
    labels = path.labels.copy()
    labels[45:60] = "slice"
    labels[60:65] = "transit"
    report = current_report(PlannedPath(path.points, path.heading, path.sensor_dir, labels),
                            PlanCurrent(0.2, 0.0), 0.5)
    assert [(p["kind"], p["index"]) for p in report["pieces"]] == [
        ("lane", 1), ("turn", 1), ("contour", 1), ("transit", 1), ("lane", 2)]


def test_lanes_aligned_with_the_current_run_along_its_axis():
    assert aligned_sweep_angle(PlanCurrent(0.3, 0.0)) == 90.0  # towards north: lanes along y
    assert aligned_sweep_angle(PlanCurrent(0.3, 90.0)) == 0.0
    assert aligned_sweep_angle(PlanCurrent(0.3, 225.0)) == 45.0  # towards south-west


def test_bad_currents_are_refused_in_one_line():
    assert parse_current("0.4,90", 0.1) == PlanCurrent(0.4, 90.0, 0.1)
    with pytest.raises(ValueError, match="--current: expected 'SPEED,TOWARDS_DEG'"):
        parse_current("0.4")
    with pytest.raises(ValueError, match=r"SPEED = -1 is out of range; must be in \[0, 5\]"):
        parse_current("-1,0")
    with pytest.raises(ValueError, match=r"--tide: 9 is out of range"):
        parse_current("0.4,0", 9.0)
    with pytest.raises(ValueError, match="speed must be > 0"):
        current_report(_two_lanes(), PlanCurrent(), 0.0)


def test_plan_reports_the_current_and_aligns_the_lanes_with_it(tmp_path, small_tif, capsys):
    import json

    from drake_auv.cli import main

    common = [str(small_tif), "--no-figures", "--no-3d-metrics", "--export", "", "--speed",
              "0.5", "--current", "1.1,90"]
    assert main(["plan", *common, "--sweep-angle", "90", "-o", str(tmp_path / "a")]) == 0
    printed = capsys.readouterr().out
    report = json.loads((tmp_path / "a" / "report.json").read_text())["current"]
    kinds = {p["kind"] for p in report["pieces"]}
    assert {"lane", "contour"} <= kinds
    lanes = [p for p in report["pieces"] if p["kind"] == "lane" and p["length_m"] > 10]
    # Lanes along y in a current towards east: 1.1 m/s across is beyond what sway holds.
    assert lanes and all(not p["flyable"] for p in lanes)
    assert report["duration_s"] is None
    assert "cannot be flown" in printed and "--align-with-current (sweep angle 0 deg" in printed
    assert "## In a current: 1.1 m/s towards 90 deg" in (tmp_path / "a" / "report.md").read_text()
    assert main(["plan", *common, "--align-with-current", "-o", str(tmp_path / "b")]) == 0
    aligned = json.loads((tmp_path / "b" / "report.json").read_text())
    assert aligned["parameters"]["sweep_angle_deg"] == pytest.approx(0.0)
    lanes = [p for p in aligned["current"]["pieces"] if p["kind"] == "lane"
             and p["length_m"] > 10]
    assert lanes and all(p["flyable"] for p in lanes)
    assert "--align-with-current (" not in capsys.readouterr().out


@pytest.mark.parametrize("extra, message", [
    (["--tide", "0.2"], "--tide and --align-with-current need --current"),
    (["--current", "0.3,0", "--align-with-current", "--sweep-angle", "10"],
     "--sweep-angle or --align-with-current, not both"),
    (["--current", "0.3"], "--current: expected 'SPEED,TOWARDS_DEG'")])
def test_plan_refuses_a_bad_current(tmp_path, small_tif, capsys, extra, message):
    from drake_auv.cli import main

    assert main(["plan", str(small_tif), "--no-figures", "-o", str(tmp_path / "o"),
                 *extra]) == 2
    assert message in capsys.readouterr().err


def test_the_offer_of_aligned_lanes_states_their_thrust_against_the_plans():
    from drake_auv.vehicle.current_feasibility import summary_lines

    path = _two_lanes()  # lanes east and north
    report = current_report(path, PlanCurrent(0.6, 0.0), 0.5)  # towards north
    along = report["aligned_lanes"]
    # Along the axis: 1.1 m/s through the water into it, surge (two thrusters, 307.6 N).
    assert along["thrust_share"] == pytest.approx(148.0 * 1.1 ** 2 / 307.6, abs=2e-3)
    # The plan's: lane 1 has it across (sway, one thruster), lane 2 behind it.
    assert report["lanes"]["thrust_share"] == pytest.approx(148.0 * 0.36 / 153.8, abs=2e-3)
    lines = summary_lines(report, 0.0)
    assert lines[-1].startswith("lanes along the current: --align-with-current (sweep angle "
                                "90 deg instead of 0)")
    assert "0.58 / 0.58 along it, 0.35 / 0.35 now" in lines[-1]
    assert not any("align" in line for line in summary_lines(report, 90.0))
