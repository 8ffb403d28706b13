"""The sonar and coverage LeafSystems in small diagrams (vehicle poses fed directly)."""

import numpy as np
import pytest
import trimesh
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder
from pydrake.systems.primitives import ConstantVectorSource, TrajectorySource
from pydrake.trajectories import PiecewisePolynomial

from drake_auv.geometry import RayCaster
from drake_auv.scenarios import get_scenario
from drake_auv.sonar import SonarNoise, SonarReturns, fan_angles, scan
from drake_auv.coverage.recorder import CoverageRecorder
from drake_auv.sonar.multibeam import MultibeamSonar
from drake_auv.sonar.profiler import PencilBeamProfiler
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh

POOL_START = np.r_[-4.0, 0.0, -4.0, np.zeros(9)]  # the pool scenario's start: facing +x


def _state(x=0.0, y=0.0, z=0.0, roll=0.0, pitch=0.0, yaw=0.0):
    s = np.zeros(12)
    s[:6] = x, y, z, roll, pitch, yaw
    return s


def _run_sensor(sensor, true_state, estimated_state=None, t_end=1.0):
    builder = DiagramBuilder()
    builder.AddNamedSystem("sensor", sensor)
    truth = builder.AddNamedSystem("true_state", ConstantVectorSource(true_state))
    est = builder.AddNamedSystem("estimated_state", ConstantVectorSource(
        true_state if estimated_state is None else estimated_state))
    builder.Connect(truth.get_output_port(), sensor.GetInputPort("true_state"))
    builder.Connect(est.get_output_port(), sensor.GetInputPort("estimated_state"))
    builder.ExportOutput(sensor.GetOutputPort("returns"), "returns")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(t_end)
    return diagram.GetOutputPort("returns").Eval(simulator.get_context())


def test_profiler_in_the_pool_steps_the_head_and_hits_the_walls():
    sc = get_scenario("pool")
    caster = RayCaster(sc.world)
    profiler = PencilBeamProfiler(caster, scan_plane="horizontal")
    assert profiler.get_input_port(0).get_name() == "true_state"
    assert profiler.get_output_port(0).get_name() == "returns"
    start = POOL_START
    returns = _run_sensor(profiler, start, t_end=1.0)
    assert isinstance(returns, SonarReturns)
    # Updates at t = 0, 0.1, ..., 0.9 (AdvanceTo leaves the one at t = 1 to the next step).
    assert returns.sequence == 10 and returns.time == pytest.approx(0.9)
    assert len(returns) == 3  # 30 pings/s in 10 batches
    np.testing.assert_allclose(np.degrees(returns.angles), -180 + 0.9 * np.arange(27, 30),
                               atol=1e-9)
    # The pool's walls at |x| = 8, |y| = 4: every ping returns from one of them.
    p = returns.points_nav
    wall = np.minimum(np.abs(np.abs(p[:, 0]) - 8), np.abs(np.abs(p[:, 1]) - 4))
    assert returns.hit.all() and wall.max() < 0.05  # nearest echo in a 1.5 deg cone


def test_profiler_sector_sweep_in_the_vertical_plane_meets_the_v_bottom():
    sc = get_scenario("pool")
    profiler = PencilBeamProfiler(sc.world, scan_plane="vertical", sector_deg=(-90, 0),
                                  update_rate=30.0, beam_width_deg=0.0)
    assert profiler.update_angles(0).shape == (1,)
    sweep = np.concatenate([profiler.update_angles(n) for n in range(300)])
    assert np.degrees(sweep.min()) == pytest.approx(-90) and np.degrees(sweep.max()) <= 1e-9
    r = _run_sensor(profiler, POOL_START, t_end=50.5 / 30)
    # Ping 50 points 45 deg down from (-4, 0, -4) and meets the ramp z = -6 - (x + 4) / 4
    # at x = -4 + 8/3.
    assert r.sequence == 51 and np.degrees(r.angles[0]) == pytest.approx(-45.0)
    np.testing.assert_allclose(r.points_nav[0], [-4 + 8 / 3, 0.0, -4 - 8 / 3], atol=1e-4)


def test_multibeam_over_flat_seabed_and_named_ports():
    seabed = bathymetry_to_mesh(Bathymetry(np.full((41, 41), -30.0), (2.0, 2.0), (-40.0, -40.0)))
    sonar = MultibeamSonar(seabed, mount_position=(0.3, 0.0, -0.2))
    r = _run_sensor(sonar, _state(1.0, 2.0, -22.0, yaw=0.4), t_end=0.35)
    assert r.sequence == 4 and len(r) == 480
    angles = fan_angles(480, np.radians(120))
    np.testing.assert_allclose(r.ranges, 7.8 / np.cos(angles), atol=1e-4)
    np.testing.assert_allclose(r.points_nav[:, 2], -30.0, atol=1e-4)


