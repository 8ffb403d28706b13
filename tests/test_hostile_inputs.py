"""Hostile inputs through the `drake-auv` command line: never silently wrong. Each case is
refused with exit 2, one line on stderr (no traceback) naming the offending input and its
allowed range, within 15 s of the call (before any long work). Every case builds its files
(tiny) in its own folder and runs in this process, as `drake-auv` would."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from drake_auv.cli import main
from drake_auv.terrain.bathymetry import ELEVATION_RANGE_M, Bathymetry
from drake_auv.terrain.readers import write_geotiff

REFUSAL_S = 15.0  # s, the contract's bound from the call to the refusal
LOW, HIGH = ELEVATION_RANGE_M


def refuse(argv, capsys) -> str:
    """Runs `drake-auv argv`; asserts exit 2, one non-empty stderr line without a traceback,
    within REFUSAL_S; returns that line."""
    capsys.readouterr()
    start = time.perf_counter()
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exit_:
        code = exit_.code
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, (code, err[-2000:])
    assert len(lines) == 1 and lines[0].strip() and "Traceback" not in err, err[-2000:]
    assert lines[0].startswith("drake-auv"), lines[0][:300]  # nothing before it (a bar)
    assert len(lines[0]) < 1000, lines[0][:300]
    assert elapsed < REFUSAL_S, f"refused after {elapsed:.1f} s"
    return lines[0]


def _slope_grid() -> np.ndarray:
    """A 40 x 30 m seabed 40 m deep with a 7 m wall: plannable in a second."""
    yy, xx = np.mgrid[0:40, 0:30] * 1.0
    return -40.0 + 0.05 * yy + np.clip(xx - 12.0, 0.0, 8.0) * 0.9


def _tif(tmp_path, z, name="grid.tif", origin=(1000.0, 2000.0), crs="EPSG:32631"):
    path = tmp_path / name
    write_geotiff(Bathymetry(np.asarray(z, float), (1.0, 1.0), origin, crs), path)
    return path


def _set_cells(path, value, where=(slice(4, 6), slice(7, 9))):
    import rasterio

    with rasterio.open(path, "r+") as ds:
        data = ds.read(1)
        data[where] = value
        ds.write(data, 1)
    return path


# --- the fly step: a vehicle mission placed in the rock, above the surface, holding forever ---

def _qgc_mission(tmp_path, waypoints) -> "os.PathLike":
    """The UTM test site (seabed 20 m deep) and a mission flying a QGroundControl plan of
    `waypoints`: (easting, northing, frame, param 7 altitude, param 1 hold)."""
    from pyproj import Transformer

    from sites import CRS, write_utm_site

    mission = write_utm_site(tmp_path)
    to_wgs84 = Transformer.from_crs(CRS, "EPSG:4326", always_xy=True)
    items = [{"type": "SimpleItem", "command": 178, "frame": 2,
              "params": [1, 0.5, -1, 0, 0, 0, 0]}]  # DO_CHANGE_SPEED 0.5 m/s
    for east, north, frame, alt, hold in waypoints:
        lon, lat = to_wgs84.transform(east, north)
        items.append({"type": "SimpleItem", "command": 16, "frame": frame,
                      "params": [hold, 1.0, 0, None, lat, lon, alt]})
    (tmp_path / "hostile.plan").write_text(json.dumps(
        {"fileType": "Plan", "version": 1, "mission": {"firmwareType": 3, "items": items}}))
    spec = yaml.safe_load(mission.read_text())
    spec["steps"] = [{"fly": {"file": "hostile.plan"}}]
    spec["limits"] = {}
    mission.write_text(yaml.safe_dump(spec))
    return mission


def fly_500_m_deep(tmp_path):
    """Item 2 500 m deep (frame 3) where the seabed is 20 m deep."""
    from sites import SEABED_Z

    mission = _qgc_mission(tmp_path, [(499985.0, 4599985.0, 3, -5.0, 0),
                                      (499990.0, 4599985.0, 3, -500.0, 0)])
    return ["run", mission, "-o", tmp_path / "o"], [
        "steps[0].fly.file", "hostile.plan: item 2", "depth 500 m is", "inside the world",
        f"its top surface there: {-SEABED_Z:.1f} m deep", f"depth in [0, {-SEABED_Z:.1f}) m"]


def fly_1000_m_altitude(tmp_path):
    """1000 m above the seabed (frame 10), 20 m deep: 980 m above the surface."""
    from sites import SEABED_Z

    mission = _qgc_mission(tmp_path, [(499985.0, 4599985.0, 10, 1000.0, 0)])
    return ["run", mission, "-o", tmp_path / "o"], [
        "steps[0].fly.file", "hostile.plan: item 1",
        f"{1000.0 + SEABED_Z:.2f} m above the sea surface", f"depth in [0, {-SEABED_Z:.1f}) m"]


def fly_hold_1e9_s(tmp_path):
    mission = _qgc_mission(tmp_path, [(499985.0, 4599985.0, 3, -5.0, 1.0e9)])
    return ["run", mission, "-o", tmp_path / "o"], ["mission item 1", "hold (param 1, s)",
                                                    "[0, 3600"]


def _path_csv(tmp_path, depths=(-5.0, -5.0, -5.0)):
    path = tmp_path / "path.csv"
    rows = ["x,y,z,heading,sensor_x,sensor_y,sensor_z,label"]
    rows += [f"{10 * k},0,{z},0,0,0,-1,0" for k, z in enumerate(depths)]
    path.write_text("\n".join(rows) + "\n")
    return path


def simulate_above_the_surface(tmp_path):
    return ["simulate", _path_csv(tmp_path, (-5.0, 50.0, -5.0)), "-o", tmp_path / "o",
            "--no-html", "--quiet"], ["path.csv:3", "50.00 m above the sea surface", "z <= 0 m"]


# --- bathymetry rasters ---

def plan_minus_1e30(tmp_path):
    """Every cell -1e30 m: a no-data value the file does not declare."""
    path = _set_cells(_tif(tmp_path, _slope_grid()), -1e30, (slice(None), slice(None)))
    return ["plan", path, "-o", tmp_path / "o"], \
        ["grid.tif", f"{_slope_grid().size} cell(s) outside [{LOW:g}, {HIGH:g}] m",
         "-1e+30 at row 0, column 0"]


def plan_plus_inf_cells(tmp_path):
    path = _set_cells(_tif(tmp_path, _slope_grid()), np.inf)
    return ["plan", path, "-o", tmp_path / "o"], ["grid.tif", "4 infinite cell(s)",
                                                  "row 4, column 7", f"[{LOW:g}, {HIGH:g}]"]


def plan_nan_cells(tmp_path):
    """Every cell NaN (some NaN cells are no-data, stated: `test_no_data_cells_are_stated`)."""
    path = _set_cells(_tif(tmp_path, _slope_grid()), np.nan, (slice(None), slice(None)))
    return ["plan", path, "-o", tmp_path / "o"], ["grid.tif", "all no-data"]


def plan_no_go_projected_without_crs(tmp_path):
    grid = _tif(tmp_path, _slope_grid(), origin=(500000.0, 4000000.0))
    ring = [[500005, 4000005], [500015, 4000005], [500015, 4000015], [500005, 4000005]]
    zone = tmp_path / "zone.geojson"
    zone.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {},
         "geometry": {"type": "Polygon", "coordinates": [ring]}}]}))
    return ["plan", grid, "--no-go", zone, "-o", tmp_path / "o"], \
        ["zone.geojson", "not longitudes and latitudes"]


def plan_200000_squared_raster(tmp_path):
    """A 200,000 x 200,000 float32 GeoTIFF (160 GB of cells) stored sparse: a few kB."""
    import rasterio
    from affine import Affine

    path = tmp_path / "huge.tif"
    with rasterio.open(path, "w", driver="GTiff", width=200_000, height=200_000, count=1,
                       dtype="float32", crs="EPSG:32631",
                       transform=Affine(1.0, 0.0, 0.0, 0.0, -1.0, 2e5),
                       tiled=True, blockxsize=512, blockysize=512, compress="deflate",
                       sparse_ok=True, BIGTIFF="YES"):
        pass
    assert path.stat().st_size < 10_000_000
    return ["plan", path, "-o", tmp_path / "o"], ["huge.tif", "200000 x 200000 cells needs",
                                                      "GiB available"]


# --- plan options ---

def _plan_with(options, expected, before_planning=False):
    """`plan` of a small wall with `options`; `before_planning`: refused before
    `plan_coverage` is called (the others: inside it, before any route is built)."""
    def case(tmp_path):
        grid = tmp_path / "wall.npz"
        np.savez(grid, z=_slope_grid(), spacing=[1.0, 1.0])
        return ["plan", grid, "--no-figures", "--no-3d-metrics", *options, "-o",
                tmp_path / "o"], expected
    case.before_planning = before_planning
    return case


# --- missions ---

def explore_region_1e6_m(tmp_path):
    return ["run", "boulder_explore", "-o", tmp_path / "o", "--set",
            "steps.0.explore.region=[0, 0, -1000000, 1000000, 1000000, -5]"], \
        ["region", "planning cells) needs", "GiB"]


def reconstruct_identical_points(tmp_path):
    from drake_auv.reconstruction.pointcloud import PointCloud, write_ply

    n = 500
    cloud = PointCloud(np.tile([1.0, 2.0, -10.0], (n, 1)), np.tile([1.0, 2.0, 0.0], (n, 1)),
                       np.arange(n, dtype=float), np.zeros(n, np.uint8))
    write_ply(cloud, tmp_path / "same.ply")
    return ["reconstruct", tmp_path / "same.ply", "-o", tmp_path / "o" / "s.ply", "--quiet"], \
        ["same.ply", "1 distinct position(s) among its 500 points", "at least 10"]


def campaign_1000_workers(tmp_path):
    return ["campaign", "boulder", "--seeds", "0:2", "--workers", "1000", "-o",
            tmp_path / "o", "--quiet"], ["--workers 1000", "[1, "]


def campaign_a_billion_seeds(tmp_path):
    return ["campaign", "boulder", "--seeds", "0:1000000000", "--workers", "1", "-o",
            tmp_path / "o", "--quiet"], ["--seeds 0:1000000000", "1000000000 runs",
                                         "at most 100000 runs"]


def envelope_too_many_runs(tmp_path):
    """(50 x 360 + 1) currents x 100 seeds: 1,800,100 runs."""
    return ["envelope", "boulder", "--speeds", "0:5:0.1", "--directions", "360", "--seeds",
            "0:100", "--workers", "1", "-o", tmp_path / "o", "--quiet"], \
        ["--speeds x --directions x --seeds", "1800100 runs", "at most 100000 runs"]


def lawnmower_altitude_1e_6(tmp_path):
    return ["lawnmower", "--altitude", "1e-6", "-o", tmp_path / "o", "--no-html", "--quiet"], \
        ["--altitude 1e-06", "[0.5, 100] m"]


ALIAS_BOMB = ("a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{b}: &{b} [{', '.join([f'*{a}'] * 10)}]\n" for a, b in zip("abcdefgh", "bcdefghi")))


def mission_alias_bomb(tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text("name: bomb\nsite: {scenario: boulder}\nsteps: [{plan: {omega: 6}}]\n"
                    + ALIAS_BOMB.replace("i: &i", "limits: &i"))
    return ["run", path, "-o", tmp_path / "o"], ["bomb.yaml", "expands to more than 100000 values",
                                                 "allowed: at most"]


def mission_max_time_negative_1e9(tmp_path):
    """`-1.0e9` is read as a number (YAML 1.2) and judged by its range."""
    path = tmp_path / "m.yaml"
    path.write_text("name: m\nsite: {scenario: boulder}\nsteps: [{plan: {omega: 6}}]\n"
                    "limits: {max_time_s: -1.0e9}\n")
    return ["run", path, "-o", tmp_path / "o"], ["limits.max_time_s", "-1000000000.0",
                                                 "allowed: > 0 s"]


# --- files: missing, corrupt, unwritable ---

def _garbage(tmp_path, name):
    path = tmp_path / name
    path.write_bytes(np.random.default_rng(7).bytes(4096))
    return path


def missing_file(tmp_path):
    return ["plan", tmp_path / "nowhere.tif", "-o", tmp_path / "o"], ["nowhere.tif"]


def corrupt_tif(tmp_path):
    return ["plan", _garbage(tmp_path, "noise.tif"), "-o", tmp_path / "o"], ["noise.tif"]


def corrupt_yaml(tmp_path):
    return ["run", _garbage(tmp_path, "noise.yaml"), "-o", tmp_path / "o"], ["noise.yaml"]


def corrupt_plan(tmp_path):
    mission = _qgc_mission(tmp_path, [(499985.0, 4599985.0, 3, -5.0, 0)])
    _garbage(tmp_path, "hostile.plan")
    return ["run", mission, "-o", tmp_path / "o"], ["hostile.plan"]


def corrupt_mcap(tmp_path):
    return ["replay", _garbage(tmp_path, "noise.mcap"), "-o", tmp_path / "o"], ["noise.mcap"]


def corrupt_ply(tmp_path):
    return ["reconstruct", _garbage(tmp_path, "noise.ply"), "-o", tmp_path / "o" / "s.ply"], \
        ["noise.ply"]


def corrupt_netcdf(tmp_path):
    return ["run", "boulder", "-o", tmp_path / "o", "--set",
            f"ocean.file={_garbage(tmp_path, 'noise.nc')}"], ["ocean.file", "noise.nc"]


def _output_under_a_file(*argv):
    """`argv` with `-o` under a file ("path.csv" in it: a good path CSV)."""
    def case(tmp_path):
        (tmp_path / "file.txt").write_text("a file, not a folder\n")
        given = [_path_csv(tmp_path) if a == "path.csv" else a for a in argv]
        return [*given, "-o", tmp_path / "file.txt" / "o"], ["-o", "file.txt/o"]
    return case


def output_in_a_read_only_folder(tmp_path):
    """A folder without write permission; for root, who writes through permissions, a folder
    of Linux's read-only sysfs."""
    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    if os.access(locked, os.W_OK):
        locked = Path("/sys/class")
        if not locked.is_dir() or os.access(locked, os.W_OK) and not _sysfs_refuses(locked):
            pytest.skip("no folder this user cannot write into")
    grid = tmp_path / "g.npz"
    np.savez(grid, z=_slope_grid(), spacing=[1.0, 1.0])
    return ["plan", grid, "-o", locked / "o"], [str(locked)]


