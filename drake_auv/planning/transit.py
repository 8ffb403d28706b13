"""Transits between the parts of a mission: a straight line, kept above the terrain and below
the surface.

The line from `start` to `end` is sampled every `spacing` m and each interior sample is lifted
to at least `clearance` above the terrain below it (a heightfield such as the prior map: a
survey from above, so an overhang's top counts as terrain and the transit passes over it),
then held at least `min_depth` below the sea surface (z = 0). The yaw turns from the start's
towards the horizontal direction of motion (steep segments keep the heading they had) and
ends at `end_yaw`. Pure numpy; world frame, z up, m, rad.
"""

from __future__ import annotations

import numpy as np

from drake_auv.planning.path import PlannedPath
from drake_auv.planning.polyline import densify, motion_heading

# A transit segment whose horizontal length is at most this share of its length (steeper than
# 78 deg: a lift over the terrain) keeps the heading it had: at the pool's shallow end a lift of
# 2.5 m with 6 cm of horizontal drift turned the yaw to -137 deg and back, 266 deg of needless
# turning where the goal was 94 deg away.
STEEP = 0.2


def transit(start, end, start_yaw: float, end_yaw: float | None = None, terrain=None,
            clearance: float = 3.0, min_depth: float = 1.0, spacing: float = 1.0) -> PlannedPath:
    """The transit `PlannedPath` (labelled "transit", sensor down) from `start` to `end` (3,).

    Args:
        start_yaw: heading at the start, rad; end_yaw: at the end (None: along the motion).
        terrain: callable (x, y) -> terrain elevation z, m (None: no terrain check).
        clearance: least height above the terrain of the interior samples, m, >= 0.
        min_depth: least depth of every sample, m, >= 0 (ends included: a transit never
            leaves the water).
        spacing: largest distance between samples, m, > 0.
    """
    start, end = (np.asarray(p, dtype=float).reshape(3) for p in (start, end))
    if not (np.all(np.isfinite(start)) and np.all(np.isfinite(end))):
        raise ValueError(f"transit ends must be finite 3-vectors, got {start} and {end}")
    if not (np.isfinite(clearance) and clearance >= 0 and np.isfinite(min_depth)
            and min_depth >= 0 and np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"transit needs clearance >= 0 m, min_depth >= 0 m and spacing > 0 m,"
                         f" got {clearance}, {min_depth}, {spacing}")
    points = densify(np.vstack([start, end]), spacing)
    if terrain is not None and len(points) > 2:
        inner = points[1:-1]
        floor = np.asarray(terrain(inner[:, 0], inner[:, 1]), dtype=float) + clearance
        inner[:, 2] = np.maximum(inner[:, 2], np.nan_to_num(floor, nan=-np.inf))
    points[:, 2] = np.minimum(points[:, 2], -min_depth)
    heading = motion_heading(points, fallback=start_yaw, min_horizontal=STEEP)
    heading[0] = start_yaw
    if end_yaw is not None:
        heading[-1] = end_yaw
    return PlannedPath(points, heading, (0.0, 0.0, -1.0), "transit")
