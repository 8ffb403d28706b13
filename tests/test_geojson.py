"""The GeoJSON export: what RFC 7946 says (2D WGS 84 positions, depths and altitudes as
properties), read by GDAL through pyogrio, written to a Shapefile, validated by
geojson-validator, and faithful to the path."""

import json

import numpy as np
import pyogrio
import pytest
from scipy.spatial import cKDTree

from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.export import write_outputs
from drake_auv.planning.geo import CALDERA_ORIGIN_LONLAT, GeoFrame
from drake_auv.terrain.synthetic import caldera_site

FIELDS = ["label", "run", "seq", "heave", "depth_a", "depth_b", "alt_a", "alt_b", "length_m",
          "sens_az", "sens_dep"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    plan = plan_coverage(caldera_site(cell=2.0), omega=4.0, compute_metrics=False)
    out = tmp_path_factory.mktemp("gj")
    write_outputs(plan, out, figures=False, exports=("geojson",),
                  origin_lonlat=CALDERA_ORIGIN_LONLAT, metrics_3d=False)
    return plan, out / "path.geojson"


def test_positions_are_2d_wgs84_with_depths_as_properties(exported):
    plan, f = exported
    gj = json.loads(f.read_text())
    assert "crs" not in gj
    feats = gj["features"]
    assert len(feats) == len(plan.path) - 1
    coords = np.array([f["geometry"]["coordinates"] for f in feats])  # (M, 2, 2): no height
    assert coords.shape == (len(feats), 2, 2)
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    ends = geo.from_lonlat(coords[:, 1])
    assert np.abs(ends - plan.path.points[1:, :2]).max() < 0.1
    depth = np.array([f["properties"]["depth_b"] for f in feats])
    np.testing.assert_allclose(depth, -plan.path.points[1:, 2], atol=1e-3)
    alt = np.array([f["properties"]["alt_a"] for f in feats])
    p = plan.path.points[:-1]
    np.testing.assert_allclose(alt, p[:, 2] - plan.surface.elevation(p[:, 0], p[:, 1]),
                               atol=1e-3)
    labels = np.array([f["properties"]["label"] for f in feats])
    assert labels.tolist() == plan.path.labels[1:].astype(str).tolist()
    lanes = labels == "planar"
    assert {f["properties"]["heave"] for f, lane in zip(feats, lanes) if lane} == {"altitude"}
    assert sum(f["properties"]["length_m"] for f in feats) == pytest.approx(plan.path.length,
                                                                             rel=1e-4)


def test_gdal_reads_it_and_writes_a_shapefile(exported, tmp_path):
    plan, f = exported
    meta, _, geometry, fields = pyogrio.raw.read(f)
    assert meta["geometry_type"] == "LineString" and meta["crs"] == "EPSG:4326"
    assert list(meta["fields"]) == FIELDS and len(geometry) == len(plan.path) - 1
    assert all(len(name) <= 10 for name in meta["fields"])
    shp = tmp_path / "path.shp"
    pyogrio.raw.write(shp, geometry, fields, fields=meta["fields"], crs=meta["crs"],
                      geometry_type="LineString", driver="ESRI Shapefile")
    back, _, _, back_fields = pyogrio.raw.read(shp)
    assert list(back["fields"]) == FIELDS  # no name truncated, every value a scalar
    np.testing.assert_allclose(back_fields[FIELDS.index("depth_b")],
                               fields[FIELDS.index("depth_b")])
    assert back_fields[0].tolist() == fields[0].tolist()


def test_geojson_validator_finds_nothing(exported):
    import geojson_validator

    _, f = exported
    gj = json.loads(f.read_text())
    assert geojson_validator.validate_structure(gj, check_crs=True) == {}
    result = geojson_validator.validate_geometries(gj)
    assert result["invalid"] == {} and result["problematic"] == {}
    assert set(result["count_geometry_types"]) == {"LineString"}


def test_every_sample_is_in_the_file(exported):
    plan, f = exported
    gj = json.loads(f.read_text())
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    pts = np.vstack([np.column_stack([geo.from_lonlat(np.array(ft["geometry"]["coordinates"])),
                                      [-ft["properties"]["depth_a"], -ft["properties"]["depth_b"]]])
                     for ft in gj["features"]])
    assert cKDTree(pts).query(plan.path.points)[0].max() < 0.1
