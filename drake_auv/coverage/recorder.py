"""`CoverageRecorder`: which target faces of the true world the payload sensor has seen.

Camera mode: a cone of `aperture_deg` about `axis_body` (default straight down), range
`max_range`; multibeam mode: the faces hit by a fan of beams. Periodic discrete update at
`rate` (frames per second) from the true state; the discrete state is the best viewing angle
per target face (rad, NaN while unseen) and, in a second group, the time each face was first
seen (s, NaN while unseen): the coverage-against-time curve of the whole dive follows from that
one vector after the run (`mission.report.summary.coverage_curve`), nothing stored per step. Outputs: `coverage`, the
seen share of the target area, and `face_angles`, the best angles (for colouring the mesh in
Meshcat).
The pure work is in `drake_auv.geometry.visibility`.

A multibeam recorder built with `hits_input` does not cast: it reads the faces the payload
multibeam's beam axes hit in the same update (`MultibeamSonar(axis_hits_output=True)`, the
same fan, range, mount and rate), one ray query serving the sonar and its score.
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.vehicle.control import rotation_world_body
from drake_auv.geometry.visibility import FaceVisibility, angle_histogram, coverage_share
from drake_auv.signals import VehicleState
from drake_auv.sonar.beams import AxisHits, SonarMount, fan_angles
from drake_auv.sonar.range_sonar import as_caster
from drake_auv.vehicle.model import STATE_SIZE


class CoverageRecorder(LeafSystem):
    """Input `true_state` (12); outputs `coverage` (1, share of the target area in [0, 1]) and
    `face_angles` (T, best viewing angle per target face, rad, NaN while unseen).

    Args:
        world: true world, a trimesh or a shared `RayCaster`.
        target_faces: (F,) bool mask of the world's faces to cover (all if None).
        sensor: "camera" or "multibeam".
        aperture_deg: camera cone, full angle, deg (the reference's camera: 60).
        max_range: camera visibility or sonar range, m, > 0.
        axis_body: camera axis in the body frame.
        position_body: sensor position in the body frame, m.
        rate: frames (or pings) per second, > 0.
        num_beams, fan_deg, mount: the multibeam fan (see `MultibeamSonar`).
        hits_input: (multibeam) declare the abstract input `axis_hits` and score the
            `AxisHits` of a multibeam with this fan, range, mount and rate instead of casting.
    """

    def __init__(self, world, target_faces=None, sensor: str = "camera",
                 aperture_deg: float = 60.0, max_range: float = 8.0, axis_body=(0.0, 0.0, -1.0),
                 position_body=(0.0, 0.0, 0.0), rate: float = 2.0, num_beams: int = 480,
                 fan_deg: float = 120.0, mount: str = "down", hits_input: bool = False):
        super().__init__()
        if sensor not in ("camera", "multibeam"):
            raise ValueError(f"sensor must be 'camera' or 'multibeam', got {sensor!r}")
        if not (0 < aperture_deg < 180):
            raise ValueError(f"aperture_deg must be in (0, 180), got {aperture_deg}")
        if not (np.isfinite(max_range) and max_range > 0):
            raise ValueError(f"max_range must be > 0 m, got {max_range}")
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be > 0 Hz, got {rate}")
        if hits_input and sensor != "multibeam":
            raise ValueError("hits_input needs sensor='multibeam' (a camera casts its own rays)")
        axis = np.asarray(axis_body, dtype=float)
        if axis.shape != (3,) or not np.isfinite(axis).all() or np.linalg.norm(axis) < 1e-9:
            raise ValueError(f"axis_body must be a non-zero 3-vector, got {axis_body}")
        self.caster = as_caster(world)
        self.visibility = FaceVisibility(self.caster, target_faces)
        self.sensor = sensor
        self.aperture = np.radians(aperture_deg)
        self.max_range = float(max_range)
        self.axis_body = axis / np.linalg.norm(axis)
        self.mount = SonarMount.named(mount, position_body) if sensor == "multibeam" \
            else SonarMount(np.asarray(position_body, dtype=float))
        if sensor == "multibeam":
            a = fan_angles(num_beams, np.radians(fan_deg))
            self._beams_body = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)]) \
                @ self.mount.rotation.T
        self.true_state_input = self.DeclareVectorInputPort("true_state", STATE_SIZE)
        self.hits_input = (self.DeclareAbstractInputPort(
            "axis_hits", AbstractValue.Make(AxisHits.empty(self.max_range)))
            if hits_input else None)
        num_target = len(self.visibility.target_index)
        self._best_index = self.DeclareDiscreteState(BasicVector(np.full(num_target, np.nan)))
        self._first_seen_index = self.DeclareDiscreteState(
            BasicVector(np.full(num_target, np.nan)))
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / rate, 0.0, self._update_best)
        self.coverage_output = self.DeclareVectorOutputPort(
            "coverage", 1, self._calc_coverage,
            prerequisites_of_calc={self.discrete_state_ticket(self._best_index)})
        self.face_angles_output = self.DeclareVectorOutputPort(
            "face_angles", num_target, self._calc_face_angles,
            prerequisites_of_calc={self.discrete_state_ticket(self._best_index)})

    def _update_best(self, context, discrete_state):
        if self.hits_input is not None:
            hits = self._shared_hits(context)
            slots, angles = self.visibility.beams(hits, hits.directions)
        else:
            state = VehicleState(self.true_state_input.Eval(context))
            r_wb = rotation_world_body(*state.attitude)
            origin = state.position + r_wb @ self.mount.position
            if self.sensor == "camera":
                slots, angles = self.visibility.camera(origin, r_wb @ self.axis_body,
                                                       self.aperture, self.max_range)
            else:
                directions = self._beams_body @ r_wb.T
                hits = self.caster.cast(origin, directions, self.max_range)
                slots, angles = self.visibility.beams(hits, directions)
        if len(slots):
            # In place on the update's own copy of the state (Drake fills it with the current
            # values): only the observed slots are read and written, not all T faces.
            best = discrete_state.get_mutable_value(self._best_index)
            first = discrete_state.get_mutable_value(self._first_seen_index)
            unseen = slots[np.isnan(best[slots])]
            np.fmin.at(best, slots, angles)  # the smallest angle per slot, NaN (unseen) skipped
            first[unseen[np.isfinite(best[unseen])]] = context.get_time()

    def _shared_hits(self, context) -> AxisHits:
        """The multibeam's `AxisHits` of this update; a ValueError if they are of another
        time or fan (the sonar is not this recorder's twin)."""
        hits = self.hits_input.Eval(context)
        if hits.time != context.get_time() or len(hits.faces) != len(self._beams_body) \
                or hits.max_range != self.max_range:
            raise ValueError(
                f"{self.get_name()}: axis_hits of t = {hits.time} s, {len(hits.faces)} beams, "
                f"{hits.max_range} m at t = {context.get_time()} s: connect a multibeam of "
                f"{len(self._beams_body)} beams, {self.max_range} m and the recorder's rate")
        return hits

    def _calc_coverage(self, context, output):
        output.SetAtIndex(0, self.coverage(context))

    def _calc_face_angles(self, context, output):
        output.SetFromVector(context.get_discrete_state(self._best_index).get_value())

    def best_angles(self, context) -> np.ndarray:
        """(T,) best viewing angle per target face, rad, NaN where unseen."""
        return context.get_discrete_state(self._best_index).get_value().copy()

    def first_seen(self, context) -> np.ndarray:
        """(T,) time each target face was first seen (its best angle became finite), s, NaN
        where unseen."""
        return context.get_discrete_state(self._first_seen_index).get_value().copy()

    def coverage(self, context) -> float:
        """Seen share of the target area."""
        return coverage_share(self.best_angles(context), self.visibility.areas)

    def face_angles(self, context) -> np.ndarray:
        """(F,) best viewing angle per world face, rad: NaN for unseen and non-target faces.
        For colouring the mesh."""
        out = np.full(self.caster.num_faces, np.nan)
        out[self.visibility.target_index] = self.best_angles(context)
        return out

    def viewing_angle_histogram(self, context, bin_deg: float = 5.0):
        """(area per bin (m^2), bin edges (deg)) of the seen target faces' best angles."""
        return angle_histogram(self.best_angles(context), self.visibility.areas, bin_deg)
