"""Sonar scans and camera coverage in Meshcat.

`SonarVisualizer` draws the last scan of a sonar (`returns` input) as beam segments from the
sensor to each return plus the return points, optionally keeping the points of the last
`history` scans as a depth-coloured cloud. `CoverageVisualizer` colours the target surface by
best viewing angle (from `CoverageRecorder.face_angles`), in 15 deg bands: unseen faces grey,
seen faces from green (0 deg, head-on) to red (90 deg, grazing). `draw_coverage` does the same
once, offline.

Both publish periodically (not every step). Drake's Meshcat recordings animate transforms and
properties, not geometry, so a saved HTML shows the last scan and coverage drawn; watch live
for the evolution. Each takes a `meshcat` object and draws under its own `path`.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Rgba
from pydrake.perception import BaseField, Fields, PointCloud
from pydrake.systems.framework import LeafSystem

from drake_auv.sonar.returns import SonarReturns
from drake_auv.visualization.legend import LegendEntry, swatch

UNSEEN_RGB = (0.55, 0.55, 0.55)
COVERAGE_BAND_DEG = 15.0  # the coverage layer's colour bands, deg of viewing angle


def angle_colors(angles: np.ndarray) -> np.ndarray:
    """(n, 3) RGB for viewing angles (rad): green at 0, yellow at 45 deg, red at 90 deg;
    grey where NaN (unseen)."""
    angles = np.asarray(angles, dtype=float)
    t = np.clip(np.nan_to_num(angles, nan=0.0) / (np.pi / 2), 0.0, 1.0)
    rgb = np.column_stack([np.minimum(1.0, 2 * t), np.minimum(1.0, 2 * (1 - t)),
                           np.full_like(t, 0.15)])
    rgb[np.isnan(angles)] = UNSEEN_RGB
    return rgb


def depth_colors(z: np.ndarray) -> np.ndarray:
    """(n, 3) RGB by elevation: the shallowest points yellow, the deepest blue."""
    z = np.asarray(z, dtype=float)
    span = max(float(np.ptp(z)) if len(z) else 0.0, 1e-9)
    t = (z - z.min()) / span if len(z) else z
    return np.column_stack([t, 0.3 + 0.6 * t, 1.0 - t])


def coverage_bands() -> list[tuple[str, np.ndarray]]:
    """[(name, RGB)] of the coverage layer's bands: `COVERAGE_BAND_DEG` wide from head-on
    (coloured by `angle_colors` at their centre), then the unseen faces."""
    edges = np.arange(0.0, 90.0, COVERAGE_BAND_DEG)
    colours = angle_colors(np.radians(edges + COVERAGE_BAND_DEG / 2))
    return [(f"{lo:.0f}-{lo + COVERAGE_BAND_DEG:.0f}_deg", rgb)
            for lo, rgb in zip(edges, colours)] + [("unseen", np.array(UNSEEN_RGB))]


def coverage_legend(path: str) -> LegendEntry:
    """The legend's entry of the coverage drawn at `path`."""
    return LegendEntry("coverage", "green to red", f"best multibeam angle on the target, in "
                       f"{COVERAGE_BAND_DEG:.0f}° bands: green head-on, yellow 45°, red "
                       "grazing, grey unseen",
                       swatch([rgb for _, rgb in coverage_bands()], smooth=False), path)


