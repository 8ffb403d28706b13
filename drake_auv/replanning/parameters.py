"""The replanning loop's parameters: the section's size, the cost's weights, STOMP's
settings; shared by the section (`replanning.section`) and its cost (`replanning.cost`)."""

from __future__ import annotations

from dataclasses import dataclass

from drake_auv.params import nested, param, validate
from drake_auv.replanning.stomp import StompParameters


@dataclass(frozen=True)
class ReplanningParameters:
    """Parameters of the replanning loop (cost weights: docs/replanning.md, "Cost"); ranges
    in the fields' `param` metadata, `key`: the mission file's name of a field.

    Attributes:
        radius: R, waypoints closer than this to the vehicle form the section, m.
        max_waypoints: K, most waypoints in one section.
        omega: offset to keep from the mapped structure, m (> 0).
        clearance: distance to any occupied voxel under which the obstacle cost rises, m.
        depth_band: half-height of the band of voxels the offset is measured against, m (> 0).
        offset_metric: "horizontal": the offset is the horizontal distance to the band's
            voxels (walls with the seabed closer than Omega below, as at the breakwater);
            "3d": the 3D distance to any voxel, the offset along the surface normal of the
            slicing planner (sloping faces, as on the boulder).
        spacing: distance between trajectory points, m (> 0).
        margin: how far the optimised trajectory may leave the initial one (the largest
            prior-map plus navigation error the plan assumes), m (> 0); sizes the map query.
        min_log_odds: log-odds a voxel needs to count in the cost (1.5: two hits more than
            the misses, with OctoMap's 0.7 / 0.4 model one hit is 0.85), >= 0.
        huber: |d - Omega| beyond which the offset cost grows linearly, m (> 0).
        offset_weight, obstacle_weight, depth_weight, route_weight, progress_weight,
        terminal_weight, spacing_weight: cost weights (>= 0), per trajectory point.
        crossing_weight: weight of the crossing term (>= 0), per metre of a segment between
            trajectory points inside a mapped voxel: 10^4, so one face crossed (0.5 m) costs
            more than a section's other terms together (tens to hundreds a point).
        current_aware: with a forecast current, the cost knows it (`ReplanningCost`: effort in
            the velocity through the water, clearance inflated where the current pushes
            towards the structure); False: the current-blind cost of still water.
        current_weight: weight of the effort term (>= 0), per point.
        current_margin_s: tau, the clearance grows by tau times the current's speed towards
            the nearest voxel, s: the distance the water carries a vehicle that cannot answer
            it (thrust spent, or a change of current the tracker's integral, 5.3 s time
            constant, has not yet taken up) in that time (docs/replanning.md).
        stomp: `StompParameters` (rollouts, iterations, noise, smoothness weight).
    """

    radius: float = param(5.0, low=0.5, high=50.0, unit="m", key="R")
    max_waypoints: int = param(10, low=1, high=200, integer=True, key="K")
    omega: float = param(6.0, low=0.0, low_open=True, unit="m")
    clearance: float = param(4.0, low=0.5, high=20.0, unit="m", key="clearance_m")
    depth_band: float = param(1.5, low=0.0, low_open=True, unit="m")
    offset_metric: str = param("horizontal", kind="choice", choices=("horizontal", "3d"))
    spacing: float = param(0.5, low=0.0, low_open=True, unit="m")
    margin: float = param(6.0, low=0.0, low_open=True, unit="m")
    min_log_odds: float = param(1.5, low=0.0)
    huber: float = param(1.0, low=0.0, low_open=True, unit="m")
    offset_weight: float = param(3.0, low=0.0)
    obstacle_weight: float = param(50.0, low=0.0)
    depth_weight: float = param(1.0, low=0.0)
    route_weight: float = param(1.0, low=0.0)
    progress_weight: float = param(0.1, low=0.0)
    terminal_weight: float = param(3.0, low=0.0)
    spacing_weight: float = param(10.0, low=0.0)
    crossing_weight: float = param(1.0e4, low=0.0)
    current_aware: bool = param(True, kind="bool", key="current_aware")
    current_weight: float = param(0.5, low=0.0)
    current_margin_s: float = param(5.0, low=0.0, high=60.0, unit="s")
    stomp: StompParameters = nested(StompParameters, lambda: StompParameters(
        num_rollouts=10, max_iterations=40, noise_std=0.5, smoothness_weight=50.0,
        patience=8))

    def __post_init__(self):
        validate(self)
