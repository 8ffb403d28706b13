"""Pure sonar models (no Drake): ranges against known geometry, frames, noise, bad input."""

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from drake_auv.geometry import RayCaster
from drake_auv.sonar import (SonarModel, SonarMount, SonarNoise, fan_angles, head_angles,
                               scan)
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh


def _state(x=0.0, y=0.0, z=0.0, roll=0.0, pitch=0.0, yaw=0.0):
    s = np.zeros(12)
    s[:6] = x, y, z, roll, pitch, yaw
    return s


def _wall(distance, thickness=1.0, size=60.0):
    """A wall whose near face is the plane x = distance."""
    box = trimesh.creation.box(extents=(thickness, size, size))
    box.apply_translation([distance + thickness / 2, 0.0, 0.0])
    return box


def _flat_seabed(z=-30.0):
    return bathymetry_to_mesh(Bathymetry(np.full((61, 61), z), (2.0, 2.0), (-60.0, -60.0)))


def test_profiler_wall_distance_grazing_range_and_occlusion():
    caster = RayCaster(_wall(4.0))
    model = SonarModel(SonarMount.named("horizontal"), max_range=20.0)
    angles = np.radians(np.arange(-89.1, 89.2, 0.9))
    ret = scan(caster, model, angles, _state(), _state())
    # Where the wall is within range and the beam is not grazing: d / cos(a).
    expected = 4.0 / np.cos(angles)
    ok = (expected <= 20.0) & (np.abs(angles) <= np.radians(85.0))
    np.testing.assert_allclose(ret.ranges[ok], expected[ok], atol=1e-4)
    assert np.isnan(ret.ranges[~ok]).all()
    # Grazing: the wall 1 m away at 87 deg is 19.1 m along the beam (in range) but returns nothing.
    graze = scan(RayCaster(_wall(1.0)), model, np.radians([87.0, 80.0]), _state(), _state())
    assert np.isnan(graze.ranges[0]) and abs(graze.ranges[1] - 1.0 / np.cos(np.radians(80))) < 1e-4
    # Beyond range.
    assert np.isnan(scan(RayCaster(_wall(25.0)), model, [0.0], _state(), _state()).ranges).all()
    # Occlusion: a post in front of the wall hides it.
    post = trimesh.creation.box(extents=(0.4, 0.4, 4.0))
    post.apply_translation([2.0, 0.0, 0.0])
    both = RayCaster(trimesh.util.concatenate([_wall(4.0), post]))
    ranges = scan(both, model, [0.0], _state(), _state()).ranges
    np.testing.assert_allclose(ranges, [1.8], atol=1e-4)


def test_pencil_beam_width_reports_the_nearest_echo_in_the_cone():
    caster = RayCaster(_wall(4.0))
    wide = SonarModel(SonarMount.named("horizontal"), beam_width=np.radians(2.0))
    ret = scan(caster, wide, np.radians([0.0, 30.0]), _state(), _state())
    assert abs(ret.ranges[0] - 4.0) < 1e-4  # the axis is the nearest at normal incidence
    # At 30 deg the cone edge towards the normal comes back first: 4 / cos(29 deg).
    assert abs(ret.ranges[1] - 4.0 / np.cos(np.radians(29.0))) < 1e-3
    assert ret.ranges[1] < 4.0 / np.cos(np.radians(30.0))


def test_multibeam_over_flat_seabed_returns_h_over_cos():
    caster = RayCaster(_flat_seabed(-30.0))
    angles = fan_angles(480, np.radians(120.0))
    assert len(angles) == 480 and abs(np.degrees(angles[-1] - angles[0]) - 120) < 1e-9
    model = SonarModel(SonarMount.named("down", position=(0.2, 0.0, -0.3)), max_range=20.0)
    s = _state(3.0, -2.0, -21.7, yaw=0.8)
    ret = scan(caster, model, angles, s, s)
    h = 8.0  # sensor at -22.0
    np.testing.assert_allclose(ret.ranges, h / np.cos(angles), atol=1e-4)
    np.testing.assert_allclose(ret.points_nav[:, 2], -30.0, atol=1e-4)
    # Across track: positive angles to port (+y in the body).
    assert np.all(np.diff(ret.points_body[:, 1]) > 0)


