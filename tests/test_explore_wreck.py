"""examples/explore_wreck.py: a site given as files (a wreck on a rough seabed), a world mesh and
no prior map at all, explored; a step that needs a prior is refused there."""

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest
import yaml

from drake_auv.cli import main
from drake_auv.mission.config import MissionFileError, load_mission
from drake_auv.terrain.synthetic import wreck_site

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "explore_wreck.py"
spec = importlib.util.spec_from_file_location("explore_wreck", EXAMPLE)
example = importlib.util.module_from_spec(spec)
spec.loader.exec_module(example)


def test_the_wreck_sits_on_a_rough_seabed_and_its_target_is_what_can_be_seen():
    world, target = wreck_site(seed=0, origin=(0.0, 0.0))
    # The hull (20 m x 6 m, a 6 m bow, 5 m high) and the deckhouse (5 x 4 x 3 m) less the two
    # faces they share (2 x 20 m^2) and the hull's bottom, settled 1 m (up to 2.5 m on the
    # rough seabed and the heel) into the seabed: only what stands above it is the target.
    perimeter = 2 * 14.0 + 6.0 + 2 * np.hypot(6.0, 3.0)
    deck = 14.0 * 6.0 + 6.0 * 6.0 / 2
    above = (deck - 20.0) + 2 * (20.0 + 15.0 + 12.0) - 20.0
    assert above + 2.5 * perimeter < target.area < above + 4.0 * perimeter
    assert np.all(target.triangles_center[:, 2] > world.bounds[0, 2])
    lo, hi = world.bounds
    assert hi[2] < -24.0 and lo[2] > -34.0  # the deckhouse's top, the deepest seabed
    edges = target.edges_unique_length
    assert edges.max() <= 0.5 + 1e-9  # scored per face: faces no longer than 0.5 m


@pytest.mark.slow
def test_the_wreck_mission_runs_from_its_files_at_the_command_line(tmp_path):
    path = example.write_wreck_mission(tmp_path / "site", seed=0)
    out = tmp_path / "run"
    assert main(["run", str(path), "--out", str(out), "--no-html", "--quiet",
                 "--set", "limits.max_time_s=20"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["mission"]["site"] == "world" and report["exploration"]["viewpoints"] >= 1


def test_the_wreck_mission_needs_no_prior_and_refuses_a_plan(tmp_path):
    path = example.write_wreck_mission(tmp_path, seed=3)
    spec = load_mission(path)
    assert spec.site.prior is None and spec.seed == 3
    assert [s.KIND for s in spec.steps] == ["explore"]
    raw = yaml.safe_load(path.read_text())
    raw["steps"].insert(0, {"plan": {"omega": 3.0}})
    path.write_text(yaml.safe_dump(raw))
    with pytest.raises(MissionFileError, match=r"steps\[0\].plan: needs a prior map"):
        load_mission(path)


@pytest.mark.slow
def test_explore_covers_the_wreck_without_contact(tmp_path):
    """The acceptance: >= 80 % multibeam coverage of the wreck, no contact (the mission file
    on the site's files, realistic sonars, drift)."""
    from drake_auv.mission.report.summary import summarise
    from drake_auv.mission.runner import run_mission

    path = example.write_wreck_mission(tmp_path / "site", seed=0)
    report = summarise(run_mission(load_mission(path), progress=False))
    assert report["coverage"]["multibeam"] >= 0.8, report["coverage"]
    assert not report["contact"] and report["min_clearance_m"] > 1.0
