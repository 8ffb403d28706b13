"""Sites: built-in scenarios and a user's own files in UTM, in the local frame."""

import numpy as np
import pytest
import trimesh
import yaml

from drake_auv.mission.config import MissionFileError, SiteSpec, load_mission
from drake_auv.geometry.distance import mesh_distance
from drake_auv.mission.plan import check_against_site
from drake_auv.mission.site import TARGET_TOLERANCE, load_site, prior_offset, shift_prior
from drake_auv.scenarios import get_scenario
from drake_auv.terrain.mesh import top_surface
from sites import BOX_CENTRE, BOX_SIZE, CRS, LOCAL_ORIGIN, SEABED_Z, utm_prior, write_utm_site


def _mission(path, **site):
    raw = yaml.safe_load(path.read_text())
    raw["site"].update(site)
    path.write_text(yaml.safe_dump(raw))
    return load_mission(path)


def test_builtin_site_is_the_scenario():
    spec = load_mission("boulder")
    site = load_site(spec.site, spec.seed)
    scenario = get_scenario("boulder")
    assert site.name == "boulder" and site.crs is None
    np.testing.assert_array_equal(site.origin, [0.0, 0.0])
    np.testing.assert_array_equal(site.world.vertices, scenario.world.vertices)
    np.testing.assert_array_equal(site.target_faces, scenario.target_faces)
    np.testing.assert_array_equal(site.start_state, [-25.0, 0, -30.0] + [0.0] * 9)
    # the prior: the world's top surface on the scenario's 0.4 m grid, moved by the seeded 3 m
    unshifted = top_surface(scenario.world, 0.4)
    shift = prior_offset(3.0, spec.seed)
    assert np.hypot(*shift) == pytest.approx(3.0)
    np.testing.assert_array_equal(site.prior_shift, shift)
    np.testing.assert_array_equal(site.prior.origin, np.add(unshifted.origin, shift))
    np.testing.assert_array_equal(site.prior.z, unshifted.z)
    assert site.max_range == 20.0
    check_against_site(spec, site)  # the built-in missions fit their sites
    for name in ("breakwater", "pool", "c_object"):
        other = load_mission(name)
        check_against_site(other, load_site(other.site, other.seed))


def test_builtin_site_loads_as_its_files_would(tmp_path):
    """A scenario is a site like a user's files: the pool written as world and target meshes
    loads into the same Site (frame, faces, prior, start) as the built-in pool (PLY keeps
    float32 coordinates: equal to 1e-6 m)."""
    scenario = get_scenario("pool")
    scenario.world.export(tmp_path / "world.ply")
    scenario.world.submesh([np.flatnonzero(scenario.target_faces)], append=True).export(
        tmp_path / "target.ply")
    builtin = load_site(SiteSpec(scenario="pool", prior_error_m=1.5), seed=3)
    files = load_site(SiteSpec(world=tmp_path / "world.ply", target=tmp_path / "target.ply",
                               prior_error_m=1.5, prior_spacing_m=0.25, start=scenario.start),
                      seed=3)
    assert (files.name, builtin.name) == ("world", "pool")
    np.testing.assert_array_equal(files.origin, builtin.origin)
    np.testing.assert_allclose(files.world.vertices, builtin.world.vertices, atol=1e-6, rtol=0)
    # A target mesh picks the world's faces within 5 cm of it: the pool's, and two faces
    # straddling the surface whose centroid is that close to the submerged half of their cell.
    extra = files.target_faces & ~builtin.target_faces
    assert files.target_faces[builtin.target_faces].all() and extra.sum() == 2
    near = mesh_distance(builtin.target_mesh, files.world.triangles_center[extra])
    assert np.all(near <= TARGET_TOLERANCE)
    assert files.prior.origin == builtin.prior.origin and files.prior.spacing == (0.25, 0.25)
    np.testing.assert_allclose(files.prior.z, builtin.prior.z, atol=1e-6, rtol=0)
    np.testing.assert_array_equal(files.start_state, builtin.start_state)
    np.testing.assert_array_equal(files.prior_shift, builtin.prior_shift)


def test_user_site_in_utm(tmp_path):
    spec = load_mission(write_utm_site(tmp_path))
    site = load_site(spec.site, seed=spec.seed, label="mission.yaml")
    np.testing.assert_array_equal(site.origin, LOCAL_ORIGIN)
    assert site.crs == CRS and site.start_state is None
    lo, hi = site.world.bounds
    assert np.all(np.abs(lo[:2]) <= 30.0) and np.all(np.abs(hi[:2]) <= 30.0)  # small and local
    assert lo[2] == pytest.approx(-20.5) and hi[2] == pytest.approx(-14.5)  # z unchanged
    # the prior: the raster in the local frame, shifted by the seeded 2 m error
    unshifted = utm_prior()
    expected = shift_prior(unshifted, 2.0, spec.seed)
    shift = np.subtract(expected.origin, unshifted.origin)
    assert np.hypot(*shift) == pytest.approx(2.0)
    np.testing.assert_allclose(site.prior.origin, np.subtract(unshifted.origin, LOCAL_ORIGIN)
                               + shift, atol=1e-6)
    np.testing.assert_allclose(site.prior.z, unshifted.z)
    np.testing.assert_allclose(site.prior.world_to_crs([[0.0, 0.0]]), [LOCAL_ORIGIN])
    other = load_site(spec.site, seed=1)
    assert not np.allclose(other.prior.origin, site.prior.origin)
    # site <-> local
    p = np.array([[500003.25, 4600001.5, -17.0], [499980.0, 4599990.0, -20.0]])
    local = site.to_local(p)
    np.testing.assert_allclose(local[0], [3.25, 1.5, -17.0])
    np.testing.assert_array_equal(site.to_site(local), p)
    np.testing.assert_array_equal(site.to_site(site.to_local(p[0, :2])), p[0, :2])
    # the target faces are the cube's (12 triangles, 6 m sides)
    assert site.target_faces.sum() == 12
    centroids = site.world.triangles_center[site.target_faces]
    np.testing.assert_allclose(centroids.mean(axis=0), site.to_local(BOX_CENTRE), atol=1e-9)
    assert site.target_mesh.area == pytest.approx(6 * BOX_SIZE**2)
    check_against_site(spec, site)


