"""Where a mission flies: the true world, the target, the prior map and the local frame.

A site's files share one horizontal frame, the site's (the prior raster's CRS, often UTM with
eastings near 500 km). The mission works in a LOCAL frame: local = site - origin in x, y (z
unchanged, z up, sea surface z = 0), `origin` the centre of the world's horizontal bounds
rounded to 1 m, so float32 ray casting keeps millimetres. `Site.to_site` converts outputs
back. Pure Python, no Drake.

Every site is loaded one way, by `load_site`, from the same data: a world mesh, its target (a
mesh of part of it, or its faces), a prior raster or the cell at which the world's top surface
is sampled as one, and a start pose. A user's files give them, so does a built-in scenario
(`drake_auv.scenarios`, whose world is already local: its origin is 0). The loader moves them to
the local frame, shifts the prior by the seeded prior-map error and makes the start state.

A site given as `tile` + `roi` (a survey grid and a region of it) is made of files generated
once by `terrain.site_files.write_site_files` (1 m world, the grid as prior, UTM) into a cache
folder, `$DRAKE_AUV_CACHE/sites/<tile stem>_<roi>` (default `~/.cache/drake_auv`), and then
loaded as a site given by its files.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import shutil
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

from drake_auv.mission.spec import MissionFileError, SiteSpec
from drake_auv.random_streams import generator
from drake_auv.scenarios import get_scenario
from drake_auv.signals import VehicleState
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import top_surface

TARGET_TOLERANCE = 0.05  # m, a world face lies on the target when its centroid is this close
DEFAULT_PRIOR_SPACING = 1.0  # m, the prior's cell when sampled from a user's world
TILE_WORLD_SPACING = 1.0  # m, the world mesh's cell of a site cut from a tile
TILE_MARGIN = 40.0  # m of world around a tile site's region
MAX_PRIOR_ERROR = 5.0  # m, the reference's largest prior-map error


def cache_dir() -> Path:
    """Where generated site files go: $DRAKE_AUV_CACHE, else ~/.cache/drake_auv."""
    return Path(os.environ.get("DRAKE_AUV_CACHE") or Path.home() / ".cache" / "drake_auv")


def tile_site_files(spec: SiteSpec, label: str = "mission") -> SiteSpec:
    """`spec` (a `tile` + `roi` site) as a site given by its files, generated on first use into
    `cache_dir()` (in a temporary folder renamed into place, so concurrent runs never read a
    half-written site). Raises MissionFileError for a missing or unusable tile."""
    from drake_auv.terrain.readers import read_bathymetry
    from drake_auv.terrain.site_files import write_site_files

    tile = spec.tile
    if not tile.is_file():
        raise MissionFileError(label, "site.tile", f"{tile.name} not found ({tile})",
                               "an existing georeferenced bathymetry grid (GeoTIFF)")
    folder = cache_dir() / "sites" / (tile.stem + "_" + "_".join(f"{v:g}" for v in spec.roi))
    if not (folder / "prior.tif").is_file():
        try:
            bathy = read_bathymetry(tile)
            folder.parent.mkdir(parents=True, exist_ok=True)
            work = Path(tempfile.mkdtemp(dir=folder.parent, prefix=".partial-"))
            write_site_files(bathy, spec.roi, work, world_spacing=TILE_WORLD_SPACING,
                             margin=TILE_MARGIN)
            try:
                work.rename(folder)
            except OSError:  # another run wrote it first
                shutil.rmtree(work, ignore_errors=True)
        except ValueError as err:
            raise MissionFileError(label, "site.roi", " ".join(str(err).split()),
                                   "a region inside the tile with room for the margin "
                                   f"({TILE_MARGIN:g} m)") from None
        except OSError as err:
            raise MissionFileError(label, "site.tile", f"cannot write the site files to "
                                   f"{folder} ({err.strerror or err})",
                                   "a writable $DRAKE_AUV_CACHE") from None
    return dataclasses.replace(spec, tile=None, roi=None, world=folder / "world.ply",
                               target=folder / "target.ply", prior=folder / "prior.tif")


@dataclass
class Site:
    """A loaded site, in the local frame.

    Attributes:
        name: the built-in scenario's name or the world file's stem.
        world: true world mesh, local frame, m.
        target_faces: (len(world.faces),) bool, the faces whose coverage is scored.
        prior: the prior map the planner holds, local frame, already shifted by the seeded
            prior error; its `to_crs` maps local (x, y) to the site's CRS.
        origin: (2,) site coordinates of the local frame's origin, m.
        crs: the site's CRS (e.g. "EPSG:32631"), or None.
        start_state: (12,) local start state `[x, y, z, roll, pitch, yaw, u, v, w, p, q, r]`,
            or None (the runner chooses).
        max_range: range of the sonars, m.
        prior_shift: (2,) the prior map's horizontal error, m (where the map puts things,
            less where they are).
    """

    name: str
    world: trimesh.Trimesh = field(repr=False)
    target_faces: np.ndarray = field(repr=False)
    prior: Bathymetry = field(repr=False)
    origin: np.ndarray
    crs: str | None = None
    start_state: np.ndarray | None = None
    max_range: float = 20.0
    prior_shift: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def to_local(self, points) -> np.ndarray:
        """(..., 2) or (..., 3) site coordinates -> local (x, y shifted, z unchanged), m."""
        return self._shift(points, -1.0)

    def to_site(self, points) -> np.ndarray:
        """(..., 2) or (..., 3) local coordinates -> site coordinates, m."""
        return self._shift(points, 1.0)

    def _shift(self, points, sign: float) -> np.ndarray:
        out = np.array(points, dtype=float)
        out[..., :2] += sign * np.asarray(self.origin, dtype=float)
        return out

    @functools.cached_property
    def target_mesh(self) -> trimesh.Trimesh:
        """The target faces as their own mesh (local frame), built once."""
        return self.world.submesh([np.flatnonzero(self.target_faces)], append=True)

    @functools.cached_property
    def clearance(self):
        """The world's `geometry.clearance.WorldClearance` (local frame), built once: signed
        clearance, negative inside the world or above the sea surface."""
        from drake_auv.geometry.clearance import WorldClearance

        return WorldClearance(self.world)


def shift_prior(bathy: Bathymetry, error_m: float, seed: int) -> Bathymetry:
    """`bathy` moved horizontally by `error_m` (m, in [0, 5]) in a direction drawn from
    the run's `seed`: the prior-map error. The grid, CRS and world-to-CRS map are kept (the
    cells now claim wrong positions)."""
    if not (np.isfinite(error_m) and 0.0 <= error_m <= MAX_PRIOR_ERROR):
        raise ValueError(f"prior map: error_m must be in [0, {MAX_PRIOR_ERROR}] m, "
                         f"got {error_m}")
    return Bathymetry(bathy.z, bathy.spacing,
                      tuple(np.add(bathy.origin, prior_offset(error_m, seed))), bathy.crs,
                      bathy.to_crs)


def prior_offset(error_m: float, seed: int) -> np.ndarray:
    """(2,) the horizontal shift of a prior map with error `error_m` (m), its direction drawn
    from the run's `prior_map` stream (`drake_auv.random_streams`)."""
    theta = generator(seed, "prior_map").uniform(0.0, 2.0 * np.pi)
    return error_m * np.array([np.cos(theta), np.sin(theta)])


