"""How COLA2 flies a mission: the kinematic replay of its goto, section and park maneuvers.

The semantics modelled (read in Iqua Robotics' COLA2, `srv/cola2_core`,
`cola2_control/src/cola2_control/controllers/los_cte.cpp`, see docs/planning.md): a section's
controller (line of sight with cross-track error) steers along the line from the initial to the
final point and commands the FINAL depth, or the final altitude above the seabed in altitude
mode, from the section's start; only with the `heave_in_3D` configuration, and only in depth
mode, it interpolates the depth from the initial to the final depth by the along-track distance
(clamped to the section). A goto holds its final depth or altitude likewise; a park holds its
position.

The vehicle's change of z is modelled conservatively: it moves its controlled coordinate
(depth, or altitude in altitude mode) toward the command no faster than `heave_speed` while it
advances at the section's surge speed (full speed: COLA2 slows near the ends, which only
shortens the change), and it may be anywhere between that rate-limited follower and the
command. Both bounds are replayed. A section ends with its command reached (COLA2 waits at the
final point for z within tolerance). Pure numpy, world frame (z up, sea surface z = 0, m).
"""

from __future__ import annotations

import numpy as np

HEAVE_SPEED = 0.1  # m/s: slowest vertical speed assumed for the change of z (conservative)
DEFAULT_SURGE = 0.5  # m/s: COLA2's default los_cte max surge, when an item gives none


def follower_gap(s: np.ndarray, gap0: float, slope: float, rate: float) -> np.ndarray:
    """Gap (follower - command) along s, m, of a coordinate that moves toward a command of
    constant `slope` (per m along track) no faster than `rate` (per m along track), starting
    `gap0` away: it closes at `rate + slope * sign(gap0)` and then, where the command is faster
    than `rate`, opens behind it."""
    s = np.asarray(s, float)
    sign = np.sign(gap0)
    close = rate + slope * sign
    if gap0 != 0 and close <= 0:  # the command runs away from the follower
        return gap0 - sign * close * s
    s1 = abs(gap0) / close if gap0 != 0 else 0.0
    gap = np.where(s < s1, gap0 - sign * close * s, 0.0)
    if abs(slope) > rate:
        gap = np.where(s >= s1, -np.sign(slope) * (abs(slope) - rate) * (s - s1), gap)
    return gap


def held_band(xy0, xy1, altitude_mode: bool, target: float, z0: float, seabed,
              start_z: float | None = None, heave_in_3d: bool = False, spacing: float = 1.0,
              speed: float = DEFAULT_SURGE, heave_speed: float = HEAVE_SPEED):
    """The z a COLA2 vehicle may hold along one section (or goto) from xy0 to xy1.

    Args:
        altitude_mode: the section holds `target` as altitude above `seabed` (m), else as an
            elevation (`target` = -final depth, m).
        z0: the vehicle's elevation at the start, m.
        start_z: the section's initial elevation (-initial_depth), for `heave_in_3d`.
        seabed: callable (x, y) -> elevation, m.
        spacing: largest distance between samples along the line, m.
    Returns:
        xy (M, 2), z_follow (M,) the rate-limited vehicle, z_cmd (M,) the command; the
        vehicle lies between them.
    """
    xy0, xy1 = np.asarray(xy0, float), np.asarray(xy1, float)
    length = float(np.hypot(*(xy1 - xy0)))
    n = max(int(np.ceil(length / spacing)), 1)
    s = np.linspace(0.0, length, n + 1)
    xy = xy0 + (s / length if length > 0 else np.zeros_like(s))[:, None] * (xy1 - xy0)
    ground = seabed(xy[:, 0], xy[:, 1])
    rate = heave_speed / speed
    if altitude_mode:
        cmd = np.full(len(s), float(target))
        gap = follower_gap(s, (z0 - ground[0]) - target, 0.0, rate)
        return xy, ground + cmd + gap, ground + cmd
    if heave_in_3d and start_z is not None and length > 0:
        slope = (target - start_z) / length
        cmd = start_z + slope * s
    else:
        slope, cmd = 0.0, np.full(len(s), float(target))
    return xy, cmd + follower_gap(s, z0 - cmd[0], slope, rate), cmd


def replay_cola2(legs, seabed, start, heave_in_3d: bool = False, spacing: float = 1.0,
                 heave_speed: float = HEAVE_SPEED) -> tuple[np.ndarray, np.ndarray]:
    """Replays `legs` (`autopilot.items.localise` of a COLA2 mission) as COLA2 flies them.

    Args:
        seabed: callable (x, y) -> elevation, m (what the DVL's altitude is measured to).
        start: (3,) the vehicle's position before the first item, m.
        heave_in_3d: the vehicle's los_cte `heave_in_3D` setting.
        spacing: largest distance between samples along a leg, m.
    Returns:
        positions (N, 3) and (N,) the index of the item each sample belongs to. Along a leg
        each xy carries the rate-limited vehicle's z and, where it differs, the command's next
        to it (the band between them is what the vehicle may hold); a park holds its point.
    """
    pos = np.asarray(start, float).reshape(3)
    out, owner = [], []
    for k, leg in enumerate(legs):
        altitude = leg.z_mode == "altitude"
        end = np.asarray(leg.end, float)
        if altitude:
            target = float(leg.z)
        else:
            target = -float(leg.z)
        if leg.kind == "park":
            ground = float(seabed(end[:1], end[1:])[0])
            z_end = ground + target if altitude else target
            pts = np.array([[end[0], end[1], pos[2]], [end[0], end[1], z_end]])
        else:
            xy0 = np.asarray(leg.start if leg.kind == "section" and leg.start is not None
                             else pos[:2], float)
            xy, z_f, z_c = held_band(xy0, end, altitude, target, pos[2], seabed,
                                     leg.start_z, heave_in_3d and leg.kind == "section",
                                     spacing, leg.speed or DEFAULT_SURGE, heave_speed)
            both = np.abs(z_f - z_c) > 1e-9
            xyz = np.column_stack([np.repeat(xy, 1 + both, axis=0),
                                   np.ravel(np.column_stack([z_f, z_c]))[
                                       np.ravel(np.column_stack([np.ones_like(both), both]))]])
            z_end = z_c[-1]
            pts = np.vstack([xyz, [end[0], end[1], z_end]])
        out.append(pts)
        owner.append(np.full(len(pts), k))
        pos = np.array([end[0], end[1], z_end])
    return np.vstack(out), np.concatenate(owner)

