"""Regions with holes and no-go zones: no lane, contour or transit within Omega of a zone
(hypothesis on random zones), transits around them, zone files in any CRS, clear errors."""

import json

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drake_auv.cli import main
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.nogo import NoGo
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import write_geotiff
from drake_auv.terrain.synthetic import random_seabed


def _wall_seabed():
    """60 x 80 m, 1 m cells, a steep band (slope 0.9) so plans hold slices too."""
    yy, xx = np.mgrid[0:60, 0:80] * 1.0
    return Bathymetry(-40.0 + 0.05 * yy + np.clip(xx - 50.0, 0.0, 10.0) * 0.9, (1.0, 1.0))


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 10_000), n=st.integers(1, 3), omega=st.floats(1.5, 3.0))
def test_no_sample_within_omega_of_random_zones(seed, n, omega):
    rng = np.random.default_rng(seed)
    bathy = _wall_seabed() if seed % 2 else random_seabed(seed, shape=(60, 80))
    zones = shapely.union_all([
        shapely.Point(rng.uniform(15, 65), rng.uniform(15, 45)).buffer(rng.uniform(2, 7))
        .intersection(shapely.box(*rng.uniform(0, 80, 2).clip(0, 60), 80, 60).union(
            shapely.box(0, 0, 80, 30))) for _ in range(n)])
    if zones.is_empty:
        return
    plan = plan_coverage(bathy, CoverageParameters(omega=omega), no_go=zones, compute_metrics=False)
    for path in (plan.path, plan.lawnmower):
        d = shapely.distance(zones, shapely.points(path.points[:, :2]))
        assert d.min() >= omega - 0.02 * omega, d.min()
    assert plan.unreachable_pieces == 0


def test_transits_go_around_a_zone():
    nogo = NoGo(shapely.box(40, 0, 45, 50), 2.0, (0, 100, 0, 60))
    xy = nogo.detour((20, 20), (70, 20))
    assert len(xy) > 2 and not nogo.inside(xy).any()
    dense = shapely.segmentize(shapely.LineString(xy), 0.1)
    assert shapely.distance(nogo.zones, shapely.points(np.asarray(dense.coords))).min() >= 2.0
    assert shapely.length(dense) < 50 + 2 * 2 * (50 + 2)  # round the top, not the world
    assert nogo.detour((20, 20), (30, 25)).shape == (2, 2)  # clear: straight
    closed = NoGo(shapely.box(40, -5, 45, 65), 2.0, (0, 100, 0, 60))  # cuts the grid in two
    assert closed.detour((20, 20), (70, 20)) is None


def test_a_copy_routes_alike_on_a_forbidden_set_of_its_own():
    from concurrent.futures import ThreadPoolExecutor

    nogo = NoGo(shapely.union_all([shapely.box(40, 0, 45, 50), shapely.box(60, 10, 62, 60)]),
                2.0, (0, 100, 0, 60))
    other = nogo.copy()
    assert other.forbidden is not nogo.forbidden and shapely.equals_exact(
        other.forbidden, nogo.forbidden, 0.0)
    ends = np.random.default_rng(0).uniform((0, 0), (100, 60), (200, 2, 2))
    ends = ends[~nogo.inside(ends.reshape(-1, 2)).reshape(-1, 2).any(axis=1)]

    def routes(n):
        return [n.detour(a, b) for a, b in ends]

    with ThreadPoolExecutor(2) as pool:  # each thread on its own prepared geometry
        mine, theirs = pool.map(routes, (nogo, other))
    for a, b in zip(mine, theirs):
        assert (a is None and b is None) or np.array_equal(a, b)


@pytest.fixture()
def utm_tif(tmp_path):
    yy, xx = np.mgrid[0:60, 0:80] * 1.0
    z = -40.0 + 0.05 * yy + np.clip(xx - 50.0, 0.0, 10.0) * 0.9
    path = tmp_path / "site.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (500000.0, 4000000.0), "EPSG:32631"), path)
    return path


def _geojson_wgs84(tmp_path, name, rings_utm):
    """A GeoJSON polygon file in WGS 84 of rings given in EPSG:32631."""
    from pyproj import Transformer

    t = Transformer.from_crs("EPSG:32631", "EPSG:4326", always_xy=True)
    rings = [np.vstack([r, r[:1]]) for r in (np.asarray(r, float) for r in rings_utm)]
    coords = [np.column_stack(t.transform(*r.T)).tolist() for r in rings]
    path = tmp_path / name
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [{
        "type": "Feature", "properties": {},
        "geometry": {"type": "Polygon", "coordinates": coords}}]}))
    return path


