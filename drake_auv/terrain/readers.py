"""Bathymetry readers: any raster GDAL reads through rasterio (GeoTIFF, ESRI ASCII grid, XYZ
grid, netCDF/GMT grid, BAG), plus a plain `.npz` (z, spacing, origin).

The world frame of the returned `Bathymetry` is the grid's own frame in ground metres: x along
the columns, y along the rows (rows reordered so that x, y, z is right-handed with the map's
axes), origin at the centre of the first cell. `to_crs` maps world (x, y) back to the file's
map coordinates, so exports land in its CRS. Ground metres differ from map units for
geographic CRSs (degrees, converted with the local radius) and for Mercator projections
(map metres are inflated by 1 / cos(latitude); scaled by cos of the grid centre's latitude).
A CRS-less grid whose coordinate variables are in degrees (GMT/COARDS netCDF) is taken as
WGS 84 longitude/latitude; any other CRS-less grid is taken to be in metres.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from drake_auv.output_files import replacing
from drake_auv.resources import check_memory
from drake_auv.terrain.bathymetry import Bathymetry, elevation_problem

_EARTH_RADIUS = 6378137.0  # WGS 84 semi-major axis, m (the sphere of Pseudo-Mercator)
_MERCATOR_EPSG = {3857, 3395, 900913, 3785, 54004}
# Reading a raster holds its band (up to float64), the mask, the float64 copy and the filled
# grid at once: bytes per cell, checked against the machine before the read.
READ_BYTES_PER_CELL = 25


def read_bathymetry(path) -> Bathymetry:
    """Reads a bathymetric grid (elevation, m, z up) into a `Bathymetry` in ground metres.

    No-data cells (the file's nodata value, a mask, or NaN) become NaN, which planners treat
    as no-go. Raises FileNotFoundError for a missing file and ValueError for an unreadable one.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"bathymetry file not found: {path}")
    if path.suffix.lower() == ".npz":
        return _read_npz(path)
    return _read_raster(path)


def _read_npz(path: Path) -> Bathymetry:
    try:
        with np.load(path, allow_pickle=False) as data:
            keys = set(data.keys())
            if "z" not in keys:
                raise ValueError(f"{path}: an .npz bathymetry needs an array 'z' "
                                 f"(and optional 'spacing', 'origin', 'crs'), has {sorted(keys)}")
            z = np.asarray(data["z"], dtype=float)
            spacing = tuple(np.ravel(data["spacing"])) if "spacing" in keys else (1.0, 1.0)
            origin = tuple(np.ravel(data["origin"])) if "origin" in keys else (0.0, 0.0)
            crs = str(data["crs"]) if "crs" in keys else None
    except (OSError, EOFError, zipfile.BadZipFile) as err:
        raise ValueError(f"{path}: not a readable .npz file ({err})") from None
    try:
        return Bathymetry(z, spacing, origin, crs)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None


def _ground_scale(crs, centre_map: np.ndarray, degrees: bool) -> tuple[float, float]:
    """Ground metres per map unit along map x and y at the grid centre."""
    if crs is None and not degrees:
        return 1.0, 1.0
    if degrees or crs.is_geographic:
        lat = np.radians(centre_map[1])
        per_deg = np.pi / 180.0 * _EARTH_RADIUS
        return per_deg * np.cos(lat), per_deg
    epsg = crs.to_epsg()
    proj4 = crs.to_proj4() if hasattr(crs, "to_proj4") else ""
    if epsg in _MERCATOR_EPSG or "+proj=merc" in proj4:
        lat = 2.0 * np.arctan(np.exp(centre_map[1] / _EARTH_RADIUS)) - np.pi / 2.0
        unit = crs.linear_units_factor[1] if crs.linear_units_factor else 1.0
        return unit * np.cos(lat), unit * np.cos(lat)
    unit = crs.linear_units_factor[1] if crs.linear_units_factor else 1.0
    return unit, unit


def _degree_axes(tags: dict) -> bool:
    """True when a CRS-less grid (typically a GMT/COARDS netCDF) declares degree coordinates."""
    return any(k.endswith("#units") and "degree" in str(v).lower() for k, v in tags.items())


_ELEVATION_NAMES = ("z", "elevation", "band1", "height", "topo", "bathymetry")