def start_state(pose, origin) -> np.ndarray:
    """The local state (`signals.VehicleState`) at rest at `pose` (x, y, z, yaw_deg), site
    coordinates, m and deg; `origin` (2,) the local frame's."""
    state = VehicleState.zeros()
    x, y, z, yaw_deg = pose
    state.x, state.y, state.z, state.yaw = x - origin[0], y - origin[1], z, math.radians(yaw_deg)
    return state[:]


def load_mesh(path, where: str, label: str) -> trimesh.Trimesh:
    """A mesh file as one finite, non-empty Trimesh (a Scene is concatenated; coordinates as
    stored, z up, also for GLB, whose convention is y up). A missing, unreadable or empty file
    raises `MissionFileError` naming `where` (the field or option) and `label` (the file)."""
    if not path.is_file():
        raise MissionFileError(label, where, f"{path.name} not found ({path})",
                               "an existing PLY, OBJ, STL or GLB mesh file")
    try:
        loaded = trimesh.load(path, process=False)
    except Exception as err:  # trimesh raises many types for unreadable files
        raise MissionFileError(label, where, f"{path.name} is not a readable mesh "
                               f"({' '.join(str(err).split())})",
                               "a PLY, OBJ, STL or GLB triangle mesh") from None
    if isinstance(loaded, trimesh.Scene):
        parts = [g for g in loaded.dump() if isinstance(g, trimesh.Trimesh)]
        loaded = trimesh.util.concatenate(parts) if parts else None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise MissionFileError(label, where, f"{path.name} holds no triangles",
                               "a triangle mesh with at least one face")
    if not np.all(np.isfinite(loaded.vertices)):
        raise MissionFileError(label, where, f"{path.name} has non-finite vertices",
                               "finite coordinates, m")
    return loaded


