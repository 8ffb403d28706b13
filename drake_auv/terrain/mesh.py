"""Bathymetric grid <-> triangle mesh (trimesh).

`bathymetry_to_mesh`: the grid as the surface the simulated sensors see. Vertices sit at the cell centres of the grid (world frame, z up). Each square between four
neighbouring samples becomes two triangles, wound counter-clockwise seen from above so the face
normals point up (out of the seabed, into the water); a square with a no-data (NaN) corner gets
no triangles, so holes in the survey stay holes in the mesh.
`top_surface`: the other way, a mesh as a survey from above sees it (overhangs hidden).
"""

from __future__ import annotations

import numpy as np
import trimesh

from drake_auv.geometry.raycast import RayCaster
from drake_auv.terrain.bathymetry import Bathymetry


def bathymetry_to_mesh(bathy: Bathymetry, stride: int = 1) -> trimesh.Trimesh:
    """The seabed surface of `bathy` as a triangle mesh.

    Args:
        bathy: the elevation grid (m, NaN for no-data).
        stride: keep every `stride`-th sample along each axis (1 = full resolution, >= 1).
    Returns:
        A `trimesh.Trimesh` with two triangles per valid grid square; unused vertices removed.
    """
    if not isinstance(bathy, Bathymetry):
        raise ValueError(f"bathymetry_to_mesh needs a Bathymetry, got {type(bathy).__name__}")
    if int(stride) != stride or stride < 1:
        raise ValueError(f"bathymetry_to_mesh: stride must be an integer >= 1, got {stride}")
    stride = int(stride)
    z = bathy.z[::stride, ::stride]
    xs = bathy.x[::stride]
    ys = bathy.y[::stride]
    ny, nx = z.shape
    if ny < 2 or nx < 2:
        raise ValueError(f"bathymetry_to_mesh: stride {stride} leaves fewer than 2 x 2 samples")
    vertices = np.empty((ny * nx, 3))
    vertices[:, 0] = np.tile(xs, ny)
    vertices[:, 1] = np.repeat(ys, nx)
    vertices[:, 2] = np.nan_to_num(z.ravel())
    valid = np.isfinite(z)
    quad_ok = (valid[:-1, :-1] & valid[:-1, 1:] & valid[1:, :-1] & valid[1:, 1:]).ravel()
    if not quad_ok.any():
        raise ValueError("bathymetry_to_mesh: no grid square has four valid corners")
    v00 = (np.arange(ny - 1)[:, None] * nx + np.arange(nx - 1)).ravel()  # sample (i, j)
    if not quad_ok.all():
        v00 = v00[quad_ok]
    # Counter-clockwise from above (+x then +y): normals point up. The two triangles of a
    # square are neighbours in the face list: (i, j), (i, j + 1), (i + 1, j + 1) and
    # (i, j), (i + 1, j + 1), (i + 1, j).
    faces = np.empty((len(v00), 2, 3), dtype=np.int64)
    faces[:, :, 0] = v00[:, None]
    faces[:, 0, 1] = v00 + 1
    faces[:, 0, 2] = faces[:, 1, 1] = v00 + nx + 1
    faces[:, 1, 2] = v00 + nx
    faces = faces.reshape(-1, 3)
    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    if not quad_ok.all():  # else every sample is a corner of some square
        mesh.remove_unreferenced_vertices()
    return mesh


def top_surface(world: trimesh.Trimesh, spacing: float) -> Bathymetry:
    """The first surface of `world` seen from above, sampled by vertical rays on a regular
    grid of `spacing` (m, > 0) over its horizontal bounds (world frame, z up); NaN where
    nothing lies below."""
    if not (np.isfinite(spacing) and spacing > 0):
        raise ValueError(f"top_surface: spacing must be > 0 m, got {spacing}")
    lo, hi = world.bounds
    xmin, xmax, ymin, ymax = lo[0], hi[0], lo[1], hi[1]
    nx = int(np.floor((xmax - xmin) / spacing)) + 1
    ny = int(np.floor((ymax - ymin) / spacing)) + 1
    if nx < 3 or ny < 3:
        raise ValueError(f"top_surface: spacing {spacing} m leaves fewer than 3 x 3 cells")
    gx, gy = np.meshgrid(xmin + spacing * np.arange(nx), ymin + spacing * np.arange(ny))
    top = hi[2] + 1.0
    origins = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, top)])
    hits = RayCaster(world).cast(origins, np.tile([0.0, 0.0, -1.0], (gx.size, 1)),
                                 top - lo[2] + 1.0)
    return Bathymetry(hits.points[:, 2].reshape(gx.shape), (spacing, spacing), (xmin, ymin))
