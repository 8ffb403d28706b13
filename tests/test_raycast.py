"""Ray casting against trimesh meshes with embree, and grid -> mesh conversion."""

import numpy as np
import pytest
import trimesh

from drake_auv.geometry import RayCaster
from drake_auv.geometry.raycast import face_centroids, face_normals_and_areas
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh


def _plane_bathy(nx=21, ny=11, spacing=(1.0, 2.0), origin=(5.0, -3.0), slope=(0.1, -0.05),
                 z0=-20.0):
    """A tilted plane z = z0 + slope . (xy - origin)."""
    gx, gy = np.meshgrid(spacing[0] * np.arange(nx), spacing[1] * np.arange(ny))
    return Bathymetry(z0 + slope[0] * gx + slope[1] * gy, spacing, origin)


def test_grid_mesh_has_two_triangles_per_cell_and_upward_normals():
    bathy = _plane_bathy()
    mesh = bathymetry_to_mesh(bathy)
    assert len(mesh.faces) == 2 * 20 * 10
    expected_n = np.array([-0.1, 0.05, 1.0]) / np.linalg.norm([-0.1, 0.05, 1.0])
    np.testing.assert_allclose(mesh.face_normals, np.tile(expected_n, (len(mesh.faces), 1)),
                               atol=1e-9)
    np.testing.assert_allclose(mesh.area, 20 * 20 * np.linalg.norm([-0.1, 0.05, 1.0]), rtol=1e-9)


def test_grid_mesh_skips_cells_with_nodata_corner():
    bathy = _plane_bathy()
    z = bathy.z.copy()
    z[4, 7] = np.nan  # an interior sample touches 4 cells
    z[0, 0] = np.nan  # a corner sample touches 1 cell
    mesh = bathymetry_to_mesh(bathy.with_z(z))
    assert len(mesh.faces) == 2 * (200 - 4 - 1)
    assert np.all(np.isfinite(mesh.vertices))
    assert len(mesh.vertices) == 21 * 11 - 2  # no unused vertices kept


def test_grid_mesh_stride_and_bad_input():
    bathy = _plane_bathy()
    assert len(bathymetry_to_mesh(bathy, stride=2).faces) == 2 * 10 * 5
    with pytest.raises(ValueError, match="stride"):
        bathymetry_to_mesh(bathy, stride=0)
    with pytest.raises(ValueError, match="Bathymetry"):
        bathymetry_to_mesh(np.zeros((5, 5)))


def test_vertical_rays_hit_grid_surface_at_its_elevation():
    bathy = _plane_bathy()
    caster = RayCaster(bathymetry_to_mesh(bathy))
    rng = np.random.default_rng(3)
    xy = np.column_stack([rng.uniform(6, 24, 500), rng.uniform(-2, 16, 500)])
    origins = np.column_stack([xy, np.zeros(500)])
    hits = caster.cast(origins, [0.0, 0.0, -1.0] * np.ones((500, 1)), 100.0)
    z_true = bathy.elevation_at(xy[:, 0], xy[:, 1])
    assert np.all(hits.faces >= 0)
    np.testing.assert_allclose(hits.ranges, -z_true, atol=1e-4)
    np.testing.assert_allclose(hits.points[:, 2], z_true, atol=1e-4)