def test_system_output_equals_pure_scan_and_noise_is_seeded():
    sc = get_scenario("breakwater")
    caster = RayCaster(sc.world)
    s = _state(0.0, -8.5, -5.0, 0.02, -0.03, np.pi / 2)
    est = s + np.r_[0.4, -0.3, 0.1, 0, 0, 0.02, np.zeros(6)]
    clean = _run_sensor(MultibeamSonar(caster, mount="forward"), s, est, t_end=0.0)
    pure = scan(caster, MultibeamSonar(caster, mount="forward").model,
                fan_angles(480, np.radians(120)), s, est)
    np.testing.assert_array_equal(clean.ranges, pure.ranges)
    np.testing.assert_allclose(clean.points_nav, pure.points_nav)
    noise = SonarNoise(range_sigma=0.1, dropout_prob=0.2)
    runs = [_run_sensor(MultibeamSonar(caster, mount="forward", noise=noise, seed=seed), s, est,
                        t_end=0.5) for seed in (1, 1, 2)]
    np.testing.assert_array_equal(runs[0].ranges, runs[1].ranges)
    assert not np.array_equal(np.nan_to_num(runs[0].ranges), np.nan_to_num(runs[2].ranges))
    assert 0.1 < np.mean(~runs[0].hit & clean.hit) / np.mean(clean.hit) < 0.3


def test_coverage_recorder_lawnmower_through_a_diagram():
    cell, altitude = 0.2, 2.0
    footprint = 2 * altitude * np.tan(np.radians(30))
    lanes, length = 4, 12.0
    ny, nx = int(round(lanes * footprint / cell)) + 1, int(round(length / cell)) + 1
    world = bathymetry_to_mesh(Bathymetry(np.full((ny, nx), -10.0), (cell, cell), (0.0, 0.0)))
    # Boustrophedon at 0.5 m/s as a first-order-hold trajectory of 12-vector states.
    knots, t = [], 0.0
    times = []
    for k in range(lanes):
        y = (k + 0.5) * footprint
        xs = (0.0, length) if k % 2 == 0 else (length, 0.0)
        for x in xs:
            if knots:
                t += np.linalg.norm([x - knots[-1][0], y - knots[-1][1]]) / 0.5
            knots.append(_state(x, y, -10.0 + altitude, yaw=0.0 if k % 2 == 0 else np.pi))
            times.append(t)
    traj = PiecewisePolynomial.FirstOrderHold(times, np.array(knots).T)
    builder = DiagramBuilder()
    source = builder.AddNamedSystem("poses", TrajectorySource(traj))
    recorder = builder.AddNamedSystem("coverage", CoverageRecorder(world, rate=10.0))
    builder.Connect(source.get_output_port(), recorder.GetInputPort("true_state"))
    builder.ExportOutput(recorder.GetOutputPort("coverage"), "coverage")
    diagram = builder.Build()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(times[-1])
    context = recorder.GetMyContextFromRoot(simulator.get_context())
    covered = diagram.GetOutputPort("coverage").Eval(simulator.get_context())[0]
    assert covered >= 0.98
    assert recorder.coverage(context) == covered
    area, edges = recorder.viewing_angle_histogram(context)
    assert area[0] == pytest.approx(area.sum())  # flat, level: all viewed head-on
    per_face = recorder.face_angles(context)
    assert per_face.shape == (len(world.faces),) and np.isfinite(per_face).mean() >= 0.98


def test_coverage_recorder_multibeam_mode_marks_a_swath():
    world = bathymetry_to_mesh(Bathymetry(np.full((41, 41), -30.0), (0.5, 0.5), (0.0, 0.0)))
    recorder = CoverageRecorder(world, sensor="multibeam", max_range=20.0, rate=10.0)
    context = recorder.CreateDefaultContext()
    recorder.get_input_port(0).FixValue(context, _state(10.0, 10.0, -25.0))
    simulator = Simulator(recorder, context)
    simulator.AdvanceTo(0.25)
    seen = np.isfinite(recorder.face_angles(context))
    centres = world.triangles_center[seen]
    # The fan lies across track (body y): a thin line at x = 10 through the swath
    # |y - 10| <= 5 tan 60.
    assert np.abs(centres[:, 0] - 10.0).max() <= 0.5
    assert np.ptp(centres[:, 1]) > 15.0


