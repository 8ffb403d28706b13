"""Meshcat scene for drake_auv: terrain and world meshes, paths, the vehicle and its trail.

A `Scene` owns one `Meshcat` (on localhost only) and draws everything under `/drake_auv/<name>`.
Other modules add their own layers (sonar beams, octree, coverage) through `scene.meshcat` and
`scene.path_of(name)`. The vehicle is posed from a `state` port by `VehicleVisualizer`, a
LeafSystem that publishes periodically; with `start_recording` every pose (and each completed
piece of the trail, by its visibility) is also keyframed, and `write_html` saves the whole
animation as one standalone HTML file, with the camera framed on the scene, the legend of its
layers (`add_legend`, `visualization.legend`) and, with a recording, the mission clock.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
from pydrake.geometry import Box, Capsule, Meshcat, MeshcatParams, Rgba
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.systems.framework import LeafSystem

from drake_auv.output_files import write_text
from drake_auv.planning.path import PlannedPath
from drake_auv.signals import VehicleState
from drake_auv.visualization.legend import LegendEntry, css_colour, overlay_html, with_overlay

# GIRONA 500 envelope: 1.5 m long, 1.0 m wide, 1.0 m high, two buoyant upper hulls and one
# lower hull (Ribas et al. 2012); hull radius and spacing picked to match that envelope.
_HULL_RADIUS = 0.15
_HULL_LENGTH = 1.5 - 2 * _HULL_RADIUS  # cylinder part of the capsule
_HULLS = (("hull_port", (0.0, 0.3, 0.2), Rgba(0.95, 0.75, 0.1, 1.0)),
          ("hull_starboard", (0.0, -0.3, 0.2), Rgba(0.95, 0.75, 0.1, 1.0)),
          ("hull_lower", (0.0, 0.0, -0.3), Rgba(0.35, 0.35, 0.4, 1.0)))
_TRAIL_RGBA = Rgba(0.1, 0.6, 1.0, 1.0)
PATH_RGBA = (1.0, 0.55, 0.0, 1.0)  # `add_path`'s default
_CAMERA = "/Cameras/default/rotated/<object>"
_FOV_DEG = 75.0  # vertical field of view of Meshcat's default perspective camera


def _rgba(value) -> Rgba:
    if isinstance(value, Rgba):
        return value
    value = tuple(float(c) for c in value)
    if len(value) not in (3, 4) or not all(0.0 <= c <= 1.0 for c in value):
        raise ValueError(f"rgba must be 3 or 4 numbers in [0, 1], got {value}")
    return Rgba(*value) if len(value) == 4 else Rgba(*value, 1.0)


def _local_meshcat(live: bool, port: int | None) -> Meshcat:
    """A Meshcat served on localhost. Only a live one announces its URL: a headless run
    needs the server for its HTML recording alone, and nobody is meant to open it."""
    params = MeshcatParams(host="localhost")
    if port is not None:
        params.port = port
    logger = logging.getLogger("drake")
    level = logger.level
    if not live:
        logger.setLevel(logging.WARNING)
    try:
        return Meshcat(params)
    finally:
        logger.setLevel(level)


class Scene:
    """One Meshcat scene (served on localhost only). Attributes: `meshcat`, `root` (scene-tree
    prefix), `live` (a browser watches it while the mission flies: the mission Diagram then
    also draws the leg, the replanner's section and the reference, `mission.live_view`),
    `recording`, `bounds` (box of the meshes and paths drawn), `camera_framed`, `legend`
    ({name: `LegendEntry`}, in the order drawn) and `clock_legs` ([(mission time s, the leg's
    label)], by time: what the recording's clock names)."""

    def __init__(self, meshcat: Meshcat | None = None, root: str = "drake_auv",
                 live: bool = False, port: int | None = None):
        """`port`: the live view's port (None: Drake's first free one from 7000)."""
        self.meshcat = meshcat if meshcat is not None else _local_meshcat(live, port)
        self.root = "/" + root.strip("/")
        self.live = live
        self.recording = False
        self.playback_speed = 1.0
        self.time_offset = 0.0  # s of mission time before this diagram's t = 0 (multi-phase)
        self._trails = 0
        self.bounds: np.ndarray | None = None  # (2, 3) min and max corners of what is drawn
        self.camera_framed = False
        self.legend: dict[str, LegendEntry] = {}
        self.clock_legs: list[tuple[float, str]] = []

    def path_of(self, name: str) -> str:
        """The scene-tree path of a named layer."""
        return f"{self.root}/{name.strip('/')}"

    def new_trail_path(self, name: str) -> str:
        """A fresh scene-tree path for one visualizer's trail, so that the trails of the
        phases of a mission (one diagram each) all stay in the recording."""
        self._trails += 1
        return self.path_of(f"{name}_trail/{self._trails - 1}")

    def add_legend(self, entry: LegendEntry) -> None:
        """Names a layer or marker in the legend (once per name); in a live scene, also as a
        read-only entry of Meshcat's control panel."""
        if entry.name in self.legend:
            return
        self.legend[entry.name] = entry
        if self.live and entry.label not in self.meshcat.GetButtonNames():
            self.meshcat.AddButton(entry.label)

    def hide(self, name: str) -> None:
        """Starts the layer `name` hidden (drawn, one click away in the legend and in
        Meshcat's scene tree)."""
        self.meshcat.SetProperty(self.path_of(name), "visible", False)

    def include(self, points) -> None:
        """Grows `bounds` to hold `points` ((N, 3), m): what `frame_camera` looks at."""
        points = np.asarray(points, dtype=float).reshape(-1, 3)
        points = points[np.all(np.isfinite(points), axis=1)]
        if len(points) == 0:
            return
        box = np.array([points.min(axis=0), points.max(axis=0)])
        self.bounds = box if self.bounds is None else np.array(
            [np.minimum(self.bounds[0], box[0]), np.maximum(self.bounds[1], box[1])])

    def frame_camera(self, direction=(-1.0, -1.6, 1.1), margin: float = 1.1, bounds=None):
        """Points Meshcat's camera at the centre of `bounds` (default: the box of every mesh
        and path drawn, see `include`) from `direction` (world frame, target to camera), far
        enough for the box's bounding sphere to fill the view times `margin`, and brightens the
        ambient and fill lights (Meshcat's defaults leave a seabed almost black). Returns the
        camera position and the target, m."""
        box = self.bounds if bounds is None else np.asarray(bounds, dtype=float).reshape(2, 3)
        if box is None:
            raise ValueError("frame_camera: nothing drawn yet and no bounds given")
        direction = np.asarray(direction, dtype=float)
        norm = np.linalg.norm(direction)
        if direction.shape != (3,) or not np.isfinite(norm) or norm == 0:
            raise ValueError(f"direction must be a non-zero 3-vector, got {direction}")
        if not (np.isfinite(margin) and margin > 0):
            raise ValueError(f"margin must be > 0, got {margin}")
        target = box.mean(axis=0)
        radius = max(0.5 * float(np.linalg.norm(box[1] - box[0])), 1.0)
        distance = margin * radius / math.sin(math.radians(_FOV_DEG / 2))
        camera = target + distance * direction / norm
        meshcat = self.meshcat
        meshcat.SetProperty(_CAMERA, "near", 0.01 * distance)
        meshcat.SetProperty(_CAMERA, "far", 4.0 * (distance + radius))
        meshcat.SetCameraPose(camera, target)
        meshcat.SetProperty("/Lights/AmbientLight/<object>", "intensity", 1.0)
        meshcat.SetProperty("/Lights/FillLight/<object>", "intensity", 3.0)
        self.camera_framed = True
        return camera, target

    def add_mesh(self, name: str, mesh, rgba=(0.55, 0.5, 0.42, 1.0), wireframe: bool = False) -> str:
        """Draws a `trimesh.Trimesh` (world frame) at `name`; returns its scene path."""
        vertices = np.asarray(mesh.vertices, dtype=float)
        faces = np.asarray(mesh.faces, dtype=np.int32)
        if len(vertices) == 0 or len(faces) == 0:
            raise ValueError(f"add_mesh({name!r}): the mesh is empty")
        path = self.path_of(name)
        self.include(vertices)
        self.meshcat.SetTriangleMesh(path, np.asfortranarray(vertices.T),
                                     np.asfortranarray(faces.T), _rgba(rgba), wireframe)
        return path

    def add_terrain(self, bathymetry, stride: int = 1, rgba=(0.55, 0.5, 0.42, 1.0)) -> str:
        """Draws a `Bathymetry` grid as the seabed surface at `terrain` (in the legend)."""
        from drake_auv.terrain.mesh import bathymetry_to_mesh

        path = self.add_mesh("terrain", bathymetry_to_mesh(bathymetry, stride), rgba)
        self.add_legend(LegendEntry("terrain", "brown mesh", "the seabed", css_colour(rgba),
                                    path))
        return path

    def add_path(self, name: str, path, rgba=PATH_RGBA, line_width: float = 2.0) -> str:
        """Draws a `PlannedPath` (or an (N, 3) array of points) as a polyline at `name`."""
        points = path.points if isinstance(path, PlannedPath) else np.asarray(path, dtype=float)
        if points.ndim != 2 or points.shape[1] != 3 or len(points) < 2:
            raise ValueError(f"add_path({name!r}): need (N >= 2, 3) points, got {points.shape}")
        scene_path = self.path_of(name)
        self.include(points)
        self.meshcat.SetLine(scene_path, np.asfortranarray(points.T), line_width, _rgba(rgba))
        return scene_path

    def add_vehicle_visualizer(self, builder, state_port, name: str = "vehicle",
                               period: float = 0.1, trail: bool = True) -> "VehicleVisualizer":
        """Adds a `VehicleVisualizer` fed by `state_port` (12-state) to a DiagramBuilder."""
        visualizer = builder.AddNamedSystem(f"{name}_visualizer",
                                            VehicleVisualizer(self, name, period, trail))
        builder.Connect(state_port, visualizer.state_input)
        return visualizer

    def start_recording(self, playback_speed: float = 1.0, frames_per_second: float = 32.0,
                        live: bool = True) -> None:
        """Keyframes every later vehicle pose; the animation plays `playback_speed` times
        faster than simulated time. With `live`, poses also go to open browsers meanwhile."""
        if not (math.isfinite(playback_speed) and 0.01 <= playback_speed <= 1000):
            raise ValueError(f"playback_speed must be in [0.01, 1000], got {playback_speed}")
        if not (math.isfinite(frames_per_second) and 1 <= frames_per_second <= 240):
            raise ValueError(f"frames_per_second must be in [1, 240], got {frames_per_second}")
        self.playback_speed = float(playback_speed)
        self.meshcat.StartRecording(frames_per_second, live)
        self.recording = True

    def recording_time(self, sim_time: float) -> float:
        """Time in the animation of a simulated time, s; a mission of several diagrams sets
        `time_offset` to the phase's start so the phases play one after the other."""
        return (self.time_offset + sim_time) / self.playback_speed

    def write_html(self, filename) -> Path:
        """Publishes the recording (if any) and writes the scene as one standalone HTML file
        with the legend of the layers drawn and, with a recording, the mission clock; frames
        the camera on the scene first unless `frame_camera` was called."""
        if not self.camera_framed and self.bounds is not None:
            self.frame_camera()
        recorded = self.recording
        if recorded:
            self.meshcat.StopRecording()
            self.meshcat.PublishRecording()
            self.recording = False
        entries = [entry for entry in self.legend.values()
                   if entry.layer is None or self.meshcat.HasPath(entry.layer)]
        overlay = overlay_html(entries, self.playback_speed if recorded else None,
                               self.clock_legs)
        filename = Path(filename)
        filename.parent.mkdir(parents=True, exist_ok=True)
        write_text(filename, with_overlay(self.meshcat.StaticHtml(), overlay))
        return filename


class VehicleVisualizer(LeafSystem):
    """Poses the three-hull vehicle from `state` every `period` s and draws its trail.

    The trail is drawn in pieces of `trail_piece` samples; while recording, each piece is
    hidden at the start of the animation and shown from the time it was completed.
    """

    def __init__(self, scene: Scene, name: str = "vehicle", period: float = 0.1,
                 trail: bool = True, trail_piece: int = 20):
        super().__init__()
        if not (math.isfinite(period) and 1e-3 <= period <= 10.0):
            raise ValueError(f"visualizer period must be in [0.001, 10] s, got {period}")
        self.scene = scene
        self.vehicle_path = scene.path_of(name)
        self.trail_path = scene.new_trail_path(name)
        self.trail = trail
        self.trail_piece = int(trail_piece)
        self._trail_points: list[np.ndarray] = []
        self._pieces = 0
        self.state_input = self.DeclareVectorInputPort("state", 12)
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish_pose)
        self.DeclareForcedPublishEvent(self._publish_pose)
        self.DeclareInitializationPublishEvent(self._reset_trail)
        self._draw_vehicle()
        scene.add_legend(LegendEntry(name, "yellow hulls", "the GIRONA 500 at its true pose",
                                     css_colour(_HULLS[0][2]), self.vehicle_path))
        if trail:
            scene.add_legend(LegendEntry(f"{name} trail", "blue line", "where it has been",
                                         css_colour(_TRAIL_RGBA), scene.path_of(f"{name}_trail")))

    def _draw_vehicle(self):
        meshcat = self.scene.meshcat
        along_x = RotationMatrix.MakeYRotation(np.pi / 2)
        for hull, offset, rgba in _HULLS:
            path = f"{self.vehicle_path}/{hull}"
            meshcat.SetObject(path, Capsule(_HULL_RADIUS, _HULL_LENGTH), rgba)
            meshcat.SetTransform(path, RigidTransform(along_x, offset))
        for i, x in enumerate((-0.45, 0.45)):  # vertical frames joining the hulls
            path = f"{self.vehicle_path}/frame_{i}"
            meshcat.SetObject(path, Box(0.06, 0.75, 0.55), Rgba(0.2, 0.2, 0.2, 1.0))
            meshcat.SetTransform(path, RigidTransform([x, 0.0, -0.05]))

    def _reset_trail(self, context):
        self._trail_points = []
        if self._pieces:
            self.scene.meshcat.Delete(self.trail_path)
        self._pieces = 0
        self._publish_pose(context)

    def _publish_pose(self, context):
        x = VehicleState(self.state_input.Eval(context))
        t = context.get_time()
        scene = self.scene
        when = scene.recording_time(t) if scene.recording else None
        scene.meshcat.SetTransform(self.vehicle_path,
                                   RigidTransform(RollPitchYaw(x.attitude), x.position),
                                   when)
        if not self.trail:
            return
        self._trail_points.append(np.array(x.position))
        if len(self._trail_points) > self.trail_piece:
            path = f"{self.trail_path}/{self._pieces}"
            points = np.asfortranarray(np.array(self._trail_points).T)
            scene.meshcat.SetLine(path, points, 2.0, _TRAIL_RGBA)
            if scene.recording:
                scene.meshcat.SetProperty(path, "visible", False, 0.0)
                scene.meshcat.SetProperty(path, "visible", True, when)
            self._pieces += 1
            self._trail_points = self._trail_points[-1:]  # the next piece starts here
