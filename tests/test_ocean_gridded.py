"""Gridded currents from CF-conventions netCDF files written here with netCDF4: read,
placed in the site's frame (pyproj), interpolated in space and time, bad files refused in
one line."""

import math

import netCDF4
import numpy as np
import pytest
from pyproj import CRS, Transformer

from drake_auv.ocean.clock import parse_utc
from drake_auv.ocean.gridded import GriddedCurrent, cf_time_seconds, is_speed_unit

T0 = parse_utc("2024-03-01T00:00:00Z")
UTM = "EPSG:32610"  # UTM 10N: Monterey Bay is 1.2 deg east of its central meridian (-123)
LON = np.linspace(-121.84, -121.80, 6)
LAT = np.linspace(36.82, 36.79, 5)  # decreasing, as many products store it
DEPTH = np.array([0.5, 10.0, 30.0, 60.0])
HOURS = np.array([0.0, 1.0, 3.0])


def _values(shape, seed):
    return np.random.default_rng(seed).uniform(-0.5, 0.5, shape)


def write_cf(path, *, geographic=True, names=("u", "v"), units="m s-1", standard=True,
             w=False, nan_at=None, grid_mapping=None, xy=None, dims_order=None, lon=LON):
    """A CF current over (time, depth, lat, lon) or (time, depth, y, x); returns u, v."""
    longitudes = lon
    with netCDF4.Dataset(path, "w") as ds:
        ny, nx = (LAT.size, LON.size) if geographic else (len(xy[1]), len(xy[0]))
        hname, xname = ("lat", "lon") if geographic else ("y", "x")
        for name, size in (("time", HOURS.size), ("depth", DEPTH.size), (hname, ny),
                           (xname, nx)):
            ds.createDimension(name, size)
        time = ds.createVariable("time", "f8", ("time",))
        time.units, time.calendar, time.standard_name = ("hours since 2024-03-01 00:00:00",
                                                         "gregorian", "time")
        time[:] = HOURS
        depth = ds.createVariable("depth", "f8", ("depth",))
        depth.units, depth.positive, depth.standard_name = "m", "down", "depth"
        depth[:] = DEPTH
        if geographic:
            lat = ds.createVariable("lat", "f8", ("lat",))
            lat.units, lat.standard_name = "degrees_north", "latitude"
            lat[:] = LAT
            lon = ds.createVariable("lon", "f8", ("lon",))
            lon.units, lon.standard_name = "degrees_east", "longitude"
            lon[:] = longitudes
        else:
            for name, values, standard_name in (("y", xy[1], "projection_y_coordinate"),
                                                ("x", xy[0], "projection_x_coordinate")):
                var = ds.createVariable(name, "f8", (name,))
                var.units, var.standard_name = "m", standard_name
                var[:] = values
        dims = dims_order or ("time", "depth", hname, xname)
        shape = tuple(ds.dimensions[d].size for d in dims)
        out = []
        for k, (name, std) in enumerate(zip(names, ("eastward_sea_water_velocity",
                                                    "northward_sea_water_velocity"))):
            var = ds.createVariable(name, "f4", dims, fill_value=np.float32(-9999.0))
            var.units = units
            if standard:
                var.standard_name = std
            if grid_mapping is not None:
                var.grid_mapping = "crs"
            data = _values(shape, k).astype(np.float32)
            if nan_at is not None:
                data[nan_at] = np.nan
            var[:] = np.ma.masked_invalid(data)
            out.append(data.astype(float))
        if w:
            var = ds.createVariable("w", "f4", dims)
            var.units, var.standard_name = "m/s", "upward_sea_water_velocity"
            var[:] = 0.01 * _values(shape, 9).astype(np.float32)
        if grid_mapping is not None:
            crs = ds.createVariable("crs", "i4")
            crs.setncatts(grid_mapping)
    return out


def test_units_and_time_units():
    for text in ("m s-1", "m/s", "meter second-1", "m s^-1", "metres/second", "m.s-1"):
        assert is_speed_unit(text), text
    for text in ("cm s-1", "knots", "m", ""):
        assert not is_speed_unit(text), text
    np.testing.assert_allclose(cf_time_seconds([0, 1.5], "days since 2024-03-01", None, "f"),
                               [T0, T0 + 1.5 * 86400])
    np.testing.assert_allclose(cf_time_seconds([90], "seconds since 2024-3-1T00:00:00Z",
                                               "standard", "f"), [T0 + 90])
    with pytest.raises(ValueError, match="calendar"):
        cf_time_seconds([0], "days since 2024-03-01", "360_day", "f")
    with pytest.raises(ValueError, match="not CF time units"):
        cf_time_seconds([0], "fortnights since 2024-03-01", None, "f")