def test_side_looking_mounts_point_sideways():
    caster = RayCaster(_wall(4.0))
    port = SonarModel(SonarMount.named("port"))
    star = SonarModel(SonarMount.named("starboard"))
    # Yaw -90 deg: the port side (body +y) faces world +x, the wall.
    s = _state(yaw=-np.pi / 2)
    assert abs(scan(caster, port, [0.0], s, s).ranges[0] - 4.0) < 1e-4
    assert np.isnan(scan(caster, star, [0.0], s, s).ranges[0])
    s = _state(yaw=np.pi / 2)
    assert abs(scan(caster, star, [0.0], s, s).ranges[0] - 4.0) < 1e-4


@pytest.mark.parametrize("seed", range(4))
def test_returns_land_on_the_true_mesh_for_arbitrary_poses(seed):
    """Inside a closed 40 x 30 x 20 m room, every return placed with an exact navigation state
    lies on a wall, whatever the roll, pitch and yaw; directions match an independent rotation."""
    half = np.array([20.0, 15.0, 10.0])
    room = trimesh.creation.box(extents=2 * half)
    room.invert()  # normals into the room
    caster = RayCaster(room)
    rng = np.random.default_rng(seed)
    mount = SonarMount(np.array([0.5, -0.2, 0.3]),
                       Rotation.from_euler("xyz", rng.uniform(-1, 1, 3)).as_matrix())
    model = SonarModel(mount, max_range=100.0, max_incidence=np.pi / 2)
    angles = head_angles(np.arange(400), (-np.pi, np.pi), np.radians(0.9))
    for _ in range(5):
        s = _state(*rng.uniform(-5, 5, 3), *rng.uniform([-0.6, -0.6, -np.pi], [0.6, 0.6, np.pi]))
        ret = scan(caster, model, angles, s, s)
        assert ret.hit.all()
        on_wall = np.max(np.abs(ret.points_nav) / half, axis=1)
        np.testing.assert_allclose(on_wall, 1.0, atol=1e-5)
        r_wb = Rotation.from_euler("ZYX", s[[5, 4, 3]]).as_matrix()
        d_s = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
        np.testing.assert_allclose(ret.directions_nav, d_s @ (r_wb @ mount.rotation).T, atol=1e-12)
        np.testing.assert_allclose(ret.origin_nav, s[:3] + r_wb @ mount.position, atol=1e-12)
        np.testing.assert_allclose(ret.points_nav,
                                   ret.origin_nav + ret.ranges[:, None] * ret.directions_nav,
                                   atol=1e-9)
        np.testing.assert_allclose(ret.points_nav, s[:3] + ret.points_body @ r_wb.T, atol=1e-9)


def test_navigation_error_moves_returns_rigidly():
    caster = RayCaster(_flat_seabed())
    model = SonarModel(SonarMount.named("down"))
    angles = fan_angles(31, np.radians(120))
    truth = _state(1.0, 2.0, -25.0, 0.05, -0.04, 0.3)
    est = truth.copy()
    est[[0, 1, 5]] += [1.5, -0.7, 0.1]
    a, b = scan(caster, model, angles, truth, truth), scan(caster, model, angles, truth, est)
    np.testing.assert_array_equal(a.ranges, b.ranges)  # the measurement is the truth's
    np.testing.assert_allclose(a.points_body, b.points_body)
    # points_nav = p_N + R_NB R_WB^T (points_world - p_W): the scan moves rigidly with the error.
    r_wb = Rotation.from_euler("ZYX", truth[[5, 4, 3]]).as_matrix()
    r_nb = Rotation.from_euler("ZYX", est[[5, 4, 3]]).as_matrix()
    moved = (a.points_nav - truth[:3]) @ (r_nb @ r_wb.T).T + est[:3]
    np.testing.assert_allclose(b.points_nav, moved, atol=1e-9)
    assert np.linalg.norm(b.points_nav - a.points_nav, axis=1).min() > 1.0


