"""benchmarks/bench_long_mission.py's memory split (`--trace-python`), without a dive: what a
probe's two snapshots say about memory allocated between them, and bad spans get one line."""

import sys
import tracemalloc
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import bench_long_mission as bench  # noqa: E402


class _Context:
    def __init__(self, t):
        self.t = t

    def get_time(self):
        return self.t


def test_traced_finds_what_python_allocated_between_the_snapshots():
    tracemalloc.start()
    try:
        probe = bench.Probe(trace=(10.0, 20.0))
        probe(_Context(5.0))
        assert probe.snapshots == []  # before A: nothing taken
        probe(_Context(10.0))
        line = sys._getframe().f_lineno + 1
        held = [bytearray(1 << 20) for _ in range(8)]  # 8 MB
        probe(_Context(20.0))
        probe(_Context(30.0))
        assert len(probe.snapshots) == 2 and probe.snapshots[0][1] is None  # the first dumped
        memory = bench.traced(probe)
    finally:
        tracemalloc.stop()
        Path(probe.dump_path).unlink()
    assert (memory["from_s"], memory["to_s"]) == (10.0, 20.0)
    assert 7.5 < memory["python_mb"] < 9.0
    assert memory["lines"][0]["where"] == f"{Path(__file__).name}:{line}"
    assert memory["lines"][0]["mb"] == pytest.approx(8.0, abs=0.1)
    assert memory["rest_mb"] == pytest.approx(memory["rss_mb"] - memory["octree_mb"]
                                              - memory["python_mb"]
                                              - memory["tracemalloc_mb"])
    del held


@pytest.mark.parametrize("text, until", [("5:1", None), ("abc", None), ("1:2:3", None),
                                         ("-1:4", None), ("100:900", 600.0)])
def test_bad_spans_get_one_line(text, until):
    with pytest.raises(SystemExit, match="--trace-python: give A:B simulated seconds"):
        bench.parse_trace(text, until)


def test_a_span_within_the_dive_is_kept():
    assert bench.parse_trace("3600:7200", 7250.0) == (3600.0, 7200.0)
