"""Exact point-to-mesh distance (the missions' truth measure)."""

import numpy as np
import pytest
import trimesh

from drake_auv.geometry.distance import mesh_distance


def test_mesh_distance_is_exact_on_a_box():
    box = trimesh.creation.box(extents=(2.0, 2.0, 2.0))
    q = np.random.default_rng(0).uniform(-3, 3, (500, 3))
    outside = np.linalg.norm(np.maximum(np.abs(q) - 1.0, 0.0), axis=1)
    inside = np.all(np.abs(q) < 1.0, axis=1)
    expected = np.where(inside, 1.0 - np.abs(q).max(axis=1), outside)
    np.testing.assert_allclose(mesh_distance(box, q), expected, atol=1e-9)
    with pytest.raises(ValueError, match="points"):
        mesh_distance(box, [[0.0, np.nan, 0.0]])
