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
- clearance: distance from each sample to the terrain surface (3D, nearest point), m.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from drake_auv.planning.path import Path
from drake_auv.planning.surface import TerrainSurface


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


def viewing_angles(surface: TerrainSurface, points: np.ndarray, sensor_dir: np.ndarray,
                   sensor_range: float) -> np.ndarray:
    """(N,) viewing angle of each sample, rad (NaN where the axis hits nothing in range)."""
    ranges, hits = surface.raycast(points, sensor_dir, sensor_range)
    n = surface.normal(hits[:, 0], hits[:, 1])
    cos = np.clip(-np.einsum("ij,ij->i", sensor_dir, n), -1.0, 1.0)
    return np.where(np.isfinite(ranges), np.arccos(cos), np.nan)


def coverage_mask(surface: TerrainSurface, points: np.ndarray, sensor_dir: np.ndarray,
                  aperture_deg: float, sensor_range: float, chunk: int = 4096) -> np.ndarray:
    """(ny, nx) bool: grid cells seen by at least one sample (cone and range test)."""
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
    z = surface.z
    for k in range(0, len(points), chunk):
        p = points[k:k + chunk]
        d = sensor_dir[k:k + chunk]
        c = p[:, :2] + centre_offset * d[:, :2]
        ci = np.rint((c[:, 1] - bathy.origin[1]) / dy).astype(int)
        cj = np.rint((c[:, 0] - bathy.origin[0]) / dx).astype(int)
        ii = ci[:, None] + oi[None, :]
        jj = cj[:, None] + oj[None, :]
        ok = (ii >= 0) & (ii < ny) & (jj >= 0) & (jj < nx)
        ii, jj = np.clip(ii, 0, ny - 1), np.clip(jj, 0, nx - 1)
        vx = bathy.origin[0] + jj * dx - p[:, 0:1]
        vy = bathy.origin[1] + ii * dy - p[:, 1:2]
        vz = z[ii, jj] - p[:, 2:3]
        dist2 = vx * vx + vy * vy + vz * vz
        along = vx * d[:, 0:1] + vy * d[:, 1:2] + vz * d[:, 2:3]
        inside = ok & (dist2 <= sensor_range ** 2) & (along > 0) & (along * along >= cos_half ** 2 * dist2)
        seen[(ii * nx + jj)[inside]] = True
    return seen.reshape(ny, nx)


def surface_area_weights(surface: TerrainSurface) -> np.ndarray:
    """(ny, nx) surface area of each cell, m^2 (dx dy sqrt(1 + S^2)), 0 for no-data."""
    dx, dy = surface.bathy.spacing
    w = dx * dy * np.sqrt(1.0 + surface.gx ** 2 + surface.gy ** 2)
    return np.where(surface.valid, w, 0.0)


def evaluate_samples(path: Path, mask: np.ndarray, surface: TerrainSurface, aperture_deg: float,
                     sensor_range: float, region: np.ndarray, weights: np.ndarray) -> SegmentMetrics:
    """Metrics of the samples of `path` selected by `mask`; coverage is the seen share of the
    surface area of the cells in `region` (bool grid), counting imaging samples only."""
    seg = path.segment_lengths()
    length = float(seg[mask[1:]].sum())
    pts = path.points[mask]
    dirs = path.sensor_dir[mask]
    if len(pts) == 0:
        return SegmentMetrics(length, float("nan"), float("nan"), 0.0, float("nan"), 0, 0.0)
    imaging = path.labels[mask] != "transit"
    angles = viewing_angles(surface, pts[imaging], dirs[imaging], sensor_range)
    finite = np.isfinite(angles)
    deg = np.degrees(angles[finite])
    seen = coverage_mask(surface, pts[imaging], dirs[imaging], aperture_deg, sensor_range)
    area = float(weights[region].sum())
    coverage = float(weights[region & seen].sum() / area) if area > 0 else float("nan")
    clearance, _ = surface.distance(pts)
    return SegmentMetrics(
        length=length,
        view_mean_deg=float(deg.mean()) if deg.size else float("nan"),
        view_sd_deg=float(deg.std()) if deg.size else float("nan"),
        coverage=coverage,
        min_clearance=float(clearance.min()),
        samples=int(len(pts)),
        blind_share=float(1.0 - finite.mean()) if finite.size else 0.0,
    )


def evaluate_plan(plan) -> PlanMetrics:
    """Table 3 for a `CoveragePlan`: per region, total, lawnmower."""
    surface = plan.surface
    p = plan.parameters
    aperture, rng = p["aperture_deg"], p["sensor_range"]
    weights = surface_area_weights(surface)
    valid = surface.valid
    high = plan.labels.high
    path = plan.path
    everything = np.ones(len(path), dtype=bool)
    return PlanMetrics(
        high_slope=evaluate_samples(path, path.labels == "slice", surface, aperture, rng, high, weights),
        planar=evaluate_samples(path, path.labels == "planar", surface, aperture, rng,
                                valid & ~high, weights),
        total=evaluate_samples(path, everything, surface, aperture, rng, valid, weights),
        lawnmower=evaluate_samples(plan.lawnmower, np.ones(len(plan.lawnmower), dtype=bool),
                                   surface, aperture, rng, valid, weights),
    )
