"""A surface from a point cloud: Hoppe normals, oriented by the sensor, then screened Poisson.

The reference's pipeline (its Figure 89): per-point normals by Hoppe et al. (1992), the normal
of the least-squares plane through each point's k = 200 nearest neighbours, then screened
Poisson reconstruction (Kazhdan and Hoppe 2013). Both run in Open3D (the optional `open3d-cpu`
package; Poisson is Kazhdan's own code inside it). Where the reference had to orient normals
from the points alone, the recorded sensor origin orients each one here: a return's surface
faces the sensor that saw it. Poisson closes the surface everywhere, also where no data was:
vertices whose octree sampling density is in the lowest `trim` quantile are removed, then
(by default) every face that no return supports: a face goes when its centroid or one of its
vertices lies farther from the nearest return than `support` times the local spacing there
(the median nearest-neighbour spacing of the 16 returns nearest it, at least the Poisson
cell). Density alone leaves most of the surface Poisson invents beyond what was seen (a
cloud seen from one side closes into a balloon); distance to the returns removes it.

Frames: the cloud's own (any; the work is done about the cloud's centre, so site coordinates
with eastings of 1e5-1e6 m keep their precision), metres.
"""

from __future__ import annotations

import ctypes
import functools
from dataclasses import dataclass

import numpy as np
import trimesh
from scipy.spatial import cKDTree

from drake_auv.progress import RunProgress, phase_display
from drake_auv.reconstruction.pointcloud import PointCloud, optional_module

DEPTH_RANGE = (5, 12)  # Poisson octree depth: 2^depth cells across the cloud's cube
K_RANGE = (3, 1000)  # neighbours of the normal estimation
TRIM_RANGE = (0.0, 0.5)  # share of the lowest-density vertices removed, [lo, hi)
SUPPORT_RANGE = (0.0, 50.0)  # support distance in local spacings; 0: no support trim
SUPPORT = 3.0  # default: a face farther than 3 local spacings from every return is removed
SPACING_NEIGHBOURS = 16  # returns whose nearest-neighbour spacings set the local spacing
SPACING_CAP = 4.0  # a return's spacing counts up to this many times the cloud's median
POISSON_SCALE = 1.1  # Open3D's default: the octree's cube is 1.1 x the cloud's extent
OUTLIERS_RANGE = (0.0, 100.0)  # outlier ratio; 0: no outlier removal
OUTLIERS = 3.0  # default: a return whose neighbours are 3 x farther than usual is dropped
OUTLIER_NEIGHBOURS = 8
MIN_POINTS = 10
STAGES = ("normals", "screened Poisson", "support trim")  # of `reconstruct`, in order


def open3d_available() -> bool:
    """Whether Open3D imports and loads."""
    return _open3d_or_reason()[0] is not None


def open3d_error() -> str | None:
    """None when Open3D is usable, else why not (one line: the import's own error)."""
    return _open3d_or_reason()[1]


def load_open3d():
    """The `open3d` module; ValueError with the reason when it is missing or does not load."""
    module, reason = _open3d_or_reason()
    if module is None:
        raise ValueError(reason)
    return module


def retry_open3d() -> None:
    """Forgets the import attempt, so the next use tries again (for a process whose
    environment changed since: Open3D installed, removed or repaired)."""
    _open3d_or_reason.cache_clear()


@functools.cache
def _open3d_or_reason():
    """(open3d, None) or (None, reason), tried once per process. Open3D's Linux wheels link
    libusb-1.0.so.0, which a bare system lacks: the copy shipped by the `libusb-package` wheel
    (the reconstruct extra) is loaded first, RTLD_GLOBAL, and the dynamic loader then resolves
    Open3D's dependency to it by its soname."""
    try:
        import libusb_package
    except ImportError:
        pass  # the system's libusb, if any
    else:
        path = libusb_package.get_library_path()
        if path is not None:
            try:
                ctypes.CDLL(str(path), mode=ctypes.RTLD_GLOBAL)
            except OSError as err:
                return None, f"the libusb shipped by libusb-package does not load: {err}"
    try:
        open3d = optional_module("open3d", "surface reconstruction", "open3d-cpu")
    except ValueError as err:
        return None, str(err)
    open3d.utility.set_verbosity_level(open3d.utility.VerbosityLevel.Error)
    return open3d, None


@dataclass(frozen=True, eq=False)
class Reconstruction:
    """A reconstructed surface in the cloud's frame.

    Attributes:
        mesh: the trimmed triangle mesh, m. densities: (v,) Poisson sampling density of each
            vertex (the octree depth of the samples around it). normals: (n, 3) unit normals of
            the input points, oriented outwards (towards the sensors). support_m: (v,)
            distance of each vertex to the nearest input point, m.
        depth, k, trim, support: the parameters used (support 0: no support trim).
    """

    mesh: trimesh.Trimesh
    densities: np.ndarray
    normals: np.ndarray
    support_m: np.ndarray
    depth: int
    k: int
    trim: float
    support: float


