"""The recorded point cloud, its PLY/LAS files, oriented normals, screened Poisson and the
scores against the truth; bad input gets one clear line; a mission writes its points."""

import base64
import json
import re

import numpy as np
import pytest
import trimesh

from drake_auv.cli import main
from drake_auv.geometry.raycast import RayCaster
from drake_auv.mapping.scan_log import ScanBatch, ScanLog
from drake_auv.reconstruction.pointcloud import (PointCloud, from_scan_log, read_las,
                                                 read_ply, write_las, write_ply)
from drake_auv.reconstruction.scoring import (completeness_of_mesh, completeness_of_points,
                                              score, surface_samples)
from drake_auv.reconstruction.surface import (check_parameters, estimate_normals,
                                              open3d_available, open3d_error, reconstruct)
from drake_auv.rosio.replay import ReplaySite

needs_open3d = pytest.mark.skipif(not open3d_available(), reason=str(open3d_error()))
RADIUS = 2.0
CENTRE = np.array([10.0, -5.0, -20.0])


def _fan(axis, half_angle, count, rng):
    """`count` unit directions uniform in a cone of `half_angle` rad about `axis`."""
    axis = axis / np.linalg.norm(axis)
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(axis, e1)
    cos_t = 1.0 - rng.random(count) * (1.0 - np.cos(half_angle))
    phi = rng.random(count) * 2 * np.pi
    sin_t = np.sqrt(1.0 - cos_t ** 2)
    return (cos_t[:, None] * axis + sin_t[:, None] * (np.cos(phi)[:, None] * e1
                                                     + np.sin(phi)[:, None] * e2))


@pytest.fixture(scope="module")
def sphere_scan():
    """A noiseless scan of a sphere from 8 sensor origins 6 m from its centre, as a ScanLog."""
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=RADIUS)
    sphere.apply_translation(CENTRE)
    caster, rng, log = RayCaster(sphere), np.random.default_rng(1), ScanLog()
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    for k, corner in enumerate(corners):
        origin = CENTRE + 6.0 * corner / np.sqrt(3.0)
        directions = _fan(CENTRE - origin, np.arcsin(RADIUS / 6.0) * 1.05, 3000, rng)
        hits = caster.cast(origin, directions, 20.0)
        log = log.append(ScanBatch.make(k * 0.1, "multibeam", origin, directions, hits.ranges,
                                        20.0))
    return sphere, log


def test_scan_log_becomes_a_cloud_with_origins_and_times(sphere_scan):
    sphere, log = sphere_scan
    cloud = from_scan_log(log)
    batches = log.batches()
    assert len(cloud) == sum(np.isfinite(b.ranges).sum() for b in batches) > 15000
    first = np.isfinite(batches[0].ranges).sum()
    assert np.allclose(cloud.origins[:first], batches[0].origin)
    assert np.all(cloud.times[first:first + 5] == batches[1].time)
    assert np.allclose(np.linalg.norm(cloud.points - CENTRE, axis=1), RADIUS, atol=0.01)
    assert len(from_scan_log(log, sources=("profiler",))) == 0


@needs_open3d
def test_noiseless_sphere_reconstructs_within_10_cm(sphere_scan):
    sphere, log = sphere_scan
    cloud = from_scan_log(log)
    surface = reconstruct(cloud, depth=8, progress=False)
    summary, errors = score(sphere, surface.mesh, cloud.points)
    s = summary["surface"]
    assert s["accuracy_mean_m"] < 0.1 and s["accuracy_p95_m"] < 0.2
    assert s["completeness"] > 0.97
    # A real surface, not the points: a closed-looking mesh of its own vertices, about the
    # sphere's area.
    assert len(surface.mesh.vertices) != len(cloud)
    assert 0.8 < surface.mesh.area / sphere.area < 1.05  # 5 % of the vertices trimmed
    assert errors.shape == (len(surface.mesh.vertices),)
    assert summary["point_cloud"]["accuracy_mean_m"] < 0.01


@needs_open3d
def test_normals_face_the_sensor(sphere_scan):
    sphere, log = sphere_scan
    cloud = from_scan_log(log).thin(0.1)
    outward = (cloud.points - CENTRE) / RADIUS
    normals = estimate_normals(cloud.points, cloud.origins, k=30)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0)
    assert np.mean(np.einsum("ij,ij->i", normals, outward) > 0.95) > 0.99
    # The inside of a cavity seen from within faces inwards: the sensor, not the centroid.
    inside = estimate_normals(cloud.points, np.broadcast_to(CENTRE, cloud.points.shape), k=30)
    assert np.mean(np.einsum("ij,ij->i", inside, outward) < -0.95) > 0.99
    # Without origins: one consistent orientation by propagation (up to a global sign).
    propagated = estimate_normals(cloud.points, None, k=30)
    agree = np.einsum("ij,ij->i", propagated, outward)
    assert max(np.mean(agree > 0.9), np.mean(agree < -0.9)) > 0.98