def test_cli_no_go_across_the_middle_and_roi_with_a_hole(utm_tif, tmp_path, capsys):
    x0, y0 = 500000.0, 4000000.0
    zone = _geojson_wgs84(tmp_path, "zone.geojson", [[(x0 + 25, y0 - 1), (x0 + 30, y0 - 1),
                                                      (x0 + 30, y0 + 40), (x0 + 25, y0 + 40)]])
    roi = _geojson_wgs84(tmp_path, "roi.geojson", [
        [(x0, y0), (x0 + 79, y0), (x0 + 79, y0 + 59), (x0, y0 + 59)],
        [(x0 + 5, y0 + 45), (x0 + 15, y0 + 45), (x0 + 15, y0 + 55), (x0 + 5, y0 + 55)]])
    out = tmp_path / "out"
    code = main(["plan", str(utm_tif), "--roi-file", str(roi), "--no-go", str(zone),
                 "--export", "qgc,geojson", "--no-figures", "-o", str(out)])
    assert code == 0, capsys.readouterr().err
    from drake_auv.planning.path import PlannedPath

    path = PlannedPath.from_csv(out / "path.csv")
    d = shapely.distance(shapely.box(25, -1, 30, 40), shapely.points(path.points[:, :2]))
    assert d.min() >= 2.0 * 0.98
    # The ROI's hole is not covered: no lane sample over its interior.
    lanes = path.points[path.labels == "planar"]
    assert not shapely.contains_xy(shapely.box(6.5, 46.5, 13.5, 53.5), lanes[:, 0], lanes[:, 1]).any()
    fence = json.loads((out / "mission.plan").read_text())["geoFence"]["polygons"]
    assert len(fence) == 1 and fence[0]["inclusion"] is False


@pytest.mark.parametrize("content, message", [
    ("{not json", "not a polygon file"),
    ('{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, '
     '"geometry": {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]}}]}',
     "lies outside the grid"),
    ('{"type": "FeatureCollection", "features": [{"type": "Feature", "properties": {}, '
     '"geometry": {"type": "Point", "coordinates": [0, 0]}}]}', "needs polygons")])
def test_bad_no_go_files_give_one_line(utm_tif, tmp_path, capsys, content, message):
    bad = tmp_path / "bad.geojson"
    bad.write_text(content)
    code = main(["plan", str(utm_tif), "--no-go", str(bad), "--no-figures",
                 "-o", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0], err


def test_no_go_across_the_middle_of_a_monterey_tile(tmp_path):
    from drake_auv.scenarios import DATA_DIR

    tiles = sorted((DATA_DIR / "monterey").glob("*.tif"))
    if not tiles:
        pytest.skip("the shipped Monterey tiles are missing")
    import re

    from drake_auv.terrain.readers import read_bathymetry
    from drake_auv.terrain.zones import read_zones, zones_to_world

    lon0, lon1, lat0, lat1 = (float(v) for v in re.findall(r"-?\d+\.\d+", tiles[3].stem))
    lat = 0.5 * (lat0 + lat1)  # a 100 m-wide band (a cable corridor) across the middle, west-east
    band = [[lon0 + 0.002, lat - 0.00045], [lon1 - 0.002, lat - 0.00045],
            [lon1 - 0.002, lat + 0.00045], [lon0 + 0.002, lat + 0.00045], [lon0 + 0.002, lat - 0.00045]]
    f = tmp_path / "cable.geojson"
    f.write_text(json.dumps({"type": "Feature", "properties": {},
                             "geometry": {"type": "Polygon", "coordinates": [band]}}))
    bathy = read_bathymetry(tiles[3])
    zone = read_zones(f, bathy)
    plan = plan_coverage(bathy, CoverageParameters(omega=20.0), no_go=zone, compute_metrics=False)
    world = zones_to_world(zone, bathy)
    for path in (plan.path, plan.lawnmower):
        assert shapely.distance(world, shapely.points(path.points[:, :2])).min() >= 20.0 * 0.98
        assert path.points[:, 2].max() <= -1.0
