"""A gridded current read from a CF-conventions netCDF file (numpy, scipy, netCDF4, pyproj).

What ocean models write (ROMS, HYCOM, Copernicus Marine) and this reads:
- the velocity: variables with the standard names `eastward_sea_water_velocity` and
  `northward_sea_water_velocity` (or named `u`/`v`, `uo`/`vo`), optionally
  `upward_sea_water_velocity` (`w`, `wo`), in m s-1, all over the same four dimensions;
- `time` with CF units "<seconds|minutes|hours|days> since <UTC date>" (Gregorian calendar);
- `depth` in m, positive down (an axis with `positive = "up"` is negated);
- horizontally `lat`/`lon` in degrees, or projected `y`/`x` (m or km) whose CRS is the
  velocity's `grid_mapping` variable (CF attributes, read by pyproj) or, without one, the
  site's own.
Components are eastward/northward on a lat/lon grid and along the grid's axes on a projected
one; they are turned into the site's axes by the angle between the two at the site (the
meridian convergence of a UTM site, for instance).

The field is linear in time, depth and the two horizontal coordinates
(`scipy.interpolate.RegularGridInterpolator` over the 4-D grid, axes flipped to increasing
order), evaluated where the site's local points fall in the grid's CRS (pyproj). Above the
shallowest level the shallowest value is taken (the top cell is about 0.5 m deep in most
products); nothing else is extrapolated. Its time derivative is the slope between the two
time levels bracketing t. Masked (land) cells are NaN: a point that reads one is refused.
"""

from __future__ import annotations

import math
import re
from contextlib import contextmanager
from pathlib import Path

import numpy as np
from pyproj import CRS, Transformer
from scipy.interpolate import RegularGridInterpolator

from drake_auv.ocean.clock import format_utc, parse_reference

STANDARD_NAMES = {"u": "eastward_sea_water_velocity", "v": "northward_sea_water_velocity",
                  "w": "upward_sea_water_velocity"}
VARIABLE_NAMES = {"u": ("u", "uo", "water_u"), "v": ("v", "vo", "water_v"),
                  "w": ("w", "wo", "water_w")}
_TIME_UNITS = {"second": 1.0, "seconds": 1.0, "sec": 1.0, "secs": 1.0, "s": 1.0,
               "minute": 60.0, "minutes": 60.0, "min": 60.0, "mins": 60.0,
               "hour": 3600.0, "hours": 3600.0, "hr": 3600.0, "hrs": 3600.0, "h": 3600.0,
               "day": 86400.0, "days": 86400.0, "d": 86400.0}
_CALENDARS = ("standard", "gregorian", "proleptic_gregorian")
_SPEED_UNITS = ("ms-1", "m/s", "ms^-1", "ms**-1")
_LENGTH_UNITS = {"m": 1.0, "meter": 1.0, "meters": 1.0, "metre": 1.0, "metres": 1.0,
                 "km": 1000.0, "kilometer": 1000.0, "kilometers": 1000.0}


def is_speed_unit(units: str) -> bool:
    """Whether `units` (a CF/UDUNITS string) is metres per second."""
    text = re.sub(r"\b(meters?|metres?)\b", "m", str(units).strip().lower())
    text = re.sub(r"\b(seconds?|secs?)\b", "s", text)
    return re.sub(r"[\s*.]", "", text) in _SPEED_UNITS


def cf_time_seconds(values, units: str, calendar: str | None, where: str) -> np.ndarray:
    """CF time coordinate `values` as seconds since 1970-01-01 UTC."""
    match = re.fullmatch(r"\s*(\w+)\s+since\s+(.+?)\s*", str(units))
    if match is None or match[1].lower() not in _TIME_UNITS:
        raise ValueError(f"{where}: time units {units!r} are not CF time units; must be "
                         "'<seconds|minutes|hours|days> since <date>'")
    if calendar is not None and str(calendar).lower() not in _CALENDARS:
        raise ValueError(f"{where}: time calendar {calendar!r} is not supported; must be one "
                         f"of {', '.join(_CALENDARS)}")
    reference = parse_reference(match[2], where)
    return reference + np.asarray(values, dtype=float) * _TIME_UNITS[match[1].lower()]


