"""The breakwater mission of the reference (Section 5.5.3): realtime replanning on and off.

The right-most concrete block of the `breakwater` scenario is targeted by a single contour at
5 m depth with offset Omega = 6 m: an open semicircle around its three free faces, since the
0.5 m gaps between blocks leave no room to pass. The nominal contour is planned on a prior
map shifted by up to 5 m (seeded); the vehicle carries a port-looking multibeam and a
horizontal pencil-beam profiler, both at 20 m range. The same mission is flown twice per seed:
with the replanner (octree map + STOMP at 1 Hz) and nominal-only. Written to `--out`:
`breakwater_replanning.md` (the table), `breakwater_replanning.png` (like the reference's
Figure 88) and `breakwater_replanning.html` (Meshcat recording of the first replanning run).

    .venv/bin/python examples/breakwater_replanning.py --seeds 10 --out out/breakwater
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path as FilePath

import contourpy
import numpy as np
from scipy import ndimage
from tqdm import tqdm

from drake_auv.geometry.raycast import RayCaster
from drake_auv.geometry.visibility import CoverageMap
from drake_auv.planning.path import Path
from drake_auv.planning.polyline import motion_heading, resample
from drake_auv.planning.replanning import ReplanningParameters
from drake_auv.scenarios import get_scenario

CAMERA_APERTURE = np.radians(60.0)  # the reference's payload camera
VEHICLE_RADIUS = 1.0  # m, GIRONA 500 half-length, the contact threshold


def nominal_contour(prior, depth: float, omega: float, block_size: float, start,
                    spacing: float = 1.0) -> Path:
    """The nominal path planned on the prior map: the offset-Omega contour, at `depth`, of the
    cross-section of the structure, kept around the right-most block (x beyond its west face),
    flown counter-clockwise (structure to port) from the end nearest `start`, which is
    prepended (the transit from the start)."""
    solid = np.nan_to_num(prior.z, nan=-np.inf) > -depth
    if not solid.any():
        raise ValueError(f"the prior map has no structure above {depth} m depth")
    cell = prior.spacing[0]
    dist = ndimage.distance_transform_edt(~solid, sampling=(prior.spacing[1], cell))
    # Solid cell centres lie up to half a cell inside the face: the level compensates.
    lines = contourpy.contour_generator(prior.x, prior.y, dist).lines(omega + 0.5 * cell)
    line = max(lines, key=len)
    xs = prior.x[np.nonzero(solid.any(axis=0))[0]]
    west = xs.max() + 0.5 * cell - block_size  # the right-most block's west face
    keep = line[:, 0] >= west - 1.0
    # The kept part is one arc of the loop: roll the loop so it is contiguous.
    if np.allclose(line[0], line[-1]):
        line = line[:-1]
        keep = keep[:-1]
        first = np.flatnonzero(keep & ~np.roll(keep, 1))
        if first.size:
            line, keep = np.roll(line, -first[0], axis=0), np.roll(keep, -first[0])
    arc = line[keep]
    # Counter-clockwise around the block: the structure (centre of the arc's chord side) to port.
    centre = np.array([xs.max() + 0.5 * cell - 0.5 * block_size, arc[:, 1].mean()])
    rel = arc - centre
    if np.sum(rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0]) < 0:
        arc = arc[::-1]
    arc = resample(arc, spacing)
    points = np.column_stack([arc, np.full(len(arc), -depth)])
    points = np.vstack([np.asarray(start, dtype=float)[:3], points])
    heading = motion_heading(points)
    sensor = np.column_stack([-np.sin(heading), np.cos(heading), np.zeros(len(heading))])
    return Path(points, heading, sensor, "slice")
