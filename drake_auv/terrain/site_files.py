"""A mission site as files from a bathymetric grid: a fine world mesh, its target and a prior.

A real survey grid (a Monterey tile in EPSG:3857, say) becomes what `site:` in a mission file
names: the true world `world.ply` (the grid interpolated by a bicubic spline to `world_spacing`
m, a triangle mesh in site coordinates), `target.ply` (the world's faces inside the region of
interest) and `prior.tif` (the survey itself, resampled at its own ground resolution), all in
one metric CRS (by default the UTM zone of the region's centre), north up, so that the
mission's local frame, its exports (WGS 84) and the files agree. Pure numpy/scipy/pyproj.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import ndimage
from scipy.interpolate import RectBivariateSpline

from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.geo import GeoFrame
from drake_auv.terrain.mesh import bathymetry_to_mesh
from drake_auv.terrain.readers import write_geotiff


def utm_crs(lon: float, lat: float) -> str:
    """The EPSG code of the WGS 84 UTM zone holding (lon, lat) (degrees)."""
    zone = int(np.floor((lon + 180.0) / 6.0)) % 60 + 1
    return f"EPSG:{32600 + zone if lat >= 0 else 32700 + zone}"


class GridResampler:
    """Elevations of `bathy` at points of another CRS (a bicubic spline on the grid, no-data
    cells filled from their nearest valid neighbour first)."""

    def __init__(self, bathy: Bathymetry, crs: str):
        from pyproj import Transformer

        z = np.array(bathy.z, float)
        if not np.isfinite(z).all():
            nearest = ndimage.distance_transform_edt(~np.isfinite(z), return_distances=False,
                                                     return_indices=True)
            z = z[tuple(nearest)]
        self._spline = RectBivariateSpline(bathy.y, bathy.x, z, kx=3, ky=3)
        self._geo = GeoFrame(bathy)
        self._to_lonlat = Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
        self._bounds = (bathy.x[0], bathy.x[-1], bathy.y[0], bathy.y[-1])

    def world_xy(self, xy) -> np.ndarray:
        """(N, 2) points of the target CRS -> the grid's world frame, m."""
        xy = np.atleast_2d(np.asarray(xy, float))
        lon, lat = self._to_lonlat.transform(xy[:, 0], xy[:, 1])
        return self._geo.from_lonlat(np.column_stack([lon, lat]))

    def grid(self, x0: float, y0: float, nx: int, ny: int, spacing: float) -> np.ndarray:
        """(ny, nx) elevations at the cell centres x0 + j spacing, y0 + i spacing (target CRS);
        NaN outside the source grid."""
        gx, gy = np.meshgrid(x0 + spacing * np.arange(nx), y0 + spacing * np.arange(ny))
        w = self.world_xy(np.column_stack([gx.ravel(), gy.ravel()]))
        z = self._spline.ev(w[:, 1], w[:, 0])
        xmin, xmax, ymin, ymax = self._bounds
        z[(w[:, 0] < xmin) | (w[:, 0] > xmax) | (w[:, 1] < ymin) | (w[:, 1] > ymax)] = np.nan
        return z.reshape(ny, nx)


def write_site_files(bathy: Bathymetry, roi, out_dir, world_spacing: float = 1.0,
                     prior_spacing: float | None = None, margin: float = 40.0,
                     crs: str | None = None) -> dict:
    """Writes world.ply, target.ply and prior.tif for the region `roi` of `bathy`.

    Args:
        bathy: a georeferenced grid (a CRS, e.g. a GeoTIFF read by `read_bathymetry`).
        roi: (xmin, ymin, xmax, ymax) of the region of interest in `bathy`'s world frame, m.
        world_spacing: cell of the world mesh, m, in (0, 10].
        prior_spacing: cell of the prior, m (None: the grid's larger ground cell).
        margin: world beyond the region on each side, m, >= 0 (room for turns and transits;
            the prior covers the region and one of its cells more, so plans stay inside).
        crs: the site's CRS (None: the UTM zone of the region's centre).
    Returns {"world", "target", "prior": paths, "crs": the CRS, "roi": the region's
    (xmin, ymin, xmax, ymax) in the site's CRS}.
    """
    if bathy.crs is None:
        raise ValueError("write_site_files needs a georeferenced grid (one with a CRS)")
    if not (np.isfinite(world_spacing) and 0 < world_spacing <= 10):
        raise ValueError(f"world_spacing must be in (0, 10] m, got {world_spacing}")
    if not (np.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be >= 0 m, got {margin}")
    xmin, ymin, xmax, ymax = (float(v) for v in roi)
    if not (xmin < xmax and ymin < ymax):
        raise ValueError(f"roi must be (xmin, ymin, xmax, ymax) with min < max, got {roi}")
    geo = GeoFrame(bathy)
    corners = np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])
    lonlat = geo.to_lonlat(corners)
    crs = crs or utm_crs(*lonlat.mean(axis=0))
    from pyproj import Transformer

    to_site = Transformer.from_crs("EPSG:4326", crs, always_xy=True)
    sx, sy = to_site.transform(lonlat[:, 0], lonlat[:, 1])
    site_roi = (min(sx), min(sy), max(sx), max(sy))
    resampler = GridResampler(bathy, crs)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)

    def grid(spacing: float, pad: float) -> Bathymetry:
        x0 = np.floor((site_roi[0] - pad) / spacing) * spacing
        y0 = np.floor((site_roi[1] - pad) / spacing) * spacing
        nx = int(np.ceil((site_roi[2] + pad - x0) / spacing)) + 1
        ny = int(np.ceil((site_roi[3] + pad - y0) / spacing)) + 1
        return Bathymetry(resampler.grid(x0, y0, nx, ny, spacing), (spacing, spacing),
                          (x0, y0), crs)

    world_grid = grid(world_spacing, margin)
    if not np.isfinite(world_grid.z).all():
        raise ValueError(f"roi {roi} with a {margin:g} m margin reaches beyond the grid")
    world = bathymetry_to_mesh(world_grid)
    centres = world.triangles_center
    inside = ((centres[:, 0] >= site_roi[0]) & (centres[:, 0] <= site_roi[2])
              & (centres[:, 1] >= site_roi[1]) & (centres[:, 1] <= site_roi[3]))
    target = world.submesh([np.flatnonzero(inside)], append=True)
    prior = grid(prior_spacing or float(max(bathy.spacing)), float(max(bathy.spacing)))
    paths = {"world": out / "world.ply", "target": out / "target.ply", "prior": out / "prior.tif"}
    world.export(paths["world"])
    target.export(paths["target"])
    write_geotiff(prior, paths["prior"])
    return {**paths, "crs": crs, "roi": site_roi}
