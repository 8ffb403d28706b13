"""Named inspection sites: what a site's files hold, built in.

Each site gives a `Scenario`, the same data a user's site files give a mission's `site:` block
(`drake_auv.mission.site.load_site` builds the mission's `Site` from either, one way): `world`
is the true environment as a triangle mesh (world frame, z up, sea surface at z = 0, already
local: the site's coordinates are the mission's), what the simulated sensors see; solids
(blocks, the C-shaped object, the boulder) are closed and watertight, open surfaces (seabeds,
the pool) are oriented with their normals towards the water. `target_faces` marks the structure
to inspect, the faces coverage is measured on. There is no prior raster: the prior is the
world's top surface sampled at `params["prior_spacing"]` (a survey from above, overhangs hidden),
as for a user's world given without one. `start` is the start pose in the form of the mission
file's `site.start`.

Heavy geometry is built once per process (`functools.lru_cache`) and each `get_scenario` call
gets its own copy of the mesh, so callers may modify it freely.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from drake_auv.geometry.raycast import RayCaster
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh

DATA_DIR = Path(__file__).resolve().parent / "data"
MONTEREY_TILE = "MontereyBay.R_-121.825_-121.815_36.790_36.800.epsg3857.tif"


@dataclass(frozen=True)
class Scenario:
    """One built-in site's data.

    Attributes:
        name: the site's key in `list_scenarios()`.
        description: one line for the command line.
        world: true world mesh, world frame (= the mission's local frame), z up, m.
        target_faces: (len(world.faces),) bool, the structure to inspect.
        start: (x, y, z, yaw_deg) start pose, m and deg (as a mission file's `site.start`).
        params: mission parameters (omega: offset to the surface, m; depth: operating depth, m;
            speed: survey speed, m/s; prior_spacing: cell of the prior map, m; ...).
    """

    name: str
    description: str
    world: trimesh.Trimesh = field(repr=False)
    target_faces: np.ndarray = field(repr=False)
    start: tuple[float, float, float, float]
    params: dict

    @property
    def target_area(self) -> float:
        """Area of the target faces, m^2."""
        return float(self.world.area_faces[self.target_faces].sum())


# ---------------------------------------------------------------- geometry builders


def _patch(fn, nu: int, nv: int, normal_hint) -> tuple[np.ndarray, np.ndarray]:
    """A (nu x nv)-cell grid of triangles over the surface fn(u, v), u, v in [0, 1].

    Faces are wound so the mean normal agrees with `normal_hint`. Returns (vertices, faces).
    """
    u, v = np.meshgrid(np.linspace(0, 1, nu + 1), np.linspace(0, 1, nv + 1), indexing="ij")
    vertices = np.asarray(fn(u.ravel(), v.ravel()), dtype=float)
    idx = np.arange((nu + 1) * (nv + 1)).reshape(nu + 1, nv + 1)
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.vstack([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    tri = vertices[faces]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]).sum(axis=0)
    if normal @ np.asarray(normal_hint, dtype=float) < 0:
        faces = faces[:, ::-1]
    return vertices, faces


def _join(parts) -> tuple[np.ndarray, np.ndarray]:
    """Concatenates (vertices, faces) parts."""
    vertices, faces, offset = [], [], 0
    for v, f in parts:
        vertices.append(v)
        faces.append(f + offset)
        offset += len(v)
    return np.vstack(vertices), np.vstack(faces)


def _voxel_solid(occupied: np.ndarray, origin, pitch: float) -> tuple[np.ndarray, np.ndarray]:
    """The closed, outward-oriented boundary surface of a set of voxels.

    Every face between an occupied and an empty voxel becomes a square of two triangles on the
    shared vertex lattice, so the result is watertight (for voxel sets without edge-only
    contacts). Returns (vertices, faces), vertices in metres.
    """
    occ = np.pad(np.asarray(occupied, dtype=bool), 1)
    shape = np.array(occ.shape) + 1  # vertex lattice of the padded grid
    faces = []
    for axis in range(3):
        a1, a2 = (axis + 1) % 3, (axis + 2) % 3  # e_a1 x e_a2 = e_axis
        step = np.diff(occ.astype(np.int8), axis=axis)  # +1 empty->solid, -1 solid->empty
        for sign in (1, -1):
            cells = np.argwhere(step == sign)
            base = cells.copy()
            base[:, axis] += 1  # the lattice plane between the two voxels
            corners = []
            for d1, d2 in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = base.copy()
                c[:, a1] += d1
                c[:, a2] += d2
                corners.append(np.ravel_multi_index(c.T, shape))
            q0, q1, q2, q3 = corners
            quad = [np.column_stack([q0, q1, q2]), np.column_stack([q0, q2, q3])]
            tris = np.vstack(quad)
            # sign -1 (solid below along the axis): outward normal +axis, already the winding.
            faces.append(tris if sign == -1 else tris[:, ::-1])
    faces = np.vstack(faces)
    used, inverse = np.unique(faces, return_inverse=True)
    lattice = np.column_stack(np.unravel_index(used, shape)).astype(float)
    vertices = np.asarray(origin, dtype=float) + (lattice - 1.0) * pitch
    return vertices, inverse.reshape(faces.shape)


def _seabed_grid(xmin, xmax, ymin, ymax, cell, fn) -> Bathymetry:
    x = np.arange(xmin, xmax + 0.5 * cell, cell)
    y = np.arange(ymin, ymax + 0.5 * cell, cell)
    gx, gy = np.meshgrid(x, y)
    return Bathymetry(fn(gx, gy), (cell, cell), (x[0], y[0]))


def _frozen(vertices, faces, target) -> tuple:
    vertices = np.ascontiguousarray(vertices, dtype=float)
    faces = np.ascontiguousarray(faces, dtype=np.int64)
    target = np.asarray(target, dtype=bool)
    for a in (vertices, faces, target):
        a.setflags(write=False)
    return vertices, faces, target


@functools.lru_cache(maxsize=None)
def _pool_geometry(length=16.0, width=8.0, shallow=5.0, deep=7.0, coping=0.5, cell=0.25):
    """CIRS-like pool centred on the origin: x along its length, walls into the water."""
    hx, hy = length / 2, width / 2
    nx, ny = int(round(length / cell)), int(round(width / cell))
    nzs = int(round((shallow + coping) / cell))

    def bottom(x):  # the V along x: `shallow` at the end walls, `deep` at x = 0
        return -shallow - (deep - shallow) * (1.0 - np.abs(x) / hx)

    def long_wall(yw):
        def fn(u, v):
            x = -hx + length * u
            zb = bottom(x)
            return np.column_stack([x, np.full_like(u, yw), zb + v * (coping - zb)])
        return fn

    def end_wall(xw):
        def fn(u, v):
            return np.column_stack([np.full_like(u, xw), -hy + width * u,
                                    -shallow + v * (coping + shallow)])
        return fn

    def floor(u, v):
        x = -hx + length * u
        return np.column_stack([x, -hy + width * v, bottom(x)])

    nzl = int(round((deep + coping) / cell))
    walls = [_patch(long_wall(hy), nx, nzl, [0, -1, 0]), _patch(long_wall(-hy), nx, nzl, [0, 1, 0]),
             _patch(end_wall(hx), ny, nzs, [-1, 0, 0]), _patch(end_wall(-hx), ny, nzs, [1, 0, 0])]
    ground = _patch(floor, nx, ny, [0, 0, 1])
    vertices, faces = _join(walls + [ground])
    in_water = vertices[faces].mean(axis=1)[:, 2] < 0.0
    is_wall = np.arange(len(faces)) < sum(len(f) for _, f in walls)
    target = is_wall & in_water  # the submerged walls
    return _frozen(vertices, faces, target)


@functools.lru_cache(maxsize=None)
def _c_object_geometry(pitch=0.25):
    """A C-shaped solid (profile in x-z, opening towards -x) extruded 20 m along y, on a
    flat seabed at -20 m. Bottom flange z in [-20, -17], x in [0, 10]; wall x in [10, 13];
    ceiling flange z in [-9, -6], x in [0, 13]. The solid is sunk 0.5 m into the seabed."""
    x0, y0, z0 = 0.0, -10.0, -20.5
    xs = x0 + pitch * (np.arange(int(13 / pitch)) + 0.5)
    ys = y0 + pitch * (np.arange(int(20 / pitch)) + 0.5)
    zs = z0 + pitch * (np.arange(int(14.5 / pitch)) + 0.5)
    gx, gy, gz = np.meshgrid(xs, ys, zs, indexing="ij")
    occ = ((gz < -17) | (gx > 10) | (gz > -9)) & np.ones_like(gy, dtype=bool)
    solid_v, solid_f = _voxel_solid(occ, (x0, y0, z0), pitch)
    seabed = bathymetry_to_mesh(_seabed_grid(-25, 30, -25, 25, 0.5, lambda x, y: -20.0 + 0 * x))
    vertices, faces = _join([(solid_v, solid_f), (seabed.vertices, seabed.faces)])
    centroid_z = solid_v[solid_f].mean(axis=1)[:, 2]
    target = np.concatenate([centroid_z > -20.0, np.zeros(len(seabed.faces), bool)])
    return _frozen(vertices, faces, target)


BLOCK_SIZE, BLOCK_GAP, NUM_BLOCKS = 5.0, 0.5, 20


@functools.lru_cache(maxsize=None)
def _breakwater_geometry(pitch=0.25):
    """20 blocks 5 x 5 m in a row along x, 0.5 m apart, from +2 m to the seabed at -10 m
    (sunk 0.5 m into it). The right-most block (largest x) is centred on the origin and is the
    target, built finely; the others are plain boxes."""
    top, bottom = 2.0, -10.5
    parts, target = [], []
    for k in range(NUM_BLOCKS):
        cx = -(NUM_BLOCKS - 1 - k) * (BLOCK_SIZE + BLOCK_GAP)
        if k == NUM_BLOCKS - 1:
            n = int(BLOCK_SIZE / pitch)
            occ = np.ones((n, n, int(round((top - bottom) / pitch))), bool)
            v, f = _voxel_solid(occ, (cx - BLOCK_SIZE / 2, -BLOCK_SIZE / 2, bottom), pitch)
            z = v[f].mean(axis=1)[:, 2]
            target.append((z < 0.0) & (z > -10.0))
        else:
            box = trimesh.creation.box(extents=(BLOCK_SIZE, BLOCK_SIZE, top - bottom))
            box.apply_translation([cx, 0.0, 0.5 * (top + bottom)])
            v, f = box.vertices, box.faces
            target.append(np.zeros(len(f), bool))
        parts.append((v, f))
    seabed = bathymetry_to_mesh(_seabed_grid(-125, 25, -25, 25, 1.0, lambda x, y: -10.0 + 0 * x))
    parts.append((seabed.vertices, seabed.faces))
    target.append(np.zeros(len(seabed.faces), bool))
    vertices, faces = _join(parts)
    return _frozen(vertices, faces, np.concatenate(target))


@functools.lru_cache(maxsize=None)
def _boulder_geometry(seed=7, subdivisions=5):
    """An l'Amarrador-like boulder: a seeded, bumpy, leaning ellipsoid (closed, watertight)
    rising from a seabed at about -40 m to a top at -28 m, undercut all around its base and
    overhanging on its +x side."""
    rng = np.random.default_rng(seed)
    sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
    unit = np.asarray(sphere.vertices)
    # Smooth radial bumps: a few random plane waves on the unit sphere (star-shaped: no folds).
    freqs = rng.normal(size=(6, 3))
    freqs *= rng.uniform(1.5, 3.5, size=(6, 1)) / np.linalg.norm(freqs, axis=1, keepdims=True)
    phases = rng.uniform(0, 2 * np.pi, size=6)
    amps = rng.uniform(0.03, 0.07, size=6)
    radial = 1.0 + (amps * np.cos(unit @ freqs.T + phases)).sum(axis=1)
    v = unit * radial[:, None] * np.array([10.0, 7.5, 8.0])
    # Lean the upper part towards +x (a shear: still no self-intersection): an overhang.
    v[:, 0] += 3.0 * (np.clip(v[:, 2], 0, None) / 8.0) ** 2
    v[:, 2] += -28.0 - v[:, 2].max()  # top at -28 m; the bottom is buried below -40 m

    def seabed_z(x, y):
        return -40.0 + 0.3 * np.sin(x / 7.0 + 0.5) * np.cos(y / 9.0) + 0.01 * x

    seabed = bathymetry_to_mesh(_seabed_grid(-30, 30, -30, 30, 0.4, seabed_z))
    boulder_faces = np.asarray(sphere.faces)
    centroids = v[boulder_faces].mean(axis=1)
    above = centroids[:, 2] > seabed_z(centroids[:, 0], centroids[:, 1]) + 0.05
    vertices, faces = _join([(v, boulder_faces), (seabed.vertices, seabed.faces)])
    return _frozen(vertices, faces, np.concatenate([above, np.zeros(len(seabed.faces), bool)]))


@functools.lru_cache(maxsize=None)
def _caldera_geometry():
    from drake_auv.terrain.synthetic import caldera_site
    mesh = bathymetry_to_mesh(caldera_site())
    return _frozen(mesh.vertices, mesh.faces, np.ones(len(mesh.faces), bool))


@functools.lru_cache(maxsize=None)
def _monterey_geometry():
    from drake_auv.terrain.readers import read_bathymetry
    path = DATA_DIR / "monterey" / MONTEREY_TILE
    if not path.exists():
        raise FileNotFoundError(f"monterey scenario: tile {path} not found (the package's "
                                "data folder is incomplete: reinstall drake_auv)")
    mesh = bathymetry_to_mesh(read_bathymetry(path))
    return _frozen(mesh.vertices, mesh.faces, np.ones(len(mesh.faces), bool))


# ---------------------------------------------------------------- the sites


_SITES = {
    "caldera": dict(
        description=("Santorini-like caldera rim ROI, 100 m x 250 m, slopes up to 0.62; "
                     "camera at 2 m"),
        geometry=_caldera_geometry,
        start=(50.0, 5.0, -317.5, 90.0),  # 2 m above the floor
        params=dict(omega=2.0, aperture_deg=60.0, slope_threshold=0.5, speed=0.5,
                    prior_spacing=1.0, max_range=20.0)),
    "pool": dict(
        description=("CIRS-like pool 16 m x 8 m: vertical walls, 90 degree corners, V bottom; "
                     "4 m depth"),
        geometry=_pool_geometry,
        start=(-4.0, 0.0, -4.0, 0.0),
        params=dict(omega=2.0, depth=4.0, speed=0.3, laps=2, prior_spacing=0.25,
                    max_range=20.0)),
    "c_object": dict(
        description=("man-made object with a C-shaped vertical profile: floor, wall, "
                     "ceiling overhang"),
        geometry=_c_object_geometry,
        start=(-6.0, 0.0, -15.0, 0.0),
        params=dict(omega=2.0, speed=0.3, profile_plane="vertical", prior_spacing=0.5,
                    max_range=20.0)),
    "breakwater": dict(
        description="a row of 20 concrete blocks 5 m x 5 m, +2 m to the 10 m seabed, 0.5 m gaps",
        geometry=_breakwater_geometry,
        start=(0.0, -14.0, -5.0, 90.0),
        params=dict(omega=6.0, depth=5.0, speed=0.3, target_block=NUM_BLOCKS - 1,
                    block_size=BLOCK_SIZE, block_gap=BLOCK_GAP, prior_spacing=1.0,
                    max_range=20.0, replan_radius=5.0)),
    "boulder": dict(
        description=("l'Amarrador-like boulder, 40 m to 28 m depth, steep and overhanging; "
                     "0.4 m prior grid"),
        geometry=_boulder_geometry,
        start=(-25.0, 0.0, -30.0, 0.0),
        params=dict(omega=10.0, contours=2, contour_spacing=2.0, speed=0.5,
                    prior_spacing=0.4, max_range=20.0, replan_radius=5.0)),
    "monterey": dict(
        description="real Monterey Canyon head tile (NOAA DEM, ~8 x 10 m cells), depths 29-224 m",
        geometry=_monterey_geometry,
        start=None,
        params=dict(omega=20.0, aperture_deg=60.0, slope_threshold=0.5, speed=1.0,
                    prior_spacing=20.0, max_range=20.0)),
}


def list_scenarios() -> list[tuple[str, str]]:
    """(name, one-line description) of every site."""
    return [(name, site["description"]) for name, site in _SITES.items()]


def get_scenario(name: str, **overrides) -> Scenario:
    """The named site, with `overrides` replacing entries of its default `params`."""
    if name not in _SITES:
        raise ValueError(f"unknown scenario {name!r}; choose one of {sorted(_SITES)}")
    site = _SITES[name]
    unknown = set(overrides) - set(site["params"])
    if unknown:
        raise ValueError(f"scenario {name!r} has no parameter(s) {sorted(unknown)}; "
                         f"its parameters are {sorted(site['params'])}")
    vertices, faces, target = site["geometry"]()
    world = trimesh.Trimesh(vertices=vertices.copy(), faces=faces.copy(), process=False)
    params = {**site["params"], **overrides}
    start = site["start"]
    if start is None:  # above the centre of the tile at the survey offset omega
        lo, hi = world.bounds
        centre = 0.5 * (lo + hi)
        top = np.array([centre[0], centre[1], hi[2] + 1.0])
        seabed = RayCaster(world).cast(top, [[0.0, 0.0, -1.0]], hi[2] - lo[2] + 2.0)
        start = (float(centre[0]), float(centre[1]),
                 float(seabed.points[0, 2] + params["omega"]), 0.0)
    return Scenario(name, site["description"], world, target.copy(), start, params)