def test_a_projected_grid_is_exact_at_its_nodes_and_linear_between(tmp_path):
    xs, ys = np.array([-100.0, 0.0, 50.0, 200.0]), np.array([-80.0, 20.0, 120.0])
    path = tmp_path / "xy.nc"
    u, v = write_cf(path, geographic=False, xy=(xs, ys), standard=False)
    field = GriddedCurrent.from_netcdf(path)  # a local site: the grid is in its coordinates
    for (i, j, k, m) in [(0, 0, 0, 0), (1, 2, 1, 3), (2, 3, 2, 1)]:
        velocity, _ = field.water(T0 + HOURS[i] * 3600, [[xs[m], ys[k], -DEPTH[j]]])
        np.testing.assert_allclose(velocity[0], [u[i, j, k, m], v[i, j, k, m], 0.0],
                                   rtol=1e-12, atol=1e-12)
    # halfway in time, depth, y and x: the mean of the 16 corners
    t = T0 + 0.5 * 3600
    point = [[(xs[1] + xs[2]) / 2, (ys[0] + ys[1]) / 2, -(DEPTH[1] + DEPTH[2]) / 2]]
    velocity, rate = field.water(t, point)
    corners = (slice(0, 2), slice(1, 3), slice(0, 2), slice(1, 3))
    np.testing.assert_allclose(velocity[0, :2], [u[corners].mean(), v[corners].mean()],
                               rtol=1e-12)
    late, early = (np.array([a[1, 1:3, 0:2, 1:3].mean() for a in (u, v)]),
                   np.array([a[0, 1:3, 0:2, 1:3].mean() for a in (u, v)]))
    np.testing.assert_allclose(rate[0, :2], (late - early) / 3600.0, rtol=1e-12)
    # linear along one axis: a quarter of the way in x at a node otherwise
    velocity, _ = field.water(T0 + 3600, [[xs[0] + 25.0, ys[2], -DEPTH[3]]])
    np.testing.assert_allclose(velocity[0, 0], 0.75 * u[1, 3, 2, 0] + 0.25 * u[1, 3, 2, 1],
                               rtol=1e-12)
    # above the shallowest level the shallowest value is held
    top, _ = field.water(T0, [[xs[0], ys[0], 0.0]])
    np.testing.assert_allclose(top[0, 0], u[0, 0, 0, 0], rtol=1e-12)


def test_a_lat_lon_grid_is_placed_in_a_utm_site_and_its_vectors_turned(tmp_path):
    path = tmp_path / "latlon.nc"
    u, v = write_cf(path, names=("uo", "vo"), w=True)
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(to_utm.transform(-121.82, 36.805))
    field = GriddedCurrent.from_netcdf(path, UTM, origin)
    # the meridian convergence by hand: gamma ~ (lon - lon0) sin(lat); true north lies
    # west of grid north east of the central meridian, so vectors turn anticlockwise
    gamma = math.radians((-121.82 + 123.0) * math.sin(math.radians(36.805)))
    turn = np.array([[math.cos(gamma), -math.sin(gamma)], [math.sin(gamma), math.cos(gamma)]])
    i, j, k, m = 1, 2, 3, 4  # time, depth, lat (file order), lon
    easting, northing = to_utm.transform(LON[m], LAT[k])
    local = [[easting - origin[0], northing - origin[1], -DEPTH[j]]]
    velocity, _ = field.water(T0 + 3600, local)
    np.testing.assert_allclose(velocity[0, :2], turn @ [u[i, j, k, m], v[i, j, k, m]],
                               atol=2e-4)  # the convergence's formula, to 1e-3 rad
    assert np.hypot(*velocity[0, :2]) == pytest.approx(np.hypot(u[i, j, k, m], v[i, j, k, m]),
                                                       rel=1e-6)
    assert velocity[0, 2] != 0.0  # w read


def test_longitudes_from_0_to_360_are_read(tmp_path):
    east, west = tmp_path / "east.nc", tmp_path / "west.nc"
    u, v = write_cf(east, lon=LON + 360.0)  # HYCOM's convention: 238.16 for -121.84
    write_cf(west)
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(to_utm.transform(-121.82, 36.805))
    point = [[120.0, -80.0, -12.0]]
    a, _ = GriddedCurrent.from_netcdf(east, UTM, origin).water(T0 + 600.0, point)
    b, _ = GriddedCurrent.from_netcdf(west, UTM, origin).water(T0 + 600.0, point)
    np.testing.assert_allclose(a, b, rtol=1e-9)