def draw_coverage(meshcat, path: str, world, face_angles: np.ndarray,
                  faces: np.ndarray | None = None, lift: float = 0.0) -> None:
    """Draws `faces` of `world` (default: all) coloured by `face_angles` (per world face,
    rad, NaN unseen), one mesh per band of `coverage_bands` at `path`/<band name> (a band
    without faces is deleted). A band's faces share their vertices: a fraction of the bytes
    of a mesh coloured face by face, whose colours must not bleed. `lift` (m) moves the
    vertices along their normals, so the layer shows over the world mesh itself."""
    face_angles = np.asarray(face_angles, dtype=float)
    if face_angles.shape != (len(world.faces),):
        raise ValueError(f"face_angles must have one value per world face "
                         f"({len(world.faces)}), got shape {face_angles.shape}")
    faces = np.arange(len(world.faces)) if faces is None else np.asarray(faces)
    if faces.dtype == bool:
        faces = np.flatnonzero(faces)
    if len(faces) == 0:
        raise ValueError("draw_coverage: no faces to draw")
    angles = np.degrees(face_angles[faces])
    bands = coverage_bands()
    band = np.where(np.isnan(angles), len(bands) - 1, np.clip(
        np.nan_to_num(angles) // COVERAGE_BAND_DEG, 0, len(bands) - 2)).astype(int)
    corners, vertices = np.asarray(world.faces), np.asarray(world.vertices)
    normals = np.asarray(world.vertex_normals)
    for k, (name, rgb) in enumerate(bands):
        chosen = corners[faces[band == k]]
        if len(chosen) == 0:
            meshcat.Delete(f"{path}/{name}")
            continue
        used, triangles = np.unique(chosen, return_inverse=True)
        points = vertices[used] + lift * normals[used]
        meshcat.SetTriangleMesh(f"{path}/{name}", np.asfortranarray(points.T),
                                np.asfortranarray(triangles.reshape(-1, 3).T.astype(np.int32)),
                                Rgba(*rgb, 1.0))


class SonarVisualizer(LeafSystem):
    """Input `returns` (`SonarReturns`); draws it every `period` s under `path`.

    Args:
        meshcat: the Meshcat to draw in.
        path: scene-tree path, e.g. "/drake_auv/sonar/multibeam".
        period: publish period, s.
        rgba: beam colour.
        beams: draw the beams as segments from the sensor to each return.
        history: keep the return points of this many past scans (0: the last scan only).
        point_size: m.
    """

    def __init__(self, meshcat, path: str, period: float = 0.1, rgba=(1.0, 0.2, 0.2, 0.8),
                 beams: bool = True, history: int = 0, point_size: float = 0.08):
        super().__init__()
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"period must be > 0 s, got {period}")
        if int(history) != history or history < 0:
            raise ValueError(f"history must be an integer >= 0 scans, got {history}")
        self.meshcat = meshcat
        self.path = "/" + path.strip("/")
        self.rgba = Rgba(*rgba)
        self.beams = beams
        self.history = int(history)
        self.point_size = float(point_size)
        self._clouds: list[np.ndarray] = []
        self._last_sequence = -1
        self.returns_input = self.DeclareAbstractInputPort(
            "returns", AbstractValue.Make(SonarReturns.empty(1.0)))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish_scan)
        self.DeclareForcedPublishEvent(self._publish_scan)

    def _publish_scan(self, context):
        returns = self.returns_input.Eval(context)
        if returns.sequence == self._last_sequence or len(returns) == 0:
            return
        self._last_sequence = returns.sequence
        points = returns.points_nav[returns.hit]
        if self.beams:
            # Beams without return are drawn to max range: the free space they saw.
            ends = np.where(returns.hit[:, None], returns.points_nav,
                            returns.origin_nav + returns.max_range * returns.directions_nav)
            starts = np.tile(returns.origin_nav, (len(ends), 1))
            self.meshcat.SetLineSegments(f"{self.path}/beams", np.asfortranarray(starts.T),
                                         np.asfortranarray(ends.T), 1.0, self.rgba)
        self._clouds.append(points)
        self._clouds = self._clouds[-(self.history + 1):]
        cloud_points = np.vstack(self._clouds)
        cloud = PointCloud(len(cloud_points), Fields(BaseField.kXYZs | BaseField.kRGBs))
        cloud.mutable_xyzs()[:] = cloud_points.T
        cloud.mutable_rgbs()[:] = (255 * depth_colors(cloud_points[:, 2])).astype(np.uint8).T
        self.meshcat.SetObject(f"{self.path}/points", cloud, self.point_size)


class CoverageVisualizer(LeafSystem):
    """Input `face_angles` (T, from `CoverageRecorder`); redraws the coloured target surface
    every `period` s (a mesh upload: keep the period long on big worlds) under `path`."""

    def __init__(self, meshcat, path: str, world, target_index: np.ndarray,
                 period: float = 5.0):
        super().__init__()
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"period must be > 0 s, got {period}")
        self.meshcat = meshcat
        self.path = "/" + path.strip("/")
        self.world = world
        self.target_index = np.asarray(target_index)
        self.face_angles_input = self.DeclareVectorInputPort("face_angles", len(self.target_index))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish_coverage)
        self.DeclareForcedPublishEvent(self._publish_coverage)

    @classmethod
    def for_recorder(cls, builder, recorder, meshcat, path: str, period: float = 5.0):
        """Adds a visualizer fed by `recorder.face_angles` to `builder` (named) and returns it."""
        visualizer = builder.AddNamedSystem(
            f"{recorder.get_name()}_visualizer",
            cls(meshcat, path, recorder.caster.mesh, recorder.visibility.target_index, period))
        builder.Connect(recorder.face_angles_output, visualizer.face_angles_input)
        return visualizer

    def _publish_coverage(self, context):
        angles = np.full(len(self.world.faces), np.nan)
        angles[self.target_index] = self.face_angles_input.Eval(context)
        draw_coverage(self.meshcat, self.path, self.world, angles, self.target_index)
