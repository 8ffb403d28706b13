"""Writes the SYNTHETIC gridded current of the `monterey_wall` mission: a CF-conventions
netCDF file built from stated tidal constituents, not an observation nor an ocean model's
output (`drake_auv/mission/missions/monterey_wall_current.nc`).

The site is the Monterey Canyon wall (lon -121.825..-121.815, lat 36.800..36.810, 30-130 m
deep). Currents there are dominated by the tide running up and down the canyon and
strengthening towards its floor; this file stands in for a regional model's output with:

- the tide `CONSTITUENTS` (amplitude m/s, phase deg, all flooding up-canyon towards
  `FLOOD_TOWARDS_DEG`, ebbing down-canyon), phases referenced to `START_UTC`;
- a vertical factor rising linearly from `SURFACE_FACTOR` at the surface to 1 at
  `FULL_DEPTH_M` and below, and a horizontal factor 1 + `GRADIENT` x (the eastward distance
  from the grid's centre in units of the grid's half-width);
- hourly over `HOURS` h from `START_UTC`, on a 9 x 9 lat/lon grid of 0.0025 deg (the site with
  one cell of margin and more) and the depth levels `DEPTHS_M`.

    python scripts/synthetic_current.py [-o PATH]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from drake_auv.ocean.clock import parse_utc
from drake_auv.ocean.tides import TidalConstituent, TidalHarmonics

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "drake_auv" / "mission" / "missions" / "monterey_wall_current.nc"
START_UTC = "2024-03-01T00:00:00Z"
HOURS = 48
FLOOD_TOWARDS_DEG = 60.0  # up-canyon, towards Moss Landing
CONSTITUENTS = (("M2", 0.20, 0.0), ("S2", 0.06, 30.0), ("K1", 0.08, 110.0), ("O1", 0.05, 95.0))
SURFACE_FACTOR, FULL_DEPTH_M, GRADIENT = 0.5, 150.0, 0.2
LON = np.linspace(-121.830, -121.810, 9)
LAT = np.linspace(36.795, 36.815, 9)
DEPTHS_M = np.array([0.5, 5.0, 10.0, 20.0, 30.0, 50.0, 75.0, 100.0, 125.0, 150.0, 200.0])


def tide() -> TidalHarmonics:
    return TidalHarmonics([TidalConstituent(name, amplitude_mps=a, phase_deg=p,
                                            flood_towards_deg=FLOOD_TOWARDS_DEG)
                           for name, a, p in CONSTITUENTS], parse_utc(START_UTC))


def field() -> np.ndarray:
    """The current (time, depth, lat, lon, 2: east, north), m/s."""
    tides, start = tide(), parse_utc(START_UTC)
    surface = np.array([tides.velocity(start + h * 3600.0)[0] for h in range(HOURS + 1)])
    depth = SURFACE_FACTOR + (1.0 - SURFACE_FACTOR) * np.minimum(DEPTHS_M / FULL_DEPTH_M, 1.0)
    east = 1.0 + GRADIENT * (LON - LON.mean()) / ((LON[-1] - LON[0]) / 2.0)
    scale = depth[:, None, None] * np.ones(LAT.size)[:, None] * east[None, None, :]
    return surface[:, None, None, None, :] * scale[None, ..., None]


def write(path: Path) -> None:
    import netCDF4

    values = field()
    tmp = path.with_name(path.name + ".tmp")
    with netCDF4.Dataset(tmp, "w", format="NETCDF4") as ds:
        ds.setncatts({
            "Conventions": "CF-1.8",
            "title": "SYNTHETIC tidal current at the Monterey Canyon wall (monterey_wall)",
            "source": "synthetic: scripts/synthetic_current.py, not observed nor modelled",
            "comment": ("tidal constituents (name, amplitude m/s, phase deg from "
                        f"{START_UTC}): "
                        + ", ".join(f"{n} {a:g} {p:g}" for n, a, p in CONSTITUENTS)
                        + f"; flood towards {FLOOD_TOWARDS_DEG:g} deg; factor "
                        f"{SURFACE_FACTOR:g} at the surface to 1 at {FULL_DEPTH_M:g} m; "
                        f"eastward gradient {GRADIENT:g} per half-width")})
        for name, size in (("time", HOURS + 1), ("depth", DEPTHS_M.size), ("lat", LAT.size),
                           ("lon", LON.size)):
            ds.createDimension(name, size)
        coordinates = (
            ("time", np.arange(HOURS + 1, dtype=float),
             dict(standard_name="time", units="hours since 2024-03-01 00:00:00",
                  calendar="gregorian", axis="T")),
            ("depth", DEPTHS_M, dict(standard_name="depth", units="m", positive="down",
                                     axis="Z")),
            ("lat", LAT, dict(standard_name="latitude", units="degrees_north", axis="Y")),
            ("lon", LON, dict(standard_name="longitude", units="degrees_east", axis="X")))
        for name, data, attrs in coordinates:
            var = ds.createVariable(name, "f8", (name,))
            var.setncatts(attrs)
            var[:] = data
        for k, (name, standard) in enumerate((("u", "eastward_sea_water_velocity"),
                                              ("v", "northward_sea_water_velocity"))):
            var = ds.createVariable(name, "f4", ("time", "depth", "lat", "lon"), zlib=True,
                                    complevel=6)
            var.setncatts(dict(standard_name=standard, units="m s-1"))
            var[:] = values[..., k].astype(np.float32)
    tmp.replace(path)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--out", type=Path, default=OUT)
    args = parser.parse_args(argv)
    write(args.out)
    print(f"wrote {args.out} ({args.out.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()
