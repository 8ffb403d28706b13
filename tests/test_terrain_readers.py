"""Bathymetry readers: every supported format, the Monterey tiles' quirks, bad files."""

import re

import numpy as np
import pytest
import rasterio
from rasterio.transform import Affine
from scipy.io import netcdf_file

from drake_auv.scenarios import DATA_DIR as DATA
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import read_bathymetry

MONTEREY = sorted((DATA / "monterey").glob("*.tif"))
EARTH_RADIUS = 6378137.0

# A 4 x 5 grid with distinct values; row 0 is the northern row in the north-up files below.
Z = np.arange(20, dtype=np.float32).reshape(4, 5)


def from_origin(west, north, xsize, ysize):
    return Affine(xsize, 0.0, west, 0.0, -ysize, north)


def _write(path, driver, transform=from_origin(100.0, 200.0, 2.0, 3.0), crs="EPSG:32631",
           data=Z, nodata=None):
    with rasterio.open(path, "w", driver=driver, width=data.shape[1], height=data.shape[0],
                       count=1, dtype="float32", transform=transform, crs=crs,
                       nodata=nodata) as ds:
        ds.write(data, 1)


@pytest.mark.parametrize("driver, suffix", [("GTiff", "tif"), ("AAIGrid", "asc"),
                                            ("XYZ", "xyz"), ("BAG", "bag"), ("GSBG", "grd")])
def test_north_up_formats_give_rows_along_plus_y(tmp_path, driver, suffix):
    path = tmp_path / f"grid.{suffix}"
    transform = from_origin(100.0, 200.0, 2.0, 2.0)
    if driver == "GTiff":
        transform = from_origin(100.0, 200.0, 2.0, 3.0)  # non-square cells
    _write(path, driver, transform=transform, crs=None if driver == "XYZ" else "EPSG:32631")
    bathy = read_bathymetry(path)
    dx, dy = abs(transform.a), abs(transform.e)
    assert bathy.spacing == pytest.approx((dx, dy))
    # The file's last (southern) row becomes world row 0, so z grows with y like the file's rows
    # grow southwards: row i of the world grid is row (3 - i) of the file.
    np.testing.assert_array_equal(bathy.z, Z[::-1])
    # World (0, 0) is the centre of the file's south-west cell in map coordinates.
    np.testing.assert_allclose(bathy.world_to_crs([[0.0, 0.0]])[0],
                               [100.0 + dx / 2, 200.0 - 3.5 * dy])
    np.testing.assert_allclose(bathy.world_to_crs([[4 * dx, 3 * dy]])[0],
                               [100.0 + 4.5 * dx, 200.0 - 0.5 * dy])


def test_nodata_becomes_nan(tmp_path):
    data = Z.copy()
    data[1, 2] = -9999.0
    path = tmp_path / "holes.asc"
    _write(path, "AAIGrid", data=data, nodata=-9999.0)
    bathy = read_bathymetry(path)
    assert np.isnan(bathy.z[2, 2]) and np.isfinite(bathy.z).sum() == 19


def test_netcdf_gmt_grid_projected_and_geographic(tmp_path):
    path = tmp_path / "gmt.nc"
    with netcdf_file(path, "w") as f:
        f.createDimension("x", 5)
        f.createDimension("y", 4)
        vx = f.createVariable("x", "f8", ("x",))
        vx[:] = 1000.0 + 2.0 * np.arange(5)
        vx.units, vx.standard_name = "m", "projection_x_coordinate"
        vy = f.createVariable("y", "f8", ("y",))
        vy[:] = 500.0 + 3.0 * np.arange(4)  # south to north, GMT style
        vy.units, vy.standard_name = "m", "projection_y_coordinate"
        f.createVariable("z", "f4", ("y", "x"))[:] = Z
    bathy = read_bathymetry(path)
    assert bathy.spacing == pytest.approx((2.0, 3.0))
    np.testing.assert_array_equal(bathy.z, Z)  # netCDF row 0 is already the southern row
    np.testing.assert_allclose(bathy.world_to_crs([[2.0, 6.0]])[0], [1002.0, 506.0])

    path = tmp_path / "lonlat.nc"
    with netcdf_file(path, "w") as f:
        f.createDimension("lon", 5)
        f.createDimension("lat", 4)
        lon = f.createVariable("lon", "f8", ("lon",))
        lon[:] = 3.0 + 0.001 * np.arange(5)
        lon.units = "degrees_east"
        lat = f.createVariable("lat", "f8", ("lat",))
        lat[:] = 40.0 + 0.001 * np.arange(4)
        lat.units = "degrees_north"
        f.createVariable("z", "f4", ("lat", "lon"))[:] = Z
    bathy = read_bathymetry(path)
    per_degree = np.pi / 180.0 * EARTH_RADIUS
    assert bathy.spacing[1] == pytest.approx(0.001 * per_degree, rel=1e-9)
    assert bathy.spacing[0] == pytest.approx(0.001 * per_degree * np.cos(np.radians(40.0015)),
                                             rel=1e-6)
    assert bathy.crs == "EPSG:4326"
    np.testing.assert_allclose(bathy.world_to_crs([[0.0, 0.0]])[0], [3.0, 40.0], atol=1e-9)


