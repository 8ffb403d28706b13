"""COLA2 missions under COLA2's semantics: the reader on written and broken files, the replay of
what a section holds (final depth or altitude from its start; heave_in_3D), and exported
missions replayed safe on the Monterey tiles and on random seabeds, where the former export (a
section per simplified waypoint, altitude mode at the minimum depth) is not."""

import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drake_auv.autopilot.cola2 import held_band, replay_cola2
from drake_auv.autopilot.items import localise
from drake_auv.autopilot.replay import clearance_report
from drake_auv.formats.cola2 import (Cola2Sections, cola2_sections, export_cola2, read_cola2,
                                     write_cola2)
from drake_auv.planning.coverage_plan import plan_coverage
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.missions import mission_waypoints
from drake_auv.scenarios import DATA_DIR
from drake_auv.terrain.geo import CALDERA_ORIGIN_LONLAT, GeoFrame
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.synthetic import caldera_site, random_seabed

MONTEREY = sorted((DATA_DIR / "monterey").glob("*.tif"))


@pytest.fixture(scope="module")
def caldera():
    plan = plan_coverage(caldera_site(cell=2.0), CoverageParameters(omega=3.0),
                         compute_metrics=False, baseline=False)
    return plan, GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)


@pytest.fixture(scope="module")
def caldera_file(caldera, tmp_path_factory):
    plan, geo = caldera
    sec = cola2_sections(plan.path, plan.surface, 3.0, plan.parameters.min_depth)
    f = tmp_path_factory.mktemp("cola2") / "mission.xml"
    write_cola2(sec, geo, f)
    return sec, f


def test_reader_returns_what_was_written(caldera, caldera_file):
    (_, geo), (sec, f) = caldera, caldera_file
    m = read_cola2(f)
    assert m.autopilot == "cola2" and m.source == str(f)
    assert [it.kind for it in m.items] == ["goto"] + ["section"] * len(sec) + ["park"]
    legs = localise(m, geo.from_lonlat, geo.grid_north_azimuth)
    ends = np.array([leg.end for leg in legs[:-1]])
    assert np.abs(ends - sec.points[:, :2]).max() < 1e-3
    assert [leg.z_mode == "altitude" for leg in legs[1:-1]] == sec.altitude_mode.tolist()
    for prev, leg, k in zip(legs[:-2], legs[1:-1], range(len(sec))):
        assert np.allclose(leg.start, prev.end, atol=1e-3)  # a section starts where one ends
        held = sec.altitude[k + 1] if leg.z_mode == "altitude" else -sec.points[k + 1, 2]
        assert np.isclose(leg.z, held, atol=1e-6)
        assert np.hypot(*np.subtract(leg.end, leg.start)) >= leg.tolerance - 1e-6
    assert {"depth", "altitude"} <= {leg.z_mode for leg in legs}  # lanes and contours


BROKEN = [  # (what is broken, substitution on the written text, words of the message)
    ("not XML", (r"</mission>\s*$", ""), ["not XML"]),
    ("root", (r"<mission>(.*)</mission>", r"<plan>\1</plan>"), ["<plan>", "<mission>"]),
    ("version", (r"<version>2.0</version>", "<version>1.0</version>"), ["version", "'1.0'"]),
    ("missing field", (r"(<mission_step>(?:(?!</mission_step>).)*?</mission_step>\s*"
                       r"<mission_step>(?:(?!</mission_step>).)*?)<final_depth>[^<]*</final_depth>",
                       r"\1"), ["mission_step 2", "final_depth", "missing"]),
    ("non-numeric", (r"(<mission_step>(?:(?!</mission_step>).)*?</mission_step>\s*"
                     r"<mission_step>(?:(?!</mission_step>).)*?<surge_velocity>)[^<]*",
                     r"\1fast"), ["mission_step 2", "surge_velocity", "'fast'"]),
    ("latitude", (r"(<mission_step>(?:(?!</mission_step>).)*?<final_latitude>)[^<]*",
                  r"\g<1>91.5"), ["mission_step 1", "final_latitude", "[-90, 90]"]),
    ("longitude", (r"(<mission_step>(?:(?!</mission_step>).)*?</mission_step>\s*"
                   r"<mission_step>(?:(?!</mission_step>).)*?<initial_longitude>)[^<]*",
                   r"\g<1>-181"), ["mission_step 2", "initial_longitude", "[-180, 180]"]),
    ("maneuver", (r'type="park"', 'type="loiter"'), ["loiter", "goto, section, park"]),
    ("heave mode", (r"<heave_mode>\d</heave_mode>", "<heave_mode>7</heave_mode>"),
     ["mission_step 1", "heave_mode", "0 (depth)"]),
]


