"""QGroundControl / ArduSub missions: read by MAVSDK's QGC importer item by item, within the
board's budget, replayed as ArduSub AUTO flies them (frames 3 and 10) and safe on the shipped
Monterey tiles and on random seabeds; the replay's semantics and the reader's errors."""

import json
import struct
import time
from pathlib import Path

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from drake_auv.autopilot.ardusub import replay_ardusub
from drake_auv.autopilot.items import LocalLeg, localise
from drake_auv.autopilot.replay import clearance_report
from drake_auv.formats.qgc import admitted_cross_track, read_qgc_plan, write_qgc
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.surface import TerrainSurface
from drake_auv.scenarios import DATA_DIR as DATA
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT, GeoFrame
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.synthetic import caldera_site, random_seabed

MONTEREY = sorted((DATA / "monterey").glob("*.tif"))


def replay_files(files, geo, surface):
    """Reads the plan files back and replays them in order, each from where the last ended;
    returns the positions and the items read."""
    pos, items, start = [], [], None
    for f in files:
        mission = read_qgc_plan(f)
        legs = localise(mission, geo.from_lonlat, geo.grid_north_azimuth)
        if start is None:
            p0 = legs[0]
            start = np.array([*p0.end, surface.elevation(*p0.end) + p0.z
                              if p0.z_mode == "altitude" else -p0.z])
        p, _ = replay_ardusub(legs, surface.elevation, start, 1.0)
        pos.append(p)
        items += mission.items
        start = p[-1]
    return np.vstack(pos), items


def check_safe(files, geo, surface, omega):
    pos, items = replay_files(files, geo, surface)
    rep = clearance_report(pos, surface, omega, 0.5)
    assert rep["closer_than_half_omega"] == 0, rep
    assert rep["shallower_than_min_depth"] == 0, rep  # nothing above 0.5 m depth
    return rep, items


# -- MAVSDK's QGroundControl importer, in process -------------------------------------------

def _x25(data: bytes) -> int:
    crc = 0xFFFF
    for b in data:
        t = b ^ (crc & 0xFF)
        t = (t ^ (t << 4)) & 0xFF
        crc = ((crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4)) & 0xFFFF
    return crc


def ardusub_heartbeat() -> bytes:
    """A MAVLink 1 HEARTBEAT from system 1: MAV_TYPE_SUBMARINE, MAV_AUTOPILOT_ARDUPILOTMEGA."""
    payload = struct.pack("<IBBBBB", 0, 12, 3, 0, 3, 3)
    header = bytes([len(payload), 0, 1, 1, 0])
    crc = _x25(header + payload + bytes([50]))  # HEARTBEAT's CRC_EXTRA
    return b"\xfe" + header + payload + struct.pack("<H", crc)


@pytest.fixture(scope="module")
def mavsdk_importer():
    """MissionRaw of an ArduSub system known to MAVSDK through one HEARTBEAT over raw://."""
    mavsdk = pytest.importorskip("mavsdk")
    from mavsdk.plugins.mission_raw.mission_raw import MissionRaw

    sdk = mavsdk.Mavsdk(mavsdk.Configuration.create_with_component_type(
        mavsdk.ComponentType.GROUND_STATION))
    sdk.add_any_connection("raw://")
    sdk.subscribe_raw_bytes_to_be_sent(lambda data: None)  # nothing is sent anywhere
    system = None
    for _ in range(20):
        sdk.pass_received_raw_bytes(ardusub_heartbeat())
        system = sdk.first_autopilot(0.2)
        if system is not None:
            break
        time.sleep(0.05)
    assert system is not None, "MAVSDK did not see the HEARTBEAT"
    yield MissionRaw(system)
    sdk.destroy()


def check_with_mavsdk(importer, filename):
    """MAVSDK imports the file item by item as written (home first, added by the importer)."""
    plan = json.loads(Path(filename).read_text())
    items = plan["mission"]["items"]
    data = importer.import_qgroundcontrol_mission(str(filename))
    got = data.mission_items
    assert len(got) == len(items) + 1
    home = plan["mission"]["plannedHomePosition"]
    assert got[0].x == round(home[0] * 1e7) and got[0].y == round(home[1] * 1e7)
    for item, g in zip(items, got[1:]):
        assert (g.command, g.frame) == (item["command"], item["frame"])
        p = item["params"]
        if item["command"] == 16:
            assert abs(g.x - p[4] * 1e7) <= 1 and abs(g.y - p[5] * 1e7) <= 1
            assert g.z == pytest.approx(p[6], abs=1e-3)
            assert g.param2 == pytest.approx(p[1])
            assert (np.isnan(g.param4) if p[3] is None else g.param4 == pytest.approx(p[3]))
        else:
            assert g.command == 178 and g.param2 == pytest.approx(p[1])
    return len(got)


