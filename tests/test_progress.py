"""The run's one progress display: its phases in order, each ending at 100 % when its work
ends; the dive's share is the mission's own (the legs flown), not its time budget."""

import io
import re
import sys

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator, SimulatorStatus

from drake_auv.cli import main
from drake_auv.mission.config import mission_from_dict
from drake_auv.mission.diagram import build_mission_diagram
from drake_auv.mission.legs import Leg, leg_share, start_progress
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.runner import dive_share
from drake_auv.mission.site import load_site
from drake_auv.progress import RUN_PHASES, RunProgress

LINE = re.compile(r"^\[(\d)/(\d)\] (\w+) +(\d+) %")


def shown(text: str) -> list[tuple[str, int]]:
    """(phase, percent) of each line of a log's display."""
    return [(m[3], int(m[4])) for m in map(LINE.match, text.splitlines()) if m]


def test_a_log_shows_each_phase_in_order_monotone_and_ending_at_100():
    stream = io.StringIO()
    display = RunProgress(RUN_PHASES, stream=stream, tty=False)
    display.start("setup", total=2, note="site")
    with display.step("site"):
        pass
    with display.step("plan"):
        pass
    assert display.share < 1.0  # held below 100 % until the phase ends
    display.start("dive")
    for done in np.linspace(0.0, 1.0, 101):
        display.update(done)
    display.update(0.2)  # an estimate that falls back is held
    assert display.share == pytest.approx(0.999)
    display.start("results")
    display.update(0.5)
    display.start("outputs", total=3)
    for name in ("points.ply", "figures", "report"):
        with display.step(name):
            pass
    display.close()
    lines = shown(stream.getvalue())
    assert [p for p, _ in lines] == sorted((p for p, _ in lines), key=RUN_PHASES.index)
    for phase in RUN_PHASES:
        percents = [v for p, v in lines if p == phase]
        assert percents == sorted(percents) and percents[0] == 0 and percents[-1] == 100
        assert percents.count(100) == 1
    dive = [v for p, v in lines if p == "dive"]
    assert dive == list(range(0, 100, 10)) + [100]  # sparse: every 10 %, not every update
    assert lines[-1] == ("outputs", 100)
    assert "plan" in stream.getvalue().splitlines()[1]  # a step's line names it


def test_a_terminal_gets_one_line_redrawn_in_place_and_quiet_gets_nothing():
    stream = io.StringIO()
    display = RunProgress(("setup", "dive"), stream=stream, tty=True)
    display.start("setup", total=1)
    with display.step("site"):
        pass
    display.start("dive")
    display.update(0.5, note="t = 5 s")
    display.close()
    text = stream.getvalue()
    assert text.count("\n") == 1 and text.endswith("\n") and "\r" in text
    display = RunProgress(("dive",), stream=io.StringIO(), tty=True)
    display.start("dive", note="x" * 1000)  # a line wider than the terminal is cut
    assert len(display.stream.getvalue()) < 1000
    assert text.rsplit("\r", 1)[1].startswith("[2/2] dive 100 %")
    stopped = io.StringIO()
    with pytest.raises(KeyboardInterrupt), RunProgress(("dive",), stream=stopped,
                                                       tty=True) as display:
        display.start("dive")
        display.update(0.4)
        raise KeyboardInterrupt  # the line ends where the work stopped, not at 100 %
    assert stopped.getvalue().endswith("\n") and "100 %" not in stopped.getvalue()
    quiet = io.StringIO()
    display = RunProgress(("setup",), stream=quiet, enabled=False)
    display.start("setup")
    display.update(0.5)
    display.close()
    assert quiet.getvalue() == ""


def test_phases_run_in_their_order():
    display = RunProgress(RUN_PHASES, stream=io.StringIO())
    display.start("dive")
    with pytest.raises(ValueError, match="phase 'setup' cannot follow 'dive'"):
        display.start("setup")
    with pytest.raises(ValueError, match="unknown phase 'replay'"):
        display.start("replay")