def test_head_schedule_rotates_or_sweeps_the_sector():
    step = np.radians(0.9)
    full = head_angles(np.arange(800), (-np.pi, np.pi), step)
    assert np.all((full >= -np.pi) & (full < np.pi))
    np.testing.assert_allclose(np.diff(np.unwrap(full)), step, atol=1e-12)
    sector = head_angles(np.arange(400), np.radians((-45.0, 45.0)), step)
    assert sector.min() >= np.radians(-45) - 1e-12 and sector.max() <= np.radians(45) + 1e-12
    np.testing.assert_allclose(np.abs(np.diff(sector)), step, atol=1e-9)  # back and forth
    assert np.sum(np.diff(np.sign(np.diff(sector))) != 0) >= 3


def test_noise_off_by_default_and_deterministic_under_seed():
    assert not SonarNoise().enabled and not SonarModel().noise.enabled
    caster = RayCaster(_flat_seabed())
    angles = fan_angles(480, np.radians(120))
    s = _state(z=-22.0)
    clean = scan(caster, SonarModel(SonarMount.named("down")), angles, s, s)
    noise = SonarNoise(range_sigma=0.05, dropout_prob=0.1, spurious_prob=0.02)
    model = SonarModel(SonarMount.named("down"), noise=noise)
    a = scan(caster, model, angles, s, s, rng=np.random.default_rng(11))
    b = scan(caster, model, angles, s, s, rng=np.random.default_rng(11))
    c = scan(caster, model, angles, s, s, rng=np.random.default_rng(12))
    np.testing.assert_array_equal(a.ranges, b.ranges)
    assert not np.array_equal(np.nan_to_num(a.ranges), np.nan_to_num(c.ranges))
    # Statistics over many pings: dropouts ~10 %, spurious ~2 %, the rest ~N(0, 0.05).
    rng = np.random.default_rng(5)
    err = np.concatenate([scan(caster, model, angles, s, s, rng=rng).ranges - clean.ranges
                          for _ in range(40)])
    dropped = np.isnan(err).mean()
    assert 0.09 < dropped < 0.12  # 0.1 + a few spurious returns beyond range get dropped too
    good = err[np.abs(err) < 0.3]
    assert abs(good.std() - 0.05) < 0.005 and abs(good.mean()) < 0.005
    outliers = np.mean(np.abs(err[np.isfinite(err)]) >= 0.3)
    assert 0.01 < outliers < 0.03
    with pytest.raises(ValueError, match="rng"):
        scan(caster, model, angles, s, s)


def _box(lo, hi):
    box = trimesh.creation.box(extents=np.subtract(hi, lo))
    box.apply_translation(np.add(lo, hi) / 2.0)
    return box


