"""Outputs never escape their folder: written to a private temporary file, renamed into place,
never through a link planted at the destination."""

import os
import stat
from pathlib import Path

import numpy as np
import pytest

from drake_auv.cli import main
from drake_auv.output_files import PARTIAL, open_replacing, replacing, write_text
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import write_geotiff

VICTIM = "must not change\n"


def _plant(out: Path, names, outside: Path) -> dict:
    """Plants, for each name, a link in `out` to a file of its own in `outside` and one more
    link to a file all share (two links at one file lost content before); returns
    {link: target}."""
    out.mkdir(parents=True, exist_ok=True)
    outside.mkdir(parents=True, exist_ok=True)
    shared = outside / "shared.txt"
    shared.write_text(VICTIM)
    links = {}
    for k, name in enumerate(names):
        target = shared if k % 2 else outside / f"victim_{name}"
        target.write_text(VICTIM)
        (out / name).symlink_to(target)
        links[out / name] = target
    (out / "dangling.csv").symlink_to(outside / "created_by_no_one")
    return links


def _check(out: Path, links: dict, outside: Path, written) -> None:
    for link, target in links.items():
        assert target.read_text() == VICTIM, link  # the link's target is untouched
    assert not (outside / "created_by_no_one").exists()
    for name in written:
        mode = os.lstat(out / name).st_mode
        assert stat.S_ISREG(mode) and (out / name).stat().st_size > 0, name
    assert not [p for p in out.iterdir() if PARTIAL in p.name]  # no temporary left


def test_a_link_at_the_destination_is_replaced_not_followed(tmp_path):
    links = _plant(tmp_path / "out", ["a.txt", "b.txt"], tmp_path / "outside")
    write_text(tmp_path / "out" / "a.txt", "new\n")
    with open_replacing(tmp_path / "out" / "b.txt", "wb") as f:
        f.write(b"bytes")
    write_text(tmp_path / "out" / "dangling.csv", "x\n")
    _check(tmp_path / "out", links, tmp_path / "outside", ["a.txt", "b.txt", "dangling.csv"])
    assert (tmp_path / "out" / "a.txt").read_text() == "new\n"
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(os.stat(tmp_path / "out" / "a.txt").st_mode) == 0o666 & ~umask


def test_an_error_leaves_the_old_file_and_no_temporary(tmp_path):
    (tmp_path / "a.txt").write_text("old")
    with pytest.raises(RuntimeError), replacing(tmp_path / "a.txt") as temporary:
        temporary.write_text("half")
        raise RuntimeError("writer failed")
    assert (tmp_path / "a.txt").read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.txt"]
    (tmp_path / "folder.txt").mkdir()
    with pytest.raises(IsADirectoryError, match="is a folder"):
        write_text(tmp_path / "folder.txt", "x")
    with pytest.raises(FileNotFoundError, match="nothing was written"), \
            replacing(tmp_path / "b.txt"):
        pass
    with pytest.raises(ValueError, match="mode"), open_replacing(tmp_path / "c.txt", "a"):
        pass


PLAN_OUTPUTS = ("path.csv", "path.geojson", "lawnmower.geojson", "mission.xml", "mission.plan",
                "report.md", "report.json", "slope.png", "path3d.png")


def test_plan_writes_regular_files_in_o_and_leaves_planted_links_targets(tmp_path):
    yy, xx = np.mgrid[0:40, 0:30] * 1.0
    z = -40.0 + 0.05 * yy + np.clip(xx - 12.0, 0.0, 8.0) * 0.9
    tif = tmp_path / "small.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (1000.0, 2000.0), "EPSG:32631"), tif)
    out, outside = tmp_path / "out", tmp_path / "outside"
    links = _plant(out, PLAN_OUTPUTS, outside)
    assert main(["plan", str(tif), "--omega", "2", "--no-3d-metrics",
                 "--export", "geojson,cola2,qgc", "-o", str(out)]) == 0
    _check(out, links, outside, PLAN_OUTPUTS)


RUN_OUTPUTS = ("report.json", "report.md", "trajectory.csv", "points.ply", "coverage.png",
               "diagram.dot")


def test_run_writes_regular_files_in_o_and_leaves_planted_links_targets(tmp_path):
    from sites import write_utm_site

    mission = write_utm_site(tmp_path)
    out, outside = tmp_path / "out", tmp_path / "outside"
    links = _plant(out, RUN_OUTPUTS, outside)
    assert main(["run", str(mission), "-o", str(out), "--quiet", "--no-html",
                 "--set", "limits.max_time_s=5"]) == 0
    _check(out, links, outside, RUN_OUTPUTS)
