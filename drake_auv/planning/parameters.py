"""`CoverageParameters`: the off-line planner's parameters, each default and range stated once.

`plan_coverage` takes them, the mission's `plan` step exposes some of them under its own keys
(`drake_auv.mission.steps.plan.PlanStep`), and `drake-auv plan` offers them as options: all
three read the defaults and ranges declared here (`drake_auv.params.param`).
"""

from __future__ import annotations

from dataclasses import dataclass

from drake_auv.params import param, validate
from drake_auv.planning.orders import ORDERS

MAX_SLICES = 1000  # slicing planes per high-slope region (a slice_count or a slice_spacing)


@dataclass(frozen=True)
class CoverageParameters:
    """What `plan_coverage` plans with; None lets the planner choose (see each field).

    Attributes:
        omega: offset to the terrain, m.
        aperture_deg: sensor aperture, deg.
        overlap: overlap of neighbouring lanes and contours, fraction of the footprint.
        slope_threshold: delta_s, the slope |grad z| above which terrain is high-slope.
        sweep_angle_deg: lane direction of the planar cells, deg from +x (None: fewest lanes).
        slice_spacing: vertical spacing of the slicing planes, m (None: from the footprint).
        slice_count: slicing planes per high-slope region, centred on its elevation range
            (None: as many as cover the region at `slice_spacing`).
        sample_spacing: largest distance between path samples, m (None: Omega / 4).
        sensor_range: largest range at which the sensor sees, m, for metrics (None: 2 Omega).
        slice_sensor: on high-slope regions the sensor looks along the inward surface normal
            ("normal") or keeps one tilt per region matched to its median slope ("fixed-tilt").
        min_depth: minimum operating depth, m: cells shallower than it are no-go and no
            sample lies above z = -min_depth.
        order: IHO S-44 survey order (`planning.orders.ORDERS`): the lane spacing is divided
            by its coverage factor (None: 100 %).
        closing_radius, opening_radius, min_area: the classification's clean-up, m, m, m^2
            (None: `terrain.slope.classify`'s defaults).
    """

    omega: float = param(2.0, low=0.5, high=100.0, unit="m")
    aperture_deg: float = param(60.0, low=5.0, high=170.0, unit="deg")
    overlap: float = param(0.1, low=0.0, high=0.9)
    slope_threshold: float = param(0.5, low=0.0, high=10.0, low_open=True)
    sweep_angle_deg: float | None = param(None, unit="deg", nullable=True,
                                          note="a finite angle in degrees")
    slice_spacing: float | None = param(None, low=0.0, high=50.0, low_open=True, unit="m",
                                        nullable=True)
    slice_count: int | None = param(None, low=1, high=MAX_SLICES, integer=True, nullable=True)
    sample_spacing: float | None = param(None, low=0.0, low_open=True, unit="m", nullable=True)
    sensor_range: float | None = param(None, low=0.0, low_open=True, unit="m", nullable=True)
    slice_sensor: str = param("normal", kind="choice", choices=("normal", "fixed-tilt"))
    min_depth: float = param(1.0, low=0.0, unit="m")
    order: str | None = param(None, kind="choice", choices=tuple(ORDERS), nullable=True)
    closing_radius: float | None = param(None, low=0.0, unit="m", nullable=True)
    opening_radius: float | None = param(None, low=0.0, unit="m", nullable=True)
    min_area: float | None = param(None, low=0.0, unit="m^2", nullable=True)

    def __post_init__(self):
        validate(self)