def check_parameters(n_points: int, depth: int = 9, k: int = 200, trim: float = 0.05,
                     support: float = SUPPORT, outliers: float = OUTLIERS) -> None:
    """Raises ValueError naming the parameter and its allowed range when one is out of it."""
    if isinstance(depth, bool) or int(depth) != depth or not DEPTH_RANGE[0] <= depth <= \
            DEPTH_RANGE[1]:
        raise ValueError(f"depth must be an integer in [{DEPTH_RANGE[0]}, {DEPTH_RANGE[1]}], "
                         f"got {depth}")
    if isinstance(k, bool) or int(k) != k or not K_RANGE[0] <= k <= K_RANGE[1]:
        raise ValueError(f"k must be an integer in [{K_RANGE[0]}, {K_RANGE[1]}], got {k}")
    if not TRIM_RANGE[0] <= trim < TRIM_RANGE[1]:
        raise ValueError(f"trim must be in [{TRIM_RANGE[0]}, {TRIM_RANGE[1]}), got {trim}")
    if not SUPPORT_RANGE[0] <= support <= SUPPORT_RANGE[1]:
        raise ValueError(f"support must be in [{SUPPORT_RANGE[0]:g}, {SUPPORT_RANGE[1]:g}] "
                         f"local spacings (0: off), got {support}")
    if not OUTLIERS_RANGE[0] <= outliers <= OUTLIERS_RANGE[1] or 0 < outliers < 1:
        raise ValueError(f"outliers must be 0 (off) or in [1, {OUTLIERS_RANGE[1]:g}] times the "
                         f"median neighbour distance, got {outliers}")
    if n_points < MIN_POINTS:
        raise ValueError(f"the point cloud has {n_points} point(s); a surface needs at least "
                         f"{MIN_POINTS}")
    if n_points <= k:
        raise ValueError(f"the point cloud has {n_points} points, not more than k = {k} "
                         "neighbours; lower k")


def estimate_normals(points, origins=None, k: int = 200) -> np.ndarray:
    """(n, 3) unit normals of `points` (n, 3), m: the smallest principal axis of each point's
    k nearest neighbours (Hoppe et al. 1992), flipped to face the point's sensor origin
    (origins (n, 3)); without origins, oriented by propagation over the k-neighbour graph
    (Hoppe's minimum spanning tree), up to one global sign."""
    o3d = load_open3d()
    points = np.asarray(points, dtype=float)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points - centre))
    cloud.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(int(k)))
    if origins is None:
        cloud.orient_normals_consistent_tangent_plane(min(int(k), 30))
        return np.asarray(cloud.normals).copy()
    normals = np.asarray(cloud.normals).copy()
    towards = np.asarray(origins, dtype=float) - points
    normals[np.einsum("ij,ij->i", normals, towards) < 0.0] *= -1.0
    return normals


def poisson(points, normals, depth: int = 9, trim: float = 0.05,
            threads: int = 1) -> tuple[trimesh.Trimesh, np.ndarray]:
    """Screened Poisson surface of oriented points (n, 3) with normals (n, 3), trimmed of the
    vertices in the lowest `trim` quantile of density; returns (mesh, per-vertex densities).
    One thread by default: Open3D's threaded solver differs run to run in the last digits (and
    is not faster on 2 cores); -1 uses all cores."""
    o3d = load_open3d()
    points = np.asarray(points, dtype=float)
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points - centre))
    cloud.normals = o3d.utility.Vector3dVector(np.asarray(normals, dtype=float))
    mesh, densities = o3d.geometry.TriangleMesh.create_from_point_cloud_poisson(
        cloud, depth=int(depth), n_threads=threads)
    densities = np.asarray(densities)
    if trim > 0.0 and len(densities):
        low = densities < np.quantile(densities, trim)
        mesh.remove_vertices_by_mask(low)
        densities = densities[~low]
    vertices, faces = np.asarray(mesh.vertices), np.asarray(mesh.triangles)
    if len(faces) == 0:
        raise ValueError("screened Poisson produced no surface from these points (too few, "
                         "or all on a line)")
    return trimesh.Trimesh(vertices + centre, faces, process=False), densities


def support_distances(points, queries, cell: float = 0.0,
                      neighbours: int = SPACING_NEIGHBOURS, chunk: int = 200_000):
    """(distance, spacing), (q,) each, m: the distance of each of `queries` (q, 3) to the
    nearest of `points` (n, 3), and the local spacing there: the median nearest-neighbour
    spacing of the `neighbours` points nearest the query, at least `cell` and at most
    `SPACING_CAP` times the cloud's median spacing (isolated returns, ghosts of the sea
    surface or clutter, support no more surface than the cloud's own spacing allows)."""
    points = np.asarray(points, dtype=float)
    tree = cKDTree(points)
    spacing = tree.query(points, k=2)[0][:, 1]
    spacing = np.minimum(spacing, SPACING_CAP * np.median(spacing))
    queries = np.asarray(queries, dtype=float).reshape(-1, 3)
    near = min(int(neighbours), len(points))
    distance, local = np.empty(len(queries)), np.empty(len(queries))
    for start in range(0, len(queries), chunk):
        d, index = tree.query(queries[start:start + chunk], k=near)
        d, index = d.reshape(len(d), -1), index.reshape(len(index), -1)
        distance[start:start + chunk] = d[:, 0]
        local[start:start + chunk] = np.median(spacing[index], axis=1)
    return distance, np.maximum(local, cell)


