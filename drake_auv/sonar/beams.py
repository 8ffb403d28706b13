"""Range sonars as pure functions: mounts, beam fans, the pencil-beam head schedule and `scan`.

A sonar's beams lie in the x-y plane of its sensor frame S at angles `a` from S's x axis:
d_S = (cos a, sin a, 0). The mount places S on the vehicle: p_BS (body frame, m) and R_BS.
`scan` casts the beams against the true world from the true pose, applies the error model,
and expresses the returns in the body and navigation frames (navigation = estimated pose), so
navigation drift reaches the map exactly as it would at sea. R_WB = Rz(yaw) Ry(pitch) Rx(roll).

A beam is a bundle of rays with gains (its pattern): the axis (1), six rays on the edge of
its cone (0.5: the beam width is the -3 dB width) and, with a side lobe, two rays at the
side-lobe angle across the scan plane (up and down for a horizontal profiler: they reach the
sea surface and the seabed); each ray's echo has intensity gain * cos^2(incidence) and the beam reports,
along its axis, the nearest echo above the detection threshold (`SonarNoise`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from drake_auv.vehicle.control import rotation_world_body
from drake_auv.geometry.raycast import RayCaster
from drake_auv.params import nested, param, validate
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
        beam_width: full -3 dB cone angle of each beam, rad, in [0, pi/6]; 0 casts the axis
            only, otherwise the axis and 6 rays on the cone's edge are cast and the nearest
            detected echo wins, as a real transducer reports the first strong echo inside its
            beam (see the module).
        max_incidence: largest angle between beam and surface normal that still returns an
            echo, rad, in (0, pi/2]; grazing beams scatter away and return nothing.
        noise: error options (off by default).
    """

    mount: SonarMount = field(default_factory=SonarMount)
    max_range: float = param(20.0, low=0.0, low_open=True, unit="m")
    beam_width: float = param(0.0, low=0.0, high=np.pi / 6, unit="rad")
    max_incidence: float = param(np.radians(85.0), low=0.0, high=np.pi / 2, low_open=True,
                                 unit="rad")
    noise: SonarNoise = nested(SonarNoise)

    def __post_init__(self):
        validate(self)

    @functools.cached_property
    def min_echo_cosine(self) -> float:
        """cos(max_incidence), less a rounding margin: rays whose |cos(incidence)| is below
        it return nothing (computed once, read at every ping)."""
        return float(np.cos(self.max_incidence) - 1e-12)


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


EDGE_GAIN = 0.5  # two-way intensity on the edge of the -3 dB cone


def _beam_rays(directions_s: np.ndarray, half_angle: float,
               side_lobe: float = 0.0) -> np.ndarray:
    """(n, m, 3) rays per beam: the axis, 6 on the cone's edge when `half_angle` > 0, and 2
    at `side_lobe` rad across the scan plane (on either side of it) when that is > 0."""
    rings = [(half_angle, np.arange(6) * np.pi / 3)] if half_angle > 0 else []
    if side_lobe > 0:
        rings.append((side_lobe, np.array([0.5, 1.5]) * np.pi))
    if not rings:
        return directions_s[:, None, :]
    a = np.arctan2(directions_s[:, 1], directions_s[:, 0])
    e1 = np.column_stack([-np.sin(a), np.cos(a), np.zeros_like(a)])  # in the scan plane
    e2 = np.tile([0.0, 0.0, 1.0], (len(a), 1))  # out of it
    rays = [directions_s[:, None, :]]
    for angle, phi in rings:
        rays.append(np.cos(angle) * directions_s[:, None, :]
                    + np.sin(angle) * (np.cos(phi)[None, :, None] * e1[:, None, :]
                                       + np.sin(phi)[None, :, None] * e2[:, None, :]))
    return np.concatenate(rays, axis=1)