def _local_prior(path, origin: np.ndarray, label: str) -> Bathymetry:
    """The prior raster in the local frame. The site's coordinates are the raster's CRS (the
    world mesh lies in them), so its cells are placed there by its georeferencing (`to_crs`)
    and translated by -origin; their spacing is in map units. This takes every raster
    `drake-auv plan` takes whose rows and columns run along its CRS's axes and whose CRS is
    not geographic, also one whose ground-metre frame is not its CRS: a Mercator raster
    (EPSG:3857) keeps its map units, which are ground metres / cos(latitude), as the mesh's
    coordinates are (a one-line warning says so). Refused: geographic CRSs (a mesh in degrees)
    and rotated or sheared rasters (not a grid along the site's axes)."""
    from pyproj import CRS

    from drake_auv.terrain.readers import read_bathymetry

    if not path.is_file():
        raise MissionFileError(label, "site.prior", f"{path.name} not found ({path})",
                               "an existing bathymetry raster (GeoTIFF, ASCII grid, ...)")
    try:
        bathy = read_bathymetry(path)
    except ValueError as err:
        raise MissionFileError(label, "site.prior", " ".join(str(err).split()),
                               "a bathymetry raster GDAL reads") from None
    if bathy.crs is not None and CRS.from_user_input(bathy.crs).is_geographic:
        raise MissionFileError(label, "site.prior", f"{path.name} is in the geographic CRS "
                               f"{bathy.crs} (degrees), which cannot hold a world mesh",
                               "a raster in a projected CRS (the world mesh's coordinates), "
                               "e.g. UTM")
    to_crs = np.eye(3) if bathy.to_crs is None else np.asarray(bathy.to_crs, dtype=float)
    scale = np.diag(to_crs[:2, :2])  # map units per ground metre along x and y
    if not (np.all(scale > 0.0) and np.allclose(to_crs[:2, :2], np.diag(scale),
                                                atol=1e-9 * scale.max())):
        raise MissionFileError(label, "site.prior", f"{path.name}'s rows and columns do not "
                               f"run along the x and y axes of its CRS ({bathy.crs})",
                               "a north-up raster (rotation and shear terms 0)")
    if not np.allclose(scale, 1.0, atol=1e-6):
        warnings.warn(f"{label}: site.prior: {path.name} is in {bathy.crs}, where a ground "
                      f"metre is {scale[0]:.4f} map units; the dive is simulated in map units "
                      "(the world mesh's coordinates), its distances that much longer than on "
                      "the ground", stacklevel=2)
    cell0 = to_crs[:2, :2] @ bathy.origin + to_crs[:2, 2]  # site coordinates of cell (0, 0)
    local_to_crs = np.eye(3)
    local_to_crs[:2, 2] = origin
    return Bathymetry(bathy.z, tuple(scale * bathy.spacing), tuple(cell0 - origin), bathy.crs,
                      local_to_crs)


def load_site(spec: SiteSpec, seed: int, label: str = "mission") -> Site:
    """The site of `spec` (a built-in scenario, a user's files or a tile's generated files),
    its prior shifted by `spec.prior_error_m` in a direction drawn from `seed`. Raises
    MissionFileError (`label`: the mission file's name) naming the field for a missing or
    unusable file."""
    if spec.tile is not None:
        spec = tile_site_files(spec, label)
    if spec.scenario is not None:  # the built-in data, in place of the files
        scenario = get_scenario(spec.scenario)
        name, world, target, start = spec.scenario, scenario.world, scenario.target_faces, \
            scenario.start
        origin = np.zeros(2)  # already local
        spacing = spec.prior_spacing_m or scenario.params["prior_spacing"]
    else:
        name, world, start = spec.world.stem, load_mesh(spec.world, "site.world", label), None
        lo, hi = world.bounds
        if lo[2] >= 0.0:
            raise MissionFileError(label, "site.world", f"{spec.world.name} lies entirely "
                                   f"above the sea surface (lowest z {lo[2]:g} m)",
                                   "a world with its seabed below z = 0 (z up, metres)")
        target = None if spec.target is None else load_mesh(spec.target, "site.target", label)
        origin = np.round(0.5 * (lo[:2] + hi[:2]))
        spacing = spec.prior_spacing_m or DEFAULT_PRIOR_SPACING
    world.apply_translation([-origin[0], -origin[1], 0.0])
    if target is None:
        target = np.ones(len(world.faces), bool)
    elif isinstance(target, trimesh.Trimesh):
        target = _target_faces(world, target, origin, spec.target.name, label)
    if spec.prior is None:
        prior = top_surface(world, spacing)
        local_to_crs = np.eye(3)
        local_to_crs[:2, 2] = origin
        prior = Bathymetry(prior.z, prior.spacing, prior.origin, spec.crs, local_to_crs)
    else:
        prior = _local_prior(spec.prior, origin, label)
        if spec.crs is not None and prior.crs is not None and spec.crs != prior.crs:
            raise MissionFileError(label, "site.crs", f"{spec.crs} differs from the prior "
                                   f"raster's {prior.crs}", f"{prior.crs} or null")
        xmin, xmax, ymin, ymax = prior.extent
        (wx0, wy0), (wx1, wy1) = world.bounds[:, :2]
        if xmin > wx1 or xmax < wx0 or ymin > wy1 or ymax < wy0:
            raise MissionFileError(label, "site.prior", f"{spec.prior.name} does not overlap "
                                   "the world mesh", "a raster covering the world, in its frame")
    prior = shift_prior(prior, spec.prior_error_m, seed)
    if spec.start is not None:
        start = spec.start
    return Site(name, world, target, prior, origin, prior.crs or spec.crs,
                None if start is None else start_state(start, origin), spec.max_range_m,
                prior_shift=prior_offset(spec.prior_error_m, seed))


