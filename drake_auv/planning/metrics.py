"""Metrics of a coverage path (the reference's Table 3, plus coverage and clearance).

- length: 3D length of the segments of a label (a segment takes its end sample's label), m.
- viewing angle: at each imaging sample (not "transit") the sensor axis is cast against the
  terrain; the angle between the axis and the inward surface normal at the hit is the viewing
  angle (0 is ideal; for a down-looking sensor it is arctan of the slope). Mean and standard
  deviation over the samples, degrees; samples whose axis hits nothing within range are left
  out and counted in `blind_share`.
- coverage: share of the surface area of the valid ROI cells (area dx dy sqrt(1 + S^2)) seen by
  the sensor: a cell centre is seen from a sample when it lies within the aperture cone around
  the axis and within the sensor range. Occlusion is not modelled (the grid method); on height
  fields at offsets of a few metres it matters little, and the simulator's coverage recorder
  ray-casts the true mesh instead.
- clearance: signed distance from each sample to the terrain surface (3D, nearest point), m:
  negative below it or above the sea surface.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from drake_auv.jit import kernel
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.surface import TerrainSurface
from drake_auv.resources import map_chunks


@dataclass(frozen=True)
class SegmentMetrics:
    """Metrics of a set of path samples (one region's, the whole path's or the baseline's)."""

    length: float
    view_mean_deg: float
    view_sd_deg: float
    coverage: float
    min_clearance: float
    samples: int
    blind_share: float


@dataclass(frozen=True)
class PlanMetrics:
    """Table 3: per region of the combined path, its total, and the lawnmower baseline."""

    high_slope: SegmentMetrics
    planar: SegmentMetrics
    total: SegmentMetrics
    lawnmower: SegmentMetrics

    def rows(self) -> list[tuple[str, SegmentMetrics]]:
        return [("High-slope region", self.high_slope), ("Planar region", self.planar),
                ("Total (both regions)", self.total), ("Standard lawnmower path", self.lawnmower)]

    def to_dict(self) -> dict:
        return {name: asdict(m) for name, m in (("high_slope", self.high_slope),
                                               ("planar", self.planar), ("total", self.total),
                                               ("lawnmower", self.lawnmower))}

    @classmethod
    def from_dict(cls, record: dict) -> "PlanMetrics":
        """The metrics of a `to_dict` record as report.json holds it (null for a figure that
        is not a number, with its `KEY_null_reason` beside it)."""
        names = SegmentMetrics.__dataclass_fields__
        return cls(**{row: SegmentMetrics(**{k: float("nan") if fields[k] is None else fields[k]
                                             for k in names})
                      for row, fields in record.items()})


def viewing_angles(surface: TerrainSurface, points: np.ndarray, sensor_dir: np.ndarray,
                   sensor_range: float, chunk: int = 262144) -> np.ndarray:
    """(N,) viewing angle of each sample, rad (NaN where the axis hits nothing in range);
    `chunk` samples at a time on the usable cores (`resources.map_chunks`: each chunk's hits
    and normals are its own temporaries)."""
    def part(k: slice) -> np.ndarray:
        ranges, hits = surface.raycast(points[k], sensor_dir[k], sensor_range)
        n = surface.normal(hits[:, 0], hits[:, 1])
        cos = np.clip(-np.einsum("ij,ij->i", sensor_dir[k], n), -1.0, 1.0)
        return np.where(np.isfinite(ranges), np.arccos(cos), np.nan)

    return np.concatenate([np.zeros(0)] + map_chunks(part, len(points), chunk))


def coverage_mask(surface: TerrainSurface, points: np.ndarray, sensor_dir: np.ndarray,
                  aperture_deg: float, sensor_range: float, chunk: int = 65536) -> np.ndarray:
    """(ny, nx) bool: grid cells seen by at least one sample (cone and range test), `chunk`
    samples at a time on the usable cores (`resources.map_chunks`; `_mark_seen`)."""
    bathy = surface.bathy
    ny, nx = bathy.shape
    dx, dy = bathy.spacing
    half = np.radians(aperture_deg) / 2.0
    cos_half = np.cos(half)
    # Smallest sphere around the axis holding the cone truncated at the range (see module doc).
    if half < np.pi / 3:
        rho = sensor_range / (2.0 * np.cos(half))
        centre_offset = rho
    else:
        rho, centre_offset = sensor_range, 0.0
    ri, rj = int(np.ceil(rho / dy)), int(np.ceil(rho / dx))
    oi, oj = np.mgrid[-ri:ri + 1, -rj:rj + 1]
    keep = (oi * dy) ** 2 + (oj * dx) ** 2 <= (rho + 0.5 * np.hypot(dx, dy)) ** 2
    oi, oj = oi[keep], oj[keep]
    seen = np.zeros(ny * nx, dtype=bool)
    z = np.ascontiguousarray(surface.z, dtype=float)
    origin = np.asarray(bathy.origin, dtype=float)
    p = np.ascontiguousarray(points, dtype=float)
    d = np.ascontiguousarray(sensor_dir, dtype=float)
    range2, cos_half2 = float(sensor_range ** 2), float(cos_half ** 2)
    # the chunks only ever store True: their order is free
    map_chunks(lambda k: _mark_seen(z, origin, float(dx), float(dy), p[k], d[k],
                                    float(centre_offset), oi, oj, range2, cos_half2, seen),
               len(points), chunk)
    return seen.reshape(ny, nx)


@kernel
def _mark_seen(z, origin, dx, dy, points, axes, centre_offset, oi, oj, range2, cos_half2, seen):
    """`coverage_mask`'s test of each sample against the cells of the stencil (oi, oj) around
    the cell nearest to the centre of its bounding sphere: marks in `seen` (flat) the cells in
    its range and aperture cone."""
    ny, nx = z.shape
    for n in range(points.shape[0]):
        px, py, pz = points[n, 0], points[n, 1], points[n, 2]
        ax, ay, az = axes[n, 0], axes[n, 1], axes[n, 2]
        ci = int(np.rint((py + centre_offset * ay - origin[1]) / dy))
        cj = int(np.rint((px + centre_offset * ax - origin[0]) / dx))
        for m in range(len(oi)):
            i, j = ci + oi[m], cj + oj[m]
            if not (0 <= i < ny and 0 <= j < nx) or seen[i * nx + j]:
                continue
            vx = origin[0] + j * dx - px
            vy = origin[1] + i * dy - py
            vz = z[i, j] - pz
            dist2 = vx * vx + vy * vy + vz * vz
            along = vx * ax + vy * ay + vz * az
            if dist2 <= range2 and along > 0 and along * along >= cos_half2 * dist2:
                seen[i * nx + j] = True


def surface_area_weights(surface: TerrainSurface) -> np.ndarray:
    """(ny, nx) surface area of each cell, m^2 (dx dy sqrt(1 + S^2)), 0 for no-data."""
    dx, dy = surface.bathy.spacing
    w = dx * dy * np.sqrt(1.0 + surface.gx ** 2 + surface.gy ** 2)
    return np.where(surface.valid, w, 0.0)


def clearance(surface: TerrainSurface, points: np.ndarray, omega: float) -> np.ndarray:
    """(N,) signed clearance of each point to the surface, m (`TerrainSurface.signed_distance`:
    negative below it or above the sea surface; inf beyond 4 omega when some point is nearer;
    exact otherwise)."""
    d = surface.signed_distance(points, upper_bound=4.0 * omega)
    if not np.isfinite(d).any():
        d = surface.signed_distance(points)
    return d


def _summary(path: PlannedPath, mask: np.ndarray, angles: np.ndarray, dist: np.ndarray, seen: np.ndarray,
             region: np.ndarray, weights: np.ndarray) -> SegmentMetrics:
    """Metrics of the samples selected by `mask` from per-sample angles (NaN for transit or
    blind samples), distances and the cells they saw; coverage is over the cells of `region`."""
    length = float(path.segment_lengths()[mask[1:]].sum())
    n = int(mask.sum())
    if n == 0:
        return SegmentMetrics(length, float("nan"), float("nan"), 0.0, float("nan"), 0, 0.0)
    imaging = mask & (path.labels != "transit")
    a = angles[imaging]
    deg = np.degrees(a[np.isfinite(a)])
    area = float(weights[region].sum())
    return SegmentMetrics(
        length=length,
        view_mean_deg=float(deg.mean()) if deg.size else float("nan"),
        view_sd_deg=float(deg.std()) if deg.size else float("nan"),
        coverage=float(weights[region & seen].sum() / area) if area > 0 else float("nan"),
        min_clearance=float(dist[mask].min()),
        samples=n,
        blind_share=float(1.0 - deg.size / a.size) if a.size else 0.0,
    )


def evaluate_path(path: PlannedPath, surface: TerrainSurface, aperture_deg: float, sensor_range: float,
                  omega: float, groups: dict[str, tuple[np.ndarray, np.ndarray]],
                  weights: np.ndarray | None = None) -> dict[str, SegmentMetrics]:
    """Metrics of groups of samples of one path, computing each per-sample quantity once.

    `groups` maps a name to (sample mask, grid region whose coverage counts); a group's seen
    cells are those seen by its own imaging samples.
    """
    weights = surface_area_weights(surface) if weights is None else weights
    imaging = path.labels != "transit"
    dist = clearance(surface, path.points, omega)
    angles = np.full(len(path), np.nan)
    angles[imaging] = viewing_angles(surface, path.points[imaging], path.sensor_dir[imaging],
                                     sensor_range)
    seen_by_label = {}
    for lab in dict.fromkeys(path.labels[imaging].tolist()):
        m = path.labels == lab
        seen_by_label[lab] = coverage_mask(surface, path.points[m], path.sensor_dir[m],
                                           aperture_deg, sensor_range)
    out = {}
    for name, (mask, region) in groups.items():
        labels = set(path.labels[mask & imaging].tolist())
        seen = np.zeros(surface.z.shape, dtype=bool)
        for lab in labels:
            seen |= seen_by_label[lab]
        out[name] = _summary(path, mask, angles, dist, seen, region, weights)
    return out


def evaluate_plan(plan) -> PlanMetrics:
    """Table 3 for a `CoveragePlan`: per region, total, lawnmower."""
    surface = plan.surface
    p = plan.parameters
    aperture, rng, omega = p.aperture_deg, p.sensor_range, p.omega
    weights = surface_area_weights(surface)
    valid = surface.valid
    high = plan.labels.high
    path = plan.path
    m = evaluate_path(path, surface, aperture, rng, omega, {
        "high_slope": (path.labels == "slice", high),
        "planar": (path.labels == "planar", valid & ~high),
        "total": (np.ones(len(path), dtype=bool), valid)}, weights)
    lawn = plan.lawnmower
    b = evaluate_path(lawn, surface, aperture, rng, omega,
                      {"lawnmower": (np.ones(len(lawn), dtype=bool), valid)}, weights)
    return PlanMetrics(m["high_slope"], m["planar"], m["total"], b["lawnmower"])