class GriddedCurrent:
    """A 4-D (time, depth, y, x) current in a CF netCDF file, placed in a site's local frame
    (local = site CRS coordinates - `origin`, z up)."""

    def __init__(self, label, clock_s, depth_m, axis_y, axis_x, values, to_grid, rotation):
        self.label = label
        self.clock_s, self.depth_m = clock_s, depth_m
        self.axis_y, self.axis_x = axis_y, axis_x
        self._to_grid, self._rotation = to_grid, rotation  # local xy -> grid xy; grid -> site
        self._interpolator = RegularGridInterpolator(
            (clock_s, depth_m, axis_y, axis_x), values, bounds_error=False, fill_value=np.nan)

    @property
    def first_time_s(self) -> float:
        return float(self.clock_s[0])

    @classmethod
    def from_netcdf(cls, path, crs=None, origin=(0.0, 0.0)) -> "GriddedCurrent":
        """Reads `path`; `crs` the site's CRS (None: a local site, which takes a projected
        grid without grid mapping in its own coordinates), `origin` (2,) the site
        coordinates of the local frame's origin, m."""
        with _open(path) as (ds, label):
            found, order, horizontal = _layout(ds, label)
            axes = [_axis(ds, role, dim, coordinate, label)
                    for role, (dim, coordinate) in zip(("time", "depth", *horizontal), order)]
            index = [found["u"].dimensions.index(dim) for dim, _ in order]
            components = [_as_array(found[key], index) for key in ("u", "v")]
            components.append(np.zeros_like(components[0]) if found["w"] is None
                              else _as_array(found["w"], index))
            values = np.stack(components, axis=-1)
            for k, (_, flip) in enumerate(axes):
                if flip:
                    values = np.flip(values, axis=k)
            grid_crs = _grid_crs(ds, found["u"], horizontal[0] == "lat", label)
        clock, depth, axis_y, axis_x = (a[0] for a in axes)
        to_grid, rotation = _placement(crs, grid_crs, np.asarray(origin, dtype=float), label,
                                       east_of_180=axis_x[-1] > 180.0)
        return cls(label, clock, depth, axis_y, axis_x, values, to_grid, rotation)

    @staticmethod
    def check_file(path) -> None:
        """Refuses (one line) a file that is not a CF current this reads: its velocity
        variables, units, dimensions and coordinates, without reading the field."""
        with _open(path) as (ds, label):
            found, order, horizontal = _layout(ds, label)
            for role, (dim, coordinate) in zip(("time", "depth", *horizontal), order):
                _axis(ds, role, dim, coordinate, label)
            _grid_crs(ds, found["u"], horizontal[0] == "lat", label)

    def grid_xy(self, xy_local) -> np.ndarray:
        """Grid-CRS horizontal coordinates (n, 2) of local points (n, 2)."""
        xy_local = np.asarray(xy_local, dtype=float)
        return xy_local if self._to_grid is None else self._to_grid(xy_local)

    def check_coverage(self, box, deepest_m: float, start_s: float, end_s: float,
                       span: str = "") -> None:
        """Refuses (one line) a site box (xmin, ymin, xmax, ymax, local m), a deepest depth
        (m) or a dive [start_s, end_s] (s since 1970 UTC; `span`: what sets its end, named
        in the refusal) the grid does not cover."""
        if start_s < self.clock_s[0] or end_s > self.clock_s[-1]:
            raise ValueError(f"{self.label}: covers {format_utc(self.clock_s[0])} to "
                             f"{format_utc(self.clock_s[-1])}, not the dive's "
                             f"{format_utc(start_s)} to {format_utc(end_s)}"
                             + (f" ({span})" if span else "") + "; must cover the "
                             "dive's time span (see ocean.start_utc)")
        if deepest_m > self.depth_m[-1]:
            raise ValueError(f"{self.label}: reaches {self.depth_m[-1]:g} m deep, not the "
                             f"site's {deepest_m:g} m; must cover the site's depths")
        xmin, ymin, xmax, ymax = box
        s = np.linspace(0.0, 1.0, 21)
        edge = np.concatenate([np.stack([xmin + (xmax - xmin) * s, np.full_like(s, y)], 1)
                               for y in (ymin, ymax)]
                              + [np.stack([np.full_like(s, x), ymin + (ymax - ymin) * s], 1)
                                 for x in (xmin, xmax)])
        grid = self.grid_xy(edge)
        inside = ((grid[:, 0] >= self.axis_x[0]) & (grid[:, 0] <= self.axis_x[-1])
                  & (grid[:, 1] >= self.axis_y[0]) & (grid[:, 1] <= self.axis_y[-1]))
        if not np.all(inside):
            raise ValueError(
                f"{self.label}: spans x [{self.axis_x[0]:.6g}, {self.axis_x[-1]:.6g}], y "
                f"[{self.axis_y[0]:.6g}, {self.axis_y[-1]:.6g}] in its CRS, not the site's "
                f"x [{grid[:, 0].min():.6g}, {grid[:, 0].max():.6g}], y "
                f"[{grid[:, 1].min():.6g}, {grid[:, 1].max():.6g}]; must cover the site")

    def check_route(self, positions, start_s: float, end_s: float) -> None:
        """Refuses (one line) a route whose local `positions` (n, 3) read a masked or
        outside cell at any of the file's times within [start_s, end_s] (s since 1970 UTC)
        or at those two instants."""
        positions = np.atleast_2d(np.asarray(positions, dtype=float))
        inside = self.clock_s[(self.clock_s > start_s) & (self.clock_s < end_s)]
        for clock in (start_s, *inside, end_s):
            self.water(float(clock), positions)

    def water(self, clock_s: float, positions) -> tuple[np.ndarray, np.ndarray]:
        """Velocity (n, 3) m/s in the site's local axes (x east, y north, z up) and its time
        derivative (n, 3) m/s^2 at `clock_s` (s since 1970 UTC), local `positions` (n, 3).
        A point outside the grid or in a masked cell raises a ValueError."""
        positions = np.atleast_2d(np.asarray(positions, dtype=float))
        n = positions.shape[0]
        if not self.clock_s[0] <= clock_s <= self.clock_s[-1]:
            raise ValueError(f"{self.label}: no water velocity at {format_utc(clock_s)}, outside "
                             f"the file's {format_utc(self.clock_s[0])} to "
                             f"{format_utc(self.clock_s[-1])}; must stay within its times")
        k = int(np.clip(np.searchsorted(self.clock_s, clock_s, side="right") - 1, 0,
                        self.clock_s.size - 2))
        t0, t1 = self.clock_s[k], self.clock_s[k + 1]
        points = np.empty((2 * n, 4))
        points[:n, 0], points[n:, 0] = t0, t1
        points[:, 1] = np.tile(np.maximum(-positions[:, 2], self.depth_m[0]), 2)
        grid = self.grid_xy(positions[:, :2])
        points[:, 2], points[:, 3] = np.tile(grid[:, 1], 2), np.tile(grid[:, 0], 2)
        both = self._interpolator(points)
        before, after = both[:n], both[n:]
        bad = ~np.all(np.isfinite(before) & np.isfinite(after), axis=1)
        if bad.any():
            x, y, z = positions[int(np.argmax(bad))]
            raise ValueError(f"{self.label}: no water velocity at local ({x:.1f}, {y:.1f}, "
                             f"{z:.1f}) m, {format_utc(clock_s)} (outside the grid or a masked "
                             "cell); must stay within the grid's water cells and times")
        rate = (after - before) / (t1 - t0)
        velocity = before + rate * (clock_s - t0)
        velocity[:, :2] = velocity[:, :2] @ self._rotation.T
        rate[:, :2] = rate[:, :2] @ self._rotation.T
        return velocity, rate


