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
SCALE_PERCENTILE = 95  # the colour scale's top: the accuracy's p95, as the report scores it


def colour_scale(distances) -> float:
    """Top of a distance colour scale, m: the `SCALE_PERCENTILE`th percentile of the finite
    distances (the accuracy p95 the scoring reports), at least 1 cm."""
    d = np.asarray(distances, dtype=float)
    d = d[np.isfinite(d)]
    return max(float(np.percentile(d, SCALE_PERCENTILE)) if d.size else 0.0, 0.01)


def fig_reconstruction(panels, vmax: float | None = None, title: str = "") -> Figure:
    """Top and slanted views of each reconstruction, one row per panel.

    Args:
        panels: [(label, mesh, distances[, colour label])]: a mesh (any frame, m) and a
            per-vertex distance (m; by default to the truth, `TRUTH_LABEL`); one colour bar
            per distinct colour label, from 0 (dark) to its scale (yellow, and above), the
            label stating the scale.
        vmax: every scale's top, m; None: each colour label's own, `colour_scale` of its
            panels' distances together (so panels of one label compare).
    """
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    cmap = colormaps["inferno"]
    measures = [p[3] if len(p) > 3 else TRUTH_LABEL for p in panels]
    norms = {m: Normalize(0.0, vmax if vmax is not None else colour_scale(np.concatenate(
        [np.asarray(p[2], dtype=float) for p, pm in zip(panels, measures) if pm == m])))
        for m in measures}
    fig = Figure(figsize=(11, 4.8 * len(panels)))
    rows: dict[str, list] = {}
    for row, ((label, mesh, errors, *_), measure) in enumerate(zip(panels, measures)):
        rows.setdefault(measure, [])
        small, err = decimated(mesh, np.asarray(errors, dtype=float))
        triangles = np.asarray(small.triangles)
        colours = cmap(norms[measure](err[small.faces].mean(axis=1)))
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
            rows[measure].append(ax)
    for colour_label, axes in rows.items():
        top = norms[colour_label].vmax
        scale = f"{top:.2f} m" if vmax is not None else \
            f"its {SCALE_PERCENTILE}th percentile, {top:.2f} m"
        fig.colorbar(ScalarMappable(norms[colour_label], cmap), ax=axes, shrink=0.6,
                     extend="max", label=f"{colour_label}\nscale: 0 to {scale}")
    if title:
        fig.suptitle(title)
    return fig