def test_ply_round_trip(tmp_path, sphere_scan):
    cloud = from_scan_log(sphere_scan[1])
    cloud = PointCloud(cloud.points + [5e5, 4.6e6, 0.0], cloud.origins, cloud.times,
                       np.arange(len(cloud), dtype=np.uint8) % 2)
    write_ply(cloud, tmp_path / "points.ply")
    back = read_ply(tmp_path / "points.ply")
    for name in ("points", "origins", "times", "sources"):
        assert np.array_equal(getattr(back, name), getattr(cloud, name)), name
    assert (tmp_path / "points.ply").read_bytes().startswith(
        b"ply\nformat binary_little_endian 1.0\n")


def test_other_tools_plys_read(tmp_path):
    xyz = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    header = "ply\nformat {}\nelement vertex 2\nproperty float x\nproperty float y\n" \
             "property float z\nproperty uchar red\nelement face 0\n" \
             "property list uchar int vertex_indices\nend_header\n"
    data = np.zeros(2, [("x", ">f4"), ("y", ">f4"), ("z", ">f4"), ("red", "u1")])
    data["x"], data["y"], data["z"] = xyz.T
    (tmp_path / "big.ply").write_bytes(header.format("binary_big_endian 1.0").encode()
                                       + data.tobytes())
    (tmp_path / "ascii.ply").write_text(header.format("ascii 1.0")
                                        + "1 2 3 255\n4 5 6 0\n")
    for name in ("big.ply", "ascii.ply"):
        cloud = read_ply(tmp_path / name)
        assert np.array_equal(cloud.points, xyz) and not cloud.has_origins


def test_las_round_trip(tmp_path, sphere_scan):
    pytest.importorskip("laspy")
    cloud = from_scan_log(sphere_scan[1])
    write_las(cloud, tmp_path / "points.las")
    back = read_las(tmp_path / "points.las")
    assert np.allclose(back.points, cloud.points, atol=1e-3)  # millimetre scale
    assert np.array_equal(back.origins, cloud.origins)
    assert np.array_equal(back.times, cloud.times)


def test_crop_and_thin():
    points = np.array([[0.0, 0, 0], [0.01, 0, 0], [0.5, 0, 0], [3.0, 0, 0]])
    cloud = PointCloud(points, np.zeros((4, 3)), np.arange(4.0), np.zeros(4, np.uint8))
    assert len(cloud.crop([0, 0, 0], [1, 0, 0])) == 3
    assert len(cloud.crop([0, 0, 0], [1, 0, 0], margin=2.5)) == 4
    thin = cloud.thin(0.1)
    assert np.array_equal(thin.times, [0.0, 2.0, 3.0])  # the earliest of each cube


def test_completeness_is_the_share_of_target_area():
    box = trimesh.creation.box(extents=(4.0, 2.0, 1.0))
    dense = surface_samples(box, spacing=0.05, seed=3)
    samples = surface_samples(box, spacing=0.1, seed=4)
    assert completeness_of_points(dense, samples) > 0.999
    # Half the area: every face of the box has a mirror across x = 0.
    assert completeness_of_points(dense[dense[:, 0] < 0.0], samples, tolerance=0.05) == \
        pytest.approx(0.5, abs=0.03)
    assert completeness_of_points(np.zeros((0, 3)), samples) == 0.0
    assert completeness_of_mesh(box, samples) == 1.0
    fine = box.subdivide_to_size(0.2)
    left = fine.submesh([np.flatnonzero(fine.triangles_center[:, 0] < 0.0)], append=True)
    assert completeness_of_mesh(left, samples, tolerance=0.05) == pytest.approx(0.5, abs=0.03)
    summary, errors = score(box, box, dense[::10])
    assert summary["surface"]["accuracy_mean_m"] == pytest.approx(0.0, abs=1e-9)
    assert summary["point_cloud"]["accuracy_p95_m"] < 1e-9
    # Points 0.3 m off the surface are 0.3 m inaccurate and still within the 0.5 m tolerance.
    top = dense[dense[:, 2] > 0.5 - 1e-9] + [0.0, 0.0, 0.3]
    summary, _ = score(box, None, top)
    assert summary["point_cloud"]["accuracy_mean_m"] == pytest.approx(0.3, abs=1e-6)
    assert "surface" not in summary


