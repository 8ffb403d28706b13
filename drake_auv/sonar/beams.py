"""Range sonars as pure functions: mounts, beam fans, the pencil-beam head schedule and `scan`.

A sonar's beams lie in the x-y plane of its sensor frame S at angles `a` from S's x axis:
d_S = (cos a, sin a, 0). The mount places S on the vehicle: p_BS (body frame, m) and R_BS.
`scan` casts the beams against the true world from the true pose, applies the error model,
and expresses the returns in the body and navigation frames (navigation = estimated pose), so
navigation drift reaches the map exactly as it would at sea. R_WB = Rz(yaw) Ry(pitch) Rx(roll).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from drake_auv.vehicle.control import rotation_world_body
from drake_auv.geometry.raycast import RayCaster
from drake_auv.sonar.noise import SonarNoise, apply_noise
from drake_auv.sonar.returns import SonarReturns

# R_BS of the named mounts (columns: S's x, y, z axes in the body frame).
MOUNT_ROTATIONS = {
    # Horizontal scan plane: S = B; angle 0 ahead, +90 deg to port.
    "horizontal": np.eye(3),
    # Vertical scan plane (body x-z): angle 0 ahead, +90 deg straight up, -90 deg down.
    "vertical": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),
    # Down-looking fan across track (body y-z plane): angle 0 straight down, + to port.
    "down": np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]),
    # Side-looking fans in the body y-z plane: centre beam horizontal, + upwards.
    "port": np.array([[0.0, 0, 1], [1, 0, 0], [0, 1, 0]]),
    "starboard": np.array([[0.0, 0, -1], [-1, 0, 0], [0, 1, 0]]),
    # Forward-looking fan in the horizontal plane: angle 0 ahead, + to port.
    "forward": np.eye(3),
}


@dataclass(frozen=True)
class SonarMount:
    """Pose of the sensor frame S on the vehicle: position p_BS (m) and rotation R_BS."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))

    def __post_init__(self):
        p = np.asarray(self.position, dtype=float)
        r = np.asarray(self.rotation, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"SonarMount.position must be 3 finite numbers (m), got {p}")
        if r.shape != (3, 3) or not np.allclose(r @ r.T, np.eye(3), atol=1e-6) \
                or np.linalg.det(r) < 0:
            raise ValueError("SonarMount.rotation must be a 3x3 proper rotation matrix")
        object.__setattr__(self, "position", p)
        object.__setattr__(self, "rotation", r)

    @classmethod
    def named(cls, name: str, position=(0.0, 0.0, 0.0)) -> "SonarMount":
        """One of MOUNT_ROTATIONS ('horizontal', 'vertical', 'down', 'port', 'starboard',
        'forward') at `position` in the body frame."""
        if name not in MOUNT_ROTATIONS:
            raise ValueError(f"unknown sonar mount {name!r}; choose one of "
                             f"{sorted(MOUNT_ROTATIONS)}")
        return cls(np.asarray(position, dtype=float), MOUNT_ROTATIONS[name])


@dataclass(frozen=True)
class SonarModel:
    """Static description of a range sonar.

    Attributes:
        mount: where the sensor frame sits on the vehicle.
        max_range: m, > 0.
        beam_width: full cone angle of each beam, rad, in [0, pi/6]; 0 casts the axis only,
            otherwise the axis and 6 rays on the cone's edge are cast and the nearest echo
            wins, as a real transducer reports the first strong echo inside its beam.
        max_incidence: largest angle between beam and surface normal that still returns an
            echo, rad, in (0, pi/2]; grazing beams scatter away and return nothing.
        noise: error options (off by default).
    """

    mount: SonarMount = field(default_factory=SonarMount)
    max_range: float = 20.0
    beam_width: float = 0.0
    max_incidence: float = np.radians(85.0)
    noise: SonarNoise = field(default_factory=SonarNoise)

    def __post_init__(self):
        if not (np.isfinite(self.max_range) and self.max_range > 0):
            raise ValueError(f"max_range must be > 0 m, got {self.max_range}")
        if not (np.isfinite(self.beam_width) and 0 <= self.beam_width <= np.pi / 6):
            raise ValueError(f"beam_width must be in [0, 30] deg, got "
                             f"{np.degrees(self.beam_width)} deg")
        if not (np.isfinite(self.max_incidence) and 0 < self.max_incidence <= np.pi / 2):
            raise ValueError(f"max_incidence must be in (0, 90] deg, got "
                             f"{np.degrees(self.max_incidence)} deg")


def fan_angles(num_beams: int, fan: float) -> np.ndarray:
    """(num_beams,) equiangular beam angles over a fan of `fan` rad centred on 0."""
    if int(num_beams) != num_beams or num_beams < 1:
        raise ValueError(f"num_beams must be an integer >= 1, got {num_beams}")
    if not (np.isfinite(fan) and 0 <= fan < 2 * np.pi):
        raise ValueError(f"fan must be in [0, 360) deg, got {np.degrees(fan)} deg")
    if num_beams == 1:
        return np.zeros(1)
    return np.linspace(-fan / 2, fan / 2, int(num_beams))


