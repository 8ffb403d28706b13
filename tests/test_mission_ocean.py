"""The sea in the mission Diagram: a still sea adds nothing; a gridded CF current drives the
dive, and `trajectory.csv`'s current columns are that file interpolated along the true track;
a sea the file does not cover is refused before any simulation, over the dive's whole span
(up to its time cap, the legs' budgets without `limits.max_time_s`)."""

import csv

import netCDF4
import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from drake_auv.mission.config import load_mission
from drake_auv.mission.diagram import build_mission_diagram
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.report.outputs import write_trajectory
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.ocean.clock import format_utc, parse_utc

HOURS = np.array([0.0, 0.5, 1.0])
DEPTH = np.array([0.0, 20.0, 60.0])
X = np.linspace(-60.0, 60.0, 7)
Y = np.linspace(-60.0, 60.0, 5)


def _field():
    """u, v over (time, depth, y, x), m/s: a current that turns with time, shears with depth
    and varies across the site, so an interpolation error shows."""
    t, d, y, x = np.meshgrid(HOURS, DEPTH, Y, X, indexing="ij")
    u = 0.15 + 0.1 * t + 0.002 * x - 0.001 * d
    v = -0.1 + 0.05 * np.sin(0.03 * y) + 0.1 * t
    return u, v


def _write(path):
    u, v = _field()
    with netCDF4.Dataset(path, "w") as ds:
        for name, values in (("time", HOURS), ("depth", DEPTH), ("y", Y), ("x", X)):
            ds.createDimension(name, values.size)
        time = ds.createVariable("time", "f8", ("time",))
        time.units, time.standard_name = "hours since 2026-06-01 00:00:00", "time"
        time[:] = HOURS
        depth = ds.createVariable("depth", "f8", ("depth",))
        depth.units, depth.positive = "m", "down"
        depth[:] = DEPTH
        for name, values in (("y", Y), ("x", X)):
            var = ds.createVariable(name, "f8", (name,))
            var.units, var.standard_name = "m", f"projection_{name}_coordinate"
            var[:] = values
        for name, data, standard in (("u", u, "eastward_sea_water_velocity"),
                                     ("v", v, "northward_sea_water_velocity")):
            var = ds.createVariable(name, "f8", ("time", "depth", "y", "x"))
            var.units, var.standard_name = "m s-1", standard
            var[:] = data


def _boulder(*overrides):
    return load_mission("boulder", overrides=["limits.max_time_s=12", "ocean=none", *overrides])


def test_a_still_sea_adds_no_ocean_system():
    spec = _boulder()
    assert spec.ocean is None
    _, handles = build_mission_diagram(load_site(spec.site, spec.seed), spec)
    assert handles.ocean is None and "water" not in handles.logs


def test_a_gridded_current_drives_the_dive(tmp_path):
    _write(tmp_path / "current.nc")
    spec = _boulder(f"ocean.file={tmp_path / 'current.nc'}")
    result = run_mission(spec, progress=False)
    write_trajectory(result, tmp_path / "trajectory.csv")
    with open(tmp_path / "trajectory.csv") as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["t"]) for r in rows])
    xyz = np.array([[float(r[k]) for k in ("x", "y", "z")] for r in rows])
    current = np.array([[float(r[f"current_{k}"]) for k in "xyz"] for r in rows])
    u, v = _field()
    points = np.column_stack([t / 3600.0, -xyz[:, 2], xyz[:, 1], xyz[:, 0]])
    for k, data in enumerate((u, v)):
        expected = RegularGridInterpolator((HOURS, DEPTH, Y, X), data)(points)
        np.testing.assert_allclose(current[:, k], expected, atol=1e-4)
    np.testing.assert_allclose(current[:, 2], 0.0)
    # the water moved the vehicle: the same dive in still water differs
    still = run_mission(_boulder(), progress=False)
    n = min(len(still.log.times), len(result.log.times))
    assert np.abs(still.log.state[:n, :3] - result.log.state[:n, :3]).max() > 0.05


def test_a_file_that_does_not_cover_the_site_is_refused_before_the_dive(tmp_path):
    _write(tmp_path / "current.nc")
    spec = _boulder(f"ocean.file={tmp_path / 'current.nc'}", "limits.max_time_s=7200")
    with pytest.raises(ValueError, match="time"):
        build_mission_diagram(load_site(spec.site, spec.seed), spec)


def test_a_dive_without_a_time_cap_is_checked_up_to_its_legs_budgets(tmp_path):
    """With `limits.max_time_s` null the dive may fly until its legs' time budgets summed: a
    tide series must cover all of that, not only the start, and the refusal says what the
    span was; a cap shorter than the series is enough."""
    start = parse_utc("2024-03-01T00:00:00Z")

    def pool(end_s: float, *overrides):
        path = tmp_path / f"tide_{end_s:.0f}.csv"
        path.write_text(f"time_utc,east_mps,north_mps\n{format_utc(start)},0.0,0.1\n"
                        f"{format_utc(start + end_s)},0.1,0.0\n")
        return load_mission("pool", overrides=[f"ocean.tides={path}",
                                               "ocean.start_utc=2024-03-01T00:00:00Z",
                                               *overrides])

    spec = pool(3600.0)
    site = load_site(spec.site, spec.seed)
    plan = plan_mission(spec, site)
    cap, source = plan.time_cap(spec)
    assert spec.limits.max_time_s is None and cap == plan.budget > 120.0
    assert "budgets" in source
    build_mission_diagram(site, pool(cap + 60.0), plan)  # covered up to the cap
    with pytest.raises(ValueError, match=rf"not the dive's .* \(its time cap, {cap:g} s: the "
                                         r"legs' time budgets summed \(limits.max_time_s is"):
        build_mission_diagram(site, pool(cap - 60.0), plan)
    build_mission_diagram(site, pool(cap - 60.0, f"limits.max_time_s={cap - 90.0}"), plan)
    with pytest.raises(ValueError, match=r"\(its time cap, [0-9.]+ s: limits.max_time_s\)"):
        build_mission_diagram(site, pool(cap - 60.0, f"limits.max_time_s={cap - 30.0}"), plan)
