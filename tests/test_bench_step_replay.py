"""benchmarks/bench_step_replay.py's harness on a short Replanner run (no dive): the steps it
records replay to the same trajectories, its wrappers come off, bad windows get one line."""

import sys
from pathlib import Path

import numpy as np
import pytest
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_step_replay as bench  # noqa: E402
import drake_auv.replanning.replanner as replanner_module  # noqa: E402
from drake_auv.mapping.mapper import OnlineMap  # noqa: E402
from drake_auv.mapping.scan_log import ScanBatch, ScanLog  # noqa: E402
from drake_auv.planning.path import PlannedPath  # noqa: E402
from drake_auv.replanning import section as section_module  # noqa: E402
from drake_auv.replanning.replanner import Replanner  # noqa: E402


def _wall_map() -> OnlineMap:
    """The wall x = 8 m seen by five horizontal fans from (0, 0, -5) (each voxel hit 5x); the
    waypoints run 3 m from it, inside the 4 m clearance, so STOMP moves them."""
    a = np.linspace(-0.8, 0.8, 81)
    d = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
    log = ScanLog()
    for k in range(5):
        log = log.append(ScanBatch.make(0.1 * k, "multibeam", np.array([0.0, 0.0, -5.0]), d,
                                        8.0 / d[:, 0], 20.0))
    online = OnlineMap(0.5)
    online.catch_up(log)
    return online


def _record(windows):
    waypoints = np.stack([np.full(12, 5.0), np.arange(12.0), np.full(12, -5.0)], axis=1)
    replanner = Replanner(speed=0.5, period=1.0)
    context = replanner.CreateDefaultContext()
    state = np.zeros(12)
    state[:3] = 5.0, -1.0, -5.0
    replanner.state_input.FixValue(context, state)
    replanner.map_input.FixValue(context, AbstractValue.Make(_wall_map()))
    replanner.nominal_input.FixValue(context, AbstractValue.Make(
        PlannedPath(waypoints, 0.0, (1.0, 0.0, 0.0))))
    simulator = Simulator(replanner, context)
    with bench.StepRecorder(windows) as recorder:
        simulator.set_monitor(lambda c: recorder.probe(c) or EventStatus.Succeeded())
        simulator.AdvanceTo(3.5)
    return recorder.steps


def test_recorded_steps_replay_to_the_same_trajectories():
    steps = _record([(1.0, 3.0)])
    assert [s["time"] for s in steps] == [1.0, 2.0]  # the window's steps only
    for step in steps:
        assert len(step["box"].voxels) > 0 and step["query"] > 0
        plan, wall, stomp_s = bench.replay(step, repeats=2)
        assert np.array_equal(plan.trajectory, step["trajectory"])
        assert 0 < stomp_s < wall
        # The recorded box is what the step read: without it the plan differs.
        step["box"] = bench.RecordedBox(np.zeros((0, 3)), np.zeros(0), 0.5)
        assert not np.array_equal(bench.replay(step)[0].trajectory, step["trajectory"])


def test_wrappers_come_off_and_budgets_apply():
    original = replanner_module.replan_section, section_module.stomp
    step = _record([(0.0, 1.0)])[0]
    assert (replanner_module.replan_section, section_module.stomp) == original
    capped = bench.with_budget(step["params"], dict(max_iterations=1))
    assert capped.stomp.max_iterations == 1 and capped.omega == step["params"].omega
    assert bench.replay(step, capped)[0].iterations == 1


@pytest.mark.parametrize("text, until", [("5:1", np.inf), ("abc", np.inf), ("1:2:3", np.inf),
                                         ("-1:4", np.inf), ("", np.inf), ("300:700", 500.0)])
def test_bad_windows_get_one_line(text, until):
    with pytest.raises(SystemExit, match="--windows: give START:END pairs"):
        bench.parse_windows(text, until)


def test_saved_steps_load_and_replay_to_the_same_trajectories(tmp_path):
    steps = _record([(1.0, 3.0)])
    path = tmp_path / "steps.pkl"
    bench.save_steps(steps, bench.open_save(path))
    loaded = bench.load_steps(path)
    assert [s["time"] for s in loaded] == [s["time"] for s in steps]
    for step in loaded:
        assert np.array_equal(bench.replay(step)[0].trajectory, step["trajectory"])


def test_bad_recordings_and_outputs_get_one_line(tmp_path):
    with pytest.raises(SystemExit, match="--load: cannot read"):
        bench.load_steps(tmp_path / "missing.pkl")
    corrupt = tmp_path / "corrupt.pkl"
    corrupt.write_bytes(b"not a pickle")
    with pytest.raises(SystemExit, match="is not a recording"):
        bench.load_steps(corrupt)
    foreign = tmp_path / "foreign.pkl"
    bench.save_steps([1, 2], bench.open_save(foreign))
    with pytest.raises(SystemExit, match="is not a recording"):
        bench.load_steps(foreign)
    with pytest.raises(SystemExit, match="--save: cannot write"):
        bench.open_save(tmp_path / "no" / "such" / "dir" / "steps.pkl")


def test_main_replays_a_saved_recording_without_flying(tmp_path, capsys, monkeypatch):
    path = tmp_path / "steps.pkl"
    bench.save_steps(_record([(1.0, 3.0)]), bench.open_save(path))
    monkeypatch.setattr(bench, "reference_factor", lambda: 500.0)  # the vehicle's 3 runs
    monkeypatch.setattr(bench, "run_mission", None)  # flying would fail
    assert bench.main(["--load", str(path), "--windows", "1:3", "--repeats", "1"]) == 0
    out = capsys.readouterr().out
    assert "2 steps loaded" in out and "identical to the dive's: 2 of 2" in out
