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
along its axis, the nearest echo above the detection threshold (`SonarNoise`). With many
off-axis rays (a multibeam's side lobes) the axes are cast first and the other rays only as
far as their axis's echo, beyond which they cannot be the nearest: the same returns, bit for
bit, as one query of every ray to the full range, in less Embree time (docs/benchmarks.md).
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


# Off-axis rays of an update (side lobes, cone edges) below which they are cast with the axes
# in one query: a pencil beam's 3 pings x 8 do not repay a second query, a multibeam's 480 x 2
# side lobes do, most cast only to their axis's echo (measured: docs/benchmarks.md).
_SHORT_QUERY_RAYS = 256
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

    angles (n,) rad; directions_body (n, 3) beam axes; rays_body (n * m, 3) the rays cast,
    beam by beam (m per beam: the axis, the cone edge when the beam has a width, the side lobe
    when it has one); ray_gains (m,) their two-way gains and gains_per_ray (n * m,) the same
    per ray cast; side_rays_body (n * (m - 1), 3) the rays off the axes (`rays_body` without
    them) and side_gains (n * (m - 1),) their gains.
    The arrays are read-only, so the returns share them.
    """

    angles: np.ndarray
    directions_body: np.ndarray
    rays_body: np.ndarray
    rays_per_beam: int
    ray_gains: np.ndarray
    gains_per_ray: np.ndarray
    side_rays_body: np.ndarray
    side_gains: np.ndarray


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
                        _frozen(gains), _frozen(np.tile(gains, len(angles))),
                        _frozen(rays[:, 1:].reshape(-1, 3) @ rotation.T),
                        _frozen(np.tile(gains[1:], len(angles))))


def pose(state) -> tuple[np.ndarray, np.ndarray]:
    """(position (3,), R_WB (3, 3)) of a 12-vector state."""
    values = np.asarray(state, dtype=float)[:6].tolist()  # Python floats: cheap scalar maths
    if len(values) < 6 or not all(map(math.isfinite, values)):
        raise ValueError("state must start with a finite [x, y, z, roll, pitch, yaw]")
    x, y, z, roll, pitch, yaw = values
    return np.array((x, y, z)), rotation_world_body(roll, pitch, yaw)


def _surface_multipath(caster: RayCaster, origin: np.ndarray, rays: np.ndarray,
                       ranges: np.ndarray, faces: np.ndarray, reach, probability: float,
                       draws: np.ndarray):
    """Rays (world frame, from `origin` below the sea surface) that reach the surface z = 0
    within `reach` (m, scalar or one per ray) before any echo end there: those whose uniform
    `draws` (one per ray) fall below `probability` are mirrored and cast on for the rest of
    the reach, their echo coming back the same way at the total path length; the others are
    scattered away (no echo). Updates `ranges` (path lengths, m) and `faces` in place; returns
    the directions of the rays as they meet those faces (`rays` itself when none was
    mirrored)."""
    rise = rays[:, 2]
    up = rise > 1e-9
    if not up.any():
        return rays
    t = np.where(up, -origin[2] / np.maximum(rise, 1e-9), np.inf)
    at_surface = (t < reach) & ~(ranges <= t)  # NaN (no hit) compares False
    reflected = at_surface & (draws < probability)
    ranges[at_surface], faces[at_surface] = np.nan, -1
    if reflected.any():
        rays = rays.copy()
        mirrored = rays[reflected] * [1.0, 1.0, -1.0]
        t_r = t[reflected]
        rest = (reach[reflected] if np.ndim(reach) else reach) - t_r
        r2, f2 = caster.cast_unit(origin + t_r[:, None] * rays[reflected], mirrored, rest)
        ranges[reflected], faces[reflected], rays[reflected] = t_r + r2, f2, mirrored
    return rays


def _echoes(caster: RayCaster, model: SonarModel, origin: np.ndarray, rays: np.ndarray,
            reach, gains, draws: np.ndarray | None):
    """Cast `rays` (k, 3, world frame, unit) from `origin` up to `reach` (m, scalar or (k,)):
    (ranges (k,) of their detected echoes, NaN where none, faces (k,) of the first cast, -1
    for none). The surface multipath (with `draws`, one per ray; None: no multipath), the
    grazing limit and, with the threshold, the rays' `gains` (scalar or (k,)) decide which
    echoes are detected."""
    ranges, faces = caster.cast_unit(origin, rays, reach)
    first_faces, echo_rays = faces, rays
    if draws is not None:
        first_faces = faces.copy()
        echo_rays = _surface_multipath(caster, origin, rays, ranges, faces, reach,
                                       model.noise.surface_prob, draws)
    # Grazing rays scatter away: no echo beyond max_incidence from the normal; weak echoes
    # (gain * cos^2 of the incidence) stay below the detection threshold. (take's "clip"
    # reads face 0 for the misses, whose range is NaN anyway.)
    cos_inc = np.abs(np.einsum("ij,ij->i", caster.face_normals.take(faces, 0, mode="clip"),
                               echo_rays))
    lost = cos_inc < model.min_echo_cosine
    if model.noise.echo_threshold > 0:
        lost |= gains * cos_inc ** 2 < model.noise.echo_threshold
    ranges[lost] = np.nan
    return ranges, first_faces


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
    m = g.rays_per_beam
    # The multipath's draws: one per ray, beam by beam, axis first.
    draws = (rng.random(len(g.rays_body)).reshape(-1, m)
             if noise.surface_prob > 0 and origin_w[2] < 0 else None)
    two_queries = m > 1 and len(g.side_rays_body) >= _SHORT_QUERY_RAYS
    if not two_queries:  # all rays in one query
        rays_w = g.rays_body @ r_wb.T
        ranges, faces = _echoes(caster, model, origin_w, rays_w, model.max_range,
                                g.gains_per_ray, None if draws is None else draws.ravel())
        axes_w, faces = rays_w[::m], faces[::m].copy()
        if m > 1:  # the nearest echo inside the beam (fmin skips NaN)
            ranges = np.fmin.reduce(ranges.reshape(-1, m), axis=1)
    else:
        axes_w = g.directions_body @ r_wb.T
        ranges, faces = _echoes(caster, model, origin_w, axes_w, model.max_range,
                                g.ray_gains[0], None if draws is None else draws[:, 0])
    hits = None
    if axis_hits:
        hits = AxisHits(float(time), _read_only(origin_w), _read_only(axes_w),
                        _read_only(faces), float(model.max_range))
    if two_queries:
        # The beam reports its nearest echo, so a ray off the axis counts only where it echoes
        # nearer than the axis: it is cast no farther than the axis's echo (a hair beyond,
        # for ties; the whole range where the axis has none), most of them a short query.
        reach = np.repeat(np.fmin(ranges * (1.0 + 1e-6) + 1e-6, model.max_range), m - 1)
        side, _ = _echoes(caster, model, origin_w, g.side_rays_body @ r_wb.T, reach,
                          g.side_gains, None if draws is None else draws[:, 1:].ravel())
        ranges = np.fmin(ranges, np.fmin.reduce(side.reshape(-1, m - 1), axis=1))
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