def _target_faces(world: trimesh.Trimesh, target: trimesh.Trimesh, origin: np.ndarray,
                  name: str, label: str) -> np.ndarray:
    """World faces whose centroid lies within TARGET_TOLERANCE of the target mesh (site frame
    `target`, moved to the local frame here)."""
    from drake_auv.geometry.distance import mesh_distance

    target.apply_translation([-origin[0], -origin[1], 0.0])
    centroids = world.triangles_center
    lo, hi = target.bounds[0] - TARGET_TOLERANCE, target.bounds[1] + TARGET_TOLERANCE
    near = np.flatnonzero(np.all((centroids >= lo) & (centroids <= hi), axis=1))
    faces = np.zeros(len(world.faces), bool)
    if near.size:
        faces[near] = mesh_distance(target, centroids[near]) <= TARGET_TOLERANCE
    if not faces.any():
        raise MissionFileError(label, "site.target", f"no face of the world lies on {name} "
                               f"(within {TARGET_TOLERANCE} m)",
                               "a mesh of part of the world, in the same coordinates")
    return faces


def check_inside(site: Site, xy_site, where: str, label: str) -> tuple[float, float]:
    """(x, y) local of the site-coordinates point `xy_site`; raises MissionFileError (naming
    `where`) when it lies outside the world."""
    (x0, y0), (x1, y1) = site.world.bounds[:, :2]
    x, y = site.to_local(xy_site)[:2]
    if not (x0 <= x <= x1 and y0 <= y <= y1):
        (sx0, sy0), (sx1, sy1) = site.to_site(site.world.bounds[:, :2])
        raise MissionFileError(label, where, f"({xy_site[0]:g}, {xy_site[1]:g}) is outside "
                               "the world", f"x in [{sx0:.1f}, {sx1:.1f}], y in [{sy0:.1f}, "
                               f"{sy1:.1f}] m (site coordinates)")
    return x, y


def check_in_water(site: Site, points, label: str, where: str, names) -> None:
    """Raises MissionFileError (one line naming `where` and the point's name in `names`, one
    per point, or one for all, "" for none) for the first local point (n, 3) inside the world
    or above the sea surface (`Site.clearance`), with its depth against the world's top
    there."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    names = [names] * len(points) if isinstance(names, str) else list(names)
    for name, problem, (x, y, _) in zip(names, site.clearance.misplaced(points), points):
        if problem is not None:
            top = float(site.clearance.top([[x, y]])[0])
            allowed = (f"a point in the water: depth in [0, {-top:.1f}) m there, outside the "
                       "structures" if np.isfinite(top) and top < 0.0 else
                       "a point in the water, outside the world")
            raise MissionFileError(label, where, f"{name}: {problem}" if name else problem,
                                   allowed)


def check_path_in_water(path, site: Site, label: str, where: str) -> None:
    """Raises MissionFileError (one line naming `where` and the sample) for the first sample of
    a planned `path` (a `planning.path.PlannedPath`, local frame) above the sea surface or below the
    prior map it was planned on (on the map's extent)."""
    x, y, z = path.points.T
    xmin, xmax, ymin, ymax = site.prior.extent
    seabed = np.where((x >= xmin) & (x <= xmax) & (y >= ymin) & (y <= ymax),
                      site.prior.elevation_at(x, y), np.nan)
    bad = np.flatnonzero((z > 0.0) | (z < np.nan_to_num(seabed, nan=-np.inf) - 1e-6))
    if len(bad):
        k = int(bad[0])
        what = (f"{z[k]:.2f} m above the sea surface" if z[k] > 0.0 else
                f"{seabed[k] - z[k]:.2f} m below the prior map's seabed there "
                f"({-seabed[k]:.1f} m deep)")
        raise MissionFileError(label, where, f"sample {k} of the planned path: depth "
                               f"{-z[k]:.2f} m is {what}", "a path in the water the planner "
                               "planned on the prior map")