@dataclass(frozen=True)
class BeamGeometry:
    """Beams of one update in the body frame, precomputable when the angles repeat.

    angles (n,) rad; directions_body (n, 3) beam axes; rays_body (n * m, 3) the rays cast
    (m per beam: the axis, the cone edge when the beam has a width, the side lobe when it has
    one); ray_gains (m,) their two-way gains; gains_per_ray (n * m,) the same, per ray cast.
    The arrays are read-only, so the returns share them.
    """

    angles: np.ndarray
    directions_body: np.ndarray
    rays_body: np.ndarray
    rays_per_beam: int
    ray_gains: np.ndarray
    gains_per_ray: np.ndarray


def _frozen(array) -> np.ndarray:
    out = np.array(array, dtype=float)
    out.setflags(write=False)
    return out


def beam_geometry(model: SonarModel, angles) -> BeamGeometry:
    """The body-frame beams of `model` at `angles` (rad, in the scan plane)."""
    angles = np.asarray(angles, dtype=float).ravel()
    d_s = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    rotation = model.mount.rotation
    noise = model.noise
    side_lobe = np.radians(noise.side_lobe_deg) if noise.side_lobe else 0.0
    rays = _beam_rays(d_s, 0.5 * model.beam_width, side_lobe)
    gains = np.concatenate([[1.0], np.full(6 if model.beam_width > 0 else 0, EDGE_GAIN),
                            np.full(2 if side_lobe > 0 else 0, noise.side_lobe_gain)])
    return BeamGeometry(_frozen(angles), _frozen(d_s @ rotation.T),
                        _frozen(rays.reshape(-1, 3) @ rotation.T), rays.shape[1],
                        _frozen(gains), _frozen(np.tile(gains, len(angles))))