def first_time_s(path) -> float:
    """The first time of a CF current file's time axis, s since 1970 UTC (the dive's t = 0
    when the mission states no `start_utc`), without reading the field."""
    with _open(path) as (ds, label):
        _, order, _ = _layout(ds, label)
        return float(_axis(ds, "time", *order[0], label)[0][0])


@contextmanager
def _open(path):
    """(the open dataset, the label errors begin with)."""
    import netCDF4  # a reader's dependency, loaded when a file is read

    path = Path(path)
    label = f"ocean.file: {path.name}"
    if not path.is_file():
        raise FileNotFoundError(f"{label}: not found ({path}); must be a CF netCDF file")
    try:
        dataset = netCDF4.Dataset(path)
    except OSError as err:
        raise ValueError(f"{label}: cannot be read as netCDF ({err.strerror or err}); must "
                         "be a CF-conventions netCDF file") from None
    with dataset:
        yield dataset, label


def _layout(ds, label):
    """({"u", "v", "w": variable or None}, [(dimension, coordinate)] in the order time,
    depth, y, x, the horizontal roles ("lat", "lon") or ("y", "x"))."""
    found = {key: _velocity_variable(ds, key) for key in ("u", "v", "w")}
    for key in ("u", "v"):
        if found[key] is None:
            raise ValueError(f"{label}: no {key} velocity; must hold a variable named "
                             f"{'/'.join(VARIABLE_NAMES[key])} or with standard_name "
                             f"{STANDARD_NAMES[key]}")
    variables = [v for v in found.values() if v is not None]
    for var in variables:
        units = getattr(var, "units", None)
        if units is None or not is_speed_unit(units):
            raise ValueError(f"{label}: {var.name} has units {units!r}; must be m s-1")
        if var.dimensions != variables[0].dimensions:
            raise ValueError(f"{label}: {var.name} is over {var.dimensions}, "
                             f"{variables[0].name} over {variables[0].dimensions}; must share "
                             "their dimensions")
    roles = _dimension_roles(ds, variables[0], label)
    horizontal = ("lat", "lon") if "lat" in roles else ("y", "x")
    return found, [roles[r] for r in ("time", "depth", *horizontal)], horizontal


