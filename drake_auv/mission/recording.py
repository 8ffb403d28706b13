"""The mission's Meshcat recording: the site and plan before the dive, the results after it.

Layers (under the scene's root, each can be toggled in Meshcat's tree): `world` (the true
world), `nominal_path` (the off-line plan), `vehicle` and its trail (drawn while it flies),
`octree` (the on-line map's occupied voxels), `coverage` (the target coloured by the best
multibeam viewing angle, red unseen) and `reconstruction` (the surface from the returns,
coloured by its distance to the true target, when one was built). The camera opens framed on
the target (not the whole world: a seabed can be far larger than the structure), lit by
`Scene.frame_camera`.
"""

from __future__ import annotations

from pathlib import Path as FilePath

import numpy as np

from drake_auv.mission.plan import MissionPlan
from drake_auv.mission.runner import MissionResult
from drake_auv.mission.site import Site


def prepare_scene(scene, site: Site, plan: MissionPlan) -> None:
    """Draws the world and the nominal path, and frames the camera on the target."""
    scene.add_mesh("world", site.world, rgba=(0.55, 0.5, 0.42, 1.0))
    if plan.nominal is not None and len(plan.nominal) >= 2:
        scene.add_path("nominal_path", plan.nominal)
    scene.frame_camera(direction=(-0.6, -1.0, 1.8), bounds=site.target_mesh.bounds, margin=1.4)


def finish_recording(result: MissionResult, scene, filename):
    """Adds the end-of-dive layers (on-line map, coverage, and the reconstruction that
    `write_outputs` left beside `filename`) and writes the standalone HTML."""
    from drake_auv.reconstruction.products import draw_products
    from drake_auv.visualization.octree import draw_octree
    from drake_auv.visualization.sensors import draw_coverage

    world, target = result.site.world, result.site.target_faces
    best = np.full(len(world.faces), np.nan)
    best[target] = result.multibeam_best
    draw_coverage(scene.meshcat, scene.path_of("coverage"), world, best, target, lift=0.05)
    draw_octree(scene.meshcat, scene.path_of("octree"), result.online_map.map)
    draw_products(scene, result, FilePath(filename).parent)
    return scene.write_html(filename)
