"""A single-contour nominal path at a fixed depth around a structure, planned on a prior map
(the reference's breakwater mission, Section 5.5.3). Pure numpy/scipy.

Frames: the prior's world frame, z up, metres; depths positive down; headings in radians.
"""

from __future__ import annotations

import contourpy
import numpy as np
from scipy import ndimage

from drake_auv.planning.path import PlannedPath
from drake_auv.planning.polyline import motion_heading, resample
from drake_auv.terrain.bathymetry import Bathymetry

END_OVERRUN = 7.0  # m, the largest prior-map error (5 m) plus 2 m


def nominal_contour(prior: Bathymetry, depth: float, omega: float,
                    end_width: float | None = None, start=None, *, end_heading: float = 0.0,
                    overrun: float = END_OVERRUN, spacing: float = 1.0) -> PlannedPath:
    """The offset-`omega` contour, at `depth`, of the structure's cross-section in `prior`,
    flown counter-clockwise seen from above (structure to port).

    The cross-section is the set of cells rising above z = -depth; the contour is the level
    `omega` of the horizontal distance to it (the longest such loop). With `end_width`, only
    the part around one end of a long structure is kept: the points within `end_width +
    overrun` of the structure's end facing `end_heading` (e.g. the last block of a breakwater,
    `overrun` flying both side faces past their ends wherever the map error puts them).

    Args:
        prior: the prior map (elevations, m, NaN no-data).
        depth: depth of the contour, m (> 0).
        omega: offset to the structure, m (> 0).
        end_width: width of the end to fly around, m (None: the whole closed contour).
        start: (3,) position prepended to the path (the transit from the start), or None.
        end_heading: direction of that end from the structure, rad from +x.
        overrun: how far past `end_width` the contour is kept, m (>= 0).
        spacing: largest distance between path samples, m (> 0).
    Returns:
        A `PlannedPath` labelled "slice" at z = -depth, heading along the motion, the sensor to port.
    """
    for name, value in (("depth", depth), ("omega", omega), ("spacing", spacing)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"nominal_contour: {name} must be > 0 m, got {value}")
    if not (np.isfinite(overrun) and overrun >= 0):
        raise ValueError(f"nominal_contour: overrun must be >= 0 m, got {overrun}")
    if end_width is not None and not (np.isfinite(end_width) and end_width > 0):
        raise ValueError(f"nominal_contour: end_width must be > 0 m or None, got {end_width}")
    solid = np.nan_to_num(prior.z, nan=-np.inf) > -depth
    if not solid.any():
        raise ValueError(f"nominal_contour: the prior map has no structure above {depth} m "
                         "depth")
    dx, dy = prior.spacing
    dist = ndimage.distance_transform_edt(~solid, sampling=(dy, dx))
    # Solid cell centres lie up to half a cell inside the face: the level compensates.
    lines = contourpy.contour_generator(prior.x, prior.y, dist).lines(omega + 0.5 * dx)
    if not lines:
        raise ValueError(f"nominal_contour: no contour at {omega} m from the structure fits "
                         "in the prior map")
    line = max(lines, key=len)
    if end_width is not None:
        line = _end_arc(prior, solid, line, end_width + overrun, end_heading)
    elif not np.allclose(line[0], line[-1]):
        raise ValueError(f"nominal_contour: the contour at {omega} m from the structure "
                         "leaves the prior map (give end_width to fly one end)")
    # Counter-clockwise (positive area of the arc closed by its chord): structure to port.
    x, y = line[:, 0], line[:, 1]
    if np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) < 0:
        line = line[::-1]
    line = resample(line, spacing)
    points = np.column_stack([line, np.full(len(line), -depth)])
    if start is not None:
        points = np.vstack([np.asarray(start, dtype=float)[:3], points])
    heading = motion_heading(points)
    sensor = np.column_stack([-np.sin(heading), np.cos(heading), np.zeros(len(heading))])
    return PlannedPath(points, heading, sensor, "slice")


def _end_arc(prior: Bathymetry, solid: np.ndarray, line: np.ndarray, reach: float,
             heading: float) -> np.ndarray:
    """The contiguous part of the contour `line` within `reach` (m) of the structure's end
    facing `heading` (rad): points whose projection on that direction lies beyond the end's
    face less `reach`."""
    u = np.array([np.cos(heading), np.sin(heading)])
    gx, gy = np.meshgrid(prior.x, prior.y)
    along = gx[solid] * u[0] + gy[solid] * u[1]
    face = along.max() + 0.5 * (prior.spacing[0] * abs(u[0]) + prior.spacing[1] * abs(u[1]))
    keep = line @ u >= face - reach
    # A closed loop: roll it so the kept part is contiguous.
    if np.allclose(line[0], line[-1]):
        line, keep = line[:-1], keep[:-1]
        first = np.flatnonzero(keep & ~np.roll(keep, 1))
        if first.size:
            line, keep = np.roll(line, -first[0], axis=0), np.roll(keep, -first[0])
    if keep.sum() < 2:
        raise ValueError("nominal_contour: the end part of the contour holds fewer than 2 "
                         "points")
    return line[keep]
