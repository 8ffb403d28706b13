"""IHO S-44 edition 6 survey orders: the coverage each asks for, set through the lane spacing,
and what the plan achieves.

From the standard's table of minimum standards (IHO S-44 ed. 6.0.0, 2020; its uncertainty
limits are not used here): Exclusive order, cubic features > 0.5 m detected, 200 %
coverage; Special, > 1 m, 100 %; 1a, > 2 m down to 40 m depth and 10 % of the depth beyond,
100 %; 1b and 2, no feature detection, 5 %.

Lane spacing: the footprint 2 Omega tan(aperture / 2), shrunk by the overlap margin, divided by
the coverage factor (2 for 200 %: every point under two swaths; 0.05 for 5 %: systematic
lines 20 footprints apart). Achieved coverage: the share of the valid surface area seen by at
least ceil(factor) separate passes (a pass: a lane between turns, or one contour piece; 5 %:
seen at all). Detectable feature size: a cube is detected when it holds at least 3 soundings
across and along the swath (`SOUNDINGS_PER_FEATURE`) and cannot hide in a coverage gap, so
the size is the larger of 3 times the sounding spacing (Omega times the beam spacing across,
speed / ping rate along) and the diameter of the largest unseen disk in the area.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage


@dataclass(frozen=True)
class SurveyOrder:
    """One order: name, coverage factor (1 = 100 %), and the feature size it must detect, m
    (None: no feature detection), given as a size and a share of the depth beyond 40 m."""

    name: str
    coverage: float
    feature_size: float | None
    feature_share_beyond_40m: float | None = None

    def required_feature(self, depth: float) -> float | None:
        """Feature size to detect at `depth` (m, positive down), m."""
        if self.feature_size is None:
            return None
        if self.feature_share_beyond_40m is not None and depth > 40.0:
            return self.feature_share_beyond_40m * depth
        return self.feature_size


ORDERS = {
    "exclusive": SurveyOrder("Exclusive", 2.0, 0.5),
    "special": SurveyOrder("Special", 1.0, 1.0),
    "1a": SurveyOrder("1a", 1.0, 2.0, 0.10),
    "1b": SurveyOrder("1b", 0.05, None),
    "2": SurveyOrder("2", 0.05, None),
}
SOUNDINGS_PER_FEATURE = 3


def survey_order(name: str) -> SurveyOrder:
    """The order named `name` (case-insensitive); ValueError naming the allowed ones."""
    key = str(name).strip().lower()
    if key not in ORDERS:
        raise ValueError(f"--order: unknown IHO S-44 order {name!r}; choose from "
                         f"{', '.join(ORDERS)}")
    return ORDERS[key]


def pass_ids(path) -> np.ndarray:
    """(N,) index of the pass each sample belongs to: a new pass at every label change and
    every lane turn (heading change over 60 degrees between consecutive samples)."""
    turn = np.abs(np.angle(np.exp(1j * np.diff(path.heading)))) > np.radians(60.0)
    change = path.labels[1:] != path.labels[:-1]
    return np.concatenate([[0], np.cumsum(turn | change)])


def coverage_multiplicity(surface, path, aperture_deg: float, sensor_range: float) -> np.ndarray:
    """(ny, nx) number of separate passes (`pass_ids`) whose imaging samples see each cell."""
    from drake_auv.planning.metrics import coverage_mask

    counts = np.zeros(surface.z.shape, dtype=np.int32)
    ids = pass_ids(path)
    imaging = path.labels != "transit"
    for k in np.unique(ids[imaging]):
        m = imaging & (ids == k)
        counts += coverage_mask(surface, path.points[m], path.sensor_dir[m], aperture_deg,
                                sensor_range)
    return counts


def order_report(plan, order: SurveyOrder, beam_spacing_deg: float = 0.25,
                 speed: float = 0.5, ping_rate: float = 10.0) -> dict:
    """Order, coverage target and achieved, and the detectable feature size against the
    order's (see the module docstring). Defaults: the DeltaT multibeam's 120 deg / 480 beams,
    a 0.5 m/s survey and a 10 Hz ping rate."""
    p = plan.parameters
    surface = plan.surface
    counts = coverage_multiplicity(surface, plan.path, p.aperture_deg, p.sensor_range)
    from drake_auv.planning.metrics import surface_area_weights

    w = surface_area_weights(surface)
    valid = surface.valid
    need = max(1, int(np.ceil(order.coverage - 1e-9)))
    achieved = float(w[valid & (counts >= need)].sum() / w[valid].sum())
    unseen = valid & (counts == 0)
    gap = 0.0
    if unseen.any():
        dist = ndimage.distance_transform_edt(unseen, sampling=surface.bathy.spacing[::-1])
        gap = float(2.0 * dist.max())
    across = p.omega * np.radians(beam_spacing_deg)
    along = speed / ping_rate
    resolution = SOUNDINGS_PER_FEATURE * max(across, along)
    size = max(resolution, gap)
    depth = float(-np.nanmax(surface.bathy.z))  # shallowest: the strictest 1a requirement
    required = order.required_feature(depth)
    return {"order": order.name, "coverage_target_percent": 100.0 * order.coverage,
            "lane_spacing_m": plan.lane_spacing,
            "achieved_percent": 100.0 * achieved, "passes_needed": need,
            "mean_passes_per_cell": float((counts[valid] * w[valid]).sum() / w[valid].sum()),
            "detectable_feature_m": size, "largest_gap_m": gap,
            "sounding_resolution_m": resolution,
            "required_feature_m": required,
            "meets_feature_detection": None if required is None else bool(size <= required)}
