"""Region of interest: a rectangle or a polygon in map coordinates (the file's CRS).

`crop_to_roi` returns the bathymetry cropped to the ROI's bounding box with cells outside the
polygon set to no-data, in the same world frame and georeferencing as the input.
"""

from __future__ import annotations

import numpy as np
from matplotlib.path import Path as PolygonPath

from drake_auv.terrain.bathymetry import Bathymetry


def roi_polygon(roi) -> np.ndarray:
    """(K, 2) polygon vertices from a rectangle (xmin, ymin, xmax, ymax) or a vertex list."""
    arr = np.asarray(roi, dtype=float)
    if arr.ndim == 1 and arr.size == 4:
        xmin, ymin, xmax, ymax = arr
        if not (xmax > xmin and ymax > ymin):
            raise ValueError(f"ROI rectangle must be (xmin, ymin, xmax, ymax) with xmax > xmin and "
                             f"ymax > ymin, got {tuple(arr)}")
        return np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    if arr.ndim != 2 or arr.shape[1] != 2 or len(arr) < 3:
        raise ValueError(f"ROI must be a rectangle (xmin, ymin, xmax, ymax) or >= 3 (x, y) vertices, "
                         f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("ROI vertices must be finite")
    return arr


def parse_roi(text: str) -> np.ndarray:
    """Parses a CLI ROI: 'xmin,ymin,xmax,ymax' or 'x1,y1;x2,y2;x3,y3;...'."""
    try:
        if ";" in text:
            return roi_polygon([[float(v) for v in pair.split(",")] for pair in text.split(";")])
        return roi_polygon([float(v) for v in text.split(",")])
    except ValueError as err:
        raise ValueError(f"--roi: expected 'xmin,ymin,xmax,ymax' or 'x1,y1;x2,y2;...' ({err})") from None


def crop_to_roi(bathy: Bathymetry, roi) -> Bathymetry:
    """The part of `bathy` inside `roi` (map coordinates of the file's CRS, or world metres when
    the grid has no georeferencing); cells outside the polygon become no-data."""
    poly_map = roi_polygon(roi)
    if bathy.to_crs is not None:
        to_world = np.linalg.inv(np.asarray(bathy.to_crs, dtype=float))
        poly = (np.hstack([poly_map, np.ones((len(poly_map), 1))]) @ to_world.T)[:, :2]
    else:
        poly = poly_map
    xx, yy = np.meshgrid(bathy.x, bathy.y)
    inside = PolygonPath(poly).contains_points(np.column_stack([xx.ravel(), yy.ravel()]))
    inside = inside.reshape(bathy.shape)
    if not inside.any():
        xmin, xmax, ymin, ymax = bathy.extent
        raise ValueError(f"ROI {poly_map.tolist()} does not contain any cell centre of the grid "
                         f"(world extent x [{xmin:.1f}, {xmax:.1f}], y [{ymin:.1f}, {ymax:.1f}] m)")
    rows = np.flatnonzero(inside.any(axis=1))
    cols = np.flatnonzero(inside.any(axis=0))
    i0, i1, j0, j1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    if i1 - i0 < 3 or j1 - j0 < 3:
        raise ValueError(f"ROI covers {i1 - i0} x {j1 - j0} cells; at least 3 x 3 are needed")
    z = np.where(inside, bathy.z, np.nan)[i0:i1, j0:j1]
    if np.isnan(z).all():
        raise ValueError("the ROI holds only no-data cells")
    return Bathymetry(z, bathy.spacing, (bathy.x[j0], bathy.y[i0]), bathy.crs, bathy.to_crs)