@pytest.mark.parametrize("what,sub,words", BROKEN, ids=[b[0] for b in BROKEN])
def test_broken_files_are_one_line(caldera_file, tmp_path, what, sub, words):
    text = caldera_file[1].read_text()
    broken, n = re.subn(sub[0], sub[1], text, count=1, flags=re.S)
    assert n == 1, what
    f = tmp_path / "broken.xml"
    f.write_text(broken)
    with pytest.raises(ValueError) as err:
        read_cola2(f)
    msg = str(err.value)
    assert "\n" not in msg and str(f) in msg
    for w in words:
        assert w in msg, (what, msg)


def test_missing_file_is_one_line(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.xml: no such COLA2 mission file"):
        read_cola2(tmp_path / "nothere.xml")


def test_a_section_holds_its_final_depth_from_its_start():
    flat = lambda x, y: np.full(np.shape(x), -30.0)  # noqa: E731
    # Depth mode: the final depth (12 m) from the start; the vehicle (at -5 m) descends at
    # most heave_speed per surge speed, and may be anywhere between that and the command.
    xy, z_f, z_c = held_band((0, 0), (100, 0), False, -12.0, -5.0, flat, start_z=-5.0,
                             speed=0.5, heave_speed=0.1)
    assert np.allclose(z_c, -12.0)
    assert np.isclose(np.interp(10.0, xy[:, 0], z_f), -7.0) and np.allclose(z_f[xy[:, 0] > 35], -12)
    # heave_in_3D: the depth is interpolated along the section.
    xy, z_f, z_c = held_band((0, 0), (100, 0), False, -12.0, -5.0, flat, start_z=-5.0,
                             heave_in_3d=True, speed=0.5, heave_speed=0.1)
    assert np.allclose(z_c, -5.0 - 7.0 * xy[:, 0] / 100) and np.allclose(z_f, z_c)
    # Altitude mode follows the seabed, heave_in_3D or not.
    ramp = lambda x, y: -30.0 + 0.1 * np.asarray(x)  # noqa: E731
    xy, z_f, z_c = held_band((0, 0), (100, 0), True, 4.0, -26.0, ramp, heave_in_3d=True)
    assert np.allclose(z_c, ramp(xy[:, 0], 0) + 4.0) and np.allclose(z_f, z_c)


def test_replay_flies_goto_sections_and_park():
    from drake_auv.autopilot.items import LocalLeg

    flat = lambda x, y: np.full(np.shape(x), -30.0)  # noqa: E731
    legs = (LocalLeg("goto", (0.0, 0.0), "depth", 10.0),
            LocalLeg("section", (50.0, 0.0), "depth", 20.0, start=(0.0, 0.0), start_z=-10.0),
            LocalLeg("section", (50.0, 50.0), "altitude", 5.0, start=(50.0, 0.0),
                     start_z=-20.0),
            LocalLeg("park", (50.0, 50.0), "altitude", 5.0, hold_s=10.0))
    pos, owner = replay_cola2(legs, flat, (0.0, 0.0, -10.0))
    assert owner.tolist() == sorted(owner.tolist()) and set(owner.tolist()) == {0, 1, 2, 3}
    sec = pos[owner == 1]
    assert np.isclose(sec[:, 2].min(), -20.0) and np.isclose(sec[:, 2].max(), -10.0)
    assert np.allclose(pos[owner == 3][-1], (50, 50, -25))
    rep = clearance_report(np.array([[0.0, 0.0, -29.0], [0.0, 0.0, -0.5]]),
                           _FlatSurface(-30.0), omega=4.0,
                           min_depth=1.0)
    assert rep["closer_than_half_omega"] == 1 and rep["shallower_than_min_depth"] == 1
    assert np.isclose(rep["min_clearance_m"], 1.0) and np.isclose(rep["shallowest_depth_m"], 0.5)


class _FlatSurface:
    """A horizontal seabed at `z0` with `TerrainSurface`'s distance queries (signed: below it
    negative)."""

    def __init__(self, z0):
        self.z0 = z0

    def distance(self, points, upper_bound=np.inf):
        d = np.asarray(points, float)[:, 2] - self.z0
        return np.where(d <= upper_bound, d, np.inf), None

    def signed_distance(self, points, upper_bound=np.inf):
        return self.distance(points, upper_bound)[0]


def replay_file(f, plan, geo, start, heave_in_3d=False):
    legs = localise(read_cola2(f), geo.from_lonlat, geo.grid_north_azimuth)
    pos, _ = replay_cola2(legs, plan.surface.elevation, start, heave_in_3d=heave_in_3d)
    return legs, clearance_report(pos, plan.surface, plan.parameters.omega,
                                  plan.parameters.min_depth)


@pytest.fixture(scope="module")
def monterey_plans():
    cache = {}

    def get(tile, omega):
        if (tile, omega) not in cache:
            cache[tile, omega] = plan_coverage(read_bathymetry(tile),
                                               CoverageParameters(omega=omega),
                                               compute_metrics=False, baseline=False)
        return cache[tile, omega]
    return get


@pytest.mark.parametrize("heave_in_3d", [False, True], ids=["final-depth", "heave-in-3d"])
@pytest.mark.parametrize("omega", [10.0, 20.0])
@pytest.mark.parametrize("tile", MONTEREY, ids=lambda p: p.name[12:40])
def test_monterey_missions_replay_safe(monterey_plans, tmp_path, tile, omega, heave_in_3d):
    plan = monterey_plans(tile, omega)
    geo = GeoFrame(plan.bathy)
    f = tmp_path / "mission.xml"
    out = export_cola2(plan.path, plan.surface, omega, plan.parameters.min_depth, geo, f,
                       heave_in_3d=heave_in_3d)
    rep = out["replay"]  # the written file, read back and replayed
    assert rep["closer_than_half_omega"] == 0 and rep["min_clearance_over_omega"] >= 0.5
    assert rep["shallower_than_min_depth"] == 0 and rep["shallowest_depth_m"] >= 0.5
    assert out["unresolved_sections"] == 0
    sections = [it for it in localise(read_cola2(f), geo.from_lonlat) if it.kind == "section"]
    assert len(sections) == out["sections"]
    assert all(np.hypot(*np.subtract(s.end, s.start)) >= s.tolerance - 1e-6 for s in sections)
    # Far fewer sections than the former one per simplified waypoint.
    assert out["sections"] < 0.8 * len(mission_waypoints(plan.path, plan.surface))


def waypoint_sections(plan) -> Cola2Sections:
    """The former export: one section per Douglas-Peucker waypoint (0.05 m), altitude mode on
    lanes even where the minimum depth holds them."""
    wp = mission_waypoints(plan.path, plan.surface)
    k = len(wp) - 1
    return Cola2Sections(wp.points, wp.index, wp.use_altitude[1:], wp.altitude, wp.heading,
                         np.zeros(k))


def test_the_former_waypoint_export_fails_the_replay(monterey_plans, tmp_path):
    plan = monterey_plans(MONTEREY[0], 20.0)  # the seabed rises to -13 m: the ceiling holds
    geo = GeoFrame(plan.bathy)
    f = tmp_path / "old.xml"
    write_cola2(waypoint_sections(plan), geo, f)
    _, rep = replay_file(f, plan, geo, plan.path.points[0])
    assert rep["shallower_than_min_depth"] > 0 and rep["shallowest_depth_m"] < 0.5
    assert rep["closer_than_half_omega"] > 0


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(seed=st.integers(0, 10_000), top=st.floats(-3.0, -0.2), omega=st.floats(1.5, 3.0),
       heave_in_3d=st.booleans())
def test_random_seabeds_replay_safe(tmp_path, seed, top, omega, heave_in_3d):
    # A seabed of 8 m relief whose shallowest point lies `top` below the surface: within a
    # metre of it, the minimum depth (1 m) holds the path and cells above it are no-go.
    base = random_seabed(seed, shape=(40, 50), relief=8.0, smoothness=5.0)
    plan = plan_coverage(base.with_z(base.z - np.nanmax(base.z) + top),
                         CoverageParameters(omega=omega), compute_metrics=False, baseline=False)
    geo = GeoFrame(plan.bathy, CALDERA_ORIGIN_LONLAT)
    out = export_cola2(plan.path, plan.surface, omega, 1.0, geo, tmp_path / "m.xml",
                       heave_in_3d=heave_in_3d)
    rep = out["replay"]
    # 0.5 Omega wherever the minimum depth leaves it, else the minimum depth itself.
    assert rep["closer_than_reachable"] == 0 and rep["shallower_than_min_depth"] == 0
    assert out["unresolved_sections"] == 0
