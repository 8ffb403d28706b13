"""Polygon files for regions of interest (with holes) and no-go zones: GeoJSON, Shapefile,
GeoPackage or anything else OGR reads (through pyogrio), in any CRS.

`read_zones` returns one shapely (Multi)Polygon in the map coordinates of the grid's CRS
(reprojected with pyproj from the file's CRS; a file without a CRS is taken to be in the
grid's). `zones_to_world` takes such a geometry to the grid's world frame (ground metres).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.roi import repaired


def read_zones(filename, bathy: Bathymetry, what: str = "no-go zone"):
    """The union of the polygons of `filename`, in map coordinates of `bathy`'s CRS.

    Raises FileNotFoundError for a missing file and ValueError (naming the file) for one that
    does not parse, holds no polygon, or whose CRS cannot be related to the grid's.
    """
    import pyogrio
    import shapely
    from pyproj import CRS, Transformer

    filename = Path(filename)
    if not filename.is_file():
        raise FileNotFoundError(f"{what} file not found: {filename}")
    try:
        meta, _, wkb, _ = pyogrio.raw.read(filename)
    except Exception as err:  # pyogrio raises its own DataSourceError, DataLayerError, ...
        first = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
        raise ValueError(f"{filename}: not a polygon file OGR can read ({first})") from None
    try:
        geoms = shapely.from_wkb([g for g in wkb if g is not None])
    except shapely.errors.GEOSException as err:
        raise ValueError(f"{filename}: invalid geometry ({err})") from None
    polys = [g for g in geoms if g.geom_type in ("Polygon", "MultiPolygon") and not g.is_empty]
    if not polys:
        kinds = sorted({g.geom_type for g in geoms}) or ["nothing"]
        raise ValueError(f"{filename}: a {what} file needs polygons, it holds {', '.join(kinds)}")
    geom = shapely.union_all([repaired(g, f"{filename}: {what} {k}")
                              for k, g in enumerate(polys)])
    file_crs = meta.get("crs")
    if file_crs and bathy.crs is None:
        raise ValueError(f"{filename} is in {file_crs} but the grid has no CRS: give a "
                         "georeferenced grid or a file without a CRS in the grid's coordinates")
    if file_crs and CRS.from_user_input(file_crs) != CRS.from_user_input(bathy.crs):
        x0, y0, x1, y1 = geom.bounds
        if CRS.from_user_input(file_crs).is_geographic and not (
                -180.0 <= x0 <= x1 <= 180.0 and -90.0 <= y0 <= y1 <= 90.0):
            raise ValueError(f"{filename}: its coordinates (x {x0:.6g} to {x1:.6g}, y {y0:.6g} to "
                             f"{y1:.6g}) are not longitudes and latitudes, yet the file is in "
                             f"{file_crs} (a GeoJSON without a crs member is WGS 84); allowed: "
                             "degrees, or a file that names its projected CRS")
        t = Transformer.from_crs(file_crs, bathy.crs, always_xy=True)
        try:
            geom = shapely.transform(
                geom, lambda xy: np.column_stack(t.transform(xy[:, 0], xy[:, 1], errcheck=True)))
        except Exception as err:  # pyproj's ProjError, GEOS on non-finite points
            raise ValueError(f"{filename}: its polygons cannot be moved from {file_crs} to the "
                             f"grid's {bathy.crs} ({' '.join(str(err).split())})") from None
    return geom


def zones_to_world(geom, bathy: Bathymetry):
    """A shapely geometry in map coordinates of `bathy`'s CRS -> its world frame (m)."""
    import shapely

    if bathy.to_crs is None:
        return geom
    inv = np.linalg.inv(np.asarray(bathy.to_crs, float))
    return shapely.transform(geom, lambda xy: xy @ inv[:2, :2].T + inv[:2, 2])


def check_inside_grid(geom_world, bathy: Bathymetry, filename, what: str = "no-go zone") -> None:
    """ValueError when a world-frame geometry does not overlap the grid's extent."""
    import shapely

    xmin, xmax, ymin, ymax = bathy.extent
    if not shapely.intersects(geom_world, shapely.box(xmin, ymin, xmax, ymax)):
        bx = geom_world.bounds
        raise ValueError(f"{filename}: the {what} lies outside the grid: its world bounds x "
                         f"[{bx[0]:.1f}, {bx[2]:.1f}], y [{bx[1]:.1f}, {bx[3]:.1f}] m, the grid's "
                         f"x [{xmin:.1f}, {xmax:.1f}], y [{ymin:.1f}, {ymax:.1f}] m")
