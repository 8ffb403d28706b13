"""Flying exported files: the plan of a real Monterey tile exported as COLA2 and QGC missions,
each flown in the mission Diagram with its autopilot's semantics, against the internal plan."""

import json
import shutil
from pathlib import Path

import pytest
import yaml

from drake_auv.cli import main
from drake_auv.formats.outputs import write_outputs
from drake_auv.mission.config import MissionFileError, load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.report.summary import summarise
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.scenarios import DATA_DIR
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.site_files import write_site_files

TILE = DATA_DIR / "monterey" / "MontereyBay.R_-121.815_-121.805_36.790_36.800.epsg3857.tif"
ROI = (150.0, 840.0, 190.0, 880.0)  # 40 m x 40 m of the canyon wall, tile's world frame
SITE = {"world": "world.ply", "target": "target.ply", "prior": "prior.tif", "prior_error_m": 2.0}
COMMON = dict(seed=0, site=SITE, payload={"multibeam_mount": "down"},
              navigation={"heading_bias_deg": 1.0, "dvl_scale_error": 0.01, "random_walk": 0.02})


def write_mission(folder: Path, name: str, steps) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump({"name": name, **COMMON, "steps": steps}))
    return path


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    """The internal plan flown, its exports, and each export flown, on the same site and seed."""
    folder = tmp_path_factory.mktemp("fly")
    write_site_files(read_bathymetry(TILE), ROI, folder, margin=30.0)
    internal = load_mission(write_mission(folder, "internal", [
        {"plan": {"omega": 10.0, "speed": 1.0}}, {"survey": {"replanning": False}}]))
    site = load_site(internal.site, internal.seed)
    plan = plan_mission(internal, site)
    write_outputs(plan.coverage, folder, figures=False, exports=("cola2", "qgc"),
                  surge_velocity=1.0, metrics_3d=False)
    results = {"internal": run_mission(internal, site=site, plan=plan, progress=False)}
    for name, file in (("cola2", "mission.xml"), ("ardusub", "mission.plan")):
        spec = load_mission(write_mission(folder, name, [{"fly": {"file": file, "speed": 1.0}}]))
        results[name] = run_mission(spec, progress=False)
    return folder, results, {k: summarise(r) for k, r in results.items()}


@pytest.mark.parametrize("autopilot", ["cola2", "ardusub"])
def test_the_exported_file_flies_like_the_plan(flown, autopilot):
    _, results, summaries = flown
    internal, fly = summaries["internal"], summaries[autopilot]
    assert results[autopilot].dive.outcomes == ["goal"] and results[autopilot].dive.completed
    assert not fly["contact"] and fly["min_clearance_m"] > 5.0  # Omega 10 m
    assert fly["responses"] == []  # the autopilot's own steps are no fault
    # ArduSub holds the plan's yaw (the slices face the wall) as the internal path does;
    # COLA2's sections can only head along their track, which turns the down-looking fan
    # across the contours and sees more of this wall: never less than the plan's
    gap = fly["coverage"]["multibeam"] - internal["coverage"]["multibeam"]
    assert (abs(gap) if autopilot == "ardusub" else -gap) <= 0.05, gap
    assert fly["coverage"]["multibeam"] > 0.8
    # the pilot flew the file's items, not the internal path: the tracker's reference
    # differs from the plan's samples while the vehicle covers the same ground
    duration = results[autopilot].log.duration_s / results["internal"].log.duration_s
    assert 0.6 < duration < 1.6, duration


def test_the_fly_diagram_holds_the_pilot_and_its_dvl(flown):
    """One mission Diagram: the pilot behind the reference switch, fed by the DVL; the
    internal plan's Diagram has neither."""
    _, results, _ = flown
    names = {s.get_name() for s in results["ardusub"].run.diagram.GetSystems()}
    assert {"dvl", "autopilot", "reference_switch", "mission_supervisor"} <= names
    assert results["internal"].run.handles.autopilot is None
    dot = results["cola2"].run.diagram_dot
    assert "autopilot" in dot and "seabed_elevation" in dot


