"""`LogSpool`: the mission's logs moved to disk as the dive runs give back the same samples,
and a log never holds more than one period of them."""

import numpy as np
import pytest
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import DiagramBuilder, EventStatus
from pydrake.systems.primitives import LogVectorOutput, Sine

from drake_auv.mission import runner
from drake_auv.mission.config import load_mission
from drake_auv.mission.log_spool import LogSpool
from drake_auv.signals import ReplanningStep


def _flown(period_s):
    """A 3-vector sine logged at 10 Hz and 2 Hz for 30 s, spooled every `period_s` (None: not
    spooled); the spool's reads and the most samples a log held at a step."""
    builder = DiagramBuilder()
    sine = builder.AddNamedSystem("sine", Sine([1.0, 2.0, 3.0], [0.5, 1.0, 2.0], [0, 1, 2]))
    sinks = {"fast": LogVectorOutput(sine.get_output_port(0), builder, 0.1),
             "slow": LogVectorOutput(sine.get_output_port(0), builder, 0.5)}
    simulator = Simulator(builder.Build())
    spool = LogSpool(sinks, period_s) if period_s is not None else None
    held = []

    def monitor(root_context):
        if spool is not None:
            spool.spool(root_context)
        held.append(sinks["fast"].FindLog(root_context).num_samples())
        return EventStatus.Succeeded()

    simulator.set_monitor(monitor)
    simulator.AdvanceTo(30.0)
    context = simulator.get_context()
    if spool is None:
        logs = {name: sink.FindLog(context) for name, sink in sinks.items()}
        return {n: (log.sample_times(), log.data()) for n, log in logs.items()}, max(held)
    reads = {name: spool.read(name, context) for name in sinks}
    spool.close()
    return {n: (log.sample_times(), log.data()) for n, log in reads.items()}, max(held)


def test_spooled_logs_read_back_every_sample_and_hold_one_period():
    whole, held_whole = _flown(None)
    spooled, held = _flown(2.0)
    for name in whole:
        assert np.array_equal(spooled[name][0], whole[name][0])
        assert np.array_equal(spooled[name][1], whole[name][1])
    assert whole["fast"][1].shape == (3, 301) and held_whole == 301
    assert held <= 22  # two seconds of 10 Hz samples (and the step's own), not 30 s


def test_a_mission_spooled_every_few_seconds_reports_the_same_dive(monkeypatch):
    spec = load_mission("breakwater", overrides=["limits.max_time_s=25"])
    whole = runner.run_mission(spec, progress=False)
    monkeypatch.setattr(runner, "LOG_SPOOL_S", 3.0)
    spooled = runner.run_mission(spec, progress=False)
    for field in ("times", "state", "estimated", "reference", "profile"):
        assert np.array_equal(getattr(spooled.log, field), getattr(whole.log, field),
                              equal_nan=True), field
    same = [f for f in ReplanningStep.get_fields() if not f.endswith("time") or f == "time"]
    mine, theirs = (ReplanningStep(r.mapping.replanning) for r in (spooled, whole))
    assert len(spooled.mapping.replanning) > 3 and all(
        np.array_equal(getattr(mine, f), getattr(theirs, f)) for f in same)
    assert [p.name for p in spooled.dive.phases] == [p.name for p in whole.dive.phases]
    context = spooled.run.context
    assert spooled.run.handles.logs["state"].FindLog(context).num_samples() <= 32


@pytest.mark.parametrize("period", [0.0, -1.0, np.inf, np.nan])
def test_a_bad_spool_period_gets_one_line(period):
    with pytest.raises(ValueError, match="spool's period must be a finite time > 0 s"):
        LogSpool({}, period)
