"""benchmarks/bench_exploration.py's acceptance checks, on hand-made dive rows (no dive)."""

import importlib.util
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
spec = importlib.util.spec_from_file_location("bench_exploration",
                                              ROOT / "benchmarks" / "bench_exploration.py")
bench = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bench)

PLAN = "plan + survey (boulder)"


def row(seed, t80, t90, multibeam, contact=False, clearance=2.5):
    return dict(seed=seed, t80=t80, t90=t90, multibeam=multibeam, contact=contact,
                clearance=clearance)


def groups(**change):
    g = {"gain": [row(s, 300.0, 600.0, 0.93) for s in range(3)],
         "nearest": [row(s, 400.0, None, 0.85) for s in range(3)],
         PLAN: [row(s, 200.0, 500.0, 0.98) for s in range(3)],
         bench.WRECK: [row(0, 250.0, None, 0.84)]}
    g.update(change)
    return g


def verdicts(g):
    return {what.split(" (")[0]: ok for what, ok, _ in bench.checks(g, PLAN)}


def test_every_check_passes_on_good_rows():
    assert all(verdicts(groups()).values()) and len(verdicts(groups())) == 5


def test_each_check_fails_on_its_own_fault():
    gain = groups()["gain"]
    cases = {
        "no contact in any seed": [dict(r, contact=r["seed"] == 1) for r in gain],
        ">= 90 % multibeam coverage in every seed": [dict(r, multibeam=0.89 if r["seed"] == 2
                                                          else 0.95) for r in gain],
        "median time to 90 % within 1.5x of plan + survey": [dict(r, t90=800.0) for r in gain],
        "gain reaches 80 % sooner than nearest": [dict(r, t80=450.0) for r in gain],
    }
    for check, rows in cases.items():
        v = verdicts(groups(gain=rows))
        assert not v[check] and sum(not ok for ok in v.values()) == 1, (check, v)
    wreck = verdicts(groups(**{bench.WRECK: [row(0, None, None, 0.79)]}))
    assert not wreck["a site given as files, no prior"]


def test_a_seed_that_never_reached_counts_as_infinitely_late():
    late = [row(0, 300.0, None, 0.95), row(1, 300.0, None, 0.95), row(2, 300.0, 600.0, 0.95)]
    assert bench.median_time(late, "t90") == np.inf
    assert not verdicts(groups(gain=late))["median time to 90 % within 1.5x of plan + survey"]
