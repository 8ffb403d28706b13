"""`drake-auv plan`: outputs on a small GeoTIFF, and clear errors."""

import io
import json
from contextlib import contextmanager

import numpy as np
import pytest

from drake_auv.cli import main
from drake_auv.planning.path import PlannedPath
from drake_auv.progress import PLAN_PHASES, RunProgress
from drake_auv.terrain.bathymetry import Bathymetry


def test_plan_writes_every_output(tmp_path, small_tif, capsys):
    out = tmp_path / "out"
    code = main(["plan", str(small_tif), "--omega", "2", "--aperture", "60",
                 "--roi", "1000,2000,1049,2059", "-o", str(out)])
    assert code == 0
    for name in ("path.csv", "path.geojson", "lawnmower.geojson", "report.md", "report.json",
                 "slope.png", "classification.png", "cells.png", "lanes.png", "contours.png",
                 "path3d.png", "lawnmower.png"):
        assert (out / name).stat().st_size > 0, name
    path = PlannedPath.from_csv(out / "path.csv")
    assert {"planar", "slice"} <= set(path.labels)
    report = json.loads((out / "report.json").read_text())
    assert report["classification"]["high_slope_regions"] == 1
    assert report["metrics"]["total"]["coverage"] >= 0.95
    gj = json.loads((out / "path.geojson").read_text())
    (route,) = gj["features"]  # no vehicle file asked for: the route alone
    coords = np.array(route["geometry"]["coordinates"])
    assert coords.shape[1] == 2 and "crs" not in gj  # RFC 7946 positions: lon, lat
    # WGS 84 longitude/latitude of the file's map coordinates (EPSG:32631).
    from pyproj import Transformer

    e, n = Transformer.from_crs("EPSG:4326", "EPSG:32631", always_xy=True).transform(
        coords[:, 0], coords[:, 1])
    assert e.min() >= 999.5 and e.max() <= 1049.5
    assert n.min() >= 1999.5 and n.max() <= 2059.5
    printed = capsys.readouterr().out
    assert "Standard lawnmower path" in printed
    t = report["mission_time"]
    assert t["duration_s"] == pytest.approx(path.length / 0.5, rel=1e-3)  # the default speed
    assert f"Mission time: {t['duration']} for the" in printed
    md = (out / "report.md").read_text()
    assert f"Mission time: {t['duration']}" in md
    assert "reference_table3" not in report and "Santorini" not in md  # only when asked for


