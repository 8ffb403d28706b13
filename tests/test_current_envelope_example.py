"""examples/current_envelope.py on a tiny grid: both modes' envelopes run (replanning on and
off), the side-by-side PNG, the combined CSV (one row per mode and run) and both verdicts."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "current_envelope.py"
spec = importlib.util.spec_from_file_location("current_envelope", EXAMPLE)
example = importlib.util.module_from_spec(spec)
spec.loader.exec_module(example)


def test_the_example_draws_both_envelopes(tmp_path, capsys):
    out = tmp_path / "out"
    assert example.main(["--speeds", "0.3:0.3:0.1", "--directions", "1", "--seeds", "0:1",
                         "--set", "limits.max_time_s=5", "--workers", "1",
                         "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "breakwater_current (replanning): " in printed
    assert "breakwater_current (nominal): " in printed
    with open(out / "current_envelope.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["mode"], r["speed_mps"], r["towards_deg"], r["seed"]) for r in rows) == [
        ("nominal", "0.3", "0", "0"), ("replanning", "0.3", "0", "0")]
    assert all(r["status"] == "ok" for r in rows)
    for mode, flag in (("replanning", True), ("nominal", False)):
        campaign = (out / mode / "campaign.json").read_text()
        assert f"steps.1.survey.replanning={str(flag).lower()}" in campaign
    assert (out / "current_envelope.png").read_bytes()[:4] == b"\x89PNG"
    text = (out / "current_envelope.md").read_text()
    assert "Replanning's envelope is" in text and "(nominal): " in text