# -- the caldera (bisection, splitting, fence) -------------------------------------------------

@pytest.fixture(scope="module")
def caldera_plan():
    zone = shapely.box(40.0, 100.0, 60.0, 120.0)
    return plan_coverage(caldera_site(cell=2.0), CoverageParameters(omega=4.0), no_go=zone)


def test_caldera_plan_fits_one_file_by_bisection(tmp_path, caldera_plan, mavsdk_importer):
    geo = GeoFrame(caldera_plan.bathy, CALDERA_ORIGIN_LONLAT)
    files, s = write_qgc(caldera_plan, geo, tmp_path)
    # the smallest tolerance that fits: the budget is nearly used (559 items at the admitted
    # tolerance)
    assert [f.name for f in files] == ["mission.plan"] and 650 < s["items"][0] <= 700
    admitted = admitted_cross_track(caldera_plan)
    assert s["cross_track_admitted_m"] == pytest.approx(admitted)
    assert s["tolerance_m"] < admitted
    assert check_with_mavsdk(mavsdk_importer, files[0]) == s["items"][0]
    plan = json.loads(files[0].read_text())
    items = plan["mission"]["items"]
    assert items[0]["command"] == 178 and items[0]["params"][1] == 0.5
    wps = items[1:]
    assert {(i["frame"], i["AltitudeMode"]) for i in wps} == {(10, 4), (3, 1)}
    assert plan["mission"]["globalPlanAltitudeMode"] == 0  # mixed
    for i in wps:
        assert i["Altitude"] == i["params"][6]
        assert (i["params"][6] > 0) if i["frame"] == 10 else (i["params"][6] < 0)
    # AMSLAltAboveTerrain is the waypoint's elevation: frame 10 adds the seabed below
    xy = geo.from_lonlat(np.array([[i["params"][5], i["params"][4]] for i in wps]))
    seabed = caldera_plan.surface.elevation(xy[:, 0], xy[:, 1])
    amsl = np.array([i["AMSLAltAboveTerrain"] for i in wps])
    alt = np.array([i["params"][6] for i in wps])
    terrain = np.array([i["frame"] == 10 for i in wps])
    np.testing.assert_allclose(amsl[terrain], seabed[terrain] + alt[terrain], atol=2e-3)
    np.testing.assert_allclose(amsl[~terrain], alt[~terrain], atol=1e-9)
    ring = plan["geoFence"]["polygons"][0]["polygon"]
    assert len(ring) == 4 and ring[0] != ring[-1]  # open: QGC closes the ring itself
    assert s["coverage_after"] >= s["coverage_before"] - 0.01


def test_long_missions_are_split_and_chain(tmp_path, caldera_plan, mavsdk_importer):
    geo = GeoFrame(caldera_plan.bathy, CALDERA_ORIGIN_LONLAT)
    files, s = write_qgc(caldera_plan, geo, tmp_path, max_items=40, frames="depth")
    assert len(files) >= 3 and [f.name for f in files][:2] == ["mission_1.plan", "mission_2.plan"]
    assert s["tolerance_m"] == pytest.approx(s["cross_track_admitted_m"])
    assert max(s["items"]) <= 40
    missions = [read_qgc_plan(f) for f in files]
    for a, b in zip(missions[:-1], missions[1:]):
        assert (a.items[-1].lat, a.items[-1].lon, a.items[-1].z) == (
            b.items[0].lat, b.items[0].lon, b.items[0].z)
    assert all(it.z_mode == "depth" for m in missions for it in m.items)
    assert all(json.loads(f.read_text())["mission"]["globalPlanAltitudeMode"] == 1 for f in files)
    for f, n in zip(files, s["items"]):
        assert check_with_mavsdk(mavsdk_importer, f) == n
    check_safe(files, geo, caldera_plan.surface, 4.0)


# -- the shipped Monterey tiles --------------------------------------------------------------