def test_a_grid_mapping_places_a_projected_grid(tmp_path):
    site = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(site.transform(-121.82, 36.805))
    grid_crs = CRS.from_epsg(32611)  # the next zone: a different projection of the same place
    to_grid = Transformer.from_crs(UTM, grid_crs, always_xy=True)
    gx, gy = to_grid.transform(origin[0], origin[1])
    xs, ys = gx + np.array([-500.0, 0.0, 500.0]), gy + np.array([-400.0, 0.0, 400.0])
    path = tmp_path / "mapped.nc"
    u, v = write_cf(path, geographic=False, xy=(xs, ys), grid_mapping=grid_crs.to_cf())
    field = GriddedCurrent.from_netcdf(path, UTM, origin)
    back = Transformer.from_crs(grid_crs, UTM, always_xy=True)
    x, y = back.transform(xs[1], ys[1])
    velocity, _ = field.water(T0, [[x - origin[0], y - origin[1], -DEPTH[0]]])
    expected = np.array([u[0, 0, 1, 1], v[0, 0, 1, 1]])
    assert np.hypot(*velocity[0, :2]) == pytest.approx(np.hypot(*expected), rel=1e-6)
    # by hand: the two zones' convergences (lon - lon0) sin(lat) differ by 6.0 sin(lat) deg,
    # zone 11's grid north lying west of zone 10's here: the vector turns anticlockwise
    turned = math.atan2(velocity[0, 1], velocity[0, 0]) - math.atan2(expected[1], expected[0])
    assert math.degrees(turned) == pytest.approx(6.0 * math.sin(math.radians(36.805)),
                                                 abs=0.05)


def test_coverage_of_the_site_and_the_dive_is_checked(tmp_path):
    path = tmp_path / "latlon.nc"
    write_cf(path)
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(to_utm.transform(-121.82, 36.805))
    field = GriddedCurrent.from_netcdf(path, UTM, origin)
    field.check_coverage((-500, -500, 500, 500), 50.0, T0, T0 + 3 * 3600)
    for box, deepest, span, match in [
            ((-5000, -500, 500, 500), 50.0, (T0, T0 + 3600), "must cover the site"),
            ((-500, -500, 500, 500), 80.0, (T0, T0 + 3600), "must cover the site's depths"),
            ((-500, -500, 500, 500), 50.0, (T0, T0 + 4 * 3600), "dive's time span")]:
        with pytest.raises(ValueError, match=match) as err:
            field.check_coverage(box, deepest, *span)
        assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="no water velocity at 2024-02-29T23:59:00Z, outside the "
                                         "file's 2024-03-01T00:00:00Z to 2024-03-01T03:00:00Z"):
        field.water(T0 - 60.0, [[0.0, 0.0, -5.0]])  # refused before any interpolation
    with pytest.raises(ValueError, match="outside the grid or a masked cell"):
        field.water(T0 + 60.0, [[1e7, 0.0, -5.0]])


def test_masked_cells_are_refused_where_asked(tmp_path):
    path = tmp_path / "land.nc"
    write_cf(path, nan_at=(slice(None), slice(None), 0, 0))  # a land column in a corner
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(to_utm.transform(-121.82, 36.805))
    field = GriddedCurrent.from_netcdf(path, UTM, origin)
    field.water(T0, [[0.0, 0.0, -5.0]])  # water far from it
    x, y = to_utm.transform(LON[0] + 0.001, LAT[0] - 0.001)
    with pytest.raises(ValueError, match=r"land.nc: no water velocity at local") as err:
        field.water(T0, [[x - origin[0], y - origin[1], -5.0]])
    assert "\n" not in str(err.value)


def test_dimension_order_is_read_from_the_file(tmp_path):
    path = tmp_path / "order.nc"
    xs, ys = np.array([0.0, 10.0, 20.0]), np.array([0.0, 10.0])
    u, _ = write_cf(path, geographic=False, xy=(xs, ys),
                    dims_order=("x", "y", "depth", "time"))
    field = GriddedCurrent.from_netcdf(path)
    velocity, _ = field.water(T0 + 3 * 3600, [[xs[2], ys[1], -DEPTH[1]]])
    assert velocity[0, 0] == pytest.approx(u[2, 1, 1, 2], rel=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(names=("a", "b"), standard=False), "no u velocity"),
    (dict(units="cm s-1"), "has units 'cm s-1'; must be m s-1"),
    (dict(units="knots"), "has units 'knots'; must be m s-1"),
])
def test_bad_files_are_refused_in_one_line(tmp_path, kwargs, match):
    path = tmp_path / "bad.nc"
    write_cf(path, **kwargs)
    with pytest.raises(ValueError, match=match) as err:
        GriddedCurrent.from_netcdf(path, UTM, (600000.0, 4070000.0))
    assert "\n" not in str(err.value) and "bad.nc" in str(err.value)


