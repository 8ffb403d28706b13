"""The GeoJSON export: what RFC 7946 says (2D WGS 84 positions, depths and altitudes as
properties), one route line and the waypoints the vehicle files hold, read by GDAL through
pyogrio, written to Shapefiles, validated by geojson-validator, and faithful to the path."""

import json

import numpy as np
import pyogrio
import pytest
import shapely

from drake_auv.formats.cola2 import read_cola2
from drake_auv.formats.geojson import ROUTE_TOLERANCE
from drake_auv.formats.outputs import write_outputs
from drake_auv.formats.qgc import read_qgc_plan
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT, GeoFrame
from drake_auv.terrain.synthetic import caldera_site

ROUTE = ["kind", "name", "samples", "length_m", "depth_min", "depth_max"]
WAYPOINT = ["kind", "file", "seq", "item", "heave", "depth", "alt", "yaw_deg"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    plan = plan_coverage(caldera_site(cell=2.0), CoverageParameters(omega=4.0),
                         compute_metrics=False)
    out = tmp_path_factory.mktemp("gj")
    write_outputs(plan, out, figures=False, exports=("cola2", "qgc", "geojson"),
                  origin_lonlat=CALDERA_ORIGIN_LONLAT, metrics_3d=False, max_items=60)
    return plan, out


def _features(out, kind):
    gj = json.loads((out / "path.geojson").read_text())
    assert "crs" not in gj
    return [f for f in gj["features"] if f["properties"]["kind"] == kind]


def test_one_route_line_through_every_sample(exported):
    plan, out = exported
    (route,) = _features(out, "route")
    coords = np.array(route["geometry"]["coordinates"])
    assert route["geometry"]["type"] == "LineString" and coords.shape[1] == 2  # no height
    assert len(coords) < len(plan.path)  # straight runs thinned
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    line = shapely.LineString(geo.from_lonlat(coords))
    d = shapely.distance(line, shapely.points(plan.path.points[:, :2]))
    assert d.max() < ROUTE_TOLERANCE + 0.1  # 6 decimals of a degree: ~0.1 m
    p = route["properties"]
    assert p["samples"] == len(plan.path)
    assert p["length_m"] == pytest.approx(plan.path.length, abs=1e-3)
    assert p["depth_min"] == pytest.approx(-plan.path.points[:, 2].max(), abs=1e-3)
    assert p["depth_max"] == pytest.approx(-plan.path.points[:, 2].min(), abs=1e-3)


def test_the_waypoints_are_the_vehicle_files(exported):
    plan, out = exported
    points = _features(out, "waypoint")
    files = ["mission.xml"] + sorted((f.name for f in out.glob("mission_*.plan")),
                                     key=lambda n: int(n[8:-5]))
    assert len(files) > 2  # the QGC mission is split at 60 items
    assert list(dict.fromkeys(f["properties"]["file"] for f in points)) == files
    missions = [read_cola2(out / "mission.xml")] + [read_qgc_plan(out / f) for f in files[1:]]
    items = [(f, k + 1, it) for m, f in zip(missions, files) for k, it in enumerate(m.items)]
    assert len(items) == len(points)
    seabed = plan.surface
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    for (name, seq, it), ft in zip(items, points):
        p = ft["properties"]
        assert (p["file"], p["seq"], p["item"], p["heave"]) == (name, seq, it.kind, it.z_mode)
        assert ft["geometry"]["coordinates"] == pytest.approx([it.lon, it.lat], abs=1e-6)
        held = p["depth"] if it.z_mode == "depth" else p["alt"]
        assert held == pytest.approx(it.z, abs=1e-3)
        x, y = geo.from_lonlat([[it.lon, it.lat]])[0]
        assert p["depth"] + p["alt"] == pytest.approx(-seabed.elevation(x, y), abs=2e-3)
        assert ("yaw_deg" in p) == (it.yaw is not None)
    assert {p["properties"]["heave"] for p in points} == {"altitude", "depth"}


def test_gdal_reads_it_and_writes_shapefiles(exported, tmp_path):
    plan, out = exported
    meta, _, geometry, fields = pyogrio.raw.read(out / "path.geojson")
    assert meta["crs"] == "EPSG:4326"
    names = list(meta["fields"])
    assert set(names) == set(ROUTE) | set(WAYPOINT) and all(len(n) <= 10 for n in names)
    geoms = shapely.from_wkb(geometry)
    kinds = shapely.get_type_id(geoms)
    assert kinds[0] == 1 and np.all(kinds[1:] == 0)  # a LineString, then Points
    for name, mask, gtype in (("route", kinds == 1, "LineString"), ("points", kinds == 0, "Point")):
        shp = tmp_path / f"{name}.shp"
        pyogrio.raw.write(shp, geometry[mask], [f[mask] for f in fields], fields=meta["fields"],
                          crs=meta["crs"], geometry_type=gtype, driver="ESRI Shapefile")
        back, _, back_geom, back_fields = pyogrio.raw.read(shp)
        assert list(back["fields"]) == names  # no name truncated, every value a scalar
        assert len(back_geom) == mask.sum()
        assert back_fields[names.index("kind")].tolist() == fields[names.index("kind")][mask].tolist()


def test_geojson_validator_finds_nothing(exported):
    import geojson_validator

    _, out = exported
    for name in ("path.geojson", "lawnmower.geojson"):
        gj = json.loads((out / name).read_text())
        assert geojson_validator.validate_structure(gj, check_crs=True) == {}
        result = geojson_validator.validate_geometries(gj)
        assert result["invalid"] == {} and result["problematic"] == {}
    assert set(result["count_geometry_types"]) == {"LineString"}  # the lawnmower: its route
