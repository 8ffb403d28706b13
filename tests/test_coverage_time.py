"""Coverage against mission time: the recorders' first-seen state (when each target face was
first seen), the curve and the times to 80 % / 90 % the report derives from it."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.mission.config import load_mission
from drake_auv.mission.report.figures import fig_coverage_vs_time
from drake_auv.mission.report.summary import coverage_curve, summarise, time_to_coverage
from drake_auv.mission.runner import run_mission
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh

ALTITUDE, SPEED, RATE = 2.0, 1.0, 2.0  # m, m/s, frames/s
FOOTPRINT_RADIUS = ALTITUDE * np.tan(np.radians(30.0))  # 60 deg camera, flat ground


def _strip_pass(duration=30.0, x0=-5.0):
    """A down-looking camera flown along a 20 m x 1 m strip of flat ground at 2 m altitude, at
    1 m/s from x = -5 m: the recorder, its context at the end and the strip."""
    cell = 0.25
    ground = bathymetry_to_mesh(Bathymetry(np.full((5, 81), -20.0), (cell, cell), (0.0, -0.5)))
    builder = DiagramBuilder()
    recorder = builder.AddSystem(CoverageRecorder(ground, sensor="camera", rate=RATE,
                                                  max_range=10.0))
    start, end = np.zeros(12), np.zeros(12)
    start[:3] = (x0, 0.0, -20.0 + ALTITUDE)
    end[:3] = (x0 + SPEED * duration, 0.0, -20.0 + ALTITUDE)
    state = builder.AddSystem(TrajectorySource(PiecewisePolynomial.FirstOrderHold(
        [0.0, duration], np.column_stack([start, end]))))
    builder.Connect(state.get_output_port(), recorder.true_state_input)
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(duration)
    return recorder, recorder.GetMyContextFromRoot(simulator.get_context()), ground, x0


def test_first_seen_is_when_the_camera_footprint_reaches_each_face():
    recorder, context, ground, x0 = _strip_pass()
    first = recorder.first_seen(context)
    assert np.isfinite(first).all()  # the pass covers the whole strip
    # The face is first seen at the first frame whose cone holds its centroid.
    c = ground.triangles_center
    reach = np.sqrt(FOOTPRINT_RADIUS ** 2 - c[:, 1] ** 2)
    expected = np.maximum((c[:, 0] - reach - x0) / SPEED, 0.0)
    assert np.all(first >= expected - 1e-6)
    assert np.all(first <= expected + 1.0 / RATE + 1e-6)
    # Frames come at the recorder's rate: every first-seen time is one of them.
    np.testing.assert_allclose(first * RATE, np.round(first * RATE), atol=1e-9)


def test_curve_rises_from_zero_to_the_final_coverage():
    recorder, context, ground, _ = _strip_pass()
    areas = np.asarray(ground.area_faces)
    t, share = coverage_curve(recorder.first_seen(context), areas, 30.0, period_s=2.0)
    np.testing.assert_allclose(t, np.r_[np.arange(0.0, 30.0, 2.0), 30.0])
    assert share[0] == 0.0 and np.all(np.diff(share) >= 0)
    assert share[-1] == pytest.approx(recorder.coverage(context)) and share[-1] == 1.0
    # The footprint sweeps the 20 m strip from t = 5 - r to 25 + r at 1 m/s: linear between.
    middle = (t > 8.0) & (t < 22.0)
    np.testing.assert_allclose(share[middle], (t[middle] - 5.0 + FOOTPRINT_RADIUS) / 20.0,
                               atol=0.05)
    t80 = time_to_coverage(recorder.first_seen(context), areas, 0.8)
    assert t80 == pytest.approx(5.0 + 16.0 - FOOTPRINT_RADIUS, abs=0.6)


def test_times_to_coverage_by_hand_and_bad_arguments():
    first = np.array([3.0, np.nan, 1.0, 2.0])
    areas = np.array([1.0, 1.0, 2.0, 1.0])  # shares after t = 1, 2, 3: 0.4, 0.6, 0.8
    t, share = coverage_curve(first, areas, 4.0, period_s=1.5)
    np.testing.assert_allclose(t, [0.0, 1.5, 3.0, 4.0])
    np.testing.assert_allclose(share, [0.0, 0.4, 0.8, 0.8])
    assert time_to_coverage(first, areas, 0.4) == 1.0
    assert time_to_coverage(first, areas, 0.8) == 3.0
    assert time_to_coverage(first, areas, 0.9) is None
    with pytest.raises(ValueError, match=r"period_s must be > 0 s, got 0"):
        coverage_curve(first, areas, 4.0, period_s=0.0)
    with pytest.raises(ValueError, match=r"level must be in \(0, 1\], got 80"):
        time_to_coverage(first, areas, 80)


def test_a_mission_report_holds_the_curve_ending_at_its_coverage(tmp_path):
    # The boulder mission cut short: the transit and half the loop of profile following.
    spec = load_mission("boulder", overrides=["limits.max_time_s=150", "steps.1.follow.loops=0.5"])
    result = run_mission(spec, progress=False)
    summary = summarise(result)
    curve = summary["coverage_vs_time"]
    end = result.run.context.get_time()
    assert len(curve["t_s"]) == int(np.ceil(end / 10.0)) + 1 and curve["t_s"][-1] == end
    for name in ("multibeam", "camera"):
        share = np.asarray(curve[name])
        assert len(share) == len(curve["t_s"])
        assert share[0] == 0.0 and np.all(np.diff(share) >= 0)
        assert share[-1] == pytest.approx(summary["coverage"][name], abs=1e-4)
    assert curve["multibeam"][-1] > 0.05  # the follow leg saw part of the boulder
    assert curve["time_to_s"]["multibeam"] == {"80": None, "90": None}
    fig_coverage_vs_time(result, curve).savefig(tmp_path / "coverage_vs_time.png")
    assert (tmp_path / "coverage_vs_time.png").stat().st_size > 10_000



def test_recorder_state_equals_the_pure_accumulator_over_its_frames():
    """The recorder updates its best angles and first-seen times in place, slot by slot: the
    same values as `CoverageMap` (copy-and-merge) fed the same pings. A multibeam whose fan
    lies along the track sees each face from several poses at different angles, so the
    smallest must be kept."""
    from drake_auv.geometry.visibility import CoverageMap
    from drake_auv.sonar.beams import SonarMount, fan_angles
    from drake_auv.vehicle.control import rotation_world_body

    duration, x0, yaw = 10.0, -5.0, np.pi / 2  # body y (the fan) along world -x
    ground = bathymetry_to_mesh(Bathymetry(np.full((5, 81), -20.0), (0.25, 0.25), (0.0, -0.5)))
    builder = DiagramBuilder()
    recorder = builder.AddSystem(CoverageRecorder(ground, sensor="multibeam", rate=RATE,
                                                  max_range=10.0, num_beams=64, fan_deg=90.0))
    start, end = np.zeros(12), np.zeros(12)
    start[[0, 2, 5]] = x0, -20.0 + ALTITUDE, yaw
    end[[0, 2, 5]] = x0 + SPEED * duration, -20.0 + ALTITUDE, yaw
    source = builder.AddSystem(TrajectorySource(PiecewisePolynomial.FirstOrderHold(
        [0.0, duration], np.column_stack([start, end]))))
    builder.Connect(source.get_output_port(), recorder.true_state_input)
    simulator = Simulator(builder.Build())
    simulator.AdvanceTo(duration)
    context = recorder.GetMyContextFromRoot(simulator.get_context())

    a = fan_angles(64, np.radians(90.0))
    beams = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)]) \
        @ SonarMount.named("down").rotation.T @ rotation_world_body(0.0, 0.0, yaw).T
    offline = CoverageMap(recorder.caster)
    first = np.full(len(offline.best), np.nan)
    for k in range(int(duration * RATE)):
        t = k / RATE
        origin = np.array([x0 + SPEED * t, 0.0, -20.0 + ALTITUDE])
        offline.observe_beams(recorder.caster.cast(origin, beams, 10.0), beams)
        first[np.isnan(first) & np.isfinite(offline.best)] = t
    seen = np.isfinite(offline.best)
    assert 0.05 < seen.mean() < 0.9 and np.ptp(offline.best[seen]) > 0.3  # partial, varied
    np.testing.assert_allclose(recorder.best_angles(context), offline.best, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(recorder.first_seen(context), first)