def head_angles(ping_indices, sector: tuple[float, float], step: float) -> np.ndarray:
    """Beam angles of a mechanically scanned head for the given ping indices.

    A full-circle sector (width >= 2 pi) rotates continuously from sector[0]; a narrower one
    sweeps back and forth between its ends, as the SeaKing does in sector-scan mode. Radians.
    """
    lo, hi = float(sector[0]), float(sector[1])
    k = np.asarray(ping_indices, dtype=float)
    width = hi - lo
    if width >= 2 * np.pi - 1e-9:
        return (lo + k * step + np.pi) % (2 * np.pi) - np.pi
    s = (k * step) % (2 * width)
    return lo + np.where(s <= width, s, 2 * width - s)


def _beam_rays(directions_s: np.ndarray, half_angle: float) -> np.ndarray:
    """(n, m, 3) the axis and 6 cone-edge rays per beam (m = 1 when half_angle is 0)."""
    if half_angle <= 0:
        return directions_s[:, None, :]
    a = np.arctan2(directions_s[:, 1], directions_s[:, 0])
    e1 = np.column_stack([-np.sin(a), np.cos(a), np.zeros_like(a)])  # in the scan plane
    e2 = np.tile([0.0, 0.0, 1.0], (len(a), 1))  # out of it
    phi = np.arange(6) * np.pi / 3
    ring = (np.cos(half_angle) * directions_s[:, None, :]
            + np.sin(half_angle) * (np.cos(phi)[None, :, None] * e1[:, None, :]
                                    + np.sin(phi)[None, :, None] * e2[:, None, :]))
    return np.concatenate([directions_s[:, None, :], ring], axis=1)


@dataclass(frozen=True)
class BeamGeometry:
    """Beams of one update in the body frame, precomputable when the angles repeat.

    angles (n,) rad; directions_body (n, 3) beam axes; rays_body (n * m, 3) the rays cast
    (m per beam: the axis, plus the cone edge when the beam has a width).
    """

    angles: np.ndarray
    directions_body: np.ndarray
    rays_body: np.ndarray
    rays_per_beam: int


def beam_geometry(model: SonarModel, angles) -> BeamGeometry:
    """The body-frame beams of `model` at `angles` (rad, in the scan plane)."""
    angles = np.asarray(angles, dtype=float).ravel()
    d_s = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    rotation = model.mount.rotation
    rays = _beam_rays(d_s, 0.5 * model.beam_width)
    return BeamGeometry(angles, d_s @ rotation.T, rays.reshape(-1, 3) @ rotation.T,
                        rays.shape[1])


def pose(state) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), R_WB (3, 3)) of a 12-vector state."""
    state = np.asarray(state, dtype=float)
    if state.shape[0] < 6 or not np.all(np.isfinite(state[:6])):
        raise ValueError("state must start with a finite [x, y, z, roll, pitch, yaw]")
    return state[:3].copy(), rotation_world_body(*state[3:6])


def scan(caster: RayCaster, model: SonarModel, angles, true_state, estimated_state,
         rng: np.random.Generator | None = None, time: float = 0.0, sequence: int = 0,
         geometry: BeamGeometry | None = None) -> SonarReturns:
    """One update of a sonar: the beams at `angles` (rad, in the scan plane), cast from the
    true pose against the true world, expressed with the estimated pose.

    Args:
        caster: ray caster of the true world.
        model: mount, range, beam width, grazing limit and noise.
        angles: (n,) beam angles, rad (ignored when `geometry` is given).
        true_state, estimated_state: 12-vectors.
        rng: generator for the noise (required if model.noise is enabled).
        geometry: `beam_geometry(model, angles)`, precomputed by callers that repeat angles.
    """
    g = geometry if geometry is not None else beam_geometry(model, angles)
    p_wb, r_wb = pose(true_state)
    p_nb, r_nb = pose(estimated_state)
    mount = model.mount
    origin_w = p_wb + r_wb @ mount.position
    rays_w = g.rays_body @ r_wb.T
    ranges, faces = caster.cast_unit(origin_w, rays_w, model.max_range)
    # Grazing beams scatter away: no echo beyond max_incidence from the normal.
    cos_inc = np.abs(np.einsum("ij,ij->i", caster.face_normals[np.maximum(faces, 0)], rays_w))
    ranges[cos_inc < np.cos(model.max_incidence) - 1e-12] = np.nan
    if g.rays_per_beam > 1:  # the nearest echo inside the beam (fmin skips NaN)
        ranges = np.fmin.reduce(ranges.reshape(-1, g.rays_per_beam), axis=1)
    d_b = g.directions_body
    if model.noise.enabled:
        if rng is None:
            raise ValueError("scan: a seeded rng is required when noise is enabled")
        ranges = apply_noise(ranges, origin_w, d_b @ r_wb.T, model.max_range, model.noise, rng)
    points_b = mount.position + ranges[:, None] * d_b
    return SonarReturns(
        time=float(time),
        origin_nav=p_nb + r_nb @ mount.position,
        angles=g.angles,
        ranges=ranges,
        directions_nav=d_b @ r_nb.T,
        points_nav=p_nb + points_b @ r_nb.T,
        points_body=points_b,
        max_range=float(model.max_range),
        sequence=int(sequence))
