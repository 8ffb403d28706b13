"""Following behaviours in closed loop with a kinematic vehicle and a 2D rotating pencil beam
cast against polygon profiles (no Drake): pool corners, a convex block, the C with its ceiling."""

import numpy as np
import pytest

from drake_auv.following import FollowingParams, HorizontalFollower, VerticalFollower, follow_step
from drake_auv.perception import estimate_profile


def _polyline(vertices, closed):
    v = np.asarray(vertices, float)
    if closed:
        v = np.vstack([v, v[:1]])
    return np.stack([v[:-1], v[1:]], axis=1)


def _cast(origin, dirs, segs, max_range=20.0):
    """Ranges (n,) of rays origin + t dirs to the first of segs (m, 2, 2); NaN without return."""
    a, e = segs[:, 0], segs[:, 1] - segs[:, 0]
    d = dirs[:, None, :]
    den = d[..., 0] * e[:, 1] - d[..., 1] * e[:, 0]
    den = np.where(np.abs(den) < 1e-12, np.nan, den)
    w = a[None] - origin
    t = (w[..., 0] * e[:, 1] - w[..., 1] * e[:, 0]) / den
    u = (w[..., 0] * d[..., 1] - w[..., 1] * d[..., 0]) / den
    t = np.where((t > 1e-9) & (u >= 0) & (u <= 1), t, np.inf).min(axis=1)
    return np.where(t <= max_range, t, np.nan)


def _distance(p, segs):
    a, e = segs[:, 0], segs[:, 1] - segs[:, 0]
    t = np.clip(np.sum((p - a) * e, 1) / np.sum(e * e, 1), 0, 1)
    return np.min(np.linalg.norm(a + t[:, None] * e - p, axis=1))


def _wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


STEP = np.radians(3.6)  # beam step per ping, 3 pings per 0.1 s update: a turn in 10 s
DT = 0.1


def _vehicle_step(p, yaw, ref):
    """Kinematic vehicle: velocity feed-forward plus 0.8/s position and 1/s yaw feedback."""
    p = p + DT * (ref[4:7] + 0.8 * (ref[:3] - p))
    return p, yaw + DT * (ref[7] + _wrap(ref[3] - yaw))


def _run_horizontal(segs, start, yaw, duration, params):
    follower = HorizontalFollower(params, seed=0)
    held = follower.initial_state()
    p, beam, log = np.array(start, float), 0.0, []
    for k in range(int(duration / DT)):
        angles = yaw + beam + STEP * np.arange(3)
        beam += 3 * STEP
        dirs = np.column_stack([np.cos(angles), np.sin(angles)])
        ranges = _cast(p[:2], dirs, segs)
        points = np.column_stack([p[:2] + ranges[:, None] * dirs, np.full(3, p[2])])
        state = np.zeros(12)
        state[:3], state[5] = p, yaw
        held, out = follower.update(held, k * DT, state, points)
        p, yaw = _vehicle_step(p, yaw, out.reference)
        front = _cast(p[:2], np.array([[np.cos(yaw), np.sin(yaw)]]), segs)[0]
        log.append((k * DT, p[0], p[1], p[2], _distance(p[:2], segs), front))
    return np.array(log)


def test_pool_two_laps_despite_corners():
    pool = _polyline([[0, 0], [16, 0], [16, 8], [0, 8]], closed=True)
    params = FollowingParams(offset=2.0, corner_weight=0.5)
    log = _run_horizontal(pool, [8, 2.5, -4], -np.pi / 2, 230, params)
    angle = np.unwrap(np.arctan2(log[:, 2] - 4, log[:, 1] - 8))
    assert abs(angle[-1] - angle[0]) > 2 * 2 * np.pi  # two full laps
    late = log[log[:, 0] > 20]
    assert np.all(np.abs(late[:, 4] - 2.0) < 0.5)  # nearest wall
    assert np.all(np.abs(late[:, 5] - 2.0) < 1.0)  # frontal distance: the reference's 1 m bound
    assert np.allclose(late[:, 3], -4.0)


def test_convex_block_closed_loop_without_contact():
    block = _polyline([[0, 0], [6, 0], [6, 4], [0, 4]], closed=True)
    params = FollowingParams(offset=2.0, side=-1)  # the other way round
    log = _run_horizontal(block, [3, -3, -4], np.pi / 2, 160, params)
    angle = np.unwrap(np.arctan2(log[:, 2] - 2, log[:, 1] - 3))
    assert abs(angle[-1] - angle[0]) > 2 * np.pi  # one full loop
    assert np.all(log[:, 4] > 1.5)
    assert np.all(np.abs(log[log[:, 0] > 15, 4] - 2.0) < 0.5)


# A C-shaped object opening towards +s on a seabed at h = 0, in the (s, h) plane; z = h + Z0
Z0 = -30.0
C_PROFILE = _polyline([[-20, 0], [10, 0], [10, 10], [18, 10], [18, 8], [12, 8], [12, 2],
                       [18, 2], [18, 0], [40, 0]], closed=False)


