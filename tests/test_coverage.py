"""Camera and sonar-fan coverage (pure): lawnmower lanes, occlusion, viewing angles."""

import numpy as np
import pytest
import trimesh

from drake_auv.geometry import CoverageMap, RayCaster
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh

APERTURE = np.radians(60.0)
ALTITUDE = 2.0
FOOTPRINT = 2 * ALTITUDE * np.tan(APERTURE / 2)  # 2.31 m, the reference's lane spacing


def _flat(width, length, cell=0.2, z=-20.0):
    nx, ny = int(round(width / cell)) + 1, int(round(length / cell)) + 1
    return bathymetry_to_mesh(Bathymetry(np.full((ny, nx), z), (cell, cell), (0.0, 0.0)))


def _lawnmower_coverage(spacing, lanes=6, length=20.0, step=0.1):
    width = lanes * spacing
    world = _flat(length, width)
    cov = CoverageMap(RayCaster(world))
    for k in range(lanes):
        y = (k + 0.5) * spacing
        for x in np.arange(0.0, length + 1e-9, step):
            cov.observe_camera([x, y, -20.0 + ALTITUDE], [0, 0, -1], APERTURE, 10.0)
    return cov


def test_lanes_at_footprint_width_cover_the_area():
    cov = _lawnmower_coverage(FOOTPRINT)
    assert cov.coverage() >= 0.98
    # Down-looking over flat ground: every face is viewed along its normal.
    area, edges = cov.histogram(bin_deg=5.0)
    assert area[0] == pytest.approx(area.sum()) and np.nanmax(cov.best) < 1e-6


def test_lanes_at_twice_the_footprint_cover_about_half():
    cov = _lawnmower_coverage(2 * FOOTPRINT, lanes=4)
    assert 0.45 < cov.coverage() < 0.56


def test_camera_sees_no_face_behind_an_occluder_nor_back_faces():
    ground = _flat(10.0, 10.0, cell=0.25, z=-10.0)
    slab = trimesh.creation.box(extents=(2.0, 2.0, 0.2))
    slab.apply_translation([5.0, 5.0, -8.0])
    world = trimesh.util.concatenate([ground, slab])
    target = np.r_[np.ones(len(ground.faces), bool), np.zeros(len(slab.faces), bool)]
    cov = CoverageMap(RayCaster(world), target)
    cov.observe_camera([5.0, 5.0, -5.0], [0, 0, -1], np.radians(90.0), 20.0)
    seen = np.isfinite(cov.best)
    c = world.triangles_center[:len(ground.faces)]
    # Shadow of the slab (top at -7.9, half-width 1) from a camera 5 m above the ground.
    r_shadow = 1.0 * 5.0 / (5.0 - 2.1)
    in_shadow = np.max(np.abs(c[:, :2] - 5.0), axis=1) < r_shadow - 0.2
    lit = (np.max(np.abs(c[:, :2] - 5.0), axis=1) > r_shadow + 0.2) & \
          (np.hypot(*(c[:, :2] - 5.0).T) < 5.0 * np.tan(np.radians(45)) - 0.2)
    assert in_shadow.any() and lit.any()
    assert not seen[in_shadow].any() and seen[lit].all()
    # From below the ground nothing is seen: its faces turn their backs.
    below = CoverageMap(RayCaster(ground))
    below.observe_camera([5.0, 5.0, -15.0], [0, 0, 1], APERTURE, 20.0)
    assert below.coverage() == 0.0


def test_viewing_angle_is_between_axis_and_inward_normal():
    # A 30 deg slope seen by a down-looking camera: angle 30 deg; looking along the normal: 0.
    x = np.arange(0, 20.01, 0.25)
    gx, gy = np.meshgrid(x, x)
    slope = np.tan(np.radians(30))
    world = bathymetry_to_mesh(Bathymetry(-30 + slope * gx, (0.25, 0.25), (0.0, 0.0)))
    down = CoverageMap(RayCaster(world))
    down.observe_camera([10.0, 10.0, -30 + slope * 10 + 3.0], [0, 0, -1], APERTURE, 10.0)
    np.testing.assert_allclose(np.degrees(down.best[np.isfinite(down.best)]), 30.0, atol=1e-6)
    normal = np.array([-slope, 0.0, 1.0]) / np.hypot(slope, 1.0)
    along = CoverageMap(RayCaster(world))
    along.observe_camera(np.array([10.0, 10.0, -30 + slope * 10]) + 3.0 * normal, -normal,
                         APERTURE, 10.0)
    assert np.nanmax(along.best) < 1e-6 and along.coverage() > 0
    area, edges = down.histogram(bin_deg=7.0)
    assert edges[4] == 28.0 and area[4] == pytest.approx(area.sum())  # all in [28, 35) deg


def test_sonar_fan_marks_the_faces_its_beams_hit():
    world = _flat(20.0, 20.0, cell=0.5)
    caster = RayCaster(world)
    cov = CoverageMap(caster)
    a = np.radians(np.linspace(-60, 60, 480))
    dirs = np.column_stack([np.zeros_like(a), np.sin(a), -np.cos(a)])
    hits = caster.cast([10.0, 10.0, -15.0], dirs, 20.0)
    cov.observe_beams(hits, dirs)
    seen = np.isfinite(cov.best)
    assert seen.sum() == len(np.unique(hits.faces[hits.faces >= 0]))
    np.testing.assert_allclose(np.sort(np.degrees(cov.best[seen]))[-1], 60.0, atol=0.5)


def test_bad_input():
    caster = RayCaster(_flat(4.0, 4.0))
    with pytest.raises(ValueError, match="target_faces"):
        CoverageMap(caster, np.zeros(3, bool))
    with pytest.raises(ValueError, match="empty"):
        CoverageMap(caster, np.zeros(caster.num_faces, bool))
    cov = CoverageMap(caster)
    with pytest.raises(ValueError, match="aperture"):
        cov.observe_camera([0, 0, 0], [0, 0, -1], 0.0, 5.0)
    with pytest.raises(ValueError, match="max_range"):
        cov.observe_camera([0, 0, 0], [0, 0, -1], APERTURE, -1.0)
