"""The kinematic replay of an ArduSub AUTO mission, and the clearance of what it flies (pure
numpy, no Drake).

ArduSub flies each NAV_WAYPOINT with AC_WPNav: a straight 3D track from the leg's origin (the
previous destination, or where the vehicle is) to its destination, the vertical coordinate in
the destination's frame. Frame 3 (MAV_FRAME_GLOBAL_RELATIVE_ALT, home at the surface): z is
the elevation, linear along the leg. Frame 10 (MAV_FRAME_GLOBAL_TERRAIN_ALT): the track's
vertical coordinate is the altitude above the terrain, linear between the two waypoints'
altitudes, and the position target adds the terrain's height under the vehicle at every step
(AC_WPNav::advance_wp_target_along_track adds `get_terrain_offset`, which with
TerrainSource::TERRAIN_FROM_RANGEFINDER is the downward rangefinder's terrain offset that
ArduSub's `Sub::read_rangefinder` (sensors.cpp, ROTATION_PITCH_270) passes through
`wp_nav.set_rangefinder_terrain_offset_cm`). When a leg changes frame, AC_WPNav converts the
origin into the destination's frame with the terrain offset there
(`set_wp_destination_loc`). So on a frame-10 leg the vehicle is at
seabed(x, y) + altitude(s), the seabed sampled along the leg; with a perfect rangefinder that
seabed is the map's. Acceptance radii and S-curve corner rounding are not modelled (corners
are flown through their waypoint).
"""

from __future__ import annotations

import numpy as np



def replay_ardusub(legs, seabed, start, spacing: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Where ArduSub AUTO takes the vehicle along `legs`, sampled every `spacing` m or closer
    along each leg's track (x, y and its held coordinate: elevation or altitude).

    Args:
        legs: `LocalLeg`s of kind "waypoint" (`items.localise` of a QGC plan); z_mode "depth"
            (frame 3, z = depth below the surface) or "altitude" (frame 10, z = altitude over
            the seabed).
        seabed: callable (x, y) arrays -> seabed elevation, m (world frame, z up).
        start: (3,) where the vehicle is when the mission starts, m.
        spacing: largest distance between samples along a leg, m (> 0).

    Returns:
        positions: (N, 3) world frame, the start first.
        item: (N,) index of the leg each sample belongs to (the start: 0).
    """
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"replay spacing must be > 0 m, got {spacing}")
    start = np.asarray(start, float)
    if start.shape != (3,) or not np.all(np.isfinite(start)):
        raise ValueError(f"replay start must be a finite (3,) position, got {start}")
    if not legs:
        raise ValueError("replay_ardusub needs at least one leg")
    for k, leg in enumerate(legs):
        if leg.kind != "waypoint":
            raise ValueError(f"ArduSub leg {k}: kind {leg.kind!r} is not an AUTO waypoint")
    ends = np.array([leg.end for leg in legs], float)
    terrain = np.array([leg.z_mode == "altitude" for leg in legs])
    z_target = np.array([leg.z if t else -leg.z for leg, t in zip(legs, terrain)], float)
    origins = np.vstack([start[:2], ends[:-1]])
    # The origin's z: the start's, then each previous destination's elevation.
    end_elev = np.where(terrain, seabed(ends[:, 0], ends[:, 1]) + z_target, z_target)
    origin_elev = np.concatenate([[start[2]], end_elev[:-1]])
    origin_held = np.where(terrain, origin_elev - seabed(origins[:, 0], origins[:, 1]),
                           origin_elev)
    horiz = np.linalg.norm(ends - origins, axis=1)
    counts = np.maximum(np.ceil(np.hypot(horiz, z_target - origin_held) / spacing), 1).astype(int)
    item = np.repeat(np.arange(len(legs)), counts)
    first = np.concatenate([[0], np.cumsum(counts)[:-1]])
    s = (np.arange(len(item)) - first[item] + 1) / counts[item]
    xy = origins[item] + s[:, None] * (ends - origins)[item]
    held = origin_held[item] + s * (z_target - origin_held)[item]
    z = np.where(terrain[item], seabed(xy[:, 0], xy[:, 1]) + held, held)
    positions = np.vstack([start, np.column_stack([xy, z])])
    return positions, np.concatenate([[0], item])

