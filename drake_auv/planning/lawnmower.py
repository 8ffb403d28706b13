"""The baseline: a standard constant-altitude lawnmower over the whole ROI.

Parallel lanes over every valid cell regardless of slope, at altitude Omega (vertical, as a
DVL-altitude-keeping survey flies), down-looking sensor, the same lane spacing as the coverage
planner. Lanes run along the direction with the fewest turns unless `sweep_angle_deg` is given.
With `enforce_clearance` (default) samples closer than Omega to the surface (steep ground makes
the perpendicular distance shorter than the altitude) are lifted, as the vehicle's safety layer
would.
"""

from __future__ import annotations

import numpy as np

from drake_auv.planning.boustrophedon import (best_sweep_angle, boustrophedon_waypoints,
                                              cell_lanes, decompose, exhaustive_walk,
                                              sliver_cells)
from drake_auv.planning.path import Path
from drake_auv.planning.route import RouteBuilder
from drake_auv.planning.surface import TerrainSurface
from drake_auv.terrain.bathymetry import Bathymetry


def lane_spacing(omega: float, aperture_deg: float, overlap: float) -> float:
    """Distance between lanes, m: the down-looking footprint 2 Omega tan(aperture / 2) shrunk
    by the overlap."""
    return 2.0 * omega * np.tan(np.radians(aperture_deg) / 2.0) * (1.0 - overlap)


def check_sensor_parameters(omega: float, aperture_deg: float, overlap: float) -> None:
    """ValueError naming the parameter and its range when one is out of range."""
    if not (np.isfinite(omega) and omega > 0):
        raise ValueError(f"omega (offset to the terrain) must be > 0 m, got {omega}")
    if not (np.isfinite(aperture_deg) and 0 < aperture_deg < 180):
        raise ValueError(f"aperture_deg must be in (0, 180) degrees, got {aperture_deg}")
    if not (np.isfinite(overlap) and 0 <= overlap < 1):
        raise ValueError(f"overlap must be in [0, 1), got {overlap}")


def plan_lawnmower(bathy: Bathymetry, *, omega: float = 2.0, aperture_deg: float = 60.0,
                   overlap: float = 0.1, sweep_angle_deg: float | None = None,
                   sample_spacing: float | None = None, enforce_clearance: bool = True,
                   surface: TerrainSurface | None = None) -> Path:
    """Lawnmower over the valid cells of `bathy`; labels "lawnmower" and "transit".

    Args:
        omega: altitude, m (> 0).
        aperture_deg: sensor aperture, degrees in (0, 180).
        overlap: lane overlap in [0, 1).
        sweep_angle_deg: lane direction, degrees from world +x (None: fewest turns).
        sample_spacing: largest distance between samples, m (default Omega / 4).
        surface: a prebuilt `TerrainSurface` of `bathy` to reuse.
    """
    check_sensor_parameters(omega, aperture_deg, overlap)
    spacing = lane_spacing(omega, aperture_deg, overlap)
    ds = omega / 4.0 if sample_spacing is None else float(sample_spacing)
    if not ds > 0:
        raise ValueError(f"sample_spacing must be > 0 m, got {sample_spacing}")
    surface = TerrainSurface(bathy, min(min(bathy.spacing), omega / 4.0)) if surface is None else surface
    valid = bathy.valid
    angle = (best_sweep_angle(bathy, valid, spacing) if sweep_angle_deg is None
             else np.radians(float(sweep_angle_deg)))
    dec = decompose(bathy, valid, angle)
    centroids = np.array([c.centroid(dec.frame) for c in dec.cells])
    route = RouteBuilder(surface, omega, ds)
    slivers = sliver_cells(dec, 0.5 * spacing ** 2)
    for k in exhaustive_walk(dec.adjacency(), centroids, 0):
        if k in slivers:
            continue
        here = route.position
        lanes = cell_lanes(dec.cells[k], dec.frame, spacing)
        route.add_terrain_following(
            boustrophedon_waypoints(lanes, dec.frame, None if here is None else here[:2]), "lawnmower")
    return route.build(enforce_clearance)