def test_oblique_ray_range_on_unit_box_and_no_hit_outside():
    box = trimesh.creation.box(extents=(2, 2, 2))  # faces at +-1
    caster = RayCaster(box)
    d = np.array([[1.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    o = np.array([[-5.0, -4.5, 0.0], [-10.0, 0.0, 0.0], [3.0, 0.0, 0.0], [-10.0, 0.0, 0.0]])
    hits = caster.cast(o, d, np.array([50.0, 50.0, 50.0, 8.5]))
    # Ray 0 enters x = -1 at t = 4 sqrt(2) (y = -0.5); ray 1 at t = 9; ray 2 misses; ray 3 is short.
    np.testing.assert_allclose(hits.ranges[:2], [4 * np.sqrt(2), 9.0], atol=1e-5)
    np.testing.assert_allclose(hits.points[0], [-1.0, -0.5, 0.0], atol=1e-5)
    assert np.isnan(hits.ranges[2:]).all() and np.all(hits.faces[2:] == -1)
    assert np.isnan(hits.points[2:]).all()
    assert np.all(np.abs(caster.face_normals[hits.faces[:2]] @ [1.0, 0, 0] + 1) < 1e-9)


def test_first_hit_respects_occlusion():
    near = trimesh.creation.box(extents=(0.2, 4, 4))
    near.apply_translation([3.0, 0, 0])
    far = trimesh.creation.box(extents=(0.2, 20, 20))
    far.apply_translation([8.0, 0, 0])
    caster = RayCaster(trimesh.util.concatenate([near, far]))
    # The second ray passes the near box's edge (y = 2.32 > 2 at x = 2.9) and hits the far one.
    hits = caster.cast(np.zeros(3), [[1, 0, 0], [1, 0.8, 0], [1, 0.6, 0]], 20.0)
    np.testing.assert_allclose(hits.ranges, [2.9, 7.9 * np.hypot(1, 0.8), 2.9 * np.hypot(1, 0.6)],
                               atol=1e-5)


def test_large_world_coordinates_keep_precision():
    bathy = _plane_bathy(origin=(-13_560_000.0, 4_410_000.0))
    caster = RayCaster(bathymetry_to_mesh(bathy))
    x0, y0 = bathy.origin
    o = np.array([[x0 + 3.3, y0 + 7.1, 0.0]])
    hits = caster.cast(o, [[0, 0, -1]], 1e9)
    assert abs(hits.points[0, 2] - bathy.elevation_at(o[0, 0], o[0, 1])) < 1e-3


def test_bad_meshes_and_rays_raise():
    with pytest.raises(ValueError, match="empty"):
        RayCaster(trimesh.Trimesh(vertices=np.zeros((0, 3)), faces=np.zeros((0, 3), int)))
    with pytest.raises(ValueError, match="triangle"):
        RayCaster(trimesh.PointCloud(np.random.default_rng(0).normal(size=(10, 3))))
    with pytest.raises(ValueError, match="triangle"):
        RayCaster(trimesh.load_path(np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])))
    caster = RayCaster(trimesh.creation.box())
    with pytest.raises(ValueError, match="max_range"):
        caster.cast(np.zeros(3), [[1, 0, 0]], -1.0)
    with pytest.raises(ValueError, match="non-zero"):
        caster.cast(np.zeros(3), [[0, 0, 0]], 1.0)
    with pytest.raises(ValueError, match="origins"):
        caster.cast(np.zeros((2, 3)), [[1, 0, 0]], 1.0)


def test_cast_unit_takes_scalar_or_per_ray_ranges_and_marks_misses():
    caster = RayCaster(trimesh.creation.box(extents=(2.0, 2.0, 2.0)))
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    origin = np.array([0.0, -0.5, 0.0])
    for max_range in (5.0, np.float32(5.0), [5.0, 5.0, 0.2], np.array([5.0, 5.0, 0.2])):
        ranges, faces = caster.cast_unit(origin, directions, max_range)
        np.testing.assert_allclose(ranges[:2], [1.0, 1.0], atol=1e-6)
        assert (faces[:2] >= 0).all()
        if np.ndim(max_range):  # the third ray (1.5 m to the wall) stops at 0.2 m
            assert np.isnan(ranges[2]) and faces[2] == -1
        else:
            assert abs(ranges[2] - 1.5) < 1e-6
    again, _ = caster.cast_unit(origin, directions, 5.0)
    assert not np.shares_memory(again, ranges)  # each query owns its arrays


def test_cast_unit_leaves_the_callers_ranges_alone():
    # Embree writes its hits into the query's range array: a float32 one of the caller's
    # (a sonar's per-ray reach, read again after the cast) must not be that array.
    caster = RayCaster(trimesh.creation.box(extents=(2, 2, 2)))
    reach = np.array([50.0, 0.5], dtype=np.float32)
    ranges, faces = caster.cast_unit(np.array([-10.0, 0.0, 0.0]),
                                     np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]), reach)
    np.testing.assert_allclose(ranges, [9.0, np.nan], atol=1e-5)
    np.testing.assert_array_equal(reach, np.array([50.0, 0.5], dtype=np.float32))



