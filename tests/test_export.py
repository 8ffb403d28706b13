"""Exports a vehicle runs (COLA2 mission XML, QGroundControl .plan) and the WGS 84 GeoJSON:
each written, read back (XML parsed, JSON loaded) and compared with the path (the COLA2
sections' semantics and replay: tests/test_cola2.py)."""

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
import shapely

from drake_auv.cli import main
from drake_auv.formats.outputs import write_outputs
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.missions import douglas_peucker
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.scenarios import DATA_DIR
from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT, GeoFrame
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.synthetic import caldera_site

MONTEREY = sorted((DATA_DIR / "monterey").glob("*.tif"))
ALL = ("cola2", "qgc", "geojson")


def read_cola2(filename):
    """(K, 3) lon, lat, depth of every maneuver's final point, and the maneuvers."""
    root = ET.parse(filename).getroot()
    assert root.tag == "mission" and root.find("version").text == "2.0"
    mans = [s.find("maneuver") for s in root.findall("mission_step")]
    ll = np.array([[float(m.find(t).text) for t in ("final_longitude", "final_latitude",
                                                    "final_depth")] for m in mans])
    return ll, mans


def read_qgc(outdir):
    """The waypoints of mission.plan or mission_1.plan, ... (DO_CHANGE_SPEED first in each)."""
    files = sorted(Path(outdir).glob("mission*.plan"))
    assert files
    items = []
    for f in files:
        plan = json.loads(f.read_text())
        assert plan["fileType"] == "Plan" and plan["mission"]["version"] == 2
        its = plan["mission"]["items"]
        assert its[0]["command"] == 178
        assert all(i["type"] == "SimpleItem" and i["command"] == 16 for i in its[1:])
        items += its[1:]
    return plan, items


def read_geojson(filename):
    """The file, its route's (lon, lat) vertices and its waypoints' (lon, lat, elevation):
    2D positions, depths as properties."""
    gj = json.loads(Path(filename).read_text())
    assert "crs" not in gj  # RFC 7946: WGS 84, no crs member
    route = gj["features"][0]
    assert route["properties"]["kind"] == "route" and route["geometry"]["type"] == "LineString"
    points = gj["features"][1:]
    assert all(f["geometry"]["type"] == "Point" for f in points)
    waypoints = np.array([[*f["geometry"]["coordinates"], -f["properties"]["depth"]]
                          for f in points]).reshape(-1, 3)
    return gj, np.array(route["geometry"]["coordinates"]), waypoints


def nearest_distance(points, samples):
    from scipy.spatial import cKDTree

    return cKDTree(samples).query(points)[0]


def check_exports(plan, outdir, origin=None):
    """Every export lands within 0.1 m of the path; returns the GeoJSON lon/lat."""
    geo = GeoFrame(plan.bathy, origin)
    pts = plan.path.points
    ll, mans = read_cola2(outdir / "mission.xml")
    assert [m.get("type") for m in mans[:2]] == ["goto", "section"] and mans[-1].get("type") == "park"
    # Section ends are path samples in xy; their z is what COLA2 holds (tests/test_cola2.py).
    assert nearest_distance(geo.from_lonlat(ll[:, :2]), pts[:, :2]).max() < 0.1
    cola2 = json.loads((outdir / "report.json").read_text())["exports"]["cola2"]
    assert cola2["sections"] == len(mans) - 2 and cola2["replay"]["closer_than_reachable"] == 0
    heave = np.array([int(m.find("heave_mode").text) for m in mans[:-1]])
    assert set(heave.tolist()) <= {0, 1}
    if "slice" in set(plan.path.labels):
        assert {0, 1} <= set(heave.tolist())  # altitude on lanes, depth on contours
    for m in mans[1:-1]:
        for tag in ("initial_latitude", "initial_longitude", "initial_depth", "final_altitude",
                    "surge_velocity", "tolerance_xy", "no_altitude_goes_up"):
            assert m.find(tag) is not None, tag
    qgc, items = read_qgc(outdir)
    p = np.array([i["params"][4:7] for i in items])
    frames = np.array([i["frame"] for i in items])
    assert set(frames.tolist()) <= {3, 10}
    xy = geo.from_lonlat(p[:, [1, 0]])
    seabed = plan.surface.elevation(xy[:, 0], xy[:, 1])
    z = np.where(frames == 10, seabed + p[:, 2], p[:, 2])
    assert np.all(p[frames == 10, 2] > 0) and np.all(p[frames == 3, 2] < 0)
    assert nearest_distance(np.column_stack([xy, z]), pts).max() < 0.1
    gj, route, waypoints = read_geojson(outdir / "path.geojson")
    assert nearest_distance(geo.from_lonlat(route), pts[:, :2]).max() < 0.1
    line = shapely.LineString(geo.from_lonlat(route))  # every sample lies on the route
    assert shapely.distance(line, shapely.points(pts[:, :2])).max() < 0.15
    # The waypoints are the vehicle files' items: COLA2's then QGC's, in order.
    assert len(waypoints) == len(ll) + len(items)
    np.testing.assert_allclose(waypoints[:len(ll), :2], ll[:, :2], atol=1e-6)
    np.testing.assert_allclose(waypoints[len(ll):, :2], p[:, [1, 0]], atol=1e-6)
    assert {f["properties"]["heave"] for f in gj["features"][1:]} <= {"altitude", "depth"}
    return route


