"""Region of interest: a rectangle or a polygon in map coordinates (the file's CRS).

`crop_to_roi` returns the bathymetry cropped to the ROI's bounding box with cells outside the
polygon set to no-data, in the same world frame and georeferencing as the input.
"""

from __future__ import annotations

import warnings

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
    the grid has no georeferencing); cells outside the polygon become no-data. `roi` may also
    be a shapely (Multi)Polygon, holes included (`terrain.zones.read_zones`)."""
    xx, yy = np.meshgrid(bathy.x, bathy.y)
    centres = bathy.world_to_crs(np.column_stack([xx.ravel(), yy.ravel()]))
    if hasattr(roi, "geom_type"):
        import shapely

        inside = shapely.intersects_xy(roi, centres[:, 0], centres[:, 1]).reshape(bathy.shape)
        if not inside.any():
            lo, hi = centres.min(axis=0), centres.max(axis=0)
            b = roi.bounds
            raise ValueError(f"ROI (bounds x [{b[0]:.2f}, {b[2]:.2f}], y [{b[1]:.2f}, {b[3]:.2f}]) "
                             f"lies outside the grid: its cell centres span x [{lo[0]:.2f}, "
                             f"{hi[0]:.2f}], y [{lo[1]:.2f}, {hi[1]:.2f}] in map units")
        return _crop(bathy, inside)
    poly_map = roi_polygon(roi)
    import shapely

    polygon = shapely.Polygon(poly_map)
    if not polygon.is_valid:  # a self-intersecting ring: the repaired shape, said so
        return crop_to_roi(bathy, repaired(polygon, "ROI polygon"))
    # Cell centres on the boundary count as inside (matplotlib's test is orientation-dependent
    # on the boundary, so take both signs of a tiny tolerance).
    tol = 1e-6 * float(np.ptp(poly_map, axis=0).max())
    path = PolygonPath(poly_map)
    inside = path.contains_points(centres, radius=tol) | path.contains_points(centres, radius=-tol)
    inside = inside.reshape(bathy.shape)
    if not inside.any():
        lo, hi = centres.min(axis=0), centres.max(axis=0)
        raise ValueError(f"ROI {poly_map.tolist()} lies outside the grid: its cell centres span "
                         f"x [{lo[0]:.2f}, {hi[0]:.2f}], y [{lo[1]:.2f}, {hi[1]:.2f}] in map units")
    return _crop(bathy, inside)


def repaired(geom, what: str):
    """`geom` (a shapely polygonal geometry) made valid by `shapely.make_valid`, its polygonal
    part kept, with a one-line warning naming `what`, GEOS's reason and the areas (map
    units^2, the original's by the shoelace sum, which counts a loop the other way round
    negative); `geom` itself when it is valid."""
    import shapely

    if shapely.is_valid(geom):
        return geom
    reason = shapely.is_valid_reason(geom)
    fixed = shapely.make_valid(geom)
    if fixed.geom_type == "GeometryCollection":
        fixed = shapely.union_all([g for g in fixed.geoms
                                   if g.geom_type in ("Polygon", "MultiPolygon")])
    parts = len(getattr(fixed, "geoms", [fixed]))
    warnings.warn(f"{what}: {reason}; repaired into {parts} polygon(s) of area {fixed.area:.6g} "
                  f"(was {geom.area:.6g}) map units^2, the region used", stacklevel=2)
    return fixed


def _crop(bathy: Bathymetry, inside: np.ndarray) -> Bathymetry:
    """`bathy` cropped to the bounding box of the `inside` cells, the others no-data."""
    rows = np.flatnonzero(inside.any(axis=1))
    cols = np.flatnonzero(inside.any(axis=0))
    i0, i1, j0, j1 = rows[0], rows[-1] + 1, cols[0], cols[-1] + 1
    if i1 - i0 < 3 or j1 - j0 < 3:
        raise ValueError(f"ROI covers {i1 - i0} x {j1 - j0} cells; at least 3 x 3 are needed")
    z = np.where(inside, bathy.z, np.nan)[i0:i1, j0:j1]
    if np.isnan(z).all():
        raise ValueError("the ROI holds only no-data cells")
    return Bathymetry(z, bathy.spacing, (bathy.x[j0], bathy.y[i0]), bathy.crs, bathy.to_crs)