def test_robust_scene_is_watertight_where_the_fast_traversal_leaks():
    # Rays from the centre of a closed sphere aimed at its edges' midpoints and its vertices:
    # every one must hit it; without the robust flag some pass between the faces.
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    aims = np.vstack([sphere.vertices, sphere.vertices[sphere.edges_unique].mean(axis=1)])
    aims /= np.linalg.norm(aims, axis=1, keepdims=True)
    robust, fast = RayCaster(sphere), RayCaster(sphere, robust=False)
    ranges, faces = robust.cast_unit(np.zeros(3), aims, 5.0)
    assert np.all(faces >= 0) and np.all(np.abs(ranges - 2.0) < 0.05)
    assert np.sum(fast.cast_unit(np.zeros(3), aims, 5.0)[1] < 0) > 10


def test_face_geometry_is_trimeshs_to_the_bit_and_a_degenerate_face_has_no_normal():
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=2.0)
    caster = RayCaster(sphere)
    np.testing.assert_array_equal(caster.face_normals, sphere.face_normals)
    np.testing.assert_array_equal(caster.face_areas, sphere.area_faces)
    np.testing.assert_array_equal(face_centroids(sphere.vertices, sphere.faces),
                                  sphere.triangles_center)
    v = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    sliver = trimesh.Trimesh(v, [[0, 1, 2], [0, 1, 3]], process=False)
    normals, areas = face_normals_and_areas(v, sliver.faces)
    np.testing.assert_array_equal(normals, [[0, 0, 0], [0, 0, 1]])
    np.testing.assert_array_equal(areas, [0.0, 0.5])
    # a chunk at a time (the sliver in the second chunk): the same bits
    faces = np.vstack([sphere.faces, sliver.faces + len(sphere.vertices)])
    vertices = np.vstack([sphere.vertices, v])
    normals, areas = face_normals_and_areas(vertices, faces, chunk=len(faces) - 1)
    np.testing.assert_array_equal(normals, np.vstack([sphere.face_normals, [[0, 0, 0], [0, 0, 1]]]))
    np.testing.assert_array_equal(areas, np.append(sphere.area_faces, [0.0, 0.5]))
    np.testing.assert_array_equal(face_centroids(sphere.vertices, sphere.faces, chunk=7),
                                  sphere.triangles_center)


def test_grid_mesh_is_two_triangles_per_whole_square_in_row_order():
    z = np.arange(30.0).reshape(5, 6) - 40.0
    z[2, 3] = np.nan
    mesh = bathymetry_to_mesh(Bathymetry(z, (1.0, 2.0), (5.0, -3.0)))
    gx, gy = np.meshgrid(5.0 + np.arange(6), -3.0 + 2.0 * np.arange(5))
    keep = np.isfinite(z.ravel())
    np.testing.assert_array_equal(mesh.vertices, np.column_stack(
        [gx.ravel(), gy.ravel(), z.ravel()])[keep])
    new = np.cumsum(keep) - 1  # vertex index after the unreferenced one is dropped
    expected = []
    for i in range(4):
        for j in range(5):
            a, b, c, d = i * 6 + j, i * 6 + j + 1, (i + 1) * 6 + j, (i + 1) * 6 + j + 1
            if keep[[a, b, c, d]].all():
                expected += [new[[a, b, d]], new[[a, d, c]]]
    np.testing.assert_array_equal(mesh.faces, expected)


def test_a_large_batch_is_cast_in_chunks_with_the_same_hits():
    caster = RayCaster(trimesh.creation.icosphere(subdivisions=3, radius=2.0))
    rng = np.random.default_rng(7)
    origins = rng.uniform(-3.0, 3.0, (5000, 3))
    directions = rng.normal(size=(5000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    whole = caster.cast_unit(origins, directions, 4.0, chunk=10 ** 6)
    chunked = caster.cast_unit(origins, directions, 4.0, chunk=64)
    np.testing.assert_array_equal(chunked[1], whole[1])
    np.testing.assert_array_equal(chunked[0], whole[0])
    assert (whole[1] >= 0).any() and (whole[1] < 0).any()