def test_surface_multipath_returns_the_path_length_along_the_beam():
    # A wall x >= 15 from z = -30 to -3, the sonar 2 m deep scanning the vertical plane.
    caster = RayCaster(_box((15.0, -30.0, -30.0), (16.0, 30.0, -3.0)))
    angles = np.radians(np.arange(2.0, 60.0, 2.0))
    s = _state(z=-2.0)
    model = SonarModel(SonarMount.named("vertical"), noise=SonarNoise(surface_prob=1.0))
    ret = scan(caster, model, angles, s, s, rng=np.random.default_rng(0))
    # An upward beam reaching the surface first is mirrored: it meets the wall at
    # z = -(15 tan a - 2), within it for tan a >= 1/3, in range for 15 / cos a <= 20.
    t = np.tan(angles)
    ghost = (2.0 / t < 15.0) & (t >= 1.0 / 3.0) & (15.0 / np.cos(angles) <= 20.0)
    assert ghost.sum() >= 5
    np.testing.assert_allclose(ret.ranges[ghost], 15.0 / np.cos(angles[ghost]), atol=1e-4)
    # Every surface-first return is the mirror image (z -> -z) of a point of the wall (its
    # face or its top): a straight ray into the mirrored world.
    up = 2.0 / t < 15.0
    hits = ret.points_nav[up & np.isfinite(ret.ranges)]
    assert np.all((hits[:, 0] > 15.0 - 1e-6) & (hits[:, 0] < 16.0 + 1e-6))
    assert np.all((-hits[:, 2] > -30.0) & (-hits[:, 2] < -3.0 + 1e-6))
    never = SonarModel(SonarMount.named("vertical"), noise=SonarNoise(surface_prob=1e-9))
    assert np.isnan(scan(caster, never, angles[ghost], s, s,
                         rng=np.random.default_rng(0)).ranges).all()
    # A pencil beam whose axis sees nothing: its upward side lobe, mirrored, meets a ledge
    # (z -6 to -3) that the axis passes over and the lower lobe under; the echo comes back
    # at the path length 15 / cos 20 deg and is placed on the axis, in the water column.
    ledge = RayCaster(_box((15.0, -30.0, -6.0), (16.0, 30.0, -3.0)))
    lobe = SonarNoise(surface_prob=1.0, side_lobe_deg=20.0, side_lobe_gain=1.0)
    pencil = SonarModel(SonarMount.named("horizontal"), noise=lobe)
    ret = scan(ledge, pencil, [0.0], s, s, rng=np.random.default_rng(1))
    assert ret.ranges[0] == pytest.approx(15.0 / np.cos(np.radians(20.0)), abs=1e-3)
    np.testing.assert_allclose(ret.points_nav[0], [15.96, 0.0, -2.0], atol=0.01)
    dry = SonarModel(SonarMount.named("horizontal"),
                     noise=SonarNoise(side_lobe_deg=20.0, side_lobe_gain=1.0))
    assert np.isnan(scan(ledge, dry, [0.0], s, s, rng=np.random.default_rng(1)).ranges[0])


def test_echo_threshold_loses_grazing_echoes_and_a_side_lobe_reports_a_far_wall():
    caster = RayCaster(_wall(4.0))
    s = _state()
    weak = SonarModel(SonarMount.named("horizontal"), noise=SonarNoise(echo_threshold=0.1))
    ret = scan(caster, weak, np.radians([0.0, 70.0, 75.0]), s, s, rng=np.random.default_rng(0))
    # cos^2(70 deg) = 0.117 is detected, cos^2(75 deg) = 0.067 is not.
    np.testing.assert_allclose(ret.ranges[:2], 4.0 / np.cos(np.radians([0.0, 70.0])), atol=1e-4)
    assert np.isnan(ret.ranges[2])
    # Ahead and below, a narrow ramp (|y| < 0.8 m, top z = -0.5) and a far wall x = 8: the
    # beam, 10 deg down in the vertical plane, meets the ramp at 80 deg (too weak); its side
    # lobes 20 deg to either side pass beside the ramp and meet the wall nearly normally,
    # and that echo is reported along the axis: a point below the ramp (the pool's ramp and
    # far wall confused, the reference's Figure 85).
    ramp = _box((-1.0, -0.8, -1.5), (7.9, 0.8, -0.5))
    far = _box((8.0, -30.0, -30.0), (9.0, 30.0, 30.0))
    both = RayCaster(trimesh.util.concatenate([ramp, far]))
    down = -np.radians(10.0)
    clean = scan(both, SonarModel(SonarMount.named("vertical")), [down], s, s)
    assert clean.ranges[0] == pytest.approx(0.5 / np.sin(np.radians(10.0)), abs=1e-3)
    lobed = SonarModel(SonarMount.named("vertical"), noise=SonarNoise(
        echo_threshold=0.05, side_lobe_deg=20.0, side_lobe_gain=0.08))
    ret = scan(both, lobed, [down], s, s, rng=np.random.default_rng(0))
    assert ret.ranges[0] == pytest.approx(8.0 / (np.cos(np.radians(10.0))
                                                 * np.cos(np.radians(20.0))), abs=1e-3)
    assert ret.points_nav[0, 2] < -1.0 and np.abs(ret.points_nav[0, 1]) < 0.8  # in the ramp
    faint = SonarModel(SonarMount.named("vertical"), noise=SonarNoise(
        echo_threshold=0.05, side_lobe_deg=20.0, side_lobe_gain=0.04))
    assert np.isnan(scan(both, faint, [down], s, s, rng=np.random.default_rng(0)).ranges[0])