def test_a_lat_lon_grid_needs_a_site_crs_and_a_file_must_be_netcdf(tmp_path):
    path = tmp_path / "latlon.nc"
    write_cf(path)
    with pytest.raises(ValueError, match="the site has no CRS"):
        GriddedCurrent.from_netcdf(path)
    text = tmp_path / "notes.nc"
    text.write_text("not netcdf")
    with pytest.raises(ValueError, match="cannot be read as netCDF"):
        GriddedCurrent.from_netcdf(text)
    with pytest.raises(FileNotFoundError, match="not found"):
        GriddedCurrent.from_netcdf(tmp_path / "missing.nc")


def test_the_shipped_monterey_current_is_its_stated_tide(tmp_path):
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    import synthetic_current as synthetic

    shipped = synthetic.OUT
    fresh = tmp_path / "fresh.nc"
    synthetic.write(fresh)
    with netCDF4.Dataset(shipped) as a, netCDF4.Dataset(fresh) as b:
        assert "SYNTHETIC" in a.title
        for name in ("u", "v", "time", "depth", "lat", "lon"):
            np.testing.assert_array_equal(a[name][:], b[name][:])
    # the tile (lon -121.825..-121.815, lat 36.800..36.810) in its site's UTM zone
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    corners = np.array(to_utm.transform([-121.825, -121.815], [36.800, 36.810])).T
    origin = corners.mean(axis=0)
    field = GriddedCurrent.from_netcdf(shipped, UTM, origin)
    start = parse_utc(synthetic.START_UTC)
    box = (*(corners[0] - origin), *(corners[1] - origin))
    field.check_coverage(box, 130.0, start, start + 4 * 3600.0)
    # at the grid's centre column, 150 m deep (factor 1), 7 h in: the stated tide, turned
    # from true to UTM grid north by the meridian convergence
    x, y = to_utm.transform(synthetic.LON[4], synthetic.LAT[4])
    velocity, _ = field.water(start + 7 * 3600.0, [[x - origin[0], y - origin[1], -150.0]])
    expected, _ = synthetic.tide().velocity(start + 7 * 3600.0)
    gamma = math.radians((synthetic.LON[4] + 123.0) * math.sin(math.radians(36.805)))
    turn = np.array([[math.cos(gamma), -math.sin(gamma)], [math.sin(gamma), math.cos(gamma)]])
    np.testing.assert_allclose(velocity[0, :2], turn @ expected, atol=2e-4)


def test_the_model_refuses_a_dive_its_file_does_not_cover(tmp_path):
    from drake_auv.ocean.spec import ocean_from_raw

    path = tmp_path / "land.nc"
    write_cf(path, nan_at=(slice(None), slice(None), 0, 0))
    to_utm = Transformer.from_crs("EPSG:4326", UTM, always_xy=True)
    origin = np.array(to_utm.transform(-121.82, 36.805))
    model = ocean_from_raw({"file": "land.nc", "current": {"speed_mps": 0.1}},
                           tmp_path).model(np.random.default_rng(0), UTM, origin)
    assert model.start_s == T0  # the file's first time
    route = np.array([[0.0, 0.0, -5.0], [100.0, 50.0, -20.0]])
    model.check((-500, -500, 500, 500), 50.0, 2 * 3600.0, route)
    with pytest.raises(ValueError, match="dive's time span"):
        model.check((-500, -500, 500, 500), 50.0, 4 * 3600.0, route)
    x, y = to_utm.transform(LON[0] + 0.001, LAT[0] - 0.001)
    with pytest.raises(ValueError, match="no water velocity"):
        model.check((-500, -500, 500, 500), 50.0, 3600.0,
                    np.vstack([route, [[x - origin[0], y - origin[1], -5.0]]]))
    velocity, _ = model.water(1800.0, route)
    direct, _ = model.gridded.water(T0 + 1800.0, route)
    np.testing.assert_allclose(velocity - direct, [[0.0, 0.1, 0.0]] * 2, atol=1e-15)
