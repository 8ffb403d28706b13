"""Faults at the command line: each case goes through `drake_auv.cli.main` and must end with
one line on stderr and exit 2, before anything is computed (well under a second; the work's
first step is replaced by a function that fails the test if called), losing nothing already
written."""

from __future__ import annotations

import errno
import sys
import time
from collections import namedtuple

import numpy as np
import pytest
import trimesh
import yaml

from drake_auv.cli import build_parser, main
from drake_auv.reconstruction import surface
from drake_auv.reconstruction.pointcloud import PointCloud, write_ply
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import write_geotiff

UNWRITABLE = "/sys/drake-auv-out"  # sysfs: no file can be created there, not even by root


@pytest.fixture(autouse=True, scope="module")
def _imported():
    build_parser()  # the commands' imports, so the timings below measure the checks alone


def _fail(*_, **__):
    raise AssertionError("the work started before the fault was found")


@pytest.fixture()
def no_work(monkeypatch):
    """The first step of each command's work fails the test when reached."""
    import drake_auv.mission.config
    import drake_auv.planning.coverage_plan
    import drake_auv.reconstruction.pointcloud

    monkeypatch.setattr(drake_auv.mission.config, "load_mission", _fail)
    monkeypatch.setattr(drake_auv.planning.coverage_plan, "plan_coverage", _fail)
    monkeypatch.setattr(drake_auv.reconstruction.pointcloud, "read_point_cloud", _fail)


def fault(capsys, argv: list[str], within: float = 0.5) -> str:
    """Runs `drake-auv argv`; asserts exit 2 and one line on stderr within `within` s;
    returns the line."""
    start = time.perf_counter()
    code = main(argv)
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err.strip()
    assert code == 2 and err.count("\n") == 0 and err.startswith(
        f"drake-auv {argv[0]}: error: "), err
    assert elapsed < within, f"{elapsed:.2f} s before the error"
    return err


@pytest.fixture()
def grid(tmp_path):
    """A small georeferenced GeoTIFF (EPSG:32631)."""
    path = tmp_path / "grid.tif"
    write_geotiff(Bathymetry(-30.0 + np.arange(30.0)[:, None] * np.ones(30) * 0.2, (1.0, 1.0),
                             (1000.0, 2000.0), "EPSG:32631"), path)
    return path


def _sphere_ply(path, n=400):
    rng = np.random.default_rng(0)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    write_ply(PointCloud(p, 3.0 * p, np.arange(n, dtype=float), np.zeros(n, np.uint8)), path)
    return path


# -- outputs, checked before the work ------------------------------------------------------

@pytest.mark.parametrize("command", ["run", "plan"])
def test_an_output_folder_that_is_a_file(tmp_path, capsys, no_work, grid, command):
    out = tmp_path / "results"
    out.write_text("last week's results\n")
    argv = ["run", "boulder", "-o", str(out)] if command == "run" else \
        ["plan", str(grid), "-o", str(out)]
    assert f"-o {out}: a file is in the way" in fault(capsys, argv)
    assert out.read_text() == "last week's results\n"


@pytest.mark.parametrize("command", ["run", "plan"])
def test_an_output_folder_that_cannot_be_written(tmp_path, capsys, no_work, grid, command):
    argv = ["run", "boulder", "-o", UNWRITABLE] if command == "run" else \
        ["plan", str(grid), "-o", UNWRITABLE]
    assert f"-o {UNWRITABLE}: cannot write there" in fault(capsys, argv)
    # a parent in the way is named
    (tmp_path / "file").write_text("keep")
    line = fault(capsys, [*argv[:-1], str(tmp_path / "file" / "out")])
    assert "cannot write there" in line and str(tmp_path / "file") in line
    assert (tmp_path / "file").read_text() == "keep"


@pytest.mark.parametrize("command", ["run", "plan", "reconstruct"])
def test_an_output_disk_without_room(tmp_path, capsys, no_work, monkeypatch, grid, command):
    import drake_auv.commands.outputs as outputs

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(outputs.shutil, "disk_usage", lambda _: usage(10 ** 9, 10 ** 9, 10 ** 5))
    argv = {"run": ["run", "boulder", "-o", str(tmp_path / "o")],
            "plan": ["plan", str(grid), "-o", str(tmp_path / "o")],
            "reconstruct": ["reconstruct", "x.ply", "-o", str(tmp_path / "o" / "m.ply")]}
    assert "0.1 MiB free on its disk, the outputs need at least" in fault(capsys,
                                                                         argv[command])