def pose(state) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), R_WB (3, 3)) of a 12-vector state."""
    values = np.asarray(state, dtype=float)[:6].tolist()  # Python floats: cheap scalar maths
    if len(values) < 6 or not all(map(math.isfinite, values)):
        raise ValueError("state must start with a finite [x, y, z, roll, pitch, yaw]")
    x, y, z, roll, pitch, yaw = values
    return np.array((x, y, z)), rotation_world_body(roll, pitch, yaw)


def _surface_multipath(caster: RayCaster, origin: np.ndarray, rays: np.ndarray,
                       ranges: np.ndarray, faces: np.ndarray, max_range: float,
                       probability: float, rng: np.random.Generator):
    """Rays (world frame) that reach the sea surface z = 0 before any echo end there: with
    `probability` they are mirrored and cast on for the rest of the range, their echo coming
    back the same way at the total path length; the others are scattered away (no echo).
    Updates `ranges` (path lengths, m) and `faces` in place; returns the directions of the
    rays as they meet those faces (`rays` itself when none was mirrored)."""
    if origin[2] >= 0:
        return rays
    up = rays[:, 2] > 1e-9
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(up, -origin[2] / rays[:, 2], np.inf)
    at_surface = (t < max_range) & ~(ranges <= t)  # NaN (no hit) compares False
    reflected = at_surface & (rng.random(len(rays)) < probability)
    ranges[at_surface], faces[at_surface] = np.nan, -1
    if reflected.any():
        rays = rays.copy()
        mirrored = rays[reflected] * [1.0, 1.0, -1.0]
        t_r = t[reflected]
        r2, f2 = caster.cast_unit(origin + t_r[:, None] * rays[reflected], mirrored,
                                  max_range - t_r)
        ranges[reflected], faces[reflected], rays[reflected] = t_r + r2, f2, mirrored
    return rays


@dataclass(frozen=True)
class AxisHits:
    """The faces of the true world that the beams' axes hit first, for scoring only (the
    coverage recorders; never the vehicle): the first cast of an update, before the error
    model. time (s); origin (3,) and directions (n, 3) world frame, from the true pose;
    faces (n,) face index, -1 for no hit within max_range (m)."""

    time: float
    origin: np.ndarray
    directions: np.ndarray
    faces: np.ndarray
    max_range: float

    def __deepcopy__(self, memo):
        return self  # immutable: Drake's state copies share it

    @classmethod
    def empty(cls, max_range: float) -> "AxisHits":
        return cls(-np.inf, np.zeros(3), np.zeros((0, 3)), np.zeros(0, np.int64),
                   float(max_range))


def scan(caster: RayCaster, model: SonarModel, angles, true_state, estimated_state,
         rng: np.random.Generator | None = None, time: float = 0.0, sequence: int = 0,
         geometry: BeamGeometry | None = None) -> SonarReturns:
    """One update of a sonar: the beams at `angles` (rad, in the scan plane), cast from the
    true pose against the true world, expressed with the estimated pose.

    Args:
        caster: ray caster of the true world.
        model: mount, range, beam width, grazing limit and noise (beam pattern, threshold,
            surface multipath, clutter, dropouts, range noise).
        angles: (n,) beam angles, rad (ignored when `geometry` is given).
        true_state, estimated_state: 12-vectors.
        rng: generator for the noise (required if model.noise is enabled).
        geometry: `beam_geometry(model, angles)`, precomputed by callers that repeat angles.
    """
    return scan_with_hits(caster, model, angles, true_state, estimated_state, rng, time,
                          sequence, geometry, axis_hits=False)[0]


def scan_with_hits(caster: RayCaster, model: SonarModel, angles, true_state, estimated_state,
                   rng: np.random.Generator | None = None, time: float = 0.0,
                   sequence: int = 0, geometry: BeamGeometry | None = None,
                   axis_hits: bool = True) -> tuple[SonarReturns, AxisHits | None]:
    """`scan` and the `AxisHits` of its first cast (one ray query serves both; None with
    `axis_hits` False, when no one scores the beams). The rays of the whole update go to
    Embree in one call; every array is made once, read-only, and the per-ping work is a
    fixed handful of vectorised operations (no per-beam Python)."""
    g = geometry if geometry is not None else beam_geometry(model, angles)
    noise = model.noise
    if noise.enabled and rng is None:
        raise ValueError("scan: a seeded rng is required when noise is enabled")
    p_wb, r_wb = pose(true_state)
    p_nb, r_nb = pose(estimated_state)
    mount = model.mount
    origin_w = p_wb + r_wb @ mount.position
    rays_w = g.rays_body @ r_wb.T
    ranges, faces = caster.cast_unit(origin_w, rays_w, model.max_range)
    m = g.rays_per_beam
    hits = None
    if axis_hits:
        hits = AxisHits(float(time), _read_only(origin_w), _read_only(rays_w[::m]),
                        _read_only(faces[::m].copy()), float(model.max_range))
    rays_echo = rays_w
    if noise.surface_prob > 0:
        rays_echo = _surface_multipath(caster, origin_w, rays_w, ranges, faces,
                                       model.max_range, noise.surface_prob, rng)
    # Grazing rays scatter away: no echo beyond max_incidence from the normal; weak echoes
    # (gain * cos^2 of the incidence) stay below the detection threshold. (take's "clip"
    # reads face 0 for the misses, whose range is NaN anyway.)
    cos_inc = np.abs(np.einsum("ij,ij->i", caster.face_normals.take(faces, 0, mode="clip"),
                               rays_echo))
    lost = cos_inc < model.min_echo_cosine
    if noise.echo_threshold > 0:
        lost |= g.gains_per_ray * cos_inc ** 2 < noise.echo_threshold
    ranges[lost] = np.nan
    if m > 1:  # the nearest echo inside the beam (fmin skips NaN)
        ranges = np.fmin.reduce(ranges.reshape(-1, m), axis=1)
    d_b = g.directions_body
    if noise.enabled:
        ranges = apply_noise(ranges, model.max_range, noise, rng)
    returns = SonarReturns.of_scan(
        float(time), _read_only(p_nb + r_nb @ mount.position), g.angles,
        _read_only(ranges.astype(float, copy=False)),  # Embree's float32 when clean
        _read_only(d_b @ r_nb.T), float(model.max_range), int(sequence), mount.position, d_b,
        p_nb, r_nb)
    return returns, hits


def _read_only(array: np.ndarray) -> np.ndarray:
    """`array` (a fresh float array or view the caller owns) made read-only in place."""
    array.setflags(write=False)
    return array
