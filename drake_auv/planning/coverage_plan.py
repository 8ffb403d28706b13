"""`plan_coverage`: the off-line 3D coverage planner of the reference's Section 5.2.

Bathymetry -> slope map -> classification -> boustrophedon cells over the planar area and
slicing contours over each high-slope region -> one path visiting every region (an exhaustive
walk of the graph whose nodes are the planar cells and the high-slope regions) with safe
transits -> the lawnmower baseline -> metrics for both.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import ndimage

from drake_auv.planning.boustrophedon import (Decomposition, best_sweep_angle,
                                              boustrophedon_waypoints, cell_lanes, decompose,
                                              exhaustive_walk, sliver_cells, sweep_raster)
from drake_auv.planning.lawnmower import check_omega_fits, lane_spacing, plan_lawnmower, wet_grid
from drake_auv.planning.parameters import CoverageParameters
from drake_auv.planning.path import PlannedPath
from drake_auv.planning.route import RouteBuilder
from drake_auv.planning.slicing import (Contour, fixed_depression, order_contours, slice_levels,
                                        slice_region)
from drake_auv.planning.surface import TerrainSurface
from drake_auv.progress import RunProgress, phase_display
from drake_auv.resources import check_memory
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.roi import crop_to_roi
from drake_auv.terrain.slope import TerrainLabels, classify


@dataclass(frozen=True)
class CoveragePlan:
    """Everything `plan_coverage` computed, for export, figures and the simulator.

    Attributes:
        bathy: the bathymetry the plan was made on (cropped to the ROI).
        path: combined path, labels "planar", "slice" and "transit".
        lawnmower: the baseline, labels "lawnmower" and "transit" (None if not asked for).
        labels: the terrain classification.
        cells: boustrophedon decomposition of the planar area.
        contours: slicing contour pieces in visiting order.
        visit_order: the walk over the graph nodes: ("cell", k) or ("region", r).
        parameters: the `CoverageParameters` the plan used: those asked for, with the sweep
            angle, sample spacing and sensor range the planner chose where they were None.
        lane_spacing: distance between neighbouring lanes, m (the survey order's included).
        unreachable_pieces: lanes and contours the route could not reach (dropped).
        no_go_rings: exterior rings [[x, y], ...] of the no-go zones (world frame, m).
        metrics: `PlanMetrics` of both paths (None when not computed).
        surface: the shared `TerrainSurface` (heights, normals, distances).
    """

    bathy: Bathymetry
    path: PlannedPath
    lawnmower: PlannedPath | None
    labels: TerrainLabels
    cells: Decomposition
    contours: list[Contour]
    visit_order: list[tuple[str, int]]
    parameters: CoverageParameters
    lane_spacing: float
    unreachable_pieces: int
    no_go_rings: list[list[list[float]]]
    metrics: object = None
    surface: TerrainSurface = field(default=None, repr=False)

    def parameter_record(self) -> dict:
        """The parameters as report.json records them: those the plan used, its lane spacing,
        unreachable pieces and no-go rings, the survey order by its name."""
        from drake_auv.planning.orders import survey_order

        p = self.parameters
        return dict(omega=p.omega, aperture_deg=p.aperture_deg, overlap=p.overlap,
                    slope_threshold=p.slope_threshold, sweep_angle_deg=p.sweep_angle_deg,
                    slice_spacing=p.slice_spacing, slice_count=p.slice_count,
                    lane_spacing=self.lane_spacing, sample_spacing=p.sample_spacing,
                    sensor_range=p.sensor_range, slice_sensor=p.slice_sensor,
                    min_depth=p.min_depth, unreachable_pieces=self.unreachable_pieces,
                    order=None if p.order is None else survey_order(p.order).name,
                    no_go_rings=self.no_go_rings)


def _region_adjacency(dec: Decomposition, bathy: Bathymetry, regions: np.ndarray):
    """(cell, region) pairs where a cell's free run ends against a high-slope region."""
    _, (reg,) = sweep_raster(bathy, [regions.astype(np.int32)], dec.frame.angle,
                             dec.frame.resolution)
    label = dec.label_raster
    nr, nc = label.shape
    pairs = set()
    # Across the sweep direction (run ends) and along it (cell sides): compare neighbours.
    for a_cell, b_reg in ((label[:-1, :], reg[1:, :]), (label[1:, :], reg[:-1, :]),
                          (label[:, :-1], reg[:, 1:]), (label[:, 1:], reg[:, :-1])):
        m = (a_cell > 0) & (b_reg > 0)
        if m.any():
            pairs.update(zip((a_cell[m] - 1).tolist(), b_reg[m].tolist()))
    return sorted(pairs)


def _apply_no_go(bathy: Bathymetry, no_go, omega: float):
    """The grid with the cells within Omega of the zones made no-data, and the `NoGo`."""
    from drake_auv.planning.nogo import NoGo
    from drake_auv.terrain.zones import check_inside_grid, zones_to_world

    zones = zones_to_world(no_go, bathy)
    check_inside_grid(zones, bathy, "--no-go")
    nogo = NoGo(zones, omega, bathy.extent)
    xx, yy = np.meshgrid(bathy.x, bathy.y)
    blocked = nogo.inside(np.column_stack([xx.ravel(), yy.ravel()])).reshape(bathy.shape)
    if (bathy.valid & ~blocked).sum() == 0:
        raise ValueError("the no-go zones plus Omega cover every cell of the grid")
    return bathy.with_z(np.where(blocked, np.nan, bathy.z)), nogo


def _exterior_rings(geom) -> list[list[list[float]]]:
    """Exterior rings of a (Multi)Polygon as [[x, y], ...] lists (world frame, m)."""
    polys = [geom] if geom.geom_type == "Polygon" else list(geom.geoms)
    return [np.round(np.asarray(p.exterior.coords), 3).tolist() for p in polys]


PLAN_STAGES = ("classify", "decompose", "visit order", "route", "lawnmower", "grid metrics")
# Bytes a terrain distance sample may hold (its elevation grids and, once a point far from
# the surface needs the KD-tree, their (n, 3) stack and the tree's index), and about what a
# path sample holds (position, sensor axis, heading, label, and their resampled copies).
SAMPLE_BYTES = 64


def check_samples(bathy: Bathymetry, omega: float, sample_spacing: float) -> None:
    """ValueError (`resources.check_memory`) when the terrain's distance samples (every
    min(cell, Omega / 4) over the grid) or a lane of path samples (every `sample_spacing`
    across the grid's diagonal) would need more memory than the machine has: a tiny Omega or
    sample spacing is refused before the planner allocates."""
    xmin, xmax, ymin, ymax = bathy.extent
    res = min(min(bathy.spacing), omega / 4.0)
    samples = ((xmax - xmin) / res + 1.0) * ((ymax - ymin) / res + 1.0)
    check_memory(SAMPLE_BYTES * samples,
                 f"omega {omega:g} m: the terrain's distance samples every {res:.3g} m")
    lane = float(np.hypot(xmax - xmin, ymax - ymin)) / sample_spacing
    check_memory(SAMPLE_BYTES * lane,
                 f"sample spacing {sample_spacing:.3g} m: the path's samples along one lane")


def plan_coverage(bathy: Bathymetry, params: CoverageParameters = CoverageParameters(), *,
                  roi=None, no_go=None, baseline: bool = True, compute_metrics: bool = True,
                  progress: bool | RunProgress = False) -> CoveragePlan:
    """Plans a 3D coverage path of `bathy` (optionally cropped to `roi`) with `params`.

    Args:
        params: the planner's parameters (`CoverageParameters`: defaults and ranges).
        roi: rectangle (xmin, ymin, xmax, ymax) or polygon [(x, y), ...] in map coordinates of
            the bathymetry's CRS (world metres when it has none).
        no_go: shapely (Multi)Polygon of no-go zones in the map coordinates of the grid's CRS
            (`terrain.zones.read_zones`); no lane, contour or transit comes within Omega of
            them, transits go around them (`planning.nogo`).
        baseline: also plan the lawnmower baseline (`CoveragePlan.lawnmower`, else None).
        compute_metrics: compute `PlanMetrics` for the path and the lawnmower (needs `baseline`).
        progress: show the progress over the `PLAN_STAGES`, or a caller's `RunProgress` to
            show it on (its "plan" phase, begun once the inputs are checked:
            `progress.phase_display`).

    Where Omega above the seabed would be above z = -`params.min_depth`, the path runs at the
    minimum depth instead (`report_dict` says how much of it).
    """
    if not isinstance(bathy, Bathymetry):
        raise ValueError(f"plan_coverage needs a Bathymetry, got {type(bathy).__name__}")
    omega, min_depth = params.omega, params.min_depth
    survey = None
    if params.order is not None:
        from drake_auv.planning.orders import survey_order

        survey = survey_order(params.order)
    ds = omega / 4.0 if params.sample_spacing is None else float(params.sample_spacing)
    if roi is not None:
        bathy = crop_to_roi(bathy, roi)
    check_omega_fits(omega, bathy)
    check_samples(bathy, omega, ds)
    bathy = wet_grid(bathy, min_depth)
    nogo = None
    if no_go is not None:
        bathy, nogo = _apply_no_go(bathy, no_go, omega)
    labels = classify(bathy, params.slope_threshold, params.closing_radius,
                      params.opening_radius, params.min_area)
    surface = TerrainSurface(bathy, min(min(bathy.spacing), omega / 4.0))
    spacing = (lane_spacing(omega, params.aperture_deg, params.overlap)
               / (1.0 if survey is None else survey.coverage))
    # every high-slope region's slicing planes, refused (too many) before any route is built,
    # and so before the display starts: a refusal stays one line
    levels = {r: slice_levels(surface, labels.regions == r, labels.slope, spacing,
                              params.slice_spacing, params.slice_count)
              for r in range(1, labels.n_regions + 1)}
    # the lawnmower is planned on a thread beside the route (neither reads what the other
    # builds; their numpy work releases the GIL)
    with (phase_display(progress, "plan", len(PLAN_STAGES), PLAN_STAGES[0]) as display,
          ThreadPoolExecutor(1, thread_name_prefix="drake_auv-lawnmower") as beside):
        if baseline:
            # lanes along the fewest turns whatever the plan's sweep angle, at its sample spacing
            lawn_job = beside.submit(
                plan_lawnmower, bathy, replace(params, sweep_angle_deg=None, sample_spacing=ds),
                lane_spacing_m=spacing, surface=surface,
                nogo=None if nogo is None else nogo.copy())
        display.advance(1, PLAN_STAGES[1])  # classified (with the slicing planes)
        planar = labels.planar
        if params.sweep_angle_deg is not None:
            angle = np.radians(float(params.sweep_angle_deg))
        else:
            angle = best_sweep_angle(bathy, planar, spacing) if planar.any() else 0.0
        dec = decompose(bathy, planar, angle)
        display.advance(1, PLAN_STAGES[2])
        # Graph over planar cells (0..C-1) and high-slope regions (C..C+R-1).
        n_cells = len(dec.cells)
        adjacency = dec.adjacency() + [[] for _ in range(labels.n_regions)]
        for c, r in _region_adjacency(dec, bathy, labels.regions):
            adjacency[c].append(n_cells + r - 1)
            adjacency[n_cells + r - 1].append(c)
        positions = [c.centroid(dec.frame) for c in dec.cells]
        if labels.n_regions:
            rc = np.array(ndimage.center_of_mass(labels.high, labels.regions,
                                                 np.arange(1, labels.n_regions + 1)))
            positions += list(np.asarray(bathy.origin) + rc[:, ::-1] * np.asarray(bathy.spacing))
        positions = np.array(positions).reshape(-1, 2)
        order = exhaustive_walk(adjacency, positions, 0)
        display.advance(1, PLAN_STAGES[3])
        route = RouteBuilder(surface, omega, ds, ceiling=-float(min_depth), nogo=nogo)
        contours_done: list[Contour] = []
        visit = []
        slivers = sliver_cells(dec, 0.5 * spacing ** 2)
        for node in order:
            here = route.position
            if node < n_cells:
                if node in slivers:
                    continue
                visit.append(("cell", node))
                lanes = cell_lanes(dec.cells[node], dec.frame, spacing)
                route.add_terrain_following(
                    boustrophedon_waypoints(lanes, dec.frame, None if here is None else here[:2]),
                    "planar")
                continue
            r = node - n_cells + 1
            visit.append(("region", r))
            mask = labels.regions == r
            depression = (fixed_depression(labels.slope[mask])
                          if params.slice_sensor == "fixed-tilt" else None)
            per_level = slice_region(surface, mask, r, levels[r], omega, ds, min_length=spacing,
                                     depression=depression)
            start = here if here is not None else np.append(positions[node], surface.z[mask].min())
            for c in order_contours(per_level, start):
                route.add_oriented(c.path, c.sensor_dir, "slice")
                contours_done.append(c)
        display.advance(1, PLAN_STAGES[4])
        path = route.build()
        lawn = lawn_job.result() if baseline else None
        display.advance(1, PLAN_STAGES[5])
        used = replace(params, sweep_angle_deg=float(np.degrees(angle)), sample_spacing=ds,
                       sensor_range=(2.0 * omega if params.sensor_range is None
                                     else float(params.sensor_range)), min_depth=float(min_depth))
        plan = CoveragePlan(bathy, path, lawn, labels, dec, contours_done, visit, used, spacing,
                            route.unreachable, [] if nogo is None else _exterior_rings(nogo.zones),
                            surface=surface)
        if compute_metrics and baseline:
            from drake_auv.planning.metrics import evaluate_plan

            plan = replace(plan, metrics=evaluate_plan(plan))
        display.advance(1)
    return plan