def test_a_legs_share_is_its_goals_measure():
    x = np.zeros(12)
    loops = Leg("follow", 0, "follow", "loops", 600.0, centre=(10.0, 0.0), loops=2.0)
    record = start_progress(loops, x)
    record[1] = np.pi  # half a turn of two
    assert leg_share(loops, 30.0, x, record, None) == pytest.approx(0.25)
    ahead = Leg("follow", 0, "follow", "distance", 600.0, direction=(0.0, 1.0), distance=40.0)
    x[1] = 10.0
    assert leg_share(ahead, 30.0, x, start_progress(ahead, np.zeros(12)), None) == 0.25
    path = Leg("transit", 0, "path", "arrive", 600.0, target=(0.0, 0.0, -5.0))
    assert leg_share(path, 30.0, x, start_progress(path, x), 0.6) == 0.6  # its behaviour's
    assert leg_share(path, 30.0, x, start_progress(path, x), None) == 0.05  # of its budget
    assert leg_share(path, 900.0, x, start_progress(path, x), None) == 1.0


def test_the_dive_share_follows_the_legs_not_their_budgets(tmp_path):
    """A transit then a 15 s hover: the share is the transit's part of the budgets when the
    hover begins and half-way from there to 1 half-way through the hover, though the hover's
    budget is many times 15 s."""
    spec = mission_from_dict({"name": "hover", "site": {"scenario": "pool"}, "steps": [
        {"hover": {"at": [-2.0, 1.0, -3.0], "duration_s": 15.0}}]}, tmp_path, "hover.yaml")
    site = load_site(spec.site, spec.seed)
    plan = plan_mission(spec, site)
    assert plan.legs[1].max_duration > 4 * 15.0
    diagram, handles = build_mission_diagram(site, spec, plan)
    simulator = Simulator(diagram)
    context = simulator.get_context()
    supervisor = handles.supervisor
    simulator.set_monitor(supervisor.monitor)
    shares, legs = [], []
    ended = SimulatorStatus.ReturnReason.kReachedTerminationCondition
    while simulator.AdvanceTo(context.get_time() + 0.5).reason() != ended:
        shares.append(dive_share(handles, context, plan.budget))
        legs.append(handles.supervisor.flying(supervisor.GetMyContextFromRoot(context)))
    assert dive_share(handles, context, plan.budget) == 1.0
    shares = np.array(shares)
    hover = np.array([leg is plan.legs[1] for leg in legs])
    assert np.all(np.diff(shares) >= -0.02), shares  # grows (a transit's end may settle)
    transit, hover_budget = (leg.max_duration for leg in plan.legs)
    begun = transit / (transit + hover_budget)  # the legs weigh their budgets
    assert shares[hover][0] == pytest.approx(begun, abs=0.03)
    assert shares[hover][len(shares[hover]) // 2] == pytest.approx((1 + begun) / 2, abs=0.05)
    assert shares[-1] > 0.95


def test_a_run_shows_its_phases_and_its_report_names_only_files_it_wrote(tmp_path, capsys):
    """A capped exploration (no off-line plan, so no plan.png): the log's display goes
    setup, dive, results, outputs, each ending at 100 %; every file report.md names exists."""
    out = tmp_path / "explore"
    assert main(["run", "boulder_explore", "-o", str(out), "--no-html",
                 "--set", "limits.max_time_s=20"]) == 0
    err = capsys.readouterr().err
    lines = shown(err)
    phases = [p for p, _ in lines]
    assert sorted(set(phases), key=phases.index) == list(RUN_PHASES)
    assert phases == sorted(phases, key=RUN_PHASES.index)
    for phase in RUN_PHASES:
        percents = [v for p, v in lines if p == phase]
        assert percents == sorted(percents) and percents[-1] == 100
    assert lines[-1] == ("outputs", 100) and err.rstrip().splitlines()[-1].startswith(
        "[4/4] outputs 100 %")
    text = (out / "report.md").read_text()
    named = set(re.findall(r"`([\w.-]+\.(?:png|ply|csv|dot|html|json|md|mcap|bt))`", text))
    assert {"coverage.png", "trajectory.csv", "points.ply"} <= named
    assert "plan.png" not in named and not (out / "plan.png").exists()
    assert all((out / name).stat().st_size > 0 for name in named), sorted(named)
    assert "n/a" not in text and "- Exploration (next views by gain): " in text


def test_a_phase_display_joins_its_callers_or_owns_one():
    from drake_auv.progress import phase_display

    caller = RunProgress(("plan", "outputs"), enabled=False)
    with phase_display(caller, "outputs", 4, "path.csv") as display:
        assert display is caller and (caller.phase, caller.note) == ("outputs", "path.csv")
    with phase_display(caller, "figures", 7, "a.png") as display:  # counted in "outputs"
        assert display is caller and caller.phase == "outputs" and caller.note == "a.png"
    assert caller.phase == "outputs" and caller.share < 1.0  # the caller's stays open
    with phase_display(False, "figures", 7) as own:
        assert own is not caller and own.phases == ("figures",) and own.phase == "figures"
        assert not own.enabled and own.share < 1.0
    assert own.share == 1.0  # its own ends with the work


def test_a_warning_clears_the_terminal_line_and_the_display_comes_back():
    from drake_auv.progress import print_line

    stream = io.StringIO()
    display = RunProgress(("dive",), stream=stream, tty=True)
    display.start("dive", 10.0)
    print_line("drake-auv run: warning: something", stream)
    display.update(6.0)
    display.close()
    text = stream.getvalue()
    before, after = text.split("drake-auv run: warning: something\n")
    assert before == "\r[1/1] dive   0 %" + "\r" + " " * len("[1/1] dive   0 %") + "\r"
    assert after.startswith("\r[1/1] dive  60 %")
    print_line("after the run", stream)  # no display: the line alone
    assert stream.getvalue().endswith("\nafter the run\n")


def test_a_tracked_loop_counts_its_items_and_ends_at_100_only_when_done(capsys):
    from drake_auv.progress import track

    assert list(track(range(4), "seeds")) == [0, 1, 2, 3]
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "[1/1] seeds   0 % 4 in all" and lines[-1].startswith("[1/1] seeds 100 %")
    for item in track(range(4), "seeds"):
        if item == 2:
            break
    assert "100 %" not in capsys.readouterr().err


class _Terminal(io.StringIO):
    """Standard error on a terminal."""

    def isatty(self):
        return True


def _fails(*args, **kwargs):
    raise RuntimeError("a stage failed midway")


def test_a_call_that_fails_ends_its_own_displays_line_and_leaves_a_callers(monkeypatch,
                                                                          tmp_path):
    """`plan_coverage`, `write_outputs` and `write_figures`, a stage of which fails: given
    `progress=True`, the terminal's line ends where the work stopped; given a caller's display,
    it stays the caller's to end."""
    from drake_auv.formats import outputs
    from drake_auv.planning import coverage_plan, figures
    from drake_auv.planning.parameters import CoverageParameters
    from drake_auv.progress import _SHOWN, PLAN_PHASES
    from drake_auv.terrain.bathymetry import Bathymetry

    bathy = Bathymetry(np.full((41, 31), -30.0), (0.5, 0.5))
    params = CoverageParameters(omega=2.0)
    plan = coverage_plan.plan_coverage(bathy, params)
    monkeypatch.setattr(coverage_plan, "decompose", _fails)
    monkeypatch.setattr(outputs, "report_dict", _fails)
    monkeypatch.setitem(figures.PLAN_VIEWS, "lanes.png", _fails)
    calls = {
        "plan": lambda progress: coverage_plan.plan_coverage(bathy, params, progress=progress),
        "outputs": lambda progress: outputs.write_outputs(plan, tmp_path, figures=False,
                                                          metrics_3d=False, progress=progress),
        "figures": lambda progress: figures.write_figures(plan, tmp_path, progress=progress)}
    for phase, call in calls.items():
        terminal = _Terminal()
        monkeypatch.setattr(sys, "stderr", terminal)
        with pytest.raises(RuntimeError, match="failed midway"):
            call(True)
        text = terminal.getvalue()
        assert text.startswith(f"\r[1/1] {phase}") and text.endswith("\n"), (phase, text)
        assert "100 %" not in text and terminal not in _SHOWN
        caller = RunProgress(PLAN_PHASES, stream=terminal, tty=True)
        caller.start("plan")
        with pytest.raises(RuntimeError, match="failed midway"):
            call(caller)
        assert caller.phase is not None and _SHOWN[terminal] is caller, phase
        assert not terminal.getvalue().endswith("\n"), phase
        caller.close(completed=False)