def test_reconstruct_outputs(tmp_path, capsys, no_work):
    kept = tmp_path / "meshes"
    kept.mkdir()
    (kept / "old.ply").write_text("an earlier mesh")
    assert "is a folder" in fault(capsys, ["reconstruct", "p.ply", "-o", str(kept)])
    assert "unknown extension '.xyz'" in fault(capsys, ["reconstruct", "p.ply", "-o",
                                                        str(tmp_path / "m.xyz")])
    assert "--figure" in fault(capsys, ["reconstruct", "p.ply", "-o", str(tmp_path / "m.ply"),
                                        "--figure", f"{UNWRITABLE}/f.png"])
    assert "is not a regular file" in fault(capsys, ["reconstruct", "p.ply", "-o",
                                                     str(_link(tmp_path / "full.ply"))])
    assert (kept / "old.ply").read_text() == "an earlier mesh"


def _link(path):
    path.symlink_to("/dev/full")  # writing there fails with ENOSPC
    return path


def test_an_os_error_during_the_work_is_one_line(tmp_path, capsys, grid, monkeypatch):
    import drake_auv.formats.outputs

    def full(plan, outdir, **_):
        raise OSError(errno.ENOSPC, "No space left on device", str(outdir) + "/path.csv")

    monkeypatch.setattr(drake_auv.formats.outputs, "write_outputs", full)
    code = main(["plan", str(grid), "--no-figures", "--no-3d-metrics", "-o", str(tmp_path)])
    err = capsys.readouterr().err.strip().splitlines()[-1]  # after the progress bar
    assert code == 2 and err == f"drake-auv plan: error: {tmp_path}/path.csv: No space left " \
                                "on device"


# -- inputs ------------------------------------------------------------------------------

HEADER = "ply\nformat {fmt} 1.0\nelement vertex {n}\nproperty double x\nproperty double y\n" \
         "property double z\nend_header\n"


@pytest.mark.parametrize("fmt", ["binary_little_endian", "ascii"])
def test_a_ply_header_claiming_too_many_vertices(tmp_path, capsys, fmt):
    path = tmp_path / "huge.ply"
    path.write_bytes(HEADER.format(fmt=fmt, n=10 ** 11).encode() + b"0 0 0\n" * 10)
    line = fault(capsys, ["reconstruct", str(path), "-o", str(tmp_path / "m.ply")])
    assert f"{path}: corrupt or truncated PLY, the header says 100000000000 vertices" in line
    assert "file has 60 bytes after it" in line


@pytest.mark.parametrize("rows, message", [
    ("0.5 0.5 0.5\n1.5 1.5 1.5\n2.5 2.5\n3.5 3.5 3.5\n",
     "line 10: vertex row 2 has 2 values, the header's properties are 3"),
    ("0.5 0.5 0.5\n1.5 1.5 one\n2.5 2.5 2.5\n3.5 3.5 3.5\n",
     "line 9: vertex row 1 holds a value that is not a number: '1.5 1.5 one'"),
    ("0 0 0 0\n1 1 1 1\n2 2 2 2\n3 3 3 3\n", "line 8: vertex row 0 has 4 values"),
    ("0.5 0.5 0.5\n1.5 1.5 1.5\n", "2 vertex rows where the header says 4")])
def test_an_ascii_ply_row_that_does_not_parse(tmp_path, capsys, rows, message):
    path = tmp_path / "rows.ply"
    path.write_text(HEADER.format(fmt="ascii", n=4) + rows)
    line = fault(capsys, ["reconstruct", str(path), "-o", str(tmp_path / "m.ply")])
    assert line.startswith(f"drake-auv reconstruct: error: {path}: ") and message in line


def test_origin_lonlat_on_a_georeferenced_grid(tmp_path, capsys, grid, no_work):
    line = fault(capsys, ["plan", str(grid), "--origin-lonlat", "25.4,36.4", "-o",
                          str(tmp_path / "o")])
    assert f"--origin-lonlat: {grid} is georeferenced (EPSG:32631)" in line