def _sysfs_refuses(folder: Path) -> bool:
    try:
        (folder / "drake_auv_probe").mkdir()
    except OSError:
        return True
    (folder / "drake_auv_probe").rmdir()
    return False


# --- the sea ---

def negative_hs(tmp_path):
    return ["run", "boulder", "-o", tmp_path / "o", "--set", "ocean.waves.hs_m=-1"], \
        ["ocean.waves.hs_m", "-1.0", "[0, 20] m"]


def current_6_mps(tmp_path):
    return ["run", "boulder", "-o", tmp_path / "o", "--set", "ocean.current.speed_mps=6"], \
        ["ocean.current.speed_mps", "6.0", "[0, 5] m/s"]


def netcdf_without_u_v(tmp_path):
    from test_ocean_gridded import write_cf

    write_cf(tmp_path / "current.nc", names=("a", "b"), standard=False)
    return ["run", "boulder", "-o", tmp_path / "o", "--set",
            f"ocean.file={tmp_path / 'current.nc'}"], ["ocean.file", "current.nc", "no u velocity",
                                                    "eastward_sea_water_velocity"]


CASES = {
    "fly-500-m-deep": fly_500_m_deep,
    "fly-terrain-altitude-1000-m": fly_1000_m_altitude,
    "fly-hold-1e9-s": fly_hold_1e9_s,
    "simulate-z-plus-50": simulate_above_the_surface,
    "plan-minus-1e30": plan_minus_1e30,
    "plan-plus-inf-cells": plan_plus_inf_cells,
    "plan-nan-cells": plan_nan_cells,
    "plan-no-go-projected-no-crs": plan_no_go_projected_without_crs,
    "plan-200000-squared": plan_200000_squared_raster,
    "plan-slice-spacing-1e-9": _plan_with(
        ["--slice-spacing", "1e-9"], ["slice_spacing 1e-09 m", "at most 1000 planes"]),
    "plan-omega-1e-6": _plan_with(["--omega", "1e-6"], ["--omega 1e-06", "[0.5, 100] m"], True),
    "plan-slice-count-1e9": _plan_with(
        ["--slice-count", "1e9"], ["--slice-count 1e+09", "an integer in [1, 1000]"], True),
    "plan-origin-lonlat-500-100": _plan_with(
        ["--export", "qgc", "--origin-lonlat", "500,100"],
        ["origin_lonlat", "lon in [-180, 180], lat in (-90, 90)", "(500.0, 100.0)"], True),
    "plan-max-items-0": _plan_with(["--export", "qgc", "--origin-lonlat", "3,42",
                                    "--max-items", "0"], ["--max-items", ">= 4", "got 0"], True),
    "explore-region-1e6-m": explore_region_1e6_m,
    "reconstruct-500-identical-points": reconstruct_identical_points,
    "campaign-1000-workers": campaign_1000_workers,
    "campaign-a-billion-seeds": campaign_a_billion_seeds,
    "envelope-1800100-runs": envelope_too_many_runs,
    "lawnmower-altitude-1e-6": lawnmower_altitude_1e_6,
    "plan-overlap-0.999999": _plan_with(["--overlap", "0.999999"],
                                        ["--overlap 0.999999", "[0, 0.9]"], True),
    "plan-speed-0": _plan_with(["--speed", "0"], ["--speed 0", "[0.05, 1.4] m/s"], True),
    "usage-slice-count-1.5": _plan_with(["--slice-count", "1.5"],
                                        ["--slice-count", "'1.5' is not a whole number"], True),
    "usage-unknown-option": _plan_with(["--omgea", "3"], ["unrecognized arguments: --omgea 3",
                                                         "drake-auv --help"], True),
    "mission-alias-bomb": mission_alias_bomb,
    "mission-max-time-minus-1e9": mission_max_time_negative_1e9,
    "missing-file": missing_file,
    "corrupt-tif": corrupt_tif,
    "corrupt-yaml": corrupt_yaml,
    "corrupt-plan": corrupt_plan,
    "corrupt-mcap": corrupt_mcap,
    "corrupt-ply": corrupt_ply,
    "corrupt-netcdf": corrupt_netcdf,
    "plan-output-under-a-file": _output_under_a_file("plan", "caldera"),
    "run-output-under-a-file": _output_under_a_file("run", "boulder"),
    "simulate-output-under-a-file": _output_under_a_file("simulate", "path.csv", "--no-html"),
    "lawnmower-output-under-a-file": _output_under_a_file("lawnmower", "--no-html"),
    "output-read-only": output_in_a_read_only_folder,
    "negative-hs": negative_hs,
    "current-6-mps": current_6_mps,
    "netcdf-without-u-v": netcdf_without_u_v,
}