def _elevation_subdataset(path: Path, subdatasets: list[str]) -> str:
    """The elevation variable of a multi-variable container (netCDF, HDF5)."""
    by_name = {sd.rsplit(":", 1)[-1].lower(): sd for sd in subdatasets}
    for name in _ELEVATION_NAMES:
        if name in by_name:
            return by_name[name]
    if len(subdatasets) == 1:
        return subdatasets[0]
    raise ValueError(f"{path}: no band, and none of its variables "
                     f"{[sd.rsplit(':', 1)[-1] for sd in subdatasets]} is named like an "
                     f"elevation {list(_ELEVATION_NAMES)}")


def _read_raster(path: Path) -> Bathymetry:
    import warnings

    import rasterio
    from rasterio.errors import NotGeoreferencedWarning, RasterioIOError

    try:
        with warnings.catch_warnings():
            # A grid without georeferencing is read in its own units, taken as metres.
            warnings.simplefilter("ignore", NotGeoreferencedWarning)
            source = path
            with rasterio.open(path) as ds:
                if ds.count < 1:
                    source = _elevation_subdataset(path, ds.subdatasets)
            with rasterio.open(source) as ds:
                check_memory(READ_BYTES_PER_CELL * ds.width * ds.height,
                             f"{path}: reading its {ds.height} x {ds.width} cells")
                band = ds.read(1, masked=True).astype(float)
                transform = ds.transform
                crs = ds.crs
                degrees = crs is None and _degree_axes(ds.tags())
    except RasterioIOError as err:
        raise ValueError(f"{path}: not a raster GDAL can read ({err})") from None
    z = np.ma.filled(band, np.nan)
    problem = elevation_problem(z, " of the file")  # as `Bathymetry` does, in the file's rows
    if problem is not None:
        raise ValueError(f"{path}: {problem}")
    ny, nx = z.shape
    a, b, c, d, e, f = transform.a, transform.b, transform.c, transform.d, transform.e, transform.f
    jac = np.array([[a, b], [d, e]])  # map units per (column, row) step
    if abs(np.linalg.det(jac)) < 1e-15:
        raise ValueError(f"{path}: degenerate geotransform {tuple(transform)[:6]}")
    flip = np.linalg.det(jac) < 0  # rows run against the map's y: reverse them
    if flip:
        z = z[::-1]
    centre = np.array([c, f]) + jac @ np.array([nx / 2.0, ny / 2.0])
    kx, ky = _ground_scale(crs, centre, degrees)
    col_ground = np.hypot(a * kx, d * ky)
    row_ground = np.hypot(b * kx, e * ky)
    # world (x, y) -> (column, row) of the file, centre-based -> map coordinates.
    world_to_index = np.array([[1.0 / col_ground, 0.0, 0.0],
                               [0.0, 1.0 / row_ground, 0.0],
                               [0.0, 0.0, 1.0]])
    if flip:
        world_to_index = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, ny - 1.0], [0.0, 0.0, 1.0]]) \
            @ world_to_index
    index_to_map = np.array([[a, b, c + 0.5 * (a + b)],
                             [d, e, f + 0.5 * (d + e)],
                             [0.0, 0.0, 1.0]])
    to_crs = index_to_map @ world_to_index
    crs_name = "EPSG:4326" if degrees else None
    if crs is not None:
        epsg = crs.to_epsg()
        crs_name = f"EPSG:{epsg}" if epsg else crs.to_wkt()
    try:
        return Bathymetry(z, (col_ground, row_ground), (0.0, 0.0), crs_name, to_crs)
    except ValueError as err:
        raise ValueError(f"{path}: {err}") from None


def write_geotiff(bathy: Bathymetry, path) -> None:
    """Writes `bathy` as a north-up GeoTIFF in its world frame (metres, no CRS unless known).

    Used by tests and examples to round-trip grids; NaN is written as the nodata value.
    """
    import rasterio
    from rasterio.transform import Affine

    dx, dy = bathy.spacing
    x0, y0 = bathy.origin
    ny, nx = bathy.shape
    transform = Affine(dx, 0.0, x0 - dx / 2, 0.0, -dy, y0 + (ny - 0.5) * dy)
    crs = bathy.crs if bathy.crs and bathy.crs.startswith("EPSG") else None
    with replacing(path) as temporary, rasterio.open(
            temporary, "w", driver="GTiff", width=nx, height=ny, count=1, dtype="float32",
            nodata=np.float32(-9999.0), transform=transform, crs=crs) as ds:
        data = np.where(np.isfinite(bathy.z), bathy.z, -9999.0)[::-1].astype(np.float32)
        ds.write(data, 1)
