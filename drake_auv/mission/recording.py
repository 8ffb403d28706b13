"""The mission's Meshcat recording: the site and plan before the dive, the results after it.

Layers (under the scene's root, each named in the legend and toggled by its checkbox or in
Meshcat's scene tree): `world` (the true world), `nominal_path` (the off-line plan), `vehicle`
and its trail (drawn while it flies), `current` (the water velocity at the vehicle, with a
sea), `coverage` (the target coloured by the best multibeam viewing angle, grey unseen), and,
hidden at first, `octree` (the on-line map's occupied voxels) and `reconstruction` (the
surface from the returns, coloured by its distance to the true world, when one was built).
The camera opens framed on the target and the vehicle's start (not the whole world: a seabed
can be far larger than the structure), lit by `Scene.frame_camera`; the clock shows the
mission time and the leg flying.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_auv.mission.plan import MissionPlan
from drake_auv.mission.runner import MissionResult
from drake_auv.mission.site import Site
from drake_auv.signals import VehicleState
from drake_auv.visualization.legend import LegendEntry, css_colour
from drake_auv.visualization.scene import PATH_RGBA

HIDDEN_LAYERS = ("octree", "reconstruction")  # drawn, but off until a click shows them
WORLD_RGB = (0.55, 0.5, 0.42)


def prepare_scene(scene, site: Site, plan: MissionPlan) -> None:
    """Draws the world and the nominal path, hides `HIDDEN_LAYERS`, and frames the camera on
    the target and the vehicle's start."""
    scene.add_mesh("world", site.world, rgba=(*WORLD_RGB, 1.0))
    scene.add_legend(LegendEntry("world", "brown mesh", "the seabed and the structure",
                                 css_colour(WORLD_RGB), scene.path_of("world")))
    if plan.nominal is not None and len(plan.nominal) >= 2:
        scene.add_legend(LegendEntry("nominal path", "orange line", "the off-line plan",
                                     css_colour(PATH_RGBA),
                                     scene.add_path("nominal_path", plan.nominal)))
    for name in HIDDEN_LAYERS:
        scene.hide(name)
    start = np.asarray(VehicleState(plan.start_state).position, dtype=float)
    box = np.asarray(site.target_mesh.bounds, dtype=float)
    bounds = np.array([np.minimum(box[0], start), np.maximum(box[1], start)])
    scene.frame_camera(direction=(-0.6, -1.0, 1.8), bounds=bounds, margin=1.2)


def leg_starts(result: MissionResult) -> list[tuple[float, str]]:
    """[(mission time s, label)] of each leg flown, in order, for the recording's clock."""
    from drake_auv.mission.live_view import leg_label

    if len(result.log.times) == 0:
        return []
    begun = np.r_[0, np.flatnonzero(np.diff(result.log.leg_at)) + 1]
    return [(float(result.log.times[i]), leg_label(result.plan.legs, int(result.log.leg_at[i])))
            for i in begun]


def finish_recording(result: MissionResult, scene, filename):
    """Adds the end-of-dive layers (on-line map, coverage, and the reconstruction that
    `write_outputs` left beside `filename`) and the clock's legs, and writes the standalone
    HTML."""
    from drake_auv.visualization.octree import draw_octree, octree_legend
    from drake_auv.visualization.reconstruction import draw_products
    from drake_auv.visualization.sensors import coverage_legend, draw_coverage

    world, target = result.site.world, result.site.target_faces
    best = np.full(len(world.faces), np.nan)
    best[target] = result.coverage.multibeam_best
    draw_coverage(scene.meshcat, scene.path_of("coverage"), world, best, target, lift=0.05)
    scene.add_legend(coverage_legend(scene.path_of("coverage")))
    draw_octree(scene.meshcat, scene.path_of("octree"), result.mapping.online_map.map)
    scene.add_legend(octree_legend(scene.path_of("octree")))
    draw_products(scene, result.site, Path(filename).parent)
    scene.clock_legs = leg_starts(result)
    return scene.write_html(filename)
