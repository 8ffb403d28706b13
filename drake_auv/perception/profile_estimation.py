"""Estimation of the local profile from 2D scan-plane points: distance, orientation, normal.

Input: points of the local map in a 2D frame centred on the vehicle (see `local_map`).
Steps (all our choices, the reference does not publish its regression):

1. Window and sector: keep the points within `window` metres of the vehicle and, when a look
   direction is given, within `sector` radians of it (the sector ahead of the motion).
2. Density filter: drop points with fewer than `min_neighbours` others within `density_radius`;
   spurious returns are isolated, surfaces are sampled densely by consecutive pings.
3. Sequential RANSAC line extraction (seeded; inliers weighted by 1 / (0.5 m + range) so that
   the profile beside the vehicle wins over a longer far wall), each line refined by total least squares (the
   principal axis of its inliers, exact on vertical walls, unlike y-on-x regression) and cut
   into contiguous pieces along the line; the piece nearest to the vehicle becomes a segment,
   the rest go back to the pool. Up to `max_lines` segments: one on a wall, two at a corner or
   an overhang (a wall under a ceiling).
4. Distance = distance from the vehicle to the nearest segment. Normal (unit, from the profile
   to the vehicle) = the blend of the directions from each segment's nearest point to the
   vehicle, weighted by exp(-(d_k - d_min) / blend): near a concave corner it turns smoothly
   towards the bisector instead of jumping from one wall to the next; around a convex corner
   (segment end) it rotates about the end point.
5. Normal distance: the range from the vehicle along -normal to the segments, the distance a
   sensor facing the profile measures (longer than the nearest distance in a concave corner).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from drake_auv.params import param, validate


@dataclass(frozen=True)
class EstimatorParams:
    """Parameters of `estimate_profile` (metres and radians).

    window: radius around the vehicle of the points considered, m.
    sector: half-angle of the sector around the look direction, rad, in (0, pi].
    density_radius, min_neighbours: density filter against spurious returns.
    ransac_iterations, inlier_tolerance: RANSAC; tolerance is the inlier distance, m.
    min_inliers: points a segment needs.
    gap: a segment is cut where consecutive inliers along it are further apart, m.
    max_lines: segments extracted at most.
    blend: softness of the normal blend between segments, m.
    """

    window: float = param(6.0, low=0.0, low_open=True, unit="m")
    sector: float = param(np.radians(135.0), low=0.0, high=np.pi, low_open=True, unit="rad")
    density_radius: float = param(0.4, low=0.0, low_open=True, unit="m")
    min_neighbours: int = param(2, low=0, integer=True)
    ransac_iterations: int = param(80, low=1, integer=True)
    inlier_tolerance: float = param(0.12, low=0.0, low_open=True, unit="m")
    min_inliers: int = param(8, low=3, integer=True)
    gap: float = param(0.8, low=0.0, low_open=True, unit="m")
    max_lines: int = param(3, low=1, integer=True)
    blend: float = param(0.4, low=0.0, low_open=True, unit="m")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class Segment:
    """A fitted straight piece of profile: end points (2,), unit direction, inlier count."""

    start: np.ndarray
    end: np.ndarray
    direction: np.ndarray
    n_inliers: int

    def closest_point(self, q) -> np.ndarray:
        """The point of the segment nearest to `q` (2,)."""
        length = np.linalg.norm(self.end - self.start)
        t = np.clip((np.asarray(q) - self.start) @ self.direction, 0.0, length)
        return self.start + t * self.direction


@dataclass(frozen=True)
class ProfileEstimate:
    """The local profile as seen from the vehicle (at the origin of the 2D frame).

    distance: distance to the nearest segment, m.
    normal: (2,) unit vector from the profile to the vehicle.
    closest_point: (2,) nearest point of the profile.
    orientation: direction angle of the nearest segment, rad, in (-pi/2, pi/2].
    segments: the fitted segments, nearest first.
    n_points: points used after windowing and the density filter.
    normal_distance: range along -normal to the segments (>= distance), m.
    """

    distance: float
    normal: np.ndarray
    closest_point: np.ndarray
    orientation: float
    segments: tuple
    n_points: int
    normal_distance: float


def estimate_profile(points, params: EstimatorParams = EstimatorParams(), rng=None,
                     look_direction=None, previous_normal=None) -> ProfileEstimate | None:
    """Estimates the local profile from (n, 2) points around the vehicle; None when no segment
    with `min_inliers` points is found.

    Args:
        points: (n, 2) points relative to the vehicle, m (NaN rows are ignored).
        params: `EstimatorParams`.
        rng: numpy Generator for RANSAC (default: seed 0, so the result is deterministic).
        look_direction: (2,) direction of the sector ahead; None uses all directions.
        previous_normal: (2,) used only to orient the normal if the vehicle sits on a segment.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    rng = np.random.default_rng(0) if rng is None else rng
    r = np.linalg.norm(pts, axis=1)
    keep = r <= params.window
    if look_direction is not None:
        look = np.asarray(look_direction, dtype=float)
        if look.shape != (2,) or not np.all(np.isfinite(look)) or np.linalg.norm(look) < 1e-9:
            raise ValueError(f"look_direction must be a finite non-zero 2-vector, got {look_direction!r}")
        look = look / np.linalg.norm(look)
        cos_angle = (pts @ look) / np.maximum(r, 1e-9)
        keep &= cos_angle >= np.cos(params.sector)
    pts = pts[keep]
    if len(pts) < params.min_inliers:
        return None
    if params.min_neighbours > 0:
        counts = cKDTree(pts).query_ball_point(pts, params.density_radius, return_length=True)
        pts = pts[counts - 1 >= params.min_neighbours]
    n_points = len(pts)
    segments = []
    pool = pts
    while len(segments) < params.max_lines and len(pool) >= params.min_inliers:
        found = _extract_segment(pool, params, rng)
        if found is None:
            break
        segment, used = found
        segments.append(segment)
        pool = pool[~used]
    if not segments:
        return None
    closest = np.array([s.closest_point(np.zeros(2)) for s in segments])
    dists = np.linalg.norm(closest, axis=1)
    order = np.argsort(dists)
    segments = [segments[i] for i in order]
    closest, dists = closest[order], dists[order]
    d_min = float(dists[0])
    weights = np.exp(-(dists - d_min) / params.blend)
    units = np.empty_like(closest)
    for k, (c, d) in enumerate(zip(closest, dists)):
        if d > 1e-6:
            units[k] = -c / d
        else:  # on the line: the line normal, on the side of the previous normal
            nrm = np.array([-segments[k].direction[1], segments[k].direction[0]])
            if previous_normal is not None and nrm @ np.asarray(previous_normal) < 0:
                nrm = -nrm
            units[k] = nrm
    normal = weights @ units
    norm = np.linalg.norm(normal)
    normal = units[0] if norm < 1e-6 else normal / norm
    direction = segments[0].direction
    orientation = float(np.arctan2(direction[1], direction[0]))
    if orientation <= -np.pi / 2:
        orientation += np.pi
    elif orientation > np.pi / 2:
        orientation -= np.pi
    normal_distance = max(_ray_distance(-normal, segments, params.inlier_tolerance), d_min)
    return ProfileEstimate(d_min, normal, closest[0], orientation, tuple(segments), n_points,
                           normal_distance)