def _run_vertical(profile, start_sh, duration, params, plane_yaw=0.3):
    """Kinematic vertical following in the plane along `plane_yaw`; the profile is in (s, h)
    with z = h + Z0. Log rows: s, h, true distance, cos(yaw - plane_yaw), turning, z reference."""
    e = np.array([np.cos(plane_yaw), np.sin(plane_yaw), 0.0])
    follower = VerticalFollower(params, seed=0)
    held = follower.initial_state()
    sh, yaw, beam, log = np.array(start_sh, float), plane_yaw, 0.0, []
    for k in range(int(duration / DT)):
        angles = beam + STEP * np.arange(3)
        beam += 3 * STEP
        facing = np.sign(np.cos(yaw - plane_yaw))
        dirs = np.column_stack([facing * np.cos(angles), np.sin(angles)])
        hits = sh + _cast(sh, dirs, profile)[:, None] * dirs
        state = np.zeros(12)
        state[:3], state[5] = sh[0] * e + [0, 0, sh[1] + Z0], yaw
        held, out = follower.update(held, k * DT, state,
                                    hits[:, :1] * e + (hits[:, 1:] + Z0) * [0, 0, 1])
        p, yaw = _vehicle_step(state[:3], yaw, out.reference)
        sh = np.array([p @ e, p[2] - Z0])
        log.append((sh[0], sh[1], _distance(sh, profile), np.cos(yaw - plane_yaw),
                    out.mode == "turn", out.reference[2]))
    return np.array(log), held


def test_vertical_whole_c_with_ceiling_turn():
    log, held = _run_vertical(C_PROFILE, [0.0, 2.0], 240, FollowingParams(offset=2.0))
    assert np.all(log[:, 2] > 1.5)  # no contact, offset held within 0.5 m
    above = log[:, 1] > 11.5
    under_ceiling = (log[:, 0] > 13) & (log[:, 0] < 17) & (log[:, 1] > 5) & (log[:, 1] < 7)
    inside_floor = (log[:, 0] > 13) & (log[:, 0] < 17) & (log[:, 1] > 3) & (log[:, 1] < 5)
    assert np.any(above) and np.any(under_ceiling) and np.any(inside_floor)
    # under the ceiling it moves towards -s facing -s: it turned instead of backing up
    first_ceiling = np.flatnonzero(under_ceiling)[0]
    assert log[first_ceiling, 3] < -0.9
    assert np.any(log[:, 4]) and held.turns >= 2
    assert log[-1, 0] > 25 and abs(log[-1, 1] - 2.0) < 0.3  # out of the C, back on the seabed


def test_vertical_wall_to_the_surface_respects_min_depth():
    # seabed at z = -10 (h = 20), then a quay wall at s = 6 rising above the surface
    quay = _polyline([[-20, 20], [6, 20], [6, 31], [20, 31]], closed=False)
    params = FollowingParams(offset=2.0, min_depth=1.5)
    log, _ = _run_vertical(quay, [0.0, 22.0], 90, params)
    assert np.all(log[:, 5] <= -1.5 + 1e-9)
    assert log[:, 1].max() + Z0 == pytest.approx(-1.5, abs=0.1)  # climbed to the limit
    assert np.all(log[:, 2] > 1.5)


def test_follow_step_directions_and_fading():
    wall = np.column_stack([np.full(60, 2.5), np.linspace(-3, 3, 60)])
    est = estimate_profile(wall)
    params = FollowingParams(offset=2.0, speed=0.4, slow_band=1.0)
    correction, velocity = follow_step(est, params)
    assert np.allclose(correction, [0.5, 0.0], atol=0.02)  # approach 0.5 m along -normal
    assert np.allclose(velocity, [0.0, 0.4 * 0.5], atol=0.02)  # profile on the right: +y
    _, velocity = follow_step(est, FollowingParams(offset=2.0, speed=0.4, side=-1))
    assert velocity[1] < 0


def test_params_validation():
    with pytest.raises(ValueError, match="offset"):
        FollowingParams(offset=0.0)
    with pytest.raises(ValueError, match="side"):
        FollowingParams(side=0)
    with pytest.raises(ValueError, match="window"):
        FollowingParams(offset=7.0)
    follower = HorizontalFollower()
    with pytest.raises(ValueError, match="state"):
        follower.update(follower.initial_state(), 0.0, np.full(12, np.nan), np.empty((0, 3)))
    with pytest.raises(ValueError, match="depth_z"):
        HorizontalFollower(depth_z=np.nan)


def test_update_returns_a_new_state_and_leaves_the_old_one_as_it_was():
    import copy

    wall = np.column_stack([np.full(60, 2.5), np.linspace(-3, 3, 60), np.full(60, -4.0)])
    x = np.zeros(12)
    x[2] = -4.0
    follower = HorizontalFollower(FollowingParams(), seed=4)
    first, _ = follower.update(follower.initial_state(), 0.0, x, wall)
    clone = copy.deepcopy(first)  # what Drake does to abstract state
    assert clone is first  # immutable, so Drake's copies share it
    second, a = follower.update(clone, 0.1, x, wall)
    assert len(second.map) == 120 and len(clone.map) == 60 and len(first.map) == 60
    assert clone.rng == first.rng and second.rng != first.rng  # RANSAC drew from a copy
    _, b = follower.update(first, 0.1, x, wall)
    assert np.array_equal(a.reference, b.reference)  # same draws from an equal state
    assert (second.start_time, second.time, first.time) == (0.0, 0.1, 0.0)