def test_bad_input_raises():
    box = trimesh.creation.box()
    with pytest.raises(ValueError, match="num_beams"):
        MultibeamSonar(box, num_beams=0)
    with pytest.raises(ValueError, match="max_range"):
        MultibeamSonar(box, max_range=-5.0)
    with pytest.raises(ValueError, match="max_range"):
        PencilBeamProfiler(box, max_range=-1.0)
    with pytest.raises(ValueError, match="empty"):
        PencilBeamProfiler(trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), int)))
    with pytest.raises(ValueError, match="Trimesh"):
        MultibeamSonar(trimesh.PointCloud(np.eye(3)))
    with pytest.raises(ValueError, match="scan_plane"):
        PencilBeamProfiler(box, scan_plane="diagonal")
    with pytest.raises(ValueError, match="sector_deg"):
        PencilBeamProfiler(box, sector_deg=(10, 10))
    with pytest.raises(ValueError, match="update_rate"):
        PencilBeamProfiler(box, update_rate=100.0)
    with pytest.raises(ValueError, match="mount"):
        MultibeamSonar(box, mount="up")
    with pytest.raises(ValueError, match="sensor"):
        CoverageRecorder(box, sensor="lidar")
    with pytest.raises(ValueError, match="rate"):
        CoverageRecorder(box, rate=0.0)


@pytest.mark.parametrize("sector", [(-180.0, 180.0), (-60.0, 30.0), (-50.0, 50.3)])
def test_profiler_cached_beams_match_the_schedule(sector):
    profiler = PencilBeamProfiler(trimesh.creation.box(), sector_deg=sector, ping_rate=30.0,
                                  update_rate=7.0)
    for n in list(range(0, 1500, 7)) * 2:  # second pass served from the cache
        g = profiler.update_geometry(n)
        np.testing.assert_allclose(g.angles, profiler.update_angles(n), atol=1e-9)


def _fan_over_relief(recorder_rate=10.0, sonar_rate=10.0):
    """A multibeam (side lobe and surface multipath: 3 rays a beam) crossing a bumpy seabed,
    a recorder scoring its `axis_hits` and one casting the same fan itself."""
    x = np.arange(0.0, 30.0, 0.5)
    gx, gy = np.meshgrid(x, x)
    world = bathymetry_to_mesh(Bathymetry(-12.0 + np.sin(gx / 3.0) * np.cos(gy / 2.0),
                                          (0.5, 0.5), (0.0, 0.0)))
    caster = RayCaster(world)
    noise = SonarNoise(surface_prob=0.5, side_lobe_deg=20.0, side_lobe_gain=0.08,
                       echo_threshold=0.05, range_sigma=0.1)
    traj = PiecewisePolynomial.FirstOrderHold(
        [0.0, 20.0], np.column_stack([_state(5.0, 15.0, -4.0, yaw=0.1),
                                      _state(25.0, 12.0, -3.0, roll=0.05, yaw=-0.2)]))
    builder = DiagramBuilder()
    source = builder.AddNamedSystem("poses", TrajectorySource(traj))
    sonar = builder.AddNamedSystem("multibeam", MultibeamSonar(
        caster, num_beams=120, rate=sonar_rate, mount="port", noise=noise,
        axis_hits_output=True))
    options = dict(sensor="multibeam", num_beams=120, max_range=20.0, mount="port",
                   rate=recorder_rate)
    shared = builder.AddNamedSystem("shared", CoverageRecorder(caster, hits_input=True,
                                                               **options))
    own = builder.AddNamedSystem("own", CoverageRecorder(caster, **options))
    for system in (sonar, shared, own):
        builder.Connect(source.get_output_port(), system.GetInputPort("true_state"))
    builder.Connect(source.get_output_port(), sonar.estimated_state_input)
    builder.Connect(sonar.axis_hits_output, shared.hits_input)
    diagram = builder.Build()
    return diagram, shared, own


def test_recorder_on_the_multibeam_axis_hits_scores_what_its_own_casts_score():
    diagram, shared, own = _fan_over_relief()
    simulator = Simulator(diagram)
    simulator.AdvanceTo(20.0)
    root = simulator.get_context()
    a = shared.best_angles(shared.GetMyContextFromRoot(root))
    b = own.best_angles(own.GetMyContextFromRoot(root))
    assert 0.2 < np.isfinite(a).mean() < 1.0  # a swath, not all and not nothing
    np.testing.assert_array_equal(a, b)  # the same faces at the same angles, bit for bit


def test_recorder_rejects_axis_hits_of_another_rate():
    diagram, _, _ = _fan_over_relief(recorder_rate=10.0, sonar_rate=5.0)
    simulator = Simulator(diagram)
    with pytest.raises(ValueError, match="axis_hits of t"):
        simulator.AdvanceTo(1.0)
    with pytest.raises(ValueError, match="hits_input"):
        CoverageRecorder(trimesh.creation.box(), sensor="camera", hits_input=True)
