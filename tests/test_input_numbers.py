"""Numbers in and out: `1.0e9` in a mission's YAML is a number, infinite cells of a GeoTIFF are
refused as `Bathymetry` refuses them, and no written report holds NaN or Infinity."""

import json
import math

import numpy as np
import pytest
import yaml

from drake_auv.cli import main
from drake_auv.formats import outputs
from drake_auv.mission.config import load_mission
from drake_auv.mission.yaml_text import load_yaml
from drake_auv.output_files import json_ready, write_json
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import read_bathymetry, write_geotiff

MISSION = dict(name="m", seed=0, site=dict(scenario="boulder"),
               steps=[dict(plan=dict(omega=6.0))])


@pytest.mark.parametrize("text, value", [
    ("1.0e9", 1.0e9), ("1e9", 1.0e9), ("-2.5E-3", -2.5e-3), (".5e3", 500.0),
    ("1.0e+9", 1.0e9), ("12", 12), ("1.5", 1.5), ("1e", "1e"), ("e9", "e9"), ("1.0e9x", "1.0e9x")])
def test_exponent_numbers_read_as_yaml_1_2_reads_them(text, value):
    read = load_yaml(f"k: {text}")["k"]
    assert read == value and type(read) is type(value)


def test_a_mission_key_written_1_0e9_is_a_number(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(yaml.safe_dump(MISSION) + "limits: {max_time_s: 1.0e9}\n")
    assert load_mission(path).limits.max_time_s == 1.0e9
    assert load_mission("boulder", overrides=["limits.max_time_s=2e4"]).limits.max_time_s == 2e4


@pytest.mark.parametrize("bad", [np.inf, -np.inf])
def test_infinite_geotiff_cells_are_refused_like_bathymetry_refuses_them(tmp_path, bad):
    import rasterio

    z = -20.0 - 0.1 * np.arange(40.0)[None, :] * np.ones((30, 1))
    path = tmp_path / "grid.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (0.0, 0.0), "EPSG:32631"), path)
    with rasterio.open(path, "r+") as ds:
        data = ds.read(1)
        data[4, 7] = bad
        ds.write(data, 1)
    with pytest.raises(ValueError, match=r"1 infinite cell\(s\) .* at row 4, column 7"):
        read_bathymetry(path)
    with pytest.raises(ValueError, match="infinite cell"):
        Bathymetry(np.where(z < -22.0, bad, z), (1.0, 1.0), (0.0, 0.0))


def _strict(text):
    def refuse(constant):
        raise AssertionError(f"{constant} in the JSON")
    return json.loads(text, parse_constant=refuse)


def test_json_holds_null_with_the_reason_never_nan_or_infinity(tmp_path):
    value = {"a": math.nan, "b": [1.0, math.inf, np.float32(2.0), -math.inf], "c": {"d": np.nan},
             "e": np.array([1.0, 2.0]), "f": "text", "g": None, "h": 3}
    write_json(tmp_path / "r.json", value)
    read = _strict((tmp_path / "r.json").read_text())
    assert read == {"a": None, "a_null_reason": "NaN",
                    "b": [1.0, None, 2.0, None],
                    "b_null_reason": "2 of 4 entries not finite (+Infinity, -Infinity)",
                    "c": {"d": None, "d_null_reason": "NaN"}, "e": [1.0, 2.0], "f": "text",
                    "g": None, "h": 3}
    assert json_ready({"x": 1.0}) == {"x": 1.0}


def test_plans_report_json_is_strict(tmp_path, monkeypatch):
    report_dict = outputs.report_dict

    def with_nan(plan, m3d, *args):
        return {**report_dict(plan, m3d, *args), "undefined": math.nan}

    monkeypatch.setattr(outputs, "report_dict", with_nan)
    z = -20.0 - 0.2 * np.clip(np.arange(30.0)[None, :] - 10.0, 0.0, 8.0) * np.ones((25, 1))
    grid = tmp_path / "g.npz"
    np.savez(grid, z=z, spacing=[1.0, 1.0])
    assert main(["plan", str(grid), "--no-figures", "--no-3d-metrics", "--omega", "3",
                 "-o", str(tmp_path / "o")]) == 0
    report = _strict((tmp_path / "o" / "report.json").read_text())
    assert report["undefined"] is None and report["undefined_null_reason"] == "NaN"


@pytest.mark.parametrize("text, message", [
    ("a: &a [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"{b}: &{b} [{', '.join([f'*{a}'] * 10)}]\n" for a, b in zip("abcdefgh", "bcdefghi")),
     "expands to more than 100000 values"),
    ("a: &a [1, *a]\n", "expands to more than 100000 values"),
    ("k: '" + "x" * (1 << 20) + "'\n", "more than 1048576")])
def test_yaml_bombs_are_refused_at_once_in_one_line(tmp_path, text, message):
    import time

    from drake_auv.mission.config import MissionFileError

    path = tmp_path / "bomb.yaml"
    path.write_text(text)
    start = time.perf_counter()
    with pytest.raises(MissionFileError, match=message) as info:
        load_mission(path)
    assert time.perf_counter() - start < 1.0 and len(str(info.value)) < 300
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("extra, message", [  # more: tests/test_hostile_inputs.py
    (["--export", "cola2"], "the grid has no CRS")])
def test_export_options_are_refused_before_planning(tmp_path, capsys, monkeypatch, extra,
                                                    message):
    from drake_auv.planning import coverage_plan

    def never(*args, **kwargs):
        raise AssertionError("planned before the options were checked")

    monkeypatch.setattr(coverage_plan, "plan_coverage", never)
    grid = tmp_path / "g.npz"
    np.savez(grid, z=-20.0 - 0.1 * np.arange(30.0)[None, :] * np.ones((25, 1)),
             spacing=[1.0, 1.0])
    assert main(["plan", str(grid), "-o", str(tmp_path / "o"), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not (tmp_path / "o" / "path.csv").exists()


def test_a_raster_larger_than_the_memory_is_refused_before_it_is_read(tmp_path, monkeypatch):
    from drake_auv import resources

    z = -20.0 - 0.1 * np.arange(40.0)[None, :] * np.ones((30, 1))
    path = tmp_path / "grid.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (0.0, 0.0), "EPSG:32631"), path)
    assert read_bathymetry(path).shape == (30, 40)
    monkeypatch.setattr(resources, "available_memory", lambda: 1000)
    with pytest.raises(ValueError, match=r"reading its 30 x 40 cells needs 0\.0286 MiB of memory, "
                                         r"more than the 0\.000954 MiB available"):
        read_bathymetry(path)


def test_an_explore_region_larger_than_the_memory_is_refused_at_load():
    from drake_auv.exploration.planner import ExploreParameters

    assert ExploreParameters(region=(-13.0, -11.0, -40.5, 16.0, 11.0, -26.0)).cell_m == 1.0
    with pytest.raises(ValueError, match=r"\(1e\+18 planning cells\) needs .* GiB of memory, "
                                         "more than the"):
        ExploreParameters(region=(0.0, 0.0, -1e6, 1e6, 1e6, -5.0))


def test_a_hold_longer_than_an_hour_in_a_flown_file_is_refused_naming_the_item(tmp_path):
    import re

    from drake_auv.formats.cola2 import read_cola2
    from drake_auv.formats.qgc import read_qgc_plan

    yy, xx = np.mgrid[0:40, 0:30] * 1.0
    tif = tmp_path / "small.tif"
    write_geotiff(Bathymetry(-40.0 + 0.05 * yy + np.clip(xx - 12.0, 0.0, 8.0) * 0.9, (1.0, 1.0),
                             (1000.0, 2000.0), "EPSG:32631"), tif)
    out = tmp_path / "o"
    assert main(["plan", str(tif), "--omega", "2", "--no-figures", "--no-3d-metrics",
                 "--export", "cola2,qgc", "-o", str(out)]) == 0
    assert read_qgc_plan(out / "mission.plan").items and read_cola2(out / "mission.xml").items
    plan = json.loads((out / "mission.plan").read_text())
    waypoint = next(i for i in plan["mission"]["items"] if i["command"] == 16)
    waypoint["params"][0] = 1.0e9
    (out / "mission.plan").write_text(json.dumps(plan))
    with pytest.raises(ValueError, match=r"hold \(param 1, s\) must be a number in \[0, 3600"):
        read_qgc_plan(out / "mission.plan")
    xml = (out / "mission.xml").read_text()
    (out / "mission.xml").write_text(re.sub(r"<time>[^<]*</time>", "<time>1e9</time>", xml))
    with pytest.raises(ValueError, match=r"park field 'time' must be in \[0, 3600\] s"):
        read_cola2(out / "mission.xml")


def test_the_plan_commands_table_reads_back_a_null_figure(tmp_path, capsys):
    from drake_auv.planning.metrics import PlanMetrics

    z = -20.0 * np.ones((25, 30))  # flat: no high-slope samples, NaN viewing angles there
    grid = tmp_path / "flat.npz"
    np.savez(grid, z=z, spacing=[1.0, 1.0])
    assert main(["plan", str(grid), "--no-figures", "--no-3d-metrics", "--omega", "3",
                 "-o", str(tmp_path / "o")]) == 0
    record = _strict((tmp_path / "o" / "report.json").read_text())["metrics"]
    assert record["high_slope"]["view_mean_deg"] is None
    metrics = PlanMetrics.from_dict(record)
    assert math.isnan(metrics.high_slope.view_mean_deg)
    assert metrics.total.length == record["total"]["length"]
    assert "| Total (both regions) |" in capsys.readouterr().out