@pytest.mark.parametrize("case", CASES.values(), ids=CASES.keys())
def test_a_hostile_input_is_refused_in_one_line_at_once(tmp_path, capsys, monkeypatch, case):
    if getattr(case, "before_planning", False):
        from drake_auv.planning import coverage_plan

        def never(*args, **kwargs):
            raise AssertionError("planned before the options were checked")

        monkeypatch.setattr(coverage_plan, "plan_coverage", never)
    argv, expected = case(tmp_path)
    line = refuse(argv, capsys)
    for text in expected:
        assert text in line, (text, line)
    assert not (tmp_path / "o" / "report.json").exists()


def test_no_data_cells_are_stated(tmp_path, capsys):
    """A few NaN cells are the file's no-data, planned around (no-go), and said so."""
    z = _slope_grid()
    path = _set_cells(_tif(tmp_path, z), np.nan)
    assert main(["plan", str(path), "--no-figures", "--no-3d-metrics", "-o",
                 str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert f"grid.tif: 4 of {z.size} cells are no-data" in out and "no-go" in out, out
    clean = _tif(tmp_path, z, name="clean.tif")
    assert main(["plan", str(clean), "--no-figures", "--no-3d-metrics", "-o",
                 str(tmp_path / "o")]) == 0
    assert "no-data" not in capsys.readouterr().out


def test_a_refused_campaign_ends_its_process_with_status_2(tmp_path):
    """`--workers 1000` once leaked semaphores and never ended: the real console entry point,
    in its own process, guarded by a timeout, ends with status 2 and one line."""
    import subprocess
    import sys

    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": f"{root}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
           "MPLBACKEND": "Agg"}
    done = subprocess.run([sys.executable, "-m", "drake_auv.cli", "campaign", "boulder",
                           "--seeds", "0:2", "--workers", "1e3", "-o", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr[-2000:]
    assert "--workers 1000" in lines[0] and "Traceback" not in done.stderr
    assert not (tmp_path / "o" / "results.csv").exists()
