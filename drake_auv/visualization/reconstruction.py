"""The reconstructed surface in a mission's Meshcat scene, coloured by its error.

`draw_products` draws the `reconstruction.ply` that `reconstruction.products.write_products`
left in a mission's output folder, decimated, with its legend entry.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from drake_auv.reconstruction.products import error_colours
from drake_auv.visualization.legend import LegendEntry, swatch


def draw_products(scene, site, outdir, max_faces: int = 30_000) -> None:
    """Adds the `reconstruction` layer (the surface of `outdir`/reconstruction.ply, coloured by
    error, at most `max_faces` faces; `site.to_local` brings it to the scene's frame) to a
    mission's Meshcat scene, when there is one."""
    from drake_auv.reconstruction.figures import decimated

    filename = Path(outdir) / "reconstruction.ply"
    if not filename.is_file():
        return
    mesh = trimesh.load(filename, process=False)
    rgb = np.asarray(mesh.visual.vertex_colors, dtype=float)[:, :3] / 255.0
    local = trimesh.Trimesh(site.to_local(mesh.vertices), mesh.faces, process=False)
    small, colours = decimated(local, rgb, max_faces)
    scene.meshcat.SetTriangleColorMesh(scene.path_of("reconstruction"),
                                       np.asfortranarray(small.vertices.T),
                                       np.asfortranarray(small.faces.T.astype(np.int32)),
                                       np.asfortranarray(colours.T))
    scene.add_legend(LegendEntry(
        "reconstruction", "black to yellow mesh", "the surface from the returns by its "
        "distance to the truth: black on it, yellow far (reconstruction.png)", swatch(error_colours(np.linspace(0, 1, 5), 1.0)),
        scene.path_of("reconstruction")))
