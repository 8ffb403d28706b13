"""Synthetic seabeds: the caldera-rim site of the reference's Table 3, and random test seabeds.

The real Santorini caldera ROI is not public, so `caldera_site` builds a stand-in with the
figures the reference gives: a 100 m x 250 m ROI, gently sloping floor and plateau (slopes mostly
under 0.3), one rim band crossing the ROI whose slope reaches about 0.62, 0.5 m cells.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from drake_auv.terrain.bathymetry import Bathymetry


def _grid(width: float, length: float, cell: float):
    if not (np.isfinite(cell) and 0 < cell <= min(width, length) / 2):
        raise ValueError(f"cell must be in (0, {min(width, length) / 2}] m, got {cell}")
    nx = int(round(width / cell)) + 1
    ny = int(round(length / cell)) + 1
    return np.meshgrid(np.arange(nx) * cell, np.arange(ny) * cell)


def _taper(d: np.ndarray, half_width: float, ramp: float) -> np.ndarray:
    """1 for |d| <= half_width, a cosine ramp to 0 over `ramp`, 0 beyond (C1 continuous)."""
    t = np.clip((np.abs(d) - half_width) / ramp, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * t))


def caldera_site(cell: float = 0.5, seed: int = 0) -> Bathymetry:
    """A 100 m (x) x 250 m (y) caldera-rim ROI, world origin at its south-west corner.

    The caldera floor (south) and the plateau (north) slope gently (tilt 0.1 plus undulations);
    between them the rim wall, about 90 m wide and 55 m high, runs west-east with a slight bend
    and slopes 0.5 to 0.62. A seeded, smoothed noise of a few centimetres adds texture.

    Args:
        cell: square cell size, m (the reference's map: 0.5 m).
        seed: seed of the texture noise.
    """
    x, y = _grid(100.0, 250.0, cell)
    rim_centre = 125.0 + 6.0 * np.sin(np.pi * x / 100.0)
    d = y - rim_centre
    # Rim slope along y, integrated analytically: a plateau of steepness s(x) tapered at both sides.
    steep = 0.465 + 0.035 * np.sin(2.0 * np.pi * x / 100.0 + 0.4)
    rise = steep * _integrated_taper(d, 45.0, 8.0)
    undulation = (1.0 * np.sin(2 * np.pi * x / 45.0 + 0.7) * np.cos(2 * np.pi * y / 60.0)
                  + 0.5 * np.sin(2 * np.pi * (x + y) / 33.0))
    calm = _taper(d, 42.0, 25.0)  # no undulation on the rim wall, a long fade beside it
    rng = np.random.default_rng(seed)
    noise = ndimage.gaussian_filter(rng.normal(size=x.shape), sigma=max(1.0, 3.0 / cell))
    noise *= 0.03 / max(noise.std(), 1e-12)
    z = -320.0 + 0.1 * y + rise + (1.0 - calm) * undulation + noise
    return Bathymetry(z, spacing=(cell, cell), origin=(0.0, 0.0), crs=None)


def _integrated_taper(d: np.ndarray, half_width: float, ramp: float) -> np.ndarray:
    """Integral of `_taper` from -inf to d (so its derivative in d is the taper), m."""
    a, b = half_width, half_width + ramp

    def primitive(s):  # integral of the taper from 0 to s >= 0
        s = np.asarray(s, dtype=float)
        t = np.clip((s - a) / ramp, 0.0, 1.0)
        inner = np.minimum(s, a)
        ramp_part = 0.5 * ramp * (t + np.sin(np.pi * t) / np.pi)
        return inner + ramp_part

    total = primitive(b)
    return np.where(d >= 0, total + primitive(np.abs(d)), total - primitive(np.abs(d)))


def random_seabed(seed: int, shape: tuple[int, int] = (60, 80), cell: float = 1.0,
                  relief: float = 10.0, smoothness: float = 6.0) -> Bathymetry:
    """A random smooth seabed for property-based tests: Gaussian noise smoothed over
    `smoothness` cells and scaled to `relief` metres peak-to-peak, around -50 m."""
    if relief < 0 or smoothness <= 0:
        raise ValueError(f"relief must be >= 0 m and smoothness > 0 cells, got {relief}, {smoothness}")
    rng = np.random.default_rng(seed)
    field = ndimage.gaussian_filter(rng.normal(size=shape), sigma=smoothness, mode="reflect")
    span = np.ptp(field)
    z = -50.0 + (relief * (field - field.min()) / span if span > 0 else 0.0 * field)
    return Bathymetry(z, spacing=(cell, cell), origin=(0.0, 0.0))


def wreck_site(seed: int = 0, cell: float = 0.5, half: float = 35.0, depth: float = 32.0,
               origin=(431000.0, 4071000.0)):
    """A wreck on a rough seabed, as a user's site files would give it (world and target
    meshes, no prior map): a 20 m x 6 m hull with a pointed bow, heeled 12 deg and settled
    1 m into the seabed, with a deckhouse (faces of at most 0.5 m edges: coverage is scored
    per face); the seabed `depth` m deep, rough at the metre
    scale (seeded Gaussian relief of 2.5 m peak-to-peak over ~1.5 m, on a 2 % slope).
    Horizontal coordinates are eastings/northings about `origin` (m), z up.

    Returns (world, target): trimesh meshes; the target is the wreck's faces above the seabed
    (less the deck under the deckhouse).
    """
    import trimesh

    from drake_auv.terrain.mesh import bathymetry_to_mesh

    rng = np.random.default_rng(seed)
    n = int(round(2 * half / cell)) + 1
    field = ndimage.gaussian_filter(rng.normal(size=(n, n)), sigma=1.5 / cell, mode="reflect")
    xs = np.arange(n) * cell - half
    relief = 2.5 * (field - field.min()) / np.ptp(field)
    z = -depth - 1.25 + relief + 0.02 * xs[None, :]
    seabed = Bathymetry(z, spacing=(cell, cell), origin=(origin[0] - half, origin[1] - half))
    outline = _hull_outline(20.0, 6.0)
    hull = trimesh.convex.convex_hull(np.vstack([np.column_stack([outline, np.full(5, h)])
                                                 for h in (0.0, 5.0)]))  # z from 0 to 5 m
    deckhouse = trimesh.creation.box(extents=(5.0, 4.0, 3.0))
    deckhouse.apply_translation([-3.0, 0.0, 6.5])
    wreck = trimesh.util.concatenate([hull, deckhouse])
    wreck = trimesh.Trimesh(*trimesh.remesh.subdivide_to_size(wreck.vertices, wreck.faces,
                                                              max_edge=0.5), process=False)
    c = wreck.triangles_center  # the deck under the deckhouse and its floor: never seen
    hidden = (np.abs(c[:, 2] - 5.0) < 1e-6) & (np.abs(c[:, 0] + 3.0) < 2.5) & (np.abs(c[:, 1]) < 2.0)
    wreck.apply_transform(trimesh.transformations.rotation_matrix(np.radians(12.0), [1, 0, 0]))
    wreck.apply_transform(trimesh.transformations.rotation_matrix(np.radians(25.0), [0, 0, 1]))
    wreck.apply_translation([origin[0], origin[1], -depth - 1.0])
    below = wreck.triangles_center[:, 2] <= seabed.elevation_at(
        wreck.triangles_center[:, 0], wreck.triangles_center[:, 1]) + 0.05
    target = wreck.submesh([np.flatnonzero(~below & ~hidden)], append=True)
    world = trimesh.util.concatenate([bathymetry_to_mesh(seabed), wreck])
    return world, target


def _hull_outline(length: float, beam: float) -> np.ndarray:
    """(5, 2) the hull's waterline: a rectangle with a pointed bow along +x, centred, m."""
    a, b = length / 2, beam / 2
    return np.array([(-a, -b), (a - beam, -b), (a, 0.0), (a - beam, b), (-a, b)])