def run_cli(argv):
    return main([str(a) for a in argv])


def test_bad_files_one_line_before_simulating(flown, tmp_path, capsys):
    folder, _, _ = flown
    for name in ("world.ply", "target.ply", "prior.tif", "mission.xml", "mission.plan"):
        shutil.copy(folder / name, tmp_path / name)
    (tmp_path / "broken.xml").write_text("<mission><version>2.0</version><mission_step>")
    (tmp_path / "broken.plan").write_text('{"fileType": "Plan", "mission": ')
    (tmp_path / "mission.kml").write_text("<kml/>")
    # the same mission moved 0.05 deg east: another site's file
    plan = json.loads((tmp_path / "mission.plan").read_text())
    for item in plan["mission"]["items"]:
        if item.get("command") == 16:
            item["params"][5] += 0.05
    (tmp_path / "elsewhere.plan").write_text(json.dumps(plan))
    cases = {"broken.xml": "broken.xml", "broken.plan": "broken.plan",
             "mission.kml": "unknown mission format", "elsewhere.plan": "outside the world",
             "missing.plan": "not found"}
    for file, expected in cases.items():
        mission = write_mission(tmp_path, "bad", [{"fly": {"file": file}}])
        code = run_cli(["run", mission, "-o", tmp_path / "out", "--no-html"])
        err = capsys.readouterr().err.strip()
        assert code == 2 and len(err.splitlines()) == 1 and expected in err, (file, err)
        assert not (tmp_path / "out" / "report.json").exists()


def test_a_site_without_a_crs_cannot_place_a_file(tmp_path):
    mission = tmp_path / "m.yaml"
    (tmp_path / "mission.plan").write_text("{}")
    mission.write_text(yaml.safe_dump({"name": "m", "site": {"scenario": "boulder"},
                                       "steps": [{"fly": {"file": "mission.plan"}}]}))
    spec = load_mission(mission)
    with pytest.raises(MissionFileError, match="no CRS"):
        plan_mission(spec, load_site(spec.site, spec.seed))


def test_heave_in_3d_only_for_cola2(tmp_path):
    (tmp_path / "mission.plan").write_text("{}")
    mission = tmp_path / "m.yaml"
    mission.write_text(yaml.safe_dump({"name": "m", "site": {"scenario": "boulder"}, "steps": [
        {"fly": {"file": "mission.plan", "heave_in_3d": True}}]}))
    with pytest.raises(MissionFileError, match="only for COLA2"):
        load_mission(mission)


def test_drake_auv_run_reports_a_fly_mission(flown, tmp_path):
    """`drake-auv run` on a mission that only flies a file: the report, its figures and a
    strict-JSON report.json (no Omega is known: every sample is scored)."""
    folder, _, _ = flown
    out = tmp_path / "run"
    assert run_cli(["run", folder / "cola2.yaml", "-o", out, "--no-html", "--quiet", "--set",
                    "limits.max_time_s=60"]) == 0
    report = json.loads((out / "report.json").read_text(), parse_constant=lambda c: 1 / 0)
    assert report["distance_to_target"]["near_m"] is None
    assert report["phases"][0]["name"] == "survey"
    for name in ("distance.png", "coverage.png", "trajectory.csv", "report.md"):
        assert (out / name).stat().st_size > 0, name


def test_a_campaign_flies_the_exported_file(flown, tmp_path):
    """`drake-auv campaign` over a mission whose step flies an exported file: one row per
    seed, each a dive that flew the file (the seeds move the prior and the drift)."""
    folder, _, _ = flown
    out = tmp_path / "campaign"
    code = run_cli(["campaign", folder / "ardusub.yaml", "--seeds", "0:2", "--set",
                    "limits.max_time_s=40", "--workers", "1", "--quiet", "-o", out])
    assert code == 0
    import csv
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert sorted(r["seed"] for r in rows) == ["0", "1"]
    assert all(r["status"] == "ok" for r in rows), rows