def test_douglas_peucker_keeps_corners_and_bounds_the_error():
    t = np.linspace(0, 1, 101)
    line = np.column_stack([t, np.where(t < 0.5, t, 1 - t), np.zeros_like(t)])
    idx = douglas_peucker(line, 0.01)
    assert idx.tolist() == [0, 50, 100]
    rng = np.random.default_rng(3)
    walk = np.cumsum(rng.normal(size=(300, 3)), axis=0)
    idx = douglas_peucker(walk, 0.5)
    assert 2 < len(idx) < 300
    dense = np.vstack([np.linspace(walk[a], walk[b], 50) for a, b in zip(idx[:-1], idx[1:])])
    assert nearest_distance(walk, dense).max() <= 0.5 + 1e-6
    pieces = douglas_peucker(walk, 0.5, piece=64)  # thinned 64 samples at a time
    assert set(range(0, 300, 63)) <= set(pieces.tolist()) and len(pieces) < 300
    dense = np.vstack([np.linspace(walk[a], walk[b], 50) for a, b in zip(pieces[:-1], pieces[1:])])
    assert nearest_distance(walk, dense).max() <= 0.5 + 1e-6


def test_caldera_exports_read_back(tmp_path):
    plan = plan_coverage(caldera_site(cell=1.0), CoverageParameters(omega=2.0),
                         compute_metrics=False)
    write_outputs(plan, tmp_path, figures=False, exports=ALL, origin_lonlat=CALDERA_ORIGIN_LONLAT)
    lonlat = check_exports(plan, tmp_path, CALDERA_ORIGIN_LONLAT)
    lon0, lat0 = CALDERA_ORIGIN_LONLAT  # the site is 100 m x 250 m east and north of it
    assert lon0 <= lonlat[:, 0].min() and lonlat[:, 0].max() <= lon0 + 101 / 89_600
    assert lat0 <= lonlat[:, 1].min() and lonlat[:, 1].max() <= lat0 + 251 / 110_900


def test_exports_need_a_georeference(tmp_path):
    plan = plan_coverage(caldera_site(cell=2.0), CoverageParameters(omega=3.0),
                         compute_metrics=False)
    with pytest.raises(ValueError, match="no CRS"):
        write_outputs(plan, tmp_path, figures=False, exports=("geojson",))
    assert [f.name for f in write_outputs(plan, tmp_path, figures=False)] == [
        "path.csv", "report.md", "report.json"]


@pytest.mark.parametrize("tile", MONTEREY, ids=lambda p: p.name[12:40])
def test_cli_exports_on_the_monterey_tiles(tmp_path, capsys, tile):
    code = main(["plan", str(tile), "--omega", "20", "--export", "cola2,qgc,geojson",
                 "--no-figures", "--no-3d-metrics", "-o", str(tmp_path)])
    assert code == 0, capsys.readouterr().err
    from drake_auv.planning.path import PlannedPath

    path = PlannedPath.from_csv(tmp_path / "path.csv")
    bathy = read_bathymetry(tile)
    geo = GeoFrame(bathy)
    _, route, _ = read_geojson(tmp_path / "path.geojson")
    assert nearest_distance(geo.from_lonlat(route), path.points[:, :2]).max() < 0.1
    ll, _ = read_cola2(tmp_path / "mission.xml")
    assert nearest_distance(geo.from_lonlat(ll[:, :2]), path.points[:, :2]).max() < 0.1
    _, items = read_qgc(tmp_path)
    p = np.array([i["params"][4:6] for i in items])
    assert nearest_distance(geo.from_lonlat(p[:, ::-1]), path.points[:, :2]).max() < 0.1
    cola2 = json.loads((tmp_path / "report.json").read_text())["exports"]["cola2"]
    assert cola2["sections"] == len(ll) - 2
    assert cola2["replay"]["closer_than_half_omega"] == 0
    # The tile name's extent; the raster itself overhangs it by 0.00051 deg on every side
    # (its transform: 5.5 cells), and the path covers the raster's cell centres.
    lon0, lon1, lat0, lat1 = (float(v) for v in re.findall(r"-?\d+\.\d+", tile.stem))
    m = 0.00051
    _, coords, waypoints = read_geojson(tmp_path / "path.geojson")
    ll, _ = read_cola2(tmp_path / "mission.xml")
    for c in (coords, waypoints, ll):
        assert np.all((c[:, 0] >= lon0 - m) & (c[:, 0] <= lon1 + m))
        assert np.all((c[:, 1] >= lat0 - m) & (c[:, 1] <= lat1 + m))
    assert ll[:, 2].min() >= 1.0 - 1e-9  # nothing above the minimum operating depth


def test_unknown_export_is_one_line(tmp_path, capsys):
    assert main(["plan", "caldera", "--export", "kml", "-o", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "kml" in err[0] and "cola2" in err[0]