def support_trim(mesh: trimesh.Trimesh, points, support: float = SUPPORT,
                 cell: float = 0.0) -> tuple[trimesh.Trimesh, np.ndarray, np.ndarray]:
    """`mesh` without the faces no point supports (a vertex or the centroid farther from the
    nearest of `points` than `support` local spacings, see `support_distances`) and without
    the vertices left unused; returns (mesh, kept vertex indices, their distances to the
    points, m)."""
    vertex_d, vertex_s = support_distances(points, mesh.vertices, cell)
    centre_d, centre_s = support_distances(points, mesh.triangles_center, cell)
    held = vertex_d <= support * vertex_s
    keep = held[mesh.faces].all(axis=1) & (centre_d <= support * centre_s)
    used = np.unique(mesh.faces[keep])
    remap = np.full(len(mesh.vertices), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    trimmed = trimesh.Trimesh(mesh.vertices[used], remap[mesh.faces[keep]], process=False)
    return trimmed, used, vertex_d[used]


def outlier_mask(points, ratio: float = OUTLIERS,
                 neighbours: int = OUTLIER_NEIGHBOURS) -> np.ndarray:
    """(n,) True for the points kept: those whose mean distance to their `neighbours` nearest
    points is at most `ratio` times the cloud's median of it (statistical outlier removal).
    Water-column clutter and scattered sea-surface ghosts lie far from one another; left in,
    screened Poisson closes a surface through them that the support trim cannot tell from a
    real one (the boulder demo: median vertex error 1.0 m, 0.075 m without them)."""
    points = np.asarray(points, dtype=float)
    if ratio <= 0 or len(points) <= neighbours:
        return np.ones(len(points), bool)
    mean = cKDTree(points).query(points, k=neighbours + 1)[0][:, 1:].mean(axis=1)
    return mean <= ratio * np.median(mean)


def check_spread(points: np.ndarray) -> None:
    """ValueError when `points` (n, 3) cannot carry a surface: fewer than `MIN_POINTS` distinct
    positions, or all on one line (Open3D's Poisson crashes the process on such clouds)."""
    distinct = len(np.unique(points, axis=0))
    if distinct < MIN_POINTS:
        raise ValueError(f"the point cloud has {distinct} distinct position(s) among its "
                         f"{len(points)} points; a surface needs at least {MIN_POINTS}")
    centred = points - points.mean(axis=0)
    spread = np.linalg.eigvalsh(centred.T @ centred)  # ascending
    if spread[1] <= 1e-12 * spread[2]:
        raise ValueError(f"the point cloud's {len(points)} points lie on one line; a surface "
                         "needs them spread over an area")


def reconstruct(cloud: PointCloud, depth: int = 9, trim: float = 0.05, k: int = 200,
                support: float = SUPPORT, progress: bool | RunProgress = True,
                outliers: float = OUTLIERS) -> Reconstruction:
    """The trimmed screened-Poisson surface of `cloud` (outliers dropped first, see
    `outlier_mask`, none when `outliers` is 0; normals from k neighbours, oriented by the
    recorded sensor origins when the cloud has them; faces farther than `support` local
    spacings from every point removed, none when 0). `progress`: show the progress over the
    `STAGES`, or a caller's `RunProgress` to advance by one per stage."""
    check_parameters(len(cloud), depth, k, trim, support, outliers)
    cloud = cloud.subset(np.flatnonzero(outlier_mask(cloud.points, outliers)))
    check_parameters(len(cloud), depth, k, trim, support, outliers)
    check_spread(cloud.points)
    with phase_display(progress, "reconstruct", len(STAGES),
                       f"normals (k = {k}) of {len(cloud)} points") as display:
        normals = estimate_normals(cloud.points, cloud.origins if cloud.has_origins else None, k)
        display.advance(1, f"screened Poisson, depth {depth}")
        mesh, densities = poisson(cloud.points, normals, depth, trim)
        display.advance(1, f"support trim ({support:g} local spacings)")
        extent = float(np.ptp(cloud.points, axis=0).max())
        cell = POISSON_SCALE * extent / 2 ** int(depth)
        if support > 0.0:
            mesh, kept, support_m = support_trim(mesh, cloud.points, support, cell)
            densities = densities[kept]
        else:
            support_m = support_distances(cloud.points, mesh.vertices)[0]
        if len(mesh.faces) == 0:
            raise ValueError(f"no face of the surface lies within {support:g} local spacings "
                             "of the points; raise support")
        display.advance(1)
    return Reconstruction(mesh, densities, normals, support_m, int(depth), int(k),
                          float(trim), float(support))