@pytest.mark.parametrize("n, depth, k, trim, message", [
    (0, 9, 200, 0.05, "0 point(s); a surface needs at least 10"),
    (1, 9, 200, 0.05, "1 point(s)"),
    (100, 9, 200, 0.05, "not more than k = 200"),
    (1000, 4, 200, 0.05, "depth must be an integer in [5, 12], got 4"),
    (1000, 13, 200, 0.05, "depth must be an integer in [5, 12], got 13"),
    (1000, 9, 1, 0.05, "k must be an integer in [3, 1000], got 1"),
    (1000, 9, 200, 0.5, "trim must be in [0.0, 0.5), got 0.5"),
])
def test_bad_parameters_are_named(n, depth, k, trim, message):
    with pytest.raises(ValueError) as err:
        check_parameters(n, depth, k, trim)
    assert message in str(err.value)


def test_bad_files_get_one_clear_line(tmp_path, capsys):
    one = PointCloud(np.zeros((1, 3)), np.ones((1, 3)), np.zeros(1), np.zeros(1, np.uint8))
    write_ply(one, tmp_path / "one.ply")
    (tmp_path / "empty.ply").write_bytes(b"ply\nformat binary_little_endian 1.0\n"
                                         b"element vertex 0\nproperty double x\n"
                                         b"property double y\nproperty double z\nend_header\n")
    (tmp_path / "nopos.ply").write_text("ply\nformat ascii 1.0\nelement vertex 1\n"
                                        "property float time\nend_header\n0.5\n")
    good = (tmp_path / "one.ply").read_bytes()
    (tmp_path / "cut.ply").write_bytes(good[:-20])
    (tmp_path / "text.ply").write_text("hello\n")
    cases = {"one.ply": "1 point(s)", "empty.ply": "0 point(s)",
             "nopos.ply": "no position property x, y, z (properties: time)",
             "cut.ply": "truncated PLY", "text.ply": "not a PLY file",
             "missing.ply": "does not exist", "points.xyz": "unknown point-cloud extension"}
    for name, message in cases.items():
        code = main(["reconstruct", str(tmp_path / name), "-o", str(tmp_path / "m.ply")])
        err = capsys.readouterr().err.strip()
        assert code == 2 and "\n" not in err and message in err, (name, err)
    code = main(["reconstruct", str(tmp_path / "one.ply"), "-o", "m.ply", "--depth", "20"])
    assert code == 2 and "depth must be an integer in [5, 12]" in capsys.readouterr().err


@needs_open3d
@pytest.mark.parametrize("points, message", [
    (np.outer(np.linspace(0.0, 10.0, 500), [1.0, 2.0, 3.0]), "500 points lie on one line")])