def test_bad_input_raises():
    with pytest.raises(ValueError, match="num_beams"):
        fan_angles(0, np.radians(120))
    with pytest.raises(ValueError, match="max_range"):
        SonarModel(max_range=-1.0)
    with pytest.raises(ValueError, match="beam_width"):
        SonarModel(beam_width=-0.1)
    with pytest.raises(ValueError, match="max_incidence"):
        SonarModel(max_incidence=0.0)
    with pytest.raises(ValueError, match="range_sigma"):
        SonarNoise(range_sigma=-0.1)
    with pytest.raises(ValueError, match="dropout_prob"):
        SonarNoise(dropout_prob=1.5)
    with pytest.raises(ValueError, match="side_lobe_deg"):
        SonarNoise(side_lobe_deg=120.0)
    with pytest.raises(ValueError, match="echo_threshold"):
        SonarNoise(echo_threshold=1.0)
    with pytest.raises(ValueError, match="mount"):
        SonarMount.named("upside-down")
    with pytest.raises(ValueError, match="rotation"):
        SonarMount(rotation=2 * np.eye(3))
    with pytest.raises(ValueError, match="state"):
        scan(RayCaster(_wall(4.0)), SonarModel(), [0.0], np.full(12, np.nan), _state())


def test_scan_with_hits_gives_the_axis_faces_of_the_same_cast():
    from drake_auv.sonar.beams import beam_geometry, scan_with_hits

    world = trimesh.creation.box(extents=(20.0, 20.0, 2.0))
    world.apply_translation((0.0, 0.0, -12.0))
    caster = RayCaster(world)
    noise = SonarNoise(side_lobe_deg=20.0, side_lobe_gain=0.08, echo_threshold=0.05,
                       range_sigma=0.1)
    model = SonarModel(SonarMount.named("down"), noise=noise)
    angles = fan_angles(90, np.radians(150))
    state = np.zeros(12)
    state[3:6] = 0.05, -0.03, 0.4
    returns, hits = scan_with_hits(caster, model, angles, state, state,
                                   rng=np.random.default_rng(3), time=2.5)
    g = beam_geometry(model, angles)
    assert g.rays_per_beam == 3 and len(hits.faces) == len(angles)
    expected = caster.cast(hits.origin, hits.directions, model.max_range)
    np.testing.assert_array_equal(hits.faces, expected.faces)
    assert 0 < (hits.faces >= 0).sum() < len(angles) and hits.time == 2.5
    again = scan(caster, model, angles, state, state, rng=np.random.default_rng(3), time=2.5)
    np.testing.assert_array_equal(again.ranges, returns.ranges)
    assert not returns.ranges.flags.writeable and not hits.faces.flags.writeable
    alone, no_hits = scan_with_hits(caster, model, angles, state, state,
                                    rng=np.random.default_rng(3), time=2.5, axis_hits=False)
    assert no_hits is None  # a sonar without a recorder skips them, same returns
    np.testing.assert_array_equal(alone.points_nav, returns.points_nav)


def test_scan_points_derived_on_first_read_survive_copies_and_pickling():
    import copy
    import pickle

    caster = RayCaster(_wall(4.0))
    model = SonarModel(SonarMount.named("horizontal", (0.3, 0.0, 0.1)))
    state, estimated = _state(), _state()
    estimated[[0, 5]] += 0.5, 0.1
    returns = scan(caster, model, np.linspace(-0.4, 0.4, 9), state, estimated)
    copies = [copy.deepcopy(returns), pickle.loads(pickle.dumps(returns))]
    r_nb = Rotation.from_euler("ZYX", estimated[[5, 4, 3]]).as_matrix()
    points_body = model.mount.position + returns.ranges[:, None] * np.column_stack(
        [np.cos(returns.angles), np.sin(returns.angles), np.zeros(9)])
    np.testing.assert_allclose(returns.points_body, points_body, atol=1e-12)
    np.testing.assert_allclose(returns.points_nav, estimated[:3] + points_body @ r_nb.T,
                               atol=1e-12)
    assert np.isfinite(returns.ranges).all() and not returns.points_nav.flags.writeable
    for other in copies:
        np.testing.assert_array_equal(other.points_nav, returns.points_nav)
    with pytest.raises(AttributeError, match="no attribute 'points'"):
        returns.points