def _velocity_variable(ds, key):
    for var in ds.variables.values():
        if getattr(var, "standard_name", None) == STANDARD_NAMES[key]:
            return var
    return next((ds.variables[n] for n in VARIABLE_NAMES[key] if n in ds.variables), None)


def _role(var, dim: str) -> str | None:
    standard = str(getattr(var, "standard_name", "")).lower() if var is not None else ""
    axis = str(getattr(var, "axis", "")).upper() if var is not None else ""
    units = str(getattr(var, "units", "")).lower() if var is not None else ""
    name = dim.lower()
    if standard == "time" or axis == "T" or name == "time":
        return "time"
    if standard in ("depth", "altitude", "height") or axis == "Z" or name in ("depth", "z"):
        return "depth"
    if standard == "latitude" or units.startswith("degree") and "north" in units \
            or name in ("lat", "latitude"):
        return "lat"
    if standard == "longitude" or units.startswith("degree") and "east" in units \
            or name in ("lon", "longitude"):
        return "lon"
    if standard in ("projection_y_coordinate", "grid_latitude") or axis == "Y" or name == "y":
        return "y"
    if standard in ("projection_x_coordinate", "grid_longitude") or axis == "X" or name == "x":
        return "x"
    return None


def _dimension_roles(ds, var, label) -> dict:
    """{role: (dimension, coordinate variable)} of `var`'s dimensions; refuses other layouts."""
    roles = {}
    for dim in var.dimensions:
        coordinate = ds.variables.get(dim)
        role = _role(coordinate, dim)
        if role is None or role in roles:
            raise ValueError(f"{label}: {var.name}'s dimension {dim!r} is not a (single) CF "
                             "coordinate; must be over time, depth and lat/lon or y/x")
        roles[role] = (dim, coordinate)
    wanted = ({"time", "depth", "lat", "lon"}, {"time", "depth", "y", "x"})
    if set(roles) not in wanted:
        raise ValueError(f"{label}: {var.name} is over {var.dimensions} ({sorted(roles)}); "
                         "must be over time, depth and lat/lon or y/x")
    return roles


