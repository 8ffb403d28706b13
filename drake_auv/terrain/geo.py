"""World (grid) frame <-> the grid's map CRS <-> WGS 84 longitude/latitude, through pyproj.

World frame: the `Bathymetry`'s own (x along the columns, y along the rows, ground metres).
`Bathymetry.to_crs` takes world xy to the file's map coordinates; pyproj takes those to WGS 84.
A grid without a CRS (a synthetic site, a CRS-less .npz) needs an anchor: `origin_lonlat`, the
WGS 84 position of the world origin, with world x east and y north on a transverse Mercator
projection centred there (scale 1, so world metres are ground metres to ~1e-6 within 10 km).
"""

from __future__ import annotations

import numpy as np

from drake_auv.terrain.bathymetry import Bathymetry

# Where `drake-auv plan caldera` places the synthetic caldera-rim site: the Santorini caldera's
# western rim (WGS 84 lon, lat of its south-west corner), so its exports are real positions.
CALDERA_ORIGIN_LONLAT = (25.40, 36.40)


class GeoFrame:
    """Coordinate conversions of one grid.

    Args:
        bathy: the grid (its `crs` and `to_crs`).
        origin_lonlat: WGS 84 (lon, lat) of the world origin, degrees; only for grids without
            a CRS, where it is required.
    """

    def __init__(self, bathy: Bathymetry, origin_lonlat=None):
        from pyproj import CRS, Transformer
        from pyproj.exceptions import CRSError

        if bathy.crs is None:
            if origin_lonlat is None:
                raise ValueError("the grid has no CRS: WGS 84 exports need a georeferenced file "
                                 "or an anchor (--origin-lonlat LON,LAT, origin_lonlat=(lon, lat))")
            lon, lat = (float(v) for v in origin_lonlat)
            if not (np.isfinite(lon) and np.isfinite(lat) and -180 <= lon <= 180
                    and -90 < lat < 90):
                raise ValueError(f"origin_lonlat must be lon in [-180, 180], lat in (-90, 90) "
                                 f"degrees, got {origin_lonlat}")
            crs = CRS.from_proj4(f"+proj=tmerc +lat_0={lat} +lon_0={lon} +k=1 +x_0=0 +y_0=0 "
                                 "+datum=WGS84 +units=m +no_defs")
            to_crs = np.eye(3)
        else:
            try:
                crs = CRS.from_user_input(bathy.crs)
            except CRSError as err:
                raise ValueError(f"the grid's CRS {bathy.crs!r} is not one pyproj knows ({err})") \
                    from None
            to_crs = np.eye(3) if bathy.to_crs is None else np.asarray(bathy.to_crs, float)
        self.crs = crs
        self._to_crs = to_crs
        self._from_crs = np.linalg.inv(to_crs)
        self._fwd = Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
        self._inv = Transformer.from_crs("EPSG:4326", crs, always_xy=True)

    def world_to_map(self, xy) -> np.ndarray:
        """(N, 2) world xy (m) -> map coordinates of the grid's CRS."""
        xy = np.atleast_2d(np.asarray(xy, float))
        return xy @ self._to_crs[:2, :2].T + self._to_crs[:2, 2]

    def map_to_world(self, xy) -> np.ndarray:
        """(N, 2) map coordinates of the grid's CRS -> world xy, m."""
        xy = np.atleast_2d(np.asarray(xy, float))
        return xy @ self._from_crs[:2, :2].T + self._from_crs[:2, 2]

    def to_lonlat(self, xy) -> np.ndarray:
        """(N, 2) world xy (m) -> WGS 84 (lon, lat), degrees."""
        m = self.world_to_map(xy)
        lon, lat = self._fwd.transform(m[:, 0], m[:, 1])
        return np.column_stack([lon, lat])

    def from_lonlat(self, lonlat) -> np.ndarray:
        """(N, 2) WGS 84 (lon, lat), degrees -> world xy, m."""
        ll = np.atleast_2d(np.asarray(lonlat, float))
        x, y = self._inv.transform(ll[:, 0], ll[:, 1])
        return self.map_to_world(np.column_stack([x, y]))

    def grid_north_azimuth(self, xy) -> np.ndarray:
        """(N,) azimuth of world +y at each point, radians clockwise from true north (the
        meridian convergence plus any rotation of the grid), for compass headings."""
        xy = np.atleast_2d(np.asarray(xy, float))
        a = self.to_lonlat(xy)
        b = self.to_lonlat(xy + np.array([0.0, 1.0]))
        dlat = np.radians(b[:, 1] - a[:, 1])
        dlon = np.radians(b[:, 0] - a[:, 0]) * np.cos(np.radians(a[:, 1]))
        return np.arctan2(dlon, dlat)

    def compass_yaw(self, xy, heading) -> np.ndarray:
        """(N,) world headings `heading` (rad, from world +x counter-clockwise) at world points
        `xy` (N, 2) as NED yaws: radians clockwise from true north, in [0, 2 pi)."""
        return np.mod(np.pi / 2 - np.asarray(heading, float) + self.grid_north_azimuth(xy),
                      2 * np.pi)
