"""Figures of reconstructions, like the reference's Figure 89: top and slanted views of the
surface, here coloured by each vertex's distance to the true structure (m) or to the nearest
return (the support the surface has in the data, m), lightly shaded by the faces' orientation
so the shape reads."""

from __future__ import annotations

import numpy as np
import trimesh
from matplotlib.figure import Figure
from scipy.spatial import cKDTree

MAX_FACES = 30_000  # drawn per view; larger meshes are decimated for the figure only
LIGHT = np.array([0.4, -0.6, 0.7]) / np.linalg.norm([0.4, -0.6, 0.7])  # shading direction


def decimated(mesh: trimesh.Trimesh, errors: np.ndarray, max_faces: int = MAX_FACES):
    """(mesh, per-vertex errors) with at most `max_faces` faces (quadric decimation through
    Open3D; each kept vertex takes the error of the nearest original vertex)."""
    if len(mesh.faces) <= max_faces:
        return mesh, errors
    from drake_auv.reconstruction.surface import load_open3d

    o3d = load_open3d()
    centre = mesh.bounds.mean(axis=0)
    o3d_mesh = o3d.geometry.TriangleMesh(o3d.utility.Vector3dVector(mesh.vertices - centre),
                                         o3d.utility.Vector3iVector(mesh.faces))
    small = o3d_mesh.simplify_quadric_decimation(max_faces)
    vertices = np.asarray(small.vertices) + centre
    _, nearest = cKDTree(mesh.vertices).query(vertices)
    return trimesh.Trimesh(vertices, np.asarray(small.triangles), process=False), errors[nearest]


TRUTH_LABEL = "distance of the surface to the true structure (m)"


def fig_reconstruction(panels, vmax: float = 1.0, title: str = "") -> Figure:
    """Top and slanted views of each reconstruction, one row per panel.

    Args:
        panels: [(label, mesh, distances[, colour label])]: a mesh (any frame, m) and a
            per-vertex distance (m; by default to the truth, `TRUTH_LABEL`), colour 0 (dark)
            to `vmax` m (yellow) and above; one colour bar per distinct colour label.
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    norm, cmap = Normalize(0.0, vmax), colormaps["inferno"]
    fig = Figure(figsize=(11, 4.8 * len(panels)))
    rows: dict[str, list] = {}
    for row, (label, mesh, errors, *measure) in enumerate(panels):
        rows.setdefault(measure[0] if measure else TRUTH_LABEL, [])
        small, err = decimated(mesh, np.asarray(errors, dtype=float))
        triangles = np.asarray(small.triangles)
        colours = cmap(norm(err[small.faces].mean(axis=1)))
        light = np.abs(small.face_normals @ LIGHT)
        colours[:, :3] *= (0.6 + 0.4 * light)[:, None]
        lo, hi = small.bounds
        for col, (view, elev, azim) in enumerate((("top view", 90, -90),
                                                  ("slanted view", 25, -60))):
            ax = fig.add_subplot(len(panels), 2, 2 * row + col + 1, projection="3d")
            ax.add_collection3d(Poly3DCollection(triangles, facecolors=colours, linewidths=0,
                                                 antialiased=False))
            ax.set(xlim=(lo[0], hi[0]), ylim=(lo[1], hi[1]), zlim=(lo[2], hi[2]),
                   xlabel="x (m)", ylabel="y (m)", zlabel="z (m)", title=f"{label}: {view}")
            ax.set_box_aspect(np.maximum(hi - lo, 1e-3))
            ax.view_init(elev=elev, azim=azim)
            if elev == 90:
                ax.set_zticks([])
            rows[measure[0] if measure else TRUTH_LABEL].append(ax)
    for colour_label, axes in rows.items():
        fig.colorbar(ScalarMappable(norm, cmap), ax=axes, shrink=0.6, label=colour_label)
    if title:
        fig.suptitle(title)
    return fig