@pytest.fixture(scope="module")
def monterey_plans():
    return {(t, omega): plan_coverage(read_bathymetry(t), CoverageParameters(omega=omega))
            for t in MONTEREY for omega in (10.0, 20.0)}


@pytest.mark.parametrize("frames", ["terrain", "depth"])
def test_monterey_missions_fit_and_fly_safe(tmp_path, monterey_plans, frames, mavsdk_importer):
    for (tile, omega), plan in monterey_plans.items():
        out = tmp_path / f"{tile.stem[15:40]}_{omega:g}"
        out.mkdir()
        geo = GeoFrame(plan.bathy)
        files, s = write_qgc(plan, geo, out, frames=frames)
        assert max(s["items"]) <= 700 and len(files) == len(s["items"])
        for f in files:
            for i in json.loads(f.read_text())["mission"]["items"][1:]:
                assert i["AltitudeMode"] == {3: 1, 10: 4}[i["frame"]], f
        if frames == "depth":
            assert s["tolerance_m"] <= 0.05 * omega + 1e-9  # overlap 0.1 x Omega sin 30 deg
        rep, items = check_safe(files, geo, TerrainSurface(read_bathymetry(tile)), omega)
        assert rep["min_clearance_over_omega"] >= 0.5
        assert s["coverage_after"] >= s["coverage_before"] - 0.005
        assert {it.z_mode for it in items} == ({"depth"} if frames == "depth"
                                                 else {"depth", "altitude"})
    check_with_mavsdk(mavsdk_importer, files[0])


# -- random seabeds ----------------------------------------------------------------------------

@settings(max_examples=6, deadline=None, phases=[Phase.explicit, Phase.reuse, Phase.generate],
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 2 ** 31 - 1), relief=st.floats(2.0, 12.0),
       top=st.floats(0.2, 8.0), omega=st.floats(1.5, 3.0),
       frames=st.sampled_from(["terrain", "depth"]))
def test_random_seabeds_export_and_fly_safe(tmp_path_factory, seed, relief, top, omega, frames):
    """Seabeds whose top lies `top` m below the surface (some within a metre of it, where the
    plan itself holds the 1 m minimum depth nearer than Omega / 2 to the seabed): the flight
    comes no nearer than Omega / 2 or than the plan does, and never above 0.5 m depth."""
    raw = random_seabed(seed, (40, 56), 1.0, relief, 5.0)
    bathy = Bathymetry(raw.z - np.nanmax(raw.z) - top, raw.spacing)
    plan = plan_coverage(bathy, CoverageParameters(omega=omega), compute_metrics=False)
    out = tmp_path_factory.mktemp("rand")
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    files, s = write_qgc(plan, geo, out, max_items=120, frames=frames)
    assert max(s["items"]) <= 120
    prior = TerrainSurface(bathy)
    pos, _ = replay_files(files, geo, prior)
    flown = clearance_report(pos, prior, omega, 0.5)
    planned = clearance_report(plan.path.points, prior, omega, 0.5)
    assert flown["shallower_than_min_depth"] == 0
    assert flown["min_clearance_m"] >= min(0.5 * omega, planned["min_clearance_m"]) - 0.05
    if planned["closer_than_half_omega"] == 0:
        assert flown["closer_than_half_omega"] == 0


# -- the replay's semantics --------------------------------------------------------------------

def test_replay_follows_ardusub_frames():
    seabed = lambda x, y: -20.0 + 0.1 * np.asarray(x)  # noqa: E731 - rises 1 m per 10 m east
    legs = (LocalLeg("waypoint", (10.0, 0.0), "altitude", 5.0),   # frame 10 from depth 15
            LocalLeg("waypoint", (20.0, 0.0), "altitude", 3.0),
            LocalLeg("waypoint", (30.0, 0.0), "depth", 8.0))      # frame 3
    pos, item = replay_ardusub(legs, seabed, np.array([0.0, 0.0, -15.0]), 0.5)
    assert item[0] == 0 and np.all(np.diff(item) >= 0) and set(item.tolist()) == {0, 1, 2}
    on = lambda k, x: np.interp(x, pos[item == k, 0], pos[item == k, 2])  # noqa: E731
    # leg 0: the origin (z -15 over seabed -20: altitude 5) keeps altitude 5 above a rising bed
    assert on(0, 5.0) == pytest.approx(seabed(5.0, 0) + 5.0)
    # leg 1: altitude from 5 to 3, linear along the leg, added to the seabed below
    assert on(1, 15.0) == pytest.approx(seabed(15.0, 0) + 4.0, abs=1e-6)
    # leg 2: frame 3, elevation linear from the origin's (-18 + 3 = -15) to -8
    assert on(2, 25.0) == pytest.approx(-11.5)
    assert pos[-1].tolist() == pytest.approx([30.0, 0.0, -8.0])
    assert np.linalg.norm(np.diff(pos[:, :2], axis=0), axis=1).max() <= 0.5 + 1e-9
    with pytest.raises(ValueError, match="kind 'goto'"):
        replay_ardusub((LocalLeg("goto", (1.0, 0.0), "depth", 2.0),), seabed, np.zeros(3))