def test_the_reference_table_when_asked_for(tmp_path, small_tif):
    out = tmp_path / "out"
    assert main(["plan", str(small_tif), "--no-figures", "--no-3d-metrics", "--export", "",
                 "--speed", "1.25", "--reference-table", "-o", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["reference_table3"]["total"]["length"] == 10838.5
    assert "## The reference's Table 3 (Santorini caldera ROI)" in (out / "report.md").read_text()
    t = report["mission_time"]
    assert t["speed_m_s"] == 1.25 and t["duration_s"] == pytest.approx(t["length_m"] / 1.25)
    assert t["lawnmower_duration_s"] == pytest.approx(report["metrics"]["lawnmower"]["length"]
                                                      / 1.25)


@pytest.mark.parametrize("seconds, text", [(42.4, "42 s"), (750.0, "12.5 min"),
                                           (131_760.0, "36.6 h")])
def test_human_duration(seconds, text):
    from drake_auv.planning.report import human_duration

    assert human_duration(seconds) == text


def _violations(report):
    """(file, count) of every violation report.json records for the vehicle files."""
    ex, out = report["exports"], []
    cola2 = ex["cola2"]
    out += [("mission.xml", cola2[k]) for k in ("sections_over_deviation", "unresolved_sections")]
    for name, r in (("mission.xml", cola2["replay"]), ("ArduSub", ex["qgc"]["clearance"])):
        out += [(name, r[k]) for k in ("closer_than_half_omega", "shallower_than_min_depth")]
    return [(name, n) for name, n in out if n]


def test_plan_on_a_shipped_tile_says_what_matters(tmp_path, capsys):
    """A wall of the Monterey canyon (a shipped tile, a 250 m x 310 m ROI): the mission time, a
    warning line for each violation report.json records, the split QGC files in upload order,
    a route and the vehicle files' waypoints in the GeoJSON, figures in EPSG:3857."""
    from drake_auv.scenarios import DATA_DIR

    tile = DATA_DIR / "monterey" / "MontereyBay.R_-121.815_-121.805_36.790_36.800.epsg3857.tif"
    out = tmp_path / "out"
    code = main(["plan", str(tile), "--roi=-13560435,4410686,-13560186,4410998", "--omega", "5",
                 "--export", "cola2,qgc,geojson", "--no-3d-metrics", "-o", str(out)])
    printed = capsys.readouterr()
    assert code == 0, printed.err
    report = json.loads((out / "report.json").read_text())
    t = report["mission_time"]
    assert t["duration_s"] == pytest.approx(sum(report["path_length_by_label"].values()) / 0.5)
    assert f"Mission time: {t['duration']} for the {t['length_m'] / 1000:.2f} km path" \
        in printed.out
    violations = _violations(report)
    assert violations  # this wall makes COLA2 sections stray beyond the deviation tolerance
    warnings = [line for line in printed.err.splitlines() if line.startswith("warning: ")]
    md = [line for line in (out / "report.md").read_text().splitlines() if line.startswith("- ")]
    assert len(warnings) == len(md) == len(violations), (warnings, violations)
    for (name, n), line, md_line in zip(violations, warnings, md):
        assert name in line and f" {n} " in line and md_line == "- " + line[len("warning: "):]
    files = report["exports"]["qgc"]["files"]
    assert files == [f"mission_{k + 1}.plan" for k in range(len(files))] and len(files) > 1
    upload = next(line for line in printed.out.splitlines() if line.startswith("QGroundControl"))
    assert [upload.index(f) for f in files] == sorted(upload.index(f) for f in files)
    gj = json.loads((out / "path.geojson").read_text())
    kinds = [f["properties"]["kind"] for f in gj["features"]]
    assert kinds[0] == "route" and set(kinds[1:]) == {"waypoint"}
    assert {f["properties"]["file"] for f in gj["features"][1:]} == {"mission.xml", *files}
    assert (out / "lanes.png").stat().st_size > 0


def test_plan_figures_read_the_crs_latitude_longitude_and_north(small_tif):
    """UTM 31N (EPSG:32631): the bottom and left axes read eastings and northings, the top and
    right edges the longitudes and latitudes there, and the arrow points to true north."""
    from pyproj import Transformer

    from drake_auv.planning.coverage_plan import plan_coverage
    from drake_auv.planning.parameters import CoverageParameters
    from drake_auv.planning.figures import fig_slope
    from drake_auv.terrain.geo import GeoFrame
    from drake_auv.terrain.readers import read_bathymetry

    bathy = read_bathymetry(small_tif)
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0), compute_metrics=False)
    geo = GeoFrame(bathy)
    fig = fig_slope(plan, geo)
    fig.savefig(io.BytesIO(), format="png")  # lays the secondary axes out
    ax = fig.axes[0]
    by_label = {c.get_xlabel() or c.get_ylabel(): c for c in ax.child_axes}
    east, north = by_label["easting (metre, EPSG:32631)"], by_label["northing (metre, EPSG:32631)"]
    # The axes' edges in map coordinates: the grid's outer cell edges.
    assert east.get_xlim() == pytest.approx((999.5, 1049.5))
    assert north.get_ylim() == pytest.approx((1999.5, 2059.5))
    to_ll = Transformer.from_crs("EPSG:32631", "EPSG:4326", always_xy=True)
    top, right = (c for c in ax.child_axes if not (c.get_xlabel() or c.get_ylabel()))

    def degrees(text):
        return float(text[:-2]) * (-1 if text[-1] in "WS" else 1)

    ticks = list(zip(top.get_xticks(), top.get_xticklabels()))
    assert len(ticks) >= 2
    for x, label in ticks:
        lon, _ = to_ll.transform(*geo.world_to_map([[x, bathy.extent[3] + 0.5]])[0])
        assert degrees(label.get_text()) == pytest.approx(lon, abs=2e-6), label
    for y, label in zip(right.get_yticks(), right.get_yticklabels()):
        _, lat = to_ll.transform(*geo.world_to_map([[bathy.extent[1] + 0.5, y]])[0])
        assert degrees(label.get_text()) == pytest.approx(lat, abs=2e-6), label
    (arrow,) = [t for t in ax.texts if hasattr(t, "xyann")]
    d = np.subtract(arrow.xy, arrow.xyann)
    azimuth = float(geo.grid_north_azimuth(np.array(arrow.xyann)[None])[0])
    assert d / np.linalg.norm(d) == pytest.approx([-np.sin(azimuth), np.cos(azimuth)],
                                                  abs=1e-3)
    assert [t.get_text() for t in ax.texts if t.get_text()] == ["N"]


