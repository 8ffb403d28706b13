"""The named scenario worlds: geometry, orientation, prior maps (as the site loader makes
them), parameters."""

import numpy as np
import pytest
import trimesh

from drake_auv.geometry import RayCaster
from drake_auv.mission.config import SiteSpec
from drake_auv.mission.site import load_site
from drake_auv.scenarios import DATA_DIR, MONTEREY_TILE, get_scenario, list_scenarios

NAMES = [name for name, _ in list_scenarios()]


def test_monterey_tiles_ship_with_the_package():
    """The four public-domain Monterey tiles (and their attribution) are package data."""
    tiles = sorted((DATA_DIR / "monterey").glob("*.tif"))
    assert len(tiles) == 4 and (DATA_DIR / "monterey" / MONTEREY_TILE) in tiles
    attribution = " ".join((DATA_DIR / "README.md").read_text().split())
    assert "public domain" in attribution and "NOAA" in attribution


def _prior(name, error_m=0.0, seed=0, spacing=None):
    """The prior map a mission at the scenario holds."""
    return load_site(SiteSpec(scenario=name, prior_error_m=error_m, prior_spacing_m=spacing),
                     seed).prior


def _fibonacci_directions(n):
    k = np.arange(n) + 0.5
    phi = np.arccos(1 - 2 * k / n)
    theta = np.pi * (1 + 5 ** 0.5) * k
    return np.column_stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)])


def _solid_components(world, target):
    labels = trimesh.graph.connected_component_labels(world.face_adjacency,
                                                      node_count=len(world.faces))
    for label in np.unique(labels[target]):
        part = trimesh.Trimesh(world.vertices, world.faces[labels == label], process=False)
        part.remove_unreferenced_vertices()
        yield part


def test_list_has_every_site_with_one_line():
    assert NAMES == ["caldera", "pool", "c_object", "breakwater", "boulder", "monterey"]
    for _, text in list_scenarios():
        assert 20 < len(text) <= 100 and "\n" not in text


@pytest.mark.parametrize("name", NAMES)
def test_site_is_consistent_and_start_is_in_open_water(name):
    sc = get_scenario(name)
    assert sc.target_faces.shape == (len(sc.world.faces),) and sc.target_faces.any()
    assert sc.target_area > 0
    assert len(sc.start) == 4 and np.all(np.isfinite(sc.start)) and sc.start[2] < 0
    # Every surface seen from the start faces the water: rays hit front faces only. That holds
    # only if the start is outside every solid and open surfaces are oriented towards the water.
    caster = RayCaster(sc.world)
    dirs = _fibonacci_directions(2000)
    hits = caster.cast(sc.start[:3], dirs, 2000.0)
    hit = hits.faces >= 0
    assert hit.sum() > 400
    facing = np.einsum("ij,ij->i", caster.face_normals[hits.faces[hit]], dirs[hit])
    assert np.all(facing < 0), f"{np.sum(facing >= 0)} back-face hits from the start"
    assert np.nanmin(hits.ranges) > 1.0  # room around the vehicle
    for key in ("omega", "speed", "prior_spacing", "max_range"):
        assert sc.params[key] > 0


@pytest.mark.parametrize("name", ["c_object", "breakwater", "boulder"])
def test_solids_are_watertight_and_outward(name):
    sc = get_scenario(name)
    parts = list(_solid_components(sc.world, sc.target_faces))
    assert len(parts) == 1
    assert parts[0].is_watertight and parts[0].is_winding_consistent
    assert parts[0].volume > 100.0  # positive: normals point out


def test_pool_walls_corners_and_v_bottom():
    sc = get_scenario("pool")
    assert sc.params["depth"] == 4.0
    caster = RayCaster(sc.world)
    angles = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    dirs = np.column_stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
    hits = caster.cast([0.0, 0.0, -4.0], dirs, 50.0)
    assert np.all(hits.faces >= 0)  # a closed section at 4 m depth
    x, y = np.abs(hits.points[:, 0]), np.abs(hits.points[:, 1])
    on_wall = np.minimum(np.abs(x - 8.0), np.abs(y - 4.0))
    assert on_wall.max() < 1e-3  # the rectangle |x| = 8, |y| = 4: 90 degree corners
    assert np.all(sc.target_faces[hits.faces])
    down = caster.cast(np.array([[0.0, 0, -1], [7.9, 0, -1], [-4.0, 2.0, -1]]),
                       [[0, 0, -1]] * 3, 20.0)
    np.testing.assert_allclose(down.points[:, 2], [-7.0, -5.0 - 2.0 * 0.1 / 8.0, -6.0], atol=1e-4)
    assert not sc.target_faces[down.faces].any()  # the bottom is not the target