def _ray_distance(direction, segments, tolerance) -> float:
    """Range from the origin along `direction` to the nearest segment (each extended by
    `tolerance` at its ends so a ray through a vertex hits); inf when none is hit."""
    best = np.inf
    for seg in segments:
        e = seg.direction
        den = direction[0] * e[1] - direction[1] * e[0]
        if abs(den) < 1e-9:
            continue
        a = seg.start
        t = (a[0] * e[1] - a[1] * e[0]) / den
        u = (a[0] * direction[1] - a[1] * direction[0]) / den
        if t > 0 and -tolerance <= u <= np.linalg.norm(seg.end - seg.start) + tolerance:
            best = min(best, t)
    return float(best)


def _extract_segment(pool: np.ndarray, params: EstimatorParams, rng):
    """RANSAC + TLS line in `pool`; returns (nearest contiguous Segment, mask of its points)."""
    n = len(pool)
    pairs = rng.integers(0, n, size=(params.ransac_iterations, 2))
    a, b = pool[pairs[:, 0]], pool[pairs[:, 1]]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    valid = length > 1e-6
    if not np.any(valid):
        return None
    a, d, length = a[valid], d[valid], length[valid]
    normals = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]
    residual = np.abs(pool @ normals.T - np.sum(a * normals, axis=1)).T  # (k, n)
    hits = residual <= params.inlier_tolerance
    # score favours near lines: far walls must not win over the profile beside the vehicle
    score = hits @ (1.0 / (0.5 + np.linalg.norm(pool, axis=1)))
    best = int(np.argmax(score))
    if np.count_nonzero(hits[best]) < params.min_inliers:
        return None
    inliers = residual[best] <= params.inlier_tolerance
    for _ in range(2):  # total least squares refinement, then re-select the inliers
        centre, direction = _tls_line(pool[inliers])
        normal = np.array([-direction[1], direction[0]])
        refined = np.abs((pool - centre) @ normal) <= params.inlier_tolerance
        if np.count_nonzero(refined) < params.min_inliers:
            break
        inliers = refined
    centre, direction = _tls_line(pool[inliers])
    idx = np.flatnonzero(inliers)
    t = (pool[idx] - centre) @ direction
    order = np.argsort(t)
    idx, t = idx[order], t[order]
    pieces = np.split(np.arange(len(t)), np.flatnonzero(np.diff(t) > params.gap) + 1)
    # the contiguous piece nearest to the vehicle (origin)
    dist = [np.min(np.linalg.norm(pool[idx[p]], axis=1)) for p in pieces]
    piece = pieces[int(np.argmin(dist))]
    if len(piece) < params.min_inliers:
        return None
    members = idx[piece]
    centre, direction = _tls_line(pool[members])
    t = (pool[members] - centre) @ direction
    segment = Segment(centre + t.min() * direction, centre + t.max() * direction, direction,
                      len(members))
    used = np.zeros(n, dtype=bool)
    used[members] = True
    return segment, used


def _tls_line(points: np.ndarray):
    """Total least squares line: (centroid, unit principal direction)."""
    centre = points.mean(axis=0)
    d = points - centre
    _, vectors = np.linalg.eigh(d.T @ d)  # 2 x 2 scatter matrix, ascending eigenvalues
    return centre, vectors[:, 1]
