"""`drake-auv plan`: outputs on a small GeoTIFF, and clear errors."""

import json

import numpy as np
import pytest

from drake_auv.cli import main
from drake_auv.planning.path import Path
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import write_geotiff


@pytest.fixture()
def small_tif(tmp_path):
    yy, xx = np.mgrid[0:60, 0:50] * 1.0
    z = -40.0 + 0.05 * yy + np.clip(xx - 20.0, 0.0, 12.0) * 0.9  # a wall of slope 0.9
    path = tmp_path / "small.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (1000.0, 2000.0), "EPSG:32631"), path)
    return path


def test_plan_writes_every_output(tmp_path, small_tif, capsys):
    out = tmp_path / "out"
    code = main(["plan", str(small_tif), "--omega", "2", "--aperture", "60",
                 "--roi", "1000,2000,1049,2059", "-o", str(out)])
    assert code == 0
    for name in ("path.csv", "path.geojson", "lawnmower.geojson", "report.md", "report.json",
                 "slope.png", "classification.png", "cells.png", "lanes.png", "contours.png",
                 "path3d.png", "lawnmower.png"):
        assert (out / name).stat().st_size > 0, name
    path = Path.from_csv(out / "path.csv")
    assert {"planar", "slice"} <= set(path.labels)
    report = json.loads((out / "report.json").read_text())
    assert report["classification"]["high_slope_regions"] == 1
    assert report["metrics"]["total"]["coverage"] >= 0.95
    gj = json.loads((out / "path.geojson").read_text())
    coords = np.vstack([f["geometry"]["coordinates"] for f in gj["features"]])
    assert coords.shape[1] == 2 and "crs" not in gj  # RFC 7946 positions: lon, lat
    # WGS 84 longitude/latitude of the file's map coordinates (EPSG:32631).
    from pyproj import Transformer

    e, n = Transformer.from_crs("EPSG:4326", "EPSG:32631", always_xy=True).transform(
        coords[:, 0], coords[:, 1])
    assert e.min() >= 999.5 and e.max() <= 1049.5
    assert n.min() >= 1999.5 and n.max() <= 2059.5
    assert "Standard lawnmower path" in capsys.readouterr().out


@pytest.mark.parametrize("extra, message", [
    (["--omega", "0"], "omega"), (["--aperture", "190"], "aperture_deg"),
    (["--slope-threshold", "-1"], "slope_threshold"), (["--roi", "0,0,10,10"], "outside the grid")])
def test_plan_reports_bad_input(tmp_path, small_tif, capsys, extra, message):
    code = main(["plan", str(small_tif), "--no-figures", "-o", str(tmp_path / "o"), *extra])
    assert code == 2
    assert message in capsys.readouterr().err


def test_plan_missing_file(tmp_path, capsys):
    assert main(["plan", str(tmp_path / "missing.tif"), "-o", str(tmp_path)]) == 2
    assert "not found" in capsys.readouterr().err


def _npz(tmp_path, name, z):
    path = tmp_path / name
    np.savez(path, z=z, spacing=[1.0, 1.0])
    return path


@pytest.mark.parametrize("case, extra, message", [
    ("dry", [], "minimum operating depth"), ("inf", [], "infinite"),
    ("ok", ["--omega", "1e9"], "omega (offset to the terrain) must be in (0, "),
    ("ok", ["--min-depth", "-1"], "min_depth"),
    ("ok", ["--origin-lonlat", "north"], "--origin-lonlat")])
def test_bad_grids_and_values_give_one_line(tmp_path, capsys, case, extra, message):
    x = np.arange(40.0)[None, :] * np.ones((30, 1))
    z = {"dry": 5.0 + 0.1 * x, "inf": np.where(x == 7, np.inf, -20.0 + 0.1 * x),
         "ok": -20.0 + 0.1 * x}[case]
    code = main(["plan", str(_npz(tmp_path, f"{case}.npz", z)), "--no-figures",
                 "-o", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0], err
    assert "Traceback" not in err[0]
