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
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.route import RouteBuilder
from drake_auv.planning.surface import TerrainSurface
from drake_auv.terrain.bathymetry import Bathymetry


def lane_spacing(omega: float, aperture_deg: float, overlap: float) -> float:
    """Distance between lanes, m: the down-looking footprint 2 Omega tan(aperture / 2) shrunk
    by the overlap."""
    return 2.0 * omega * np.tan(np.radians(aperture_deg) / 2.0) * (1.0 - overlap)


def check_omega_fits(omega: float, bathy: Bathymetry) -> None:
    """ValueError when Omega exceeds the grid's horizontal diagonal (the largest offset at
    which a sensor over the grid still sees it; larger values only allocate)."""
    xmin, xmax, ymin, ymax = bathy.extent
    diagonal = float(np.hypot(xmax - xmin + bathy.spacing[0], ymax - ymin + bathy.spacing[1]))
    if omega > diagonal:
        raise ValueError(f"omega (offset to the terrain) must be in (0, {diagonal:.1f}] m, the "
                         f"diagonal of the grid, got {omega:g}")


def wet_grid(bathy: Bathymetry, min_depth: float) -> Bathymetry:
    """`bathy` with the cells shallower than `min_depth` (elevation above -min_depth, m: land,
    or water too shallow to operate in) made no-data, so no lane covers them. ValueError when
    no cell is left."""
    z = bathy.z
    wet = z <= -min_depth
    if not wet.any():
        raise ValueError(f"no cell of the grid lies below the minimum operating depth "
                         f"(min_depth = {min_depth:g} m): its elevations span "
                         f"{np.nanmin(z):.2f} to {np.nanmax(z):.2f} m; a plan needs seabed "
                         f"deeper than -{min_depth:g} m (elevations are z up, negative below "
                         f"the sea surface)")
    if wet[bathy.valid].all():
        return bathy
    return bathy.with_z(np.where(wet, z, np.nan))


def plan_lawnmower(bathy: Bathymetry, params: CoverageParameters = CoverageParameters(), *,
                   enforce_clearance: bool = True, surface: TerrainSurface | None = None,
                   nogo=None, lane_spacing_m: float | None = None) -> PlannedPath:
    """Lawnmower over the valid cells of `bathy`; labels "lawnmower" and "transit".

    Args:
        params: the planner's parameters the lawnmower flies by: `omega` (the altitude, m),
            `aperture_deg` and `overlap` (the lane spacing), `sweep_angle_deg` (lane
            direction from world +x; None: fewest turns), `sample_spacing` (None: Omega / 4),
            `min_depth` (no sample above z = -min_depth).
        surface: a prebuilt `TerrainSurface` of `bathy` to reuse.
        nogo: a `planning.nogo.NoGo` the lanes keep out of and the transits go around.
        lane_spacing_m: distance between lanes, m (default `lane_spacing` of the sensor; the
            coverage planner passes its survey order's).
    """
    omega, min_depth = params.omega, params.min_depth
    check_omega_fits(omega, bathy)
    bathy = wet_grid(bathy, min_depth)
    spacing = (lane_spacing(omega, params.aperture_deg, params.overlap) if lane_spacing_m is None
               else lane_spacing_m)
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"lane_spacing_m must be > 0 m, got {lane_spacing_m}")
    ds = omega / 4.0 if params.sample_spacing is None else float(params.sample_spacing)
    surface = TerrainSurface(bathy, min(min(bathy.spacing), omega / 4.0)) if surface is None else surface
    valid = bathy.valid
    angle = (best_sweep_angle(bathy, valid, spacing) if params.sweep_angle_deg is None
             else np.radians(float(params.sweep_angle_deg)))
    dec = decompose(bathy, valid, angle)
    centroids = np.array([c.centroid(dec.frame) for c in dec.cells])
    route = RouteBuilder(surface, omega, ds, ceiling=-float(min_depth), nogo=nogo)
    slivers = sliver_cells(dec, 0.5 * spacing ** 2)
    for k in exhaustive_walk(dec.adjacency(), centroids, 0):
        if k in slivers:
            continue
        here = route.position
        lanes = cell_lanes(dec.cells[k], dec.frame, spacing)
        route.add_terrain_following(
            boustrophedon_waypoints(lanes, dec.frame, None if here is None else here[:2]), "lawnmower")
    return route.build(enforce_clearance)