def test_clearance_report_counts_violations():
    surface = TerrainSurface(Bathymetry(np.full((20, 20), -10.0), (1.0, 1.0)))
    pos = np.array([[5.0, 5.0, -2.0], [5.0, 6.0, -8.5], [5.0, 7.0, -0.2]])
    rep = clearance_report(pos, surface, 4.0, 0.5)
    assert rep["closer_than_half_omega"] == 1 and rep["shallower_than_min_depth"] == 1
    assert rep["min_clearance_m"] == pytest.approx(1.5)
    assert rep["min_clearance_over_omega"] == pytest.approx(1.5 / 4.0)
    assert rep["shallowest_depth_m"] == pytest.approx(0.2)


# -- the reader's errors -----------------------------------------------------------------------

def _plan(items, firmware=3):
    return {"fileType": "Plan", "mission": {"version": 2, "firmwareType": firmware,
                                            "items": items}}


WP = {"type": "SimpleItem", "command": 16, "frame": 3,
      "params": [0, 1.0, 0, None, 36.8, -121.81, -5.0]}


@pytest.mark.parametrize("doc, match", [
    ("{not json", r"not JSON"),
    ({"fileType": "Mission"}, r"fileType"),
    (_plan([WP], firmware=12), r"firmwareType"),
    (_plan([{**WP, "frame": 0}]), r"mission item 0: frame must be 3 .* or 10"),
    (_plan([WP, {**WP, "params": [0, 1, 0, None, 95.0, 0, -5]}]), r"mission item 1: latitude"),
    (_plan([{**WP, "params": [0, 1, 0, None, 36.8, -121.81, 4.0]}]), r"below the surface"),
    (_plan([{**WP, "frame": 10, "params": [0, 1, 0, None, 36.8, -121.81, -4.0]}]),
     r"altitude above the seabed"),
    (_plan([{**WP, "command": 22}]), r"mission item 0: command 22"),
    (_plan([{**WP, "params": [0, 1]}]), r"7 values"),
    (_plan([{"type": "ComplexItem"}]), r"SimpleItem"),
    (_plan([]), r"no NAV_WAYPOINT"),
])
def test_reader_rejects_malformed_plans_in_one_line(tmp_path, doc, match):
    f = tmp_path / "bad.plan"
    f.write_text(doc if isinstance(doc, str) else json.dumps(doc))
    with pytest.raises(ValueError, match=match) as err:
        read_qgc_plan(f)
    assert str(f) in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(FileNotFoundError, match="no such"):
        read_qgc_plan(tmp_path / "missing.plan")


def test_reader_takes_speed_radius_and_frames(tmp_path):
    speed = lambda v: {"type": "SimpleItem", "command": 178, "frame": 2,  # noqa: E731
                       "params": [1, v, -1, 0, 0, 0, 0]}
    terrain = {**WP, "frame": 10, "params": [2.0, 0, 0, 90.0, 36.8, -121.81, 6.0]}
    f = tmp_path / "ok.plan"
    f.write_text(json.dumps(_plan([WP, speed(0.8), terrain, speed(-1), WP])))
    m = read_qgc_plan(f)
    assert m.autopilot == "ardusub" and [it.kind for it in m.items] == ["waypoint"] * 3
    assert [it.speed for it in m.items] == [None, 0.8, 0.8]
    assert [(it.z_mode, it.z) for it in m.items] == [("depth", 5.0), ("altitude", 6.0),
                                                     ("depth", 5.0)]
    assert [it.tolerance for it in m.items] == [1.0, 2.0, 1.0]  # 0: WPNAV_RADIUS default
    assert m.items[1].hold_s == 2.0 and m.items[1].yaw == pytest.approx(np.pi / 2)
    assert m.items[0].yaw is None