def test_degenerate_clouds_are_refused_not_crashed_on(tmp_path, capsys, points, message):
    # Open3D's Poisson ends the process (a segmentation fault) on these (500 identical
    # points: tests/test_hostile_inputs.py)
    n = len(points)
    write_ply(PointCloud(points, np.zeros((n, 3)), np.zeros(n), np.zeros(n, np.uint8)),
              tmp_path / "bad.ply")
    code = main(["reconstruct", str(tmp_path / "bad.ply"), "-o", str(tmp_path / "m.ply")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and message in err, err


@needs_open3d
def test_reconstruct_command_scores_against_a_target(tmp_path, sphere_scan, capsys):
    sphere, log = sphere_scan
    write_ply(from_scan_log(log).thin(0.05), tmp_path / "points.ply")
    sphere.export(tmp_path / "sphere.ply")
    code = main(["reconstruct", str(tmp_path / "points.ply"), "-o", str(tmp_path / "mesh.ply"),
                 "--depth", "7", "--k", "50", "--target", str(tmp_path / "sphere.ply"),
                 "--crop", "0.5", "--quiet"])
    assert code == 0
    out = capsys.readouterr().out
    assert "every vertex to the target: accuracy median 0.0" in out and "of the seen target" in out
    mesh = trimesh.load(tmp_path / "mesh.ply", process=False)
    assert len(mesh.faces) > 1000 and mesh.visual.vertex_colors.shape[0] == len(mesh.vertices)


def test_mission_writes_its_points(tmp_path):
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.report.outputs import write_outputs
    from drake_auv.mission.runner import run_mission

    # 45 s: the transit and the start of the survey (the report needs survey samples).
    result = run_mission(load_mission("breakwater", overrides=["limits.max_time_s=12"]),
                         progress=False)
    summary = write_outputs(result, tmp_path)
    cloud = read_ply(tmp_path / "points.ply")
    batches = result.mapping.scan_log.batches()
    assert len(cloud) == sum(np.isfinite(b.ranges).sum() for b in batches) > 1000
    assert set(np.unique(cloud.sources)) == {0, 1}
    expected = result.site.to_site(np.concatenate([b.points() for b in batches]))
    assert np.allclose(cloud.points, expected)
    assert np.all(np.diff(cloud.times) >= 0.0) and cloud.has_origins
    section = json.loads((tmp_path / "report.json").read_text())["reconstruction"]
    assert section == summary["reconstruction"]
    assert "## Reconstruction" in (tmp_path / "report.md").read_text()
    # The survey has only begun: too few returns on the target for a surface.
    assert not section["built"] and "fewer than 1000 returns" in section["reason"]


def test_products_when_open3d_does_not_load_give_its_error(tmp_path, sphere_scan,
                                                           broken_open3d):
    from drake_auv.reconstruction.products import write_products

    sphere, log = sphere_scan
    section = write_products(log, ReplaySite(np.zeros(2), target_mesh=sphere), tmp_path)
    assert section == dict(built=False, reason="surface reconstruction: open3d is installed but "
                           "does not import: ImportError: libusb-1.0.so.0: cannot open shared "
                           "object file: No such file or directory")
    assert len(read_ply(tmp_path / "points.ply")) > 15000
    assert not (tmp_path / "reconstruction.ply").exists()


@needs_open3d
def test_products_of_a_dive_with_enough_returns(tmp_path, sphere_scan):
    from drake_auv.reconstruction.products import products_markdown, write_products
    from drake_auv.visualization import Scene
    from drake_auv.visualization.reconstruction import draw_products

    sphere, log = sphere_scan
    origin = np.array([4.5e5, 4.6e6])
    site = ReplaySite(origin, world=sphere, target_mesh=sphere)
    section = write_products(log, site, tmp_path)
    assert section["built"] and section["surface"]["accuracy_mean_m"] < 0.1
    assert section["surface"]["completeness"] > 0.95
    assert "| surface |" in products_markdown(section)
    mesh = trimesh.load(tmp_path / "reconstruction.ply", process=False)
    assert np.allclose(mesh.bounds.mean(axis=0), CENTRE + [*origin, 0.0], atol=0.2)
    assert (tmp_path / "reconstruction.png").stat().st_size > 10_000
    scene = Scene()
    draw_products(scene, site, tmp_path)
    html = scene.write_html(tmp_path / "mission.html").read_text()
    commands = b"".join(base64.b64decode(b64) for b64 in re.findall(
        r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html))
    assert scene.path_of("reconstruction").encode() in commands


@pytest.fixture(scope="module")
def one_sided_scan():
    """A dome (the upper half of a 2 m sphere, open below: an overhanging shell) scanned only
    from above and around (4 origins 6 m from its centre, noiseless): Poisson closes the open
    side where nothing was seen."""
    sphere = trimesh.creation.icosphere(subdivisions=5, radius=RADIUS)
    dome = sphere.submesh([np.flatnonzero(sphere.triangles_center[:, 2] > 0.0)], append=True)
    dome.apply_translation(CENTRE)
    caster, rng, log = RayCaster(dome), np.random.default_rng(2), ScanLog()
    for k, (sx, sy) in enumerate([(-1, -1), (-1, 1), (1, -1), (1, 1)]):
        origin = CENTRE + 6.0 * np.array([sx, sy, 1.0]) / np.sqrt(3.0)
        directions = _fan(CENTRE - origin, np.arcsin(RADIUS / 6.0) * 1.05, 4000, rng)
        hits = caster.cast(origin, directions, 20.0)
        log = log.append(ScanBatch.make(k * 0.1, "multibeam", origin, directions, hits.ranges,
                                        20.0))
    return dome, from_scan_log(log).thin(0.05)


@needs_open3d
def test_support_trim_removes_the_surface_no_return_supports(one_sided_scan):
    dome, cloud = one_sided_scan
    # Density trimming off: the support trim alone must remove what Poisson closed below.
    trimmed = reconstruct(cloud, depth=7, k=30, trim=0.0, progress=False)
    summary, errors = score(dome, trimmed.mesh, cloud.points, world=dome)
    s = summary["surface"]
    assert s["accuracy_median_m"] < 0.01 and s["accuracy_p95_m"] < 0.05
    assert errors.max() < 0.3 and trimmed.mesh.vertices[:, 2].min() > CENTRE[2] - 0.3
    assert s["completeness_seen"] > 0.99 and summary["accuracy_to"] == "world"
    assert trimmed.support_m.shape == (len(trimmed.mesh.vertices),)
    assert trimmed.support_m.max() < 0.3
    untrimmed = reconstruct(cloud, depth=7, k=30, trim=0.0, support=0.0, progress=False)
    _, bad_errors = score(dome, untrimmed.mesh, cloud.points, world=dome)
    assert bad_errors.max() > 1.0 and untrimmed.mesh.vertices[:, 2].min() < CENTRE[2] - 0.5
    assert untrimmed.support_m.max() > 1.0
    assert len(untrimmed.mesh.faces) > len(trimmed.mesh.faces)


def test_outliers_are_dropped_before_poisson():
    """Water-column clutter above a seen seabed: without the outlier removal screened Poisson
    closes a surface through it that the support trim keeps; with it the surface stays on the
    seabed. Fails when `outlier_mask` keeps every point."""
    pytest.importorskip("open3d")
    from drake_auv.reconstruction.pointcloud import PointCloud
    from drake_auv.reconstruction.surface import outlier_mask, reconstruct

    rng = np.random.default_rng(4)
    g = np.arange(0.0, 20.0, 0.1)
    x, y = np.meshgrid(g, g)
    seabed = np.column_stack([x.ravel(), y.ravel(), 0.02 * rng.standard_normal(x.size)])
    clutter = rng.uniform([0.0, 0.0, 1.0], [20.0, 20.0, 8.0], (10000, 3))
    points = np.vstack([seabed, clutter])
    origins = np.column_stack([points[:, :2], np.full(len(points), 10.0)])
    cloud = PointCloud(points, origins, np.zeros(len(points)), np.zeros(len(points), np.uint8))
    kept = outlier_mask(points)
    assert kept[:len(seabed)].mean() > 0.99 and kept[len(seabed):].mean() < 0.05

    def above(outliers):
        mesh = reconstruct(cloud, depth=7, k=30, progress=False, outliers=outliers).mesh
        return float((np.abs(mesh.vertices[:, 2]) > 0.5).mean())

    assert above(3.0) < 0.05 < above(0.0)


def test_the_figures_colour_scale_is_what_it_scores():
    """Each colour bar runs to the 95th percentile of the distances it shows (the accuracy
    p95 the report gives), so a surface whose median error is 7 cm is not drawn saturated."""
    from drake_auv.reconstruction.figures import TRUTH_LABEL, colour_scale, fig_reconstruction
    from drake_auv.reconstruction.products import SUPPORT_LABEL

    mesh = trimesh.creation.icosphere(subdivisions=2)
    rng = np.random.default_rng(0)
    truth, support = rng.exponential(0.07, (2, len(mesh.vertices))) * [[1.0], [0.2]]
    fig = fig_reconstruction([("sphere", mesh, truth), ("sphere", mesh, support, SUPPORT_LABEL)])
    bars = {a._colorbar.ax.get_ylabel().split("\n")[0]: a._colorbar
            for a in fig.axes if hasattr(a, "_colorbar")}
    assert set(bars) == {TRUTH_LABEL, SUPPORT_LABEL}
    for label, d in ((TRUTH_LABEL, truth), (SUPPORT_LABEL, support)):
        assert bars[label].norm.vmax == pytest.approx(np.percentile(d, 95))
        assert bars[label].norm.vmax == colour_scale(d) and np.median(d) < 0.3 * colour_scale(d)
        # the label states the scale
        assert bars[label].ax.get_ylabel().endswith(
            f"scale: 0 to its 95th percentile, {colour_scale(d):.2f} m")
    assert colour_scale([np.nan, 0.0]) == 0.01
    one = fig_reconstruction([("sphere", mesh, truth)], vmax=1.0)
    (bar,) = [a._colorbar for a in one.axes if hasattr(a, "_colorbar")]
    assert bar.norm.vmax == 1.0 and bar.ax.get_ylabel().endswith("scale: 0 to 1.00 m")