def _axis(ds, role, dim, coordinate, label):
    """(increasing values, flipped) of one coordinate axis, in s since 1970 UTC, m down, m
    or degrees."""
    if coordinate is None:
        raise ValueError(f"{label}: dimension {dim!r} has no coordinate variable; must have "
                         "one (CF)")
    values = np.ma.filled(np.ma.asarray(coordinate[:], dtype=float), np.nan).reshape(-1)
    units = str(getattr(coordinate, "units", ""))
    if role == "time":
        values = cf_time_seconds(values, units, getattr(coordinate, "calendar", None), label)
    elif role == "depth" or role in ("y", "x"):
        scale = _LENGTH_UNITS.get(units.strip().lower()) if units else 1.0
        if scale is None:
            raise ValueError(f"{label}: {dim} has units {units!r}; must be m (or km)")
        values = values * scale
        if role == "depth" and str(getattr(coordinate, "positive", "down")).lower() == "up":
            values = -values
    if values.size < 2 or not np.all(np.isfinite(values)):
        raise ValueError(f"{label}: {dim} has {values.size} values; must have at least 2 "
                         "finite ones")
    steps = np.diff(values)
    if np.all(steps > 0):
        return values, False
    if np.all(steps < 0):
        return values[::-1].copy(), True
    raise ValueError(f"{label}: {dim} is not monotonic; must be strictly increasing or "
                     "decreasing")


def _as_array(var, index) -> np.ndarray:
    """The variable as float (time, depth, y, x), masked cells NaN."""
    data = np.ma.filled(np.ma.asarray(var[:], dtype=float), np.nan)
    return np.transpose(data, index)


def _grid_crs(ds, var, geographic: bool, label):
    mapping = getattr(var, "grid_mapping", None)
    if mapping is not None:
        name = str(mapping).split(":")[0].strip()
        if name not in ds.variables:
            raise ValueError(f"{label}: grid_mapping {name!r} is not a variable; must name "
                             "the CF grid-mapping variable")
        try:
            return CRS.from_cf(ds.variables[name].__dict__)
        except Exception as err:  # pyproj raises several kinds for a bad mapping
            raise ValueError(f"{label}: grid_mapping {name!r} is not a CRS pyproj reads "
                             f"({err}); must hold CF grid-mapping attributes") from None
    return CRS.from_epsg(4326) if geographic else None


def _placement(site_crs, grid_crs, origin, label, east_of_180=False):
    """(local xy -> grid xy function or None, 2x2 rotation from the grid's velocity axes to
    the site's); `east_of_180`: a geographic grid's longitudes run in [0, 360) (HYCOM's)."""
    if grid_crs is None or (site_crs is not None and CRS.from_user_input(site_crs) == grid_crs):
        if grid_crs is not None and grid_crs.is_geographic:
            raise ValueError(f"{label}: the site's CRS {site_crs} is geographic; must be "
                             "projected (metres)")
        return ((lambda xy: xy + origin) if np.any(origin) else None), np.eye(2)
    if site_crs is None:
        raise ValueError(f"{label}: is in {grid_crs.name} and the site has no CRS; must be "
                         "a site with a CRS (site.world with site.crs, or a tile), or a "
                         "projected y/x grid in the site's coordinates without grid_mapping")
    transformer = Transformer.from_crs(CRS.from_user_input(site_crs), grid_crs, always_xy=True)
    back = Transformer.from_crs(grid_crs, CRS.from_user_input(site_crs), always_xy=True)

    def to_grid(xy):
        gx, gy = transformer.transform(xy[:, 0] + origin[0], xy[:, 1] + origin[1])
        gx = np.asarray(gx, dtype=float)
        if east_of_180 and grid_crs.is_geographic:
            gx = np.mod(gx, 360.0)
        return np.stack([gx, np.asarray(gy, dtype=float)], axis=1)

    centre = to_grid(np.zeros((1, 2)))[0]
    step = 1e-5 if grid_crs.is_geographic else 1.0
    ex, ey = back.transform([centre[0], centre[0] + step], [centre[1], centre[1]])
    angle = math.atan2(ey[1] - ey[0], ex[1] - ex[0])  # the grid's x axis in the site's axes
    rotation = np.array([[math.cos(angle), -math.sin(angle)],
                         [math.sin(angle), math.cos(angle)]])
    return to_grid, rotation
