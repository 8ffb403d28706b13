"""Meshcat scene: layers, the vehicle visualiser, and the recorded standalone HTML."""

import base64
import re

import numpy as np
import pytest
import trimesh
from pydrake.systems.analysis import Simulator

from drake_auv.vehicle.diagram import build_tracking_diagram
from drake_auv.planning import PlannedPath
from drake_auv.terrain.synthetic import random_seabed
from drake_auv.visualization import Scene


@pytest.fixture(scope="module")
def scene():
    return Scene()


def embedded_commands(html: str) -> list[bytes]:
    """The msgpack-encoded Meshcat commands a StaticHtml file replays on load."""
    return [base64.b64decode(b64) for b64 in
            re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html)]


def test_recorded_html_holds_the_animation(scene, tmp_path):
    bathy = random_seabed(seed=1, shape=(30, 40), relief=3.0)
    scene.add_terrain(bathy)
    path = PlannedPath(np.array([[2.0, 2.0, -40.0], [22.0, 2.0, -40.0], [22.0, 6.0, -40.0]]), 0.0,
                (0.0, 0.0, -1.0))
    scene.add_path("path", path)
    diagram, handles = build_tracking_diagram(path, scene=scene)
    assert handles.visualizer.get_name() == "vehicle_visualizer"
    scene.start_recording(playback_speed=10.0, frames_per_second=32.0)
    simulator = Simulator(diagram)
    simulator.AdvanceTo(handles.end_time)
    html_file = scene.write_html(tmp_path / "mission.html")
    assert not scene.recording
    html = html_file.read_text()
    assert html.lstrip().lower().startswith("<!doctype html") or "<html" in html[:200].lower()
    commands = embedded_commands(html)
    animations = [c for c in commands if b"set_animation" in c]
    assert len(animations) == 1
    animation = animations[0]
    assert b"/drake_auv/vehicle" in animation
    # 48 s simulated at 10x and 32 frames/s: about 154 frames for each of the vehicle's
    # position and quaternion tracks, plus the trail pieces' visibility keys.
    frames = handles.end_time / 10.0 * 32.0
    assert animation.count(b"time") >= 2 * 0.9 * frames
    assert animation.count(b"visible") >= 2
    objects = b"".join(c for c in commands if b"set_object" in c)
    assert b"/drake_auv/terrain" in objects and b"/drake_auv/path" in objects
    assert b"/drake_auv/vehicle/hull_lower" in objects
    assert b"/drake_auv/vehicle_trail/0" in objects


def test_scene_rejects_bad_input(scene):
    with pytest.raises(ValueError, match="empty"):
        scene.add_mesh("nothing", trimesh.Trimesh())
    with pytest.raises(ValueError, match="points"):
        scene.add_path("bad", np.zeros((1, 3)))
    with pytest.raises(ValueError, match="rgba"):
        scene.add_path("red", np.zeros((2, 3)), rgba=(2.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="playback_speed"):
        scene.start_recording(playback_speed=0.0)


def test_frame_camera_looks_at_the_drawn_box():
    scene = Scene()
    with pytest.raises(ValueError, match="nothing drawn"):
        scene.frame_camera()
    scene.add_path("diagonal", np.array([[0.0, 0.0, -30.0], [40.0, 20.0, -20.0]]))
    camera, target = scene.frame_camera(direction=(0.0, -1.0, 1.0))
    np.testing.assert_allclose(target, [20.0, 10.0, -25.0])
    view = camera - target
    assert view[0] == pytest.approx(0.0) and view[1] == pytest.approx(-view[2])
    # The box's bounding sphere (radius 21.2 m) fits the 75 degree view.
    assert np.linalg.norm(view) > 21.2 / np.sin(np.radians(37.5))
    with pytest.raises(ValueError, match="direction"):
        scene.frame_camera(direction=(0.0, 0.0, 0.0))


def animation_tracks(html: str) -> dict:
    """{(path, track name): [(frame, value)]} of a StaticHtml file's animation (msgpack, which
    dask's distributed brings)."""
    import msgpack

    tracks = {}
    for command in embedded_commands(html):
        try:
            message = msgpack.unpackb(command, strict_map_key=False)
        except (ValueError, msgpack.ExtraData):
            continue  # an embedded asset (an image, a script), not a command
        if isinstance(message, dict) and message.get("type") == "set_animation":
            for animation in message["animations"]:
                for track in animation["clip"]["tracks"]:
                    tracks[(animation["path"], track["name"])] = [
                        (key["time"], key["value"]) for key in track["keys"]]
    return tracks


def test_current_arrow_follows_the_water(tmp_path):
    from pydrake.common.eigen_geometry import Quaternion
    from pydrake.math import RotationMatrix

    from drake_auv.visualization.current import ARROW_M_PER_MPS, CurrentVisualizer

    scene = Scene()
    arrow = CurrentVisualizer(scene, period=0.5)
    context = arrow.CreateDefaultContext()
    arrow.state_input.FixValue(context, np.r_[1.0, 2.0, -30.0, np.zeros(9)])
    scene.start_recording(playback_speed=1.0, frames_per_second=10.0)
    water = np.array([0.12, -0.05, 0.02])
    for t, velocity in ((1.0, water), (2.0, np.zeros(3))):  # then still water
        context.SetTime(t)
        arrow.water_input.FixValue(context, np.r_[velocity, np.zeros(3)])
        arrow.ForcedPublish(context)
    tracks = animation_tracks(scene.write_html(tmp_path / "current.html").read_text())
    path = "/drake_auv/current/arrow"  # under the layer a user toggles
    assert tracks[(path, ".visible")] == [(10, True), (20, False)]
    (frame, position), = tracks[(path, ".position")]
    assert frame == 10
    np.testing.assert_allclose(position, [1.0, 2.0, -29.0])  # 1 m above the vehicle
    (_, scale), = tracks[(path, ".scale")]
    np.testing.assert_allclose(scale, [ARROW_M_PER_MPS * np.linalg.norm(water)] * 3)
    (_, (x, y, z, w)), = tracks[(path, ".quaternion")]
    axis = RotationMatrix(Quaternion(w, x, y, z)).matrix()[:, 2]  # the arrow's +z
    np.testing.assert_allclose(axis, water / np.linalg.norm(water), atol=1e-9)
    assert "current" in scene.legend


def test_the_page_names_the_layers_drawn_and_hides_the_hidden(tmp_path):
    from drake_auv.visualization.legend import CLOCK_ID, LEGEND_ID, LegendEntry

    scene = Scene()
    scene.add_path("route", np.array([[0.0, 0.0, -30.0], [40.0, 20.0, -20.0]]))
    for name in ("route", "never_drawn"):
        scene.add_legend(LegendEntry(name, "orange line", f"the {name}", "rgb(255,140,0)",
                                     scene.path_of(name)))
    scene.hide("route")
    html = scene.write_html(tmp_path / "still.html").read_text()
    legend = html[html.index(f'id="{LEGEND_ID}"'):]
    assert 'data-layer="/drake_auv/route"' in legend and "never_drawn" not in legend
    assert f'id="{CLOCK_ID}"' not in html  # no recording, no clock
    hidden = [c for c in embedded_commands(html) if b"set_property" in c and b"visible" in c]
    assert len(hidden) == 1 and b"/drake_auv/route" in hidden[0] and b"\xc2" in hidden[0]
