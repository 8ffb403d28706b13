"""Numbers in and out: `1.0e9` in a mission's YAML is a number, infinite cells of a GeoTIFF are
refused as `Bathymetry` refuses them, and no written report holds NaN or Infinity."""

import json
import math

import numpy as np
import pytest
import yaml

from drake_auv.cli import main
from drake_auv.mission.config import load_mission
from drake_auv.mission.yaml_text import load_yaml
from drake_auv.output_files import json_ready, write_json
from drake_auv.planning import export
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
    with pytest.raises(ValueError, match="infinite value"):
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
    report_dict = export.report_dict

    def with_nan(plan, m3d):
        return {**report_dict(plan, m3d), "undefined": math.nan}

    monkeypatch.setattr(export, "report_dict", with_nan)
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