def test_what_does_not_apply_is_left_out_of_the_report():
    """A gentle slope: no high-slope region, so no row for it, and no "nan" or "n/a"."""
    from drake_auv.planning.coverage_plan import plan_coverage
    from drake_auv.planning.parameters import CoverageParameters
    from drake_auv.planning.report import report_dict, report_markdown

    x = np.arange(40.0)[None, :] * np.ones((30, 1))
    plan = plan_coverage(Bathymetry(-20.0 + 0.05 * x, (1.0, 1.0)), CoverageParameters(omega=2.0))
    assert plan.labels.n_regions == 0 and plan.metrics.high_slope.samples == 0
    text = report_markdown(plan, report_dict(plan))
    assert "| Planar region |" in text and "| High-slope region |" not in text
    assert "nan" not in text and "n/a" not in text and "Length ratio" in text


@pytest.mark.parametrize("extra, message", [
    (["--omega", "0"], "--omega 0 is out of range; allowed: [0.5, 100] m"),
    (["--aperture", "190"], "--aperture 190 is out of range; allowed: [5, 170] deg"),
    (["--slope-threshold", "-1"], "--slope-threshold -1"), (["--roi", "0,0,10,10"], "outside the grid"),
    (["--speed", "0"], "--speed")])
def test_plan_reports_bad_input(tmp_path, small_tif, capsys, extra, message):
    code = main(["plan", str(small_tif), "--no-figures", "-o", str(tmp_path / "o"), *extra])
    assert code == 2
    assert message in capsys.readouterr().err


def test_plan_missing_file(tmp_path, capsys):
    assert main(["plan", str(tmp_path / "missing.tif"), "-o", str(tmp_path)]) == 2
    assert "not found" in capsys.readouterr().err


def _npz(tmp_path, name, z):
    path = tmp_path / name
    np.savez(path, z=z, spacing=[1.0, 1.0])
    return path


@pytest.mark.parametrize("case, extra, message", [
    ("dry", [], "minimum operating depth"), ("inf", [], "infinite"),
    ("ok", ["--omega", "1e9"], "--omega 1e+09 is out of range"),
    ("ok", ["--omega", "60"], "omega (offset to the terrain) must be in (0, 50.0] m"),
    ("ok", ["--min-depth", "-1"], "--min-depth -1 is out of range; allowed: >= 0 m"),
    ("ok", ["--origin-lonlat", "north"], "--origin-lonlat")])
def test_bad_grids_and_values_give_one_line(tmp_path, capsys, case, extra, message):
    x = np.arange(40.0)[None, :] * np.ones((30, 1))
    z = {"dry": 5.0 + 0.1 * x, "inf": np.where(x == 7, np.inf, -20.0 + 0.1 * x),
         "ok": -20.0 + 0.1 * x}[case]
    code = main(["plan", str(_npz(tmp_path, f"{case}.npz", z)), "--no-figures",
                 "-o", str(tmp_path / "o"), *extra])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0], err
    assert "Traceback" not in err[0]


def test_label_runs_draw_every_segment_once_in_its_label():
    from drake_auv.planning.figures import label_runs

    labels = np.array(list("aabbbaabba"), dtype=object)
    points = np.column_stack([np.arange(10.0), np.arange(10.0) ** 2, np.zeros(10)])
    runs = label_runs(points, labels)
    assert set(runs) == {"a", "b"}
    for name, line in runs.items():
        drawn = {(line[k, 0], line[k + 1, 0]) for k in range(len(line) - 1)
                 if np.isfinite(line[k:k + 2]).all()}
        assert drawn == {(k, k + 1.0) for k in range(9) if labels[k + 1] == name}, name
        assert np.isfinite(line[[0, -1]]).all() and line.shape[1] == 2