def test_a_self_intersecting_roi_is_reported(tmp_path, capsys, grid):
    bowtie = "1000,2000;1029,2029;1029,2000;1000,2029"
    assert main(["plan", str(grid), "--roi", bowtie, "--no-figures", "--no-3d-metrics",
                 "-o", str(tmp_path / "o")]) == 0
    warnings = [line for line in capsys.readouterr().err.splitlines() if "ROI" in line]
    assert warnings == ["drake-auv plan: warning: ROI polygon: Self-intersection[1014.5 "
                        "2014.5]; repaired into 2 polygon(s) of area 420.5 (was 0) map "
                        "units^2, the region used"]


# -- mission priors: the same CRS rules as plan's ----------------------------------------

def _site(tmp_path, crs: str, origin=(499970.0, 4599970.0)) -> str:
    """world.ply (a 60 m seabed with a 6 m cube) and prior.tif in `crs`; mission.yaml."""
    x0, y0 = origin
    gx, gy = np.meshgrid(x0 + np.arange(61.0), y0 + np.arange(61.0))
    box = (np.abs(gx - x0 - 30) <= 3) & (np.abs(gy - y0 - 30) <= 3)
    write_geotiff(Bathymetry(np.where(box, -14.5, -20.0), (1.0, 1.0), origin, crs),
                  tmp_path / "prior.tif")
    cube = trimesh.creation.box(extents=(6.0, 6.0, 6.0))
    cube.apply_translation([x0 + 30, y0 + 30, -17.5])
    seabed = trimesh.creation.box(extents=(60.0, 60.0, 1.0))
    seabed.apply_translation([x0 + 30, y0 + 30, -20.5])
    trimesh.util.concatenate([seabed, cube]).export(tmp_path / "world.ply")
    mission = dict(name="crs", seed=0, site=dict(world="world.ply", prior="prior.tif"),
                   steps=[dict(plan=dict(omega=3.0, slice_count=1)),
                          dict(survey=dict(replanning=False))])
    (tmp_path / "mission.yaml").write_text(yaml.safe_dump(mission))
    return str(tmp_path / "mission.yaml")


def test_run_takes_a_mercator_prior_in_its_map_units(tmp_path):
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.site import load_site

    mission = _site(tmp_path, "EPSG:3857")
    with pytest.warns(UserWarning, match=r"prior.tif is in EPSG:3857, where a ground metre is "
                                         r"1\.27\d\d map units"):
        site = load_site(load_mission(mission, overrides=["site.prior_error_m=0"]).site, 0)
    assert site.crs == "EPSG:3857" and site.prior.spacing == pytest.approx((1.0, 1.0))
    # the prior's cells lie where the file puts them, on the world mesh (site coordinates)
    corner = site.prior.world_to_crs([site.prior.origin])[0]
    assert corner == pytest.approx([499970.0, 4599970.0], abs=1e-6)
    top = site.prior.z[np.isclose(site.prior.z, -14.5)]
    assert len(top) == 49


def test_run_refuses_a_geographic_prior_before_the_dive(tmp_path, capsys, monkeypatch):
    import drake_auv.mission.plan

    monkeypatch.setattr(drake_auv.mission.plan, "plan_mission", _fail)
    mission = _site(tmp_path, "EPSG:4326", origin=(2.0, 41.0))
    line = fault(capsys, ["run", mission, "-o", str(tmp_path / "out")], within=1.0)
    assert "site.prior: prior.tif is in the geographic CRS EPSG:4326 (degrees)" in line


# -- an optional dependency that does not load -------------------------------------------

def test_open3d_that_does_not_load_says_why(tmp_path, capsys, broken_open3d):
    points = _sphere_ply(tmp_path / "points.ply")
    line = fault(capsys, ["reconstruct", str(points), "-o", str(tmp_path / "m.ply"),
                          "--k", "20"])
    assert line.endswith("surface reconstruction: open3d is installed but does not import: "
                         "ImportError: libusb-1.0.so.0: cannot open shared object file: No "
                         "such file or directory")
    assert not (tmp_path / "m.ply").exists()


def test_open3d_not_installed_says_how(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "open3d", None)
    surface.retry_open3d()
    try:
        line = fault(capsys, ["reconstruct", str(_sphere_ply(tmp_path / "p.ply")), "-o",
                              str(tmp_path / "m.ply"), "--k", "20"])
    finally:
        surface.retry_open3d()
    assert "needs the optional open3d-cpu package, which is not installed: pip install " \
           "'drake_auv[reconstruct]'" in line