def test_a_step_that_needs_the_missing_prior_is_one_line(tmp_path):
    """A site given by its world mesh alone has no prior map: the plan step is refused at
    load, naming the step; explore steps run without one."""
    path = write_utm_site(tmp_path)
    with pytest.raises(MissionFileError) as err:
        _mission(path, target=None, prior=None, crs=CRS)
    assert str(err.value).startswith("mission.yaml: steps[0].plan: needs a prior map and "
                                     "the site has none (site.prior is missing)")
    raw = yaml.safe_load(path.read_text())
    raw["steps"] = [{"explore": dict(region=[-10.0, -10.0, -19.0, 10.0, 10.0, -11.0])}]
    path.write_text(yaml.safe_dump(raw))
    assert load_mission(path).site.prior is None
    with pytest.raises(MissionFileError, match="site.prior_from_world: only for a world"):
        _mission(path, prior="prior.tif", prior_from_world=True)


def test_user_site_without_target_or_prior(tmp_path):
    path = write_utm_site(tmp_path)
    spec = _mission(path, target=None, prior=None, prior_from_world=True, prior_error_m=0.0,
                    prior_spacing_m=2.0, crs=CRS, start=[499990.0, 4600000.0, -10.0, 90.0])
    site = load_site(spec.site, seed=0)
    assert site.target_faces.all() and site.crs == CRS
    assert site.prior.spacing == (2.0, 2.0)
    assert np.nanmax(site.prior.z) == pytest.approx(-14.5)
    assert np.nanmin(site.prior.z) == pytest.approx(SEABED_Z)
    np.testing.assert_allclose(site.start_state[[0, 1, 2, 5]], [-10.0, 0.0, -10.0, np.pi / 2])


@pytest.mark.parametrize("change, message", [
    (dict(world="gone.ply"), "mission.yaml: site.world: gone.ply not found"),
    (dict(target="gone.ply"), "site.target: gone.ply not found"),
    (dict(prior="gone.tif"), "site.prior: gone.tif not found"),
    (dict(target="far.ply"), "site.target: no face of the world lies on far.ply"),
    (dict(world="land.ply"), "site.world: land.ply lies entirely above the sea surface"),
    (dict(world="empty.ply"), "site.world: empty.ply is not a readable mesh"),
    (dict(crs="EPSG:32630"), "site.crs: EPSG:32630 differs from the prior raster's EPSG:32631"),
])
def test_bad_site_files(tmp_path, change, message):
    path = write_utm_site(tmp_path)
    far = trimesh.creation.box(extents=(2, 2, 2))
    far.apply_translation([510000.0, 4600000.0, -19.0])
    far.export(tmp_path / "far.ply")
    land = trimesh.creation.box(extents=(2, 2, 2))
    land.apply_translation([500000.0, 4600000.0, 5.0])
    land.export(tmp_path / "land.ply")
    (tmp_path / "empty.ply").write_text("")
    spec = _mission(path, **change)
    with pytest.raises(MissionFileError) as info:
        load_site(spec.site, seed=0, label=path.name)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_mission_values_only_the_site_can_judge(tmp_path):
    path = write_utm_site(tmp_path)
    site = load_site(load_mission(path).site, seed=0)

    def error(*overrides) -> str:
        spec = load_mission(path, overrides=overrides)
        with pytest.raises(MissionFileError) as info:
            check_against_site(spec, site)
        assert "\n" not in str(info.value)
        return str(info.value)

    follow = "steps.1={follow: {mode: horizontal, depth: 25, offset: 3}}"
    assert error(follow) == ("mission.yaml: steps[1].follow.depth: 25 m is below the seabed "
                             "(20.0 m under the structure); allowed: (0, 20.0) m")
    assert "steps[1].follow.start: (600000, 4.6e+06) is outside the world; allowed: x in " \
           "[499970.0, 500030.0]" in error(
               "steps.1={follow: {mode: horizontal, depth: 15, offset: 3, start: [600000, "
               "4600000]}}")
    assert "steps[0].plan.omega: 25 m leaves no water" in error("steps.0.plan.omega=25")
    assert ("site.start: depth 25 m is 5.00 m inside the world (its top surface there: 20.0 m "
            "deep); allowed: a point in the water: depth in [0, 20.0) m there, outside the "
            "structures") in error("site.start=[499990, 4600000, -25, 0]")
    assert "site.start: depth 16 m is 1.50 m inside the world (its top surface there: 14.5 m " \
        "deep)" in error("site.start=[500004, 4600000, -16, 0]")  # inside the cube
    assert "site.start: depth -2 m is 2.00 m above the sea surface" in error(
        "site.start=[499990, 4600000, 2, 0]")
    assert "steps[0].plan.depth: 22 m cuts no structure" in error(
        "steps.0.plan={method: contour, omega: 3, depth: 22}")
    load_mission(path, overrides=[follow.replace("25", "16")])  # above the seabed: fine
    check_against_site(load_mission(path, overrides=[follow.replace("25", "16")]), site)
