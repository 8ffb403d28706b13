"""Slicing of high-slope regions (after Atkar et al., adapted to bathymetry).

Horizontal planes z = const cut the region's surface in contours (marching squares, contourpy).
The vehicle follows each contour at offset Omega along the local surface normal and its sensor
looks back along the inward normal, so it sees the wall square-on (a tilted forward-looking
sensor). Optionally the sensor keeps one fixed tilt per region (what a vehicle that is passively
stable in roll and pitch can hold without a pan-tilt unit), matched to the region's median slope.
Contours are swept level by level, bottom to top, each piece entered at its end nearest to the
vehicle.

Plane spacing: the reference spaces the planes by the sensor's footprint. A footprint of width
w = 2 Omega tan(aperture / 2) (1 - overlap) measured along a wall of slope S spans
w S / sqrt(1 + S^2) in height; we take S as a low quantile (10 %) of the region's slope so the
gentler parts of the wall are still covered without gaps. `slice_spacing` overrides it.
"""

from __future__ import annotations

from dataclasses import dataclass

import contourpy
import numpy as np
from scipy import ndimage

from drake_auv.planning.parameters import MAX_SLICES
from drake_auv.planning.polyline import length, resample
from drake_auv.planning.surface import TerrainSurface


@dataclass(frozen=True)
class Contour:
    """One piece of a slicing contour and the path that follows it.

    Attributes:
        region: high-slope region number (1-based, as in `TerrainLabels.regions`).
        level: elevation of the slicing plane, m.
        surface: (n, 3) points of the contour on the terrain.
        path: (n, 3) path samples, offset Omega along the upward normal.
        sensor_dir: (n, 3) unit sensor axes (the inward normal).
        closed: whether the contour is a loop.
    """

    region: int
    level: float
    surface: np.ndarray
    path: np.ndarray
    sensor_dir: np.ndarray
    closed: bool

    @property
    def length(self) -> float:
        return length(self.path)


def slice_levels(surface: TerrainSurface, region_mask: np.ndarray, slope: np.ndarray,
                 footprint: float, spacing: float | None = None,
                 count: int | None = None) -> np.ndarray:
    """Elevations of the slicing planes across one region, m (at least one).

    With `count`, exactly that many planes `spacing` apart, centred on the region's elevation
    range (the reference's deliberately redundant plan of two contours 2 m apart)."""
    z = surface.z[region_mask]
    zmin, zmax = float(z.min()), float(z.max())
    if spacing is None:
        s_low = float(np.nanquantile(slope[region_mask], 0.1))
        s_low = max(s_low, 0.05)
        spacing = footprint * s_low / np.sqrt(1.0 + s_low ** 2)
    n = ((zmax - zmin) / spacing if count is None else count)
    if n > MAX_SLICES:
        raise ValueError(f"slice_spacing {spacing:g} m gives {n:.3g} slicing planes over a "
                         f"high-slope region {zmax - zmin:.1f} m high; allowed: at most "
                         f"{MAX_SLICES} planes (slice_spacing >= "
                         f"{(zmax - zmin) / MAX_SLICES:.3g} m there)")
    n = max(1, int(np.ceil((zmax - zmin) / spacing - 1e-9))) if count is None else int(count)
    first = zmin + 0.5 * ((zmax - zmin) - (n - 1) * spacing)
    return first + spacing * np.arange(n)


def sensor_axes(normals: np.ndarray, depression=None) -> np.ndarray:
    """(n, 3) sensor axes looking into the wall: the inward normal -n itself, or, with a fixed
    `depression` angle below the horizontal (rad, scalar or (n,)), the axis of a sensor rigidly
    tilted on a vehicle that keeps roll and pitch level, turned to face the wall's horizontal
    normal."""
    inward = -normals
    if depression is None:
        return inward
    horiz = inward[:, :2]
    norm = np.linalg.norm(horiz, axis=1, keepdims=True)
    horiz = np.where(norm > 1e-9, horiz / np.maximum(norm, 1e-12), np.array([1.0, 0.0]))
    dep = np.broadcast_to(np.asarray(depression, dtype=float), (len(horiz),))
    return np.column_stack([np.cos(dep)[:, None] * horiz, -np.sin(dep)])