def test_c_object_has_floor_wall_and_ceiling():
    sc = get_scenario("c_object")
    caster = RayCaster(sc.world)
    hits = caster.cast([5.0, 0.0, -13.0], [[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0]], 60.0)
    np.testing.assert_allclose(hits.ranges[:3], [4.0, 4.0, 5.0], atol=1e-4)
    assert np.all(sc.target_faces[hits.faces[:3]])
    assert hits.faces[3] == -1  # the C opens towards -x
    np.testing.assert_allclose(caster.face_normals[hits.faces[0]], [0, 0, -1], atol=1e-9)


def test_breakwater_blocks_and_narrow_gaps():
    sc = get_scenario("breakwater")
    caster = RayCaster(sc.world)
    xs = np.arange(-110.0, 5.0, 0.05)
    origins = np.column_stack([xs, np.full_like(xs, -20.0), np.full_like(xs, -5.0)])
    hits = caster.cast(origins, np.tile([0.0, 1.0, 0.0], (len(xs), 1)), 40.0)
    blocked = hits.faces >= 0
    edges = np.flatnonzero(np.diff(blocked.astype(int)))
    runs = np.split(blocked, edges + 1)
    solid = [len(r) * 0.05 for r in runs if r[0]]
    gaps = [len(r) * 0.05 for r in runs[1:-1] if not r[0]]
    assert len(solid) == 20 and np.allclose(solid, 5.0, atol=0.06)
    assert len(gaps) == 19 and max(gaps) < 0.6  # too narrow for a 1 m wide vehicle
    top = caster.cast([0.0, 0.0, 10.0], [[0, 0, -1]], 30.0)
    assert abs(top.points[0, 2] - 2.0) < 1e-4
    z = sc.world.triangles_center[sc.target_faces][:, 2]
    assert z.min() > -10.0 and z.max() < 0.0  # the target is the in-water part


def test_boulder_height_steepness_and_overhang():
    sc = get_scenario("boulder")
    world = sc.world
    target = sc.target_faces
    assert abs(world.vertices[world.faces[target]][..., 2].max() + 28.0) < 1e-9
    assert 20_000 < len(world.faces) < 100_000
    normals = world.face_normals[target]
    area = world.area_faces[target]
    steep = np.abs(normals[:, 2]) < np.cos(np.radians(60))
    assert area[steep].sum() / area.sum() > 0.3
    overhang = normals[:, 2] < -0.3
    assert area[overhang].sum() > 50.0
    # From above the overhang is hidden: the prior map is on a 0.4 m grid and tops out at -28 m.
    prior = _prior("boulder")
    assert prior.spacing == (0.4, 0.4)
    assert abs(np.nanmax(prior.z) + 28.0) < 0.2 and abs(np.nanmin(prior.z) + 40.0) < 1.0


def test_prior_map_is_the_top_surface_shifted_by_a_seeded_error():
    exact = _prior("c_object")
    assert exact.spacing == (0.5, 0.5)
    # Top surface: the ceiling flange's top at -6 over the object, the seabed elsewhere.
    assert abs(exact.elevation_at(6.0, 0.0) + 6.0) < 1e-4
    assert abs(exact.elevation_at(-10.0, 0.0) + 20.0) < 1e-4
    shifted = _prior("c_object", error_m=3.0, seed=4)
    offset = np.subtract(shifted.origin, exact.origin)
    assert abs(np.linalg.norm(offset) - 3.0) < 1e-9
    np.testing.assert_array_equal(shifted.z, exact.z)
    assert np.subtract(_prior("c_object", 3.0, seed=4).origin, shifted.origin).tolist() == [0, 0]
    assert np.linalg.norm(np.subtract(_prior("c_object", 3.0, seed=5).origin,
                                      shifted.origin)) > 1e-3
    assert _prior("c_object", spacing=1.0).spacing == (1.0, 1.0)
    for bad in (-0.1, 5.5, np.nan):
        with pytest.raises(ValueError, match="error_m"):
            _prior("c_object", error_m=bad)
    with pytest.raises(ValueError, match="spacing"):
        _prior("c_object", spacing=-1.0)


