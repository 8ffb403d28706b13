"""A payload sensor added by configuration alone: a second, starboard-looking multibeam set with
`--set payload.sensors...` reaches the map, the point cloud, the MCAP log and the report; the
sensor table's checks."""

import json

import numpy as np
import pytest

from drake_auv.cli import main
from drake_auv.mission.config import (MissionFileError, load_mission, mission_from_dict,
                                      mission_to_dict)
from drake_auv.reconstruction.pointcloud import read_ply
from drake_auv.rosio.reader import DEFAULT_TOPICS, open_log
from drake_auv.sonar.sensor import BUILT_IN, stream_of

EXTRA = "starboard_multibeam"
SETTINGS = [f"payload.sensors.{EXTRA}.kind=multibeam",
            f"payload.sensors.{EXTRA}.mount=starboard",
            f"payload.sensors.{EXTRA}.num_beams=120"]


def test_a_second_multibeam_by_configuration_reaches_the_map_and_the_report(tmp_path):
    out = tmp_path / "run"
    argv = ["run", "pool", "-o", str(out), "--set", "limits.max_time_s=40", "--no-html",
            "--no-reconstruction", "--quiet", "--mcap"]
    for item in SETTINGS:
        argv += ["--set", item]
    assert main(argv) == 0
    cloud = read_ply(out / "points.ply")
    # the configured sensor comes after the built-in sources, whose indices are unchanged
    assert cloud.source_names == (*BUILT_IN, EXTRA)
    counts = np.bincount(cloud.sources, minlength=len(cloud.source_names))
    assert counts[BUILT_IN.index("multibeam")] > 0 and counts[cloud.source_names.index(EXTRA)] > 0
    # the port multibeam and the starboard one see different walls of the pool
    port = cloud.points[cloud.sources == 0] - cloud.origins[cloud.sources == 0]
    starboard = cloud.points[cloud.sources == 3] - cloud.origins[cloud.sources == 3]
    assert not np.allclose(port.mean(axis=0), starboard.mean(axis=0), atol=0.5)
    report = json.loads((out / "report.json").read_text())
    assert report["config"]["payload"]["sensors"][EXTRA]["mount"] == "starboard"
    assert report["map"]["returns"] == len(cloud)
    # the MCAP log carries its clouds in its own frame: read back as a log's multibeam
    index = open_log(out / "dive.mcap", dict(DEFAULT_TOPICS, multibeam=f"/sonar/{EXTRA}/points"),
                     {"multibeam"})
    assert index.sources["multibeam"]["count"] > 100


def test_the_sensor_table_reads_back_and_is_checked():
    spec = load_mission("pool", overrides=SETTINGS)
    sensor, = spec.payload.sensors
    assert (sensor.name, sensor.kind, sensor.mount, sensor.num_beams) == (
        EXTRA, "multibeam", "starboard", 120)
    raw = mission_to_dict(spec)
    assert mission_from_dict(raw, ".", "pool") == spec
    assert "sensors" not in mission_to_dict(load_mission("pool"))["payload"]  # none: no key
    with pytest.raises(MissionFileError, match="payload.sensors.profiler: is not a sensor"):
        load_mission("pool", overrides=["payload.sensors.profiler.kind=profiler"])
    with pytest.raises(MissionFileError, match=f"payload.sensors.{EXTRA}.mount"):
        load_mission("pool", overrides=[f"payload.sensors.{EXTRA}.mount=aft"])
    with pytest.raises(MissionFileError, match=f"payload.sensors.{EXTRA}.range"):
        load_mission("pool", overrides=[f"payload.sensors.{EXTRA}.range=3"])


def test_sensor_streams_keep_the_built_in_ones():
    assert [stream_of(name) for name in BUILT_IN] == [(name,) for name in BUILT_IN]
    assert stream_of(EXTRA)[0] == "sensors" and stream_of(EXTRA) == stream_of(EXTRA)
    assert stream_of(EXTRA) != stream_of("port_multibeam")


def test_the_sonars_and_the_dvl_are_sensors():
    import trimesh

    from drake_auv.geometry.raycast import RayCaster
    from drake_auv.sonar.altimeter import DvlAltimeter, DvlParams
    from drake_auv.sonar.beams import MOUNT_ROTATIONS
    from drake_auv.sonar.multibeam import MultibeamSonar
    from drake_auv.sonar.profiler import PencilBeamProfiler
    from drake_auv.sonar.sensor import Sensor

    caster = RayCaster(trimesh.creation.box((10.0, 10.0, 1.0)))
    multibeam = MultibeamSonar(caster, mount="starboard", rate=5.0, max_range=12.0,
                               stream=stream_of(EXTRA))
    dvl = DvlAltimeter(caster, DvlParams(rate=4.0, max_range=30.0))
    for sensor, period, max_range in ((multibeam, 0.2, 12.0), (dvl, 0.25, 30.0),
                                      (PencilBeamProfiler(caster), 0.1, 20.0)):
        assert isinstance(sensor, Sensor)
        assert (sensor.period, sensor.max_range) == (period, max_range)
    assert np.array_equal(multibeam.mount.rotation, MOUNT_ROTATIONS["starboard"])
    assert np.array_equal(dvl.mount.rotation, np.eye(3))
