"""Slope map and terrain classification into high-slope regions and the effectively planar rest.

S(x, y) = |grad z| (rise over run, dimensionless) with the true cell spacing. Cells with
S > delta_s are high-slope; a morphological closing (joins fragments of one wall), then removal
of components smaller than a minimum area clean the mask; planar specks smaller than the
minimum area are given to the high-slope class (the slicing sweeps them with the wall around
them). No opening by default: an opening of radius r erases every band narrower than 2 r, and a
near-vertical wall seen from above is a steep band one or two cells wide; thin noise goes with
the minimum area instead (`opening_radius` still opens when asked). The minimum area is a fixed
number of square metres (`MIN_AREA_M2`, at least `MIN_AREA_CELLS` cells), so the regions found
never depend on how large the ROI around them is. The reference fixes only delta_s = 0.5; the
closing size and the minimum area are ours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from drake_auv.terrain.bathymetry import Bathymetry


def _nan_gradient(z: np.ndarray, h: float, axis: int) -> np.ndarray:
    """dz/d(axis): central differences where both neighbours hold data, one-sided next to
    no-data or the grid's edge, 0 for a cell with no valid neighbour on that axis; NaN on
    no-data cells."""
    zp = np.pad(np.moveaxis(z, axis, 0), ((1, 1), (0, 0)), constant_values=np.nan)
    forward = (zp[2:] - zp[1:-1]) / h
    backward = (zp[1:-1] - zp[:-2]) / h
    ok_f, ok_b = np.isfinite(forward), np.isfinite(backward)
    g = np.where(ok_f & ok_b, 0.5 * (forward + backward),
                 np.where(ok_f, forward, np.where(ok_b, backward, 0.0)))
    g = np.moveaxis(g, 0, axis)
    return np.where(np.isfinite(z), g, np.nan)


def slope_map(bathy: Bathymetry) -> np.ndarray:
    """(ny, nx) slope |grad z| with the true spacing, NaN on no-data cells.

    Central differences inside; one-sided at the grid's edges and next to no-data.
    """
    dx, dy = bathy.spacing
    return np.hypot(_nan_gradient(bathy.z, dx, 1), _nan_gradient(bathy.z, dy, 0))


def surface_gradient(bathy: Bathymetry, z: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(dz/dx, dz/dy) on the grid, from `z` (default: the bathymetry's own, NaN kept)."""
    dx, dy = bathy.spacing
    gy, gx = np.gradient(bathy.z if z is None else z, dy, dx)
    return gx, gy


@dataclass(frozen=True)
class TerrainLabels:
    """Result of `classify`.

    Attributes:
        slope: (ny, nx) slope map S.
        high: (ny, nx) bool, cleaned high-slope mask.
        regions: (ny, nx) int, 0 for planar or no-data, k = 1..n_regions for high-slope region k.
        n_regions: number of high-slope regions.
        valid: (ny, nx) bool, cells holding data.
    """

    slope: np.ndarray
    high: np.ndarray
    regions: np.ndarray
    n_regions: int
    valid: np.ndarray

    @property
    def planar(self) -> np.ndarray:
        """(ny, nx) bool, valid cells outside every high-slope region."""
        return self.valid & ~self.high


MIN_AREA_M2 = 100.0  # default minimum area of a high-slope region (and of a planar speck), m^2
MIN_AREA_CELLS = 4   # ... and at least this many cells, so one noisy cell is never a region


def _disk(radius_cells_x: float, radius_cells_y: float) -> np.ndarray:
    rx, ry = max(radius_cells_x, 0.5), max(radius_cells_y, 0.5)
    ny, nx = int(np.floor(ry)), int(np.floor(rx))
    yy, xx = np.mgrid[-ny:ny + 1, -nx:nx + 1]
    return (xx / rx) ** 2 + (yy / ry) ** 2 <= 1.0 + 1e-9


def classify(bathy: Bathymetry, slope_threshold: float = 0.5, closing_radius: float | None = None,
             opening_radius: float | None = None, min_area: float | None = None) -> TerrainLabels:
    """Splits the valid cells into high-slope regions and the effectively planar rest.

    Args:
        slope_threshold: delta_s > 0; cells with S > delta_s are high-slope (0.5 is about 26.6 deg).
        closing_radius: radius of the disk for the closing, m (default 2 cells).
        opening_radius: radius of the disk for an opening after the closing, m (default 0: none,
            see the module docstring).
        min_area: high-slope components smaller than this are dropped and planar ones smaller
            than this become high-slope, m^2 (default `MIN_AREA_M2`, at least `MIN_AREA_CELLS`
            cells; independent of the ROI's size).
    """
    if not (np.isfinite(slope_threshold) and slope_threshold > 0):
        raise ValueError(f"slope_threshold (delta_s) must be > 0, got {slope_threshold}")
    dx, dy = bathy.spacing
    cell_area = dx * dy
    closing_radius = 2.0 * max(dx, dy) if closing_radius is None else closing_radius
    opening_radius = 0.0 if opening_radius is None else opening_radius
    for name, value in (("closing_radius", closing_radius), ("opening_radius", opening_radius)):
        if not (np.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be >= 0 m, got {value}")
    valid = bathy.valid
    if min_area is None:
        min_area = max(MIN_AREA_M2, MIN_AREA_CELLS * cell_area)
    if not (np.isfinite(min_area) and min_area >= 0):
        raise ValueError(f"min_area must be >= 0 m^2, got {min_area}")
    slope = slope_map(bathy)
    high = np.nan_to_num(slope, nan=0.0) > slope_threshold
    if not valid.all():
        # Extend the mask into the holes (nearest valid cell) so the morphology neither
        # erodes nor closes at their edges.
        _, (ii, jj) = ndimage.distance_transform_edt(~valid, sampling=bathy.spacing[::-1],
                                                     return_indices=True)
        high = high[ii, jj]
    if closing_radius > 0:
        disk = _disk(closing_radius / dx, closing_radius / dy)
        pad = max(disk.shape)
        padded = np.pad(high, pad, mode="edge")  # no closing artefacts at the grid's border
        high = ndimage.binary_closing(padded, structure=disk)[pad:-pad, pad:-pad]
    if opening_radius > 0:
        disk = _disk(opening_radius / dx, opening_radius / dy)
        pad = max(disk.shape)
        padded = np.pad(high, pad, mode="edge")
        high = ndimage.binary_opening(padded, structure=disk)[pad:-pad, pad:-pad]
    high &= valid
    # Planar specks enclosed by steep ground are swept by the slicing; steep specks dropped.
    planar, n_planar = ndimage.label(valid & ~high)
    if n_planar:
        areas = ndimage.sum_labels(np.ones_like(planar), planar, np.arange(1, n_planar + 1))
        small = np.concatenate([[False], areas * cell_area < min_area])
        high |= small[planar]
    regions, n = ndimage.label(high)
    if n:
        areas = ndimage.sum_labels(np.ones_like(regions), regions, np.arange(1, n + 1)) * cell_area
        keep = np.concatenate([[False], areas >= min_area])
        remap = np.cumsum(keep) * keep
        regions = remap[regions]
        n = int(keep.sum())
        high = regions > 0
    return TerrainLabels(slope, high, regions, n, valid)