def fixed_depression(slope: np.ndarray) -> float:
    """Depression angle (rad) of a fixed sensor that sees a wall of the median `slope` square-on:
    the inward normal of a slope S points 90 deg - arctan(S) below the horizontal."""
    return float(np.pi / 2 - np.arctan(np.nanmedian(slope)))


def slice_region(surface: TerrainSurface, region_mask: np.ndarray, region: int,
                 levels: np.ndarray, omega: float, sample_spacing: float,
                 min_length: float, depression: float | None = None) -> list[list[Contour]]:
    """Contours of one region per level (lowest level first); pieces shorter than
    `min_length` (m) are dropped, the neighbouring levels' footprints cover them.

    The sensor looks along the inward normal (`depression` None) or is tilted at a fixed
    `depression` (see `sensor_axes`); the path point is Omega back along the axis from the
    contour, which for the normal is the offset Omega along the surface normal."""
    (box,) = ndimage.find_objects(region_mask.astype(np.int8))
    box = tuple(slice(max(b.start - 1, 0), b.stop + 1) for b in box)  # contour the region's box
    grown = ndimage.binary_dilation(region_mask[box], iterations=1)  # one cell on each side
    bathy = surface.bathy
    zm = np.ma.array(surface.z[box], mask=~grown)
    gen = contourpy.contour_generator(bathy.x[box[1]], bathy.y[box[0]], zm,
                                      line_type=contourpy.LineType.Separate)
    out = []
    for level, lines in zip(levels, gen.multi_lines(levels)):
        pieces = []
        for line in lines:
            if len(line) < 2 or length(line) < min_length:
                continue
            closed = bool(np.allclose(line[0], line[-1]))
            xy = resample(line, sample_spacing)
            q = np.column_stack([xy, np.full(len(xy), level)])
            axes = sensor_axes(surface.normal(xy[:, 0], xy[:, 1]), depression)
            pieces.append(Contour(region, float(level), q, q - omega * axes, axes, closed))
        out.append(pieces)
    return out


def order_contours(levels: list[list[Contour]], start_xyz) -> list[Contour]:
    """Contour pieces in sweep order: level by level; within a level the piece nearest to the
    current position next, entered at its nearest end (loops at their nearest sample)."""
    here = np.asarray(start_xyz, dtype=float)
    ordered = []
    for pieces in levels:
        todo = list(pieces)
        while todo:
            best = None
            for k, c in enumerate(todo):
                if c.closed:
                    d = np.linalg.norm(c.path - here, axis=1)
                    i = int(np.argmin(d))
                    cand = (d[i], k, ("roll", i))
                else:
                    d0 = np.linalg.norm(c.path[0] - here)
                    d1 = np.linalg.norm(c.path[-1] - here)
                    cand = (d0, k, ("fwd",)) if d0 <= d1 else (d1, k, ("rev",))
                if best is None or cand[0] < best[0]:
                    best = cand
            _, k, how = best
            c = todo.pop(k)
            if how[0] == "rev":
                c = Contour(c.region, c.level, c.surface[::-1], c.path[::-1], c.sensor_dir[::-1], False)
            elif how[0] == "roll" and how[1]:
                i = how[1]
                c = Contour(c.region, c.level, _restart_loop(c.surface, i), _restart_loop(c.path, i),
                            _restart_loop(c.sensor_dir, i), True)
            ordered.append(c)
            here = c.path[-1]
    return ordered


def _restart_loop(samples: np.ndarray, i: int) -> np.ndarray:
    """A closed polyline (first sample == last) restarted at sample i, still closed."""
    return np.vstack([samples[i:-1], samples[:i + 1]])