def test_npz_round_trip_and_errors(tmp_path):
    path = tmp_path / "grid.npz"
    np.savez(path, z=Z.astype(float), spacing=[0.5, 0.25], origin=[10.0, -4.0])
    bathy = read_bathymetry(path)
    assert bathy.spacing == (0.5, 0.25) and bathy.origin == (10.0, -4.0)
    np.testing.assert_array_equal(bathy.z, Z)
    bad = tmp_path / "noz.npz"
    np.savez(bad, elevation=Z)
    with pytest.raises(ValueError, match="needs an array 'z'"):
        read_bathymetry(bad)
    corrupt = tmp_path / "corrupt.npz"
    corrupt.write_bytes(b"PK\x03\x04 this is not a zip archive")
    with pytest.raises(ValueError, match="not a readable .npz"):
        read_bathymetry(corrupt)
    small = tmp_path / "small.npz"
    np.savez(small, z=np.zeros((2, 5)))
    with pytest.raises(ValueError, match="at least 3 x 3"):
        read_bathymetry(small)


def test_missing_and_unreadable_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="not found"):
        read_bathymetry(tmp_path / "nope.tif")
    junk = tmp_path / "junk.tif"
    junk.write_bytes(b"\x00\x01 definitely not a GeoTIFF")
    with pytest.raises(ValueError, match="not a raster"):
        read_bathymetry(junk)
    nodata = tmp_path / "allnodata.tif"
    _write(nodata, "GTiff", data=np.full((4, 5), -1.0, np.float32), nodata=-1.0)
    with pytest.raises(ValueError, match="all no-data"):
        read_bathymetry(nodata)


@pytest.mark.parametrize("tile", MONTEREY, ids=lambda p: p.name[12:40])
def test_monterey_tile_quirks(tile):
    bathy = read_bathymetry(tile)
    with rasterio.open(tile) as ds:
        t: Affine = ds.transform
        raw = ds.read(1).astype(float)
    lat_min, lat_max = map(float, re.search(r"R_[-\d.]+_[-\d.]+_([-\d.]+)_([-\d.]+)\.epsg",
                                            tile.name).groups())
    # Pseudo-Mercator metres shrink to ground metres by cos(latitude): ~0.80 here.
    k = np.cos(np.radians(0.5 * (lat_min + lat_max)))
    assert bathy.spacing[0] == pytest.approx(t.a * k, rel=2e-3)
    assert bathy.spacing[1] == pytest.approx(t.e * k, rel=2e-3)
    assert bathy.spacing[0] < bathy.spacing[1]  # non-square cells kept
    assert t.e > 0  # positive Y scale: file row 0 is the south edge, no flip needed
    np.testing.assert_array_equal(bathy.z, raw)
    assert bathy.crs == "EPSG:3857"
    # world (x, y) -> map: the centre of file cell (row, col) for world (col dx, row dy).
    row, col = 17, 101
    xy = bathy.world_to_crs([[col * bathy.spacing[0], row * bathy.spacing[1]]])[0]
    np.testing.assert_allclose(xy, [t.a * (col + 0.5) + t.c, t.e * (row + 0.5) + t.f], atol=1e-6)
    # Depths as documented: about -13 m to -224 m.
    assert -230 < np.nanmin(bathy.z) < np.nanmax(bathy.z) < -10


def test_bathymetry_small_method_contract():
    with pytest.raises(ValueError, match="at least 3 x 3"):
        Bathymetry(np.zeros((3, 2)))


def test_rotated_geotransform_is_kept_in_to_crs(tmp_path):
    # Columns step (2 cos 30, 2 sin 30), rows step (3 sin 30, -3 cos 30) in map metres.
    c, s = np.cos(np.radians(30.0)), np.sin(np.radians(30.0))
    transform = Affine(2.0 * c, 3.0 * s, 500.0, 2.0 * s, -3.0 * c, 800.0)
    path = tmp_path / "rotated.tif"
    _write(path, "GTiff", transform=transform)
    bathy = read_bathymetry(path)
    assert bathy.spacing == pytest.approx((2.0, 3.0))
    np.testing.assert_array_equal(bathy.z, Z[::-1])  # determinant < 0: rows reversed
    for row, col in ((0, 0), (3, 4), (1, 2)):
        world = [[col * 2.0, (3 - row) * 3.0]]
        expect = [transform.a * (col + 0.5) + transform.b * (row + 0.5) + transform.c,
                  transform.d * (col + 0.5) + transform.e * (row + 0.5) + transform.f]
        np.testing.assert_allclose(bathy.world_to_crs(world)[0], expect, atol=1e-9)


def test_netcdf_with_several_variables_picks_the_elevation(tmp_path):
    path = tmp_path / "multi.nc"
    with netcdf_file(path, "w") as f:
        f.createDimension("x", 5)
        f.createDimension("y", 4)
        for name, n in (("x", 5), ("y", 4)):
            v = f.createVariable(name, "f8", (name,))
            v[:] = np.arange(float(n))
            v.units, v.standard_name = "m", f"projection_{name}_coordinate"
        f.createVariable("uncertainty", "f4", ("y", "x"))[:] = np.ones((4, 5))
        f.createVariable("elevation", "f4", ("y", "x"))[:] = Z
    np.testing.assert_array_equal(read_bathymetry(path).z, Z)
    path = tmp_path / "ambiguous.nc"
    with netcdf_file(path, "w") as f:
        f.createDimension("x", 5)
        f.createDimension("y", 4)
        f.createVariable("a", "f4", ("y", "x"))[:] = Z
        f.createVariable("b", "f4", ("y", "x"))[:] = Z
    with pytest.raises(ValueError, match="named like an elevation"):
        read_bathymetry(path)