def test_off_axis_rays_cast_only_to_the_axis_echo_give_the_returns_of_one_query(monkeypatch):
    # A seabed, a wall and a ball near the surface; fans and a wide pencil beam with the
    # missions' errors (side lobes, multipath, threshold, clutter) and random poses, many near
    # the surface: the two-query scan must equal the one-query scan bit for bit.
    from drake_auv.mission.spec import REALISTIC_NOISE
    from drake_auv.sonar import beams

    ball = trimesh.creation.icosphere(subdivisions=3, radius=3.0)
    ball.apply_translation([6.0, 4.0, -6.0])
    world = trimesh.util.concatenate([_flat_seabed(-18.0), _box((12.0, -30.0, -18.0),
                                                                 (13.0, 30.0, -2.0)), ball])
    caster = RayCaster(world)
    queries = []
    cast_unit = caster.cast_unit

    def recording(origins, directions, max_range):
        queries.append(np.broadcast_to(np.array(max_range, dtype=float), len(directions)))
        return cast_unit(origins, directions, max_range)

    monkeypatch.setattr(caster, "cast_unit", recording)
    noise = SonarNoise(**REALISTIC_NOISE)
    models = [(SonarModel(SonarMount.named(mount), noise=noise), fan_angles(480, np.radians(120)))
              for mount in ("port", "down")]
    models.append((SonarModel(SonarMount.named("horizontal"), beam_width=np.radians(6.0),
                              noise=noise), np.radians(np.arange(-180.0, 180.0, 0.9))))
    # The missions' fan takes the short queries at the default threshold.
    queries.clear()
    beams.scan_with_hits(caster, models[1][0], models[1][1], _state(z=-8.0), _state(z=-8.0),
                         rng=np.random.default_rng(0))
    assert any(len(q) == 960 and (q < models[1][0].max_range).mean() > 0.5 for q in queries)
    rng = np.random.default_rng(11)
    nearer = beams_shortened = 0
    for k in range(90):
        model, angles = models[k % 3]
        state = _state(*rng.uniform([-5, -8, -12], [10, 8, -0.5]),
                       *rng.normal(0.0, [0.15, 0.15, 2.0]))
        runs = []
        for threshold in (10 ** 9, 0):
            monkeypatch.setattr(beams, "_SHORT_QUERY_RAYS", threshold)
            queries.clear()
            draws = np.random.default_rng([3, k])
            ret, hits = beams.scan_with_hits(caster, model, angles, state, state, rng=draws)
            runs.append((ret.ranges, hits.faces, draws.random(4), list(queries)))
        (one, faces_one, after_one, _), (two, faces_two, after_two, reaches) = runs
        np.testing.assert_array_equal(one, two)
        np.testing.assert_array_equal(faces_one, faces_two)
        np.testing.assert_array_equal(after_one, after_two)  # the same draws consumed
        off_axis = len(beams.beam_geometry(model, angles).side_rays_body)
        side = next(r for r in reaches if len(r) == off_axis)  # (the first after the axes')
        beams_shortened += int(np.sum(side < model.max_range))
        axis_only = beams.scan_with_hits(
            caster, SonarModel(model.mount, model.max_range, 0.0, model.max_incidence,
                               SonarNoise(surface_prob=noise.surface_prob,
                                          echo_threshold=noise.echo_threshold)),
            angles, state, state, rng=np.random.default_rng([3, k]))[0].ranges
        nearer += int(np.sum(np.isnan(axis_only) & np.isfinite(one)))
    assert beams_shortened > 10_000  # the off-axis rays did stop at their axis's echo
    assert nearer > 50  # and the test has beams that only an off-axis ray sees
