"""The safety figures of a replayed vehicle mission against the prior map. Pure numpy.

Both replays (`autopilot.cola2.replay_cola2`, `autopilot.ardusub.replay_ardusub`) give the
positions the vehicle passes; `clearance_report` says how close they come to the seabed and to
the sea surface, the exports' acceptance (at least 0.5 Omega from the prior seabed, no shallower
than the minimum depth), and `clearance_warnings` states each violation in a line.
"""

from __future__ import annotations

import numpy as np


def clearance_report(positions: np.ndarray, surface, omega: float, min_depth: float) -> dict:
    """The replay's safety figures against the prior map.

    Args:
        positions: (N, 3) replayed samples (world frame, m).
        surface: a `planning.surface.TerrainSurface` (3D distance queries).
        omega: the plan's offset, m; a sample closer than 0.5 omega is a violation.
        min_depth: the minimum operating depth, m; a sample shallower is a violation.
    Returns:
        min_clearance_m and min_clearance_over_omega (3D distance to the surface, signed:
        negative below it or above the sea surface; None when every sample is farther than
        `checked_to_m` = 2 omega), shallowest_depth_m, samples,
        closer_than_half_omega, shallower_than_min_depth, and closer_than_reachable: samples
        closer than the least of 0.5 omega and what the minimum depth leaves (the distance
        from the point at that depth above them).
    """
    p = np.asarray(positions, float)
    bound = 2.0 * omega
    d = surface.signed_distance(p, upper_bound=bound)
    tol = 1e-6
    close = np.flatnonzero(d < 0.5 * omega - tol)
    ceiling = np.column_stack([p[close, :2], np.full(len(close), -float(min_depth))])
    reach = np.minimum(0.5 * omega, surface.distance(ceiling, upper_bound=omega)[0])
    worst = float(d.min()) if np.isfinite(d.min()) else None
    return {"samples": int(len(p)), "checked_to_m": bound, "min_clearance_m": worst,
            "min_clearance_over_omega": None if worst is None else worst / omega,
            "shallowest_depth_m": float(-p[:, 2].max()),
            "closer_than_half_omega": int(len(close)),
            "shallower_than_min_depth": int((-p[:, 2] < min_depth - tol).sum()),
            "closer_than_reachable": int((d[close] < reach - tol).sum())}


def clearance_warnings(name: str, r: dict, omega: float, min_depth: float) -> list[str]:
    """One line per violation a `clearance_report` `r` records, for the vehicle file `name`:
    samples nearer than 0.5 omega to the prior seabed, or shallower than `min_depth` (m)."""
    out = []
    if r["closer_than_half_omega"]:
        cause = ("all where the minimum depth leaves no more" if not r["closer_than_reachable"]
                 else f"{r['closer_than_reachable']} of them where the minimum depth does not "
                      "force it")
        out.append(f"{name}: flown as its autopilot flies it, {r['closer_than_half_omega']} of "
                   f"{r['samples']} samples come nearer than Omega / 2 = {0.5 * omega:g} m to "
                   f"the prior seabed (least {r['min_clearance_m']:.2f} m); {cause}")
    if r["shallower_than_min_depth"]:
        out.append(f"{name}: flown as its autopilot flies it, {r['shallower_than_min_depth']} "
                   f"of {r['samples']} samples are shallower than the {min_depth:g} m minimum "
                   f"depth (shallowest {r['shallowest_depth_m']:.3f} m)")
    return out