def test_caldera_world_matches_the_synthetic_grid():
    from drake_auv.terrain.synthetic import caldera_site
    sc = get_scenario("caldera")
    grid = caldera_site()
    lo, hi = sc.world.bounds
    assert np.allclose([hi[0] - lo[0], hi[1] - lo[1]], [100.0, 250.0])
    prior = _prior("caldera")
    rng = np.random.default_rng(0)
    x, y = rng.uniform(1, 99, 200), rng.uniform(1, 249, 200)
    assert np.max(np.abs(prior.elevation_at(x, y) - grid.elevation_at(x, y))) < 0.1


def test_monterey_is_the_real_tile():
    from drake_auv.terrain.readers import read_bathymetry
    sc = get_scenario("monterey")
    grid = read_bathymetry(DATA_DIR / "monterey" / MONTEREY_TILE)
    assert len(sc.world.faces) == 2 * np.prod(np.subtract(grid.shape, 1))
    assert abs(sc.world.bounds[0, 2] - np.nanmin(grid.z)) < 1e-6
    below = RayCaster(sc.world).cast(sc.start[:3], [[0.0, 0.0, -1.0]], 500.0)
    assert below.ranges[0] == pytest.approx(sc.params["omega"], abs=1e-3)  # survey offset


def test_overrides_copies_and_bad_names():
    a = get_scenario("pool", omega=1.5)
    assert a.params["omega"] == 1.5 and get_scenario("pool").params["omega"] == 2.0
    a.world.apply_translation([100.0, 0, 0])
    b = get_scenario("pool")
    assert b.world.bounds[0, 0] == -8.0  # each call gets its own mesh
    with pytest.raises(ValueError, match="no parameter"):
        get_scenario("pool", omgea=1.0)
    with pytest.raises(ValueError, match="unknown scenario"):
        get_scenario("atlantis")


def test_scenarios_command_lists_shows_and_exports(tmp_path, capsys):
    import argparse

    from drake_auv.commands import scenarios as command
    from drake_auv.terrain.readers import read_bathymetry

    parser = argparse.ArgumentParser()
    command.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["scenarios"])
    assert args.func(args) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert [line.split()[0] for line in lines] == NAMES
    prior = tmp_path / "pool.npz"
    args = parser.parse_args(["scenarios", "pool", "--prior", str(prior), "--error", "1.5",
                              "--world", str(tmp_path / "pool.ply")])
    assert args.func(args) == 0
    assert "target: " in capsys.readouterr().out
    loaded = read_bathymetry(prior)
    expected = _prior("pool", 1.5, seed=0)
    np.testing.assert_allclose(loaded.origin, expected.origin)
    np.testing.assert_array_equal(loaded.z, expected.z)
    assert len(trimesh.load(tmp_path / "pool.ply").faces) == len(get_scenario("pool").world.faces)
    with pytest.raises(ValueError, match="error_m"):
        args = parser.parse_args(["scenarios", "pool", "--prior", str(prior), "--error", "7"])
        args.func(args)
    with pytest.raises(ValueError, match="need a site name"):
        args = parser.parse_args(["scenarios", "--prior", str(prior)])
        args.func(args)


def test_scenarios_command_rejects_unknown_file_types_before_work(tmp_path, capsys):
    import argparse

    from drake_auv.commands import scenarios as command

    parser = argparse.ArgumentParser()
    command.add_parser(parser.add_subparsers(dest="command"))
    for option, name in (("--prior", "map.csv"), ("--world", "world.dae")):
        args = parser.parse_args(["scenarios", "pool", option, str(tmp_path / name)])
        with pytest.raises(ValueError, match=option):
            args.func(args)
    assert capsys.readouterr().out == "" and not any(tmp_path.iterdir())