def test_label_runs_thin_a_long_path_keeping_each_runs_ends():
    from drake_auv.planning.figures import label_runs

    n = 10_000
    labels = np.where((np.arange(n) // 700) % 3 == 0, "transit", "planar").astype(object)
    points = np.column_stack([np.arange(n, dtype=float), np.sin(np.arange(n) / 50.0),
                              np.zeros(n)])
    full, thin = label_runs(points, labels), label_runs(points, labels, max_vertices=1000)
    for name in full:
        ends = lambda line: line[np.isfinite(line[:, 0])][[0, -1]]  # noqa: E731
        pieces = lambda line: np.split(line, np.flatnonzero(np.isnan(line[:, 0])))  # noqa: E731
        assert len(pieces(thin[name])) == len(pieces(full[name]))
        for a, b in zip(pieces(full[name]), pieces(thin[name])):
            assert np.array_equal(ends(a), ends(b))  # every run from its first to its last
        kept = thin[name][np.isfinite(thin[name][:, 0])]
        assert np.array_equal(kept[:, 1], np.sin(kept[:, 0] / 50.0))  # vertices of the path
    assert sum(len(v) for v in thin.values()) < 0.2 * sum(len(v) for v in full.values())


def test_the_lanes_figure_draws_no_segment_across_the_slices():
    from matplotlib.figure import Figure

    from drake_auv.planning.figures import _path_lines

    labels = np.array(["transit", "slice", "slice", "transit", "planar"], dtype=object)
    points = np.column_stack([np.arange(5.0), [0.0, 5.0, 5.0, 0.0, 0.0], np.zeros(5)])
    ax = Figure().add_subplot(1, 1, 1)
    _path_lines(ax, PlannedPath(points, 0.0, (0.0, 0.0, -1.0), labels), skip=("slice",))
    drawn = {line.get_label(): np.column_stack(line.get_data()) for line in ax.get_lines()}
    assert set(drawn) == {"transit", "planar"}
    transit = drawn["transit"]
    pairs = {(a[0], b[0]) for a, b in zip(transit, transit[1:])
             if np.isfinite(a).all() and np.isfinite(b).all()}
    assert pairs == {(2.0, 3.0)}  # flown from the last slice sample; no chord from 0 to 3


class _RecordingProgress(RunProgress):
    """The plan command's display (silent) recording, at each unit done, its phase, the name
    of the unit done and the files written by then."""

    def __init__(self, outdir):
        super().__init__(PLAN_PHASES, enabled=False)
        self.outdir, self.done_units = outdir, []

    def _record(self, name):
        files = sorted(p.name for p in self.outdir.glob("*")) if self.outdir.exists() else []
        self.done_units.append((self.phase, name, files))

    def advance(self, units=1.0, note=None):
        self._record(self.note)
        super().advance(units, note)

    @contextmanager
    def step(self, note):
        with super().step(note):
            yield
        self._record(note)


def test_one_progress_display_ends_when_the_last_file_is_written(tmp_path):
    from drake_auv.formats.outputs import output_stages, write_outputs
    from drake_auv.planning.coverage_plan import PLAN_STAGES, plan_coverage
    from drake_auv.planning.parameters import CoverageParameters

    yy, xx = np.mgrid[0:40, 0:30] * 1.0
    bathy = Bathymetry(-40.0 + np.clip(xx - 12.0, 0.0, 8.0) * 0.9 + 0.02 * yy, (1.0, 1.0),
                       (1000.0, 2000.0), "EPSG:32631")
    out = tmp_path / "out"
    progress = _RecordingProgress(out)
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0), progress=progress)
    assert [(phase, name) for phase, name, _ in progress.done_units] == [
        ("plan", stage) for stage in PLAN_STAGES]
    files = write_outputs(plan, out, progress=progress)
    stages = progress.done_units[len(PLAN_STAGES):]
    assert {phase for phase, _, _ in stages} == {"outputs"}
    assert len(stages) == output_stages(("geojson",)) == 4 + 7  # and the 7 figures
    assert [name for _, name, _ in stages[:2] + stages[-2:]] == [
        "path.csv", "GeoJSON", "3D metrics", "reports"]  # the 3D metrics beside the figures
    assert progress.share < 1.0 and progress.done == output_stages(("geojson",))
    assert stages[-1][2] == sorted(f.name for f in files)  # the last unit with every file
    assert len(stages[-2][2]) == len(files) - 2  # all but report.md and report.json
    progress.close()
    assert progress.share == 1.0


def test_grid_metrics_computed_beside_the_outputs_are_the_plans_own(tmp_path):
    from drake_auv.formats.outputs import output_stages, write_outputs
    from drake_auv.planning.coverage_plan import PLAN_STAGES, plan_coverage
    from drake_auv.planning.metrics import PlanMetrics
    from drake_auv.planning.parameters import CoverageParameters

    yy, xx = np.mgrid[0:40, 0:30] * 1.0
    bathy = Bathymetry(-40.0 + np.clip(xx - 12.0, 0.0, 8.0) * 0.9 + 0.02 * yy, (1.0, 1.0),
                       (1000.0, 2000.0), "EPSG:32631")
    params = CoverageParameters(omega=2.0)
    out = tmp_path / "out"
    progress = _RecordingProgress(out)
    plan = plan_coverage(bathy, params, compute_metrics=False, progress=progress)
    assert plan.metrics is None
    write_outputs(plan, out, figures=False, progress=progress, grid_metrics=True)
    stages = [name for _, name, _ in progress.done_units[len(PLAN_STAGES):]]
    assert stages == ["path.csv", "GeoJSON", "grid metrics", "3D metrics", "reports"]
    assert len(stages) == output_stages(("geojson",), figures=False, grid_metrics=True)
    report = json.loads((out / "report.json").read_text())
    assert PlanMetrics.from_dict(report["metrics"]) == plan_coverage(bathy, params).metrics
