"""The report's `ocean` section: the sea a dive met and what it cost the vehicle.

Left out of the report in still water (`ocean: none`), so a still-water report is today's.
"""

from __future__ import annotations

import numpy as np

from drake_auv.signals import THRUSTER_NAMES, Reference, VehicleState, Water


def ocean_summary(result) -> dict | None:
    """`current_mean_mps` / `current_max_mps`: the water's speed at the vehicle over the dive;
    `thrust_saturation_share`: per thruster, the share of the dive its command was at its
    limit (`..._max` the largest); `tracking_error_p95_m`: the 95th percentile of the distance
    between the tracker's reference and the navigation's position (what the controller can
    act on), over the dive and per phase; `navigation_current_drift_m`: how far the current
    carried the navigation's estimate while the DVL tracked the water (0 with bottom lock).
    None for a still sea."""
    if result.spec.ocean is None:
        return None
    speed = np.linalg.norm(Water(result.log.water).velocity, axis=1)
    error = np.linalg.norm(Reference(result.log.reference).position
                           - VehicleState(result.log.estimated).position, axis=1)
    by_phase = []
    for phase in result.dive.phases:
        mask = np.isin(result.log.leg_at, phase.legs)
        if mask.any():
            by_phase.append(dict(name=phase.name,
                                 tracking_error_p95_m=float(np.percentile(error[mask], 95))))
    share = np.asarray(result.ocean.thrust_saturation, dtype=float)
    return dict(
        current_mean_mps=float(speed.mean()), current_max_mps=float(speed.max()),
        thrust_saturation_share=dict(zip(THRUSTER_NAMES, map(float, share))),
        thrust_saturation_share_max=float(share.max()),
        tracking_error_p95_m=float(np.percentile(error, 95)),
        phases=by_phase,
        navigation_current_drift_m=float(np.linalg.norm(result.ocean.current_drift)))


def ocean_markdown(section: dict | None) -> list[str]:
    """The report.md lines of the `ocean` section (none for a still sea)."""
    if section is None:
        return []
    worst = max(section["thrust_saturation_share"], key=section["thrust_saturation_share"].get)
    phases = ", ".join(f"{p['name']} {p['tracking_error_p95_m']:.2f} m"
                       for p in section["phases"])
    return ["", "## The sea", "",
            f"- Current at the vehicle: mean {section['current_mean_mps']:.2f} m/s, largest "
            f"{section['current_max_mps']:.2f} m/s.",
            f"- Thrusters at their limit: at most {section['thrust_saturation_share_max']:.1%} "
            f"of the dive ({worst}).",
            f"- Tracking error, 95th percentile: {section['tracking_error_p95_m']:.2f} m"
            + (f" ({phases})." if phases else "."),
            f"- Navigation drift the current caused (DVL tracking the water): "
            f"{section['navigation_current_drift_m']:.2f} m."]
