"""The operating envelope: the grid (speeds, directions, speed 0 once per seed), the verdict
from a hand-made table, and the command on a short breakwater dive: envelope.csv's columns
and rows (each run once after a rerun), the PNG and the verdict; bad input refused in one
line before anything is written."""

from __future__ import annotations

import csv
import json

import pytest

from drake_auv.campaign.envelope import (COLUMNS, envelope_runs, envelope_verdict,
                                         parse_directions, parse_speeds, verdict_line)
from drake_auv.cli import main
from drake_auv.mission.config import MissionFileError

SHORT = ["limits.max_time_s=5"]
REQUIRED = ["speed_mps", "towards_deg", "seed", "contact", "min_clearance_m",
            "coverage_multibeam"]


def test_speeds_and_directions_parse_and_reject():
    assert parse_speeds("0:0.6:0.1") == ["0", "0.1", "0.2", "0.3", "0.4", "0.5", "0.6"]
    assert parse_speeds("0.25:1:0.5") == ["0.25", "0.75"]
    assert parse_speeds("0.3:0.3:0.1") == ["0.3"]
    assert parse_directions(8) == ["0", "45", "90", "135", "180", "225", "270", "315"]
    assert parse_directions(7)[1] == "51.4286" and parse_directions(1) == ["0"]
    for bad, what in (("0:0.6", "is not A:B:STEP"), ("a:1:0.1", "is not A:B:STEP"),
                      ("0:6:1", "out of range"), ("-0.1:0.5:0.1", "out of range"),
                      ("0.5:0.1:0.1", "out of range"), ("0:1:0", "out of range"),
                      ("0:1:-0.1", "out of range"), ("0:nan:0.1", "out of range"),
                      ("0:5:0.01", "gives 501 speeds")):
        with pytest.raises(ValueError, match=f"--speeds: .*{what}"):
            parse_speeds(bad)
    for bad in (0, -3, 361):
        with pytest.raises(ValueError, match=rf"--directions: {bad} is out of range; allowed"):
            parse_directions(bad)


def test_runs_speed_zero_once_per_seed_and_keep_the_missions_sea():
    runs = envelope_runs("breakwater", ["0", "0.3"], ["0", "90", "180"], [0, 1],
                         [*SHORT, "ocean.waves.hs_m=1"])
    assert len(runs) == 2 * (1 + 3) and len({r.key for r in runs}) == len(runs)
    assert sorted(r.key for r in runs if r.values[0][1] == "0") == [("0", "0", "0"),
                                                                    ("1", "0", "0")]
    run = next(r for r in runs if r.key == ("1", "0.3", "90"))
    assert run.mission["seed"] == 1
    assert run.mission["ocean"]["current"] == {"speed_mps": 0.3, "towards_deg": 90.0}
    assert run.mission["ocean"]["waves"]["hs_m"] == 1.0  # the rest of the sea is kept
    with pytest.raises(ValueError, match="--set ocean.current.speed_mps=1: the mean current "
                                         "is the envelope's grid"):
        envelope_runs("breakwater", ["0"], ["0"], [0], ["ocean.current.speed_mps=1"])
    # A mean current plus the tides' amplitudes beyond 5 m/s: refused, naming the speed.
    with pytest.raises(MissionFileError, match=r"\(current 4.5 m/s towards 0 deg\): "
                                               r"ocean.tides: the mean current and the "
                                               r"tides' amplitudes reach 5.5"):
        envelope_runs("breakwater", ["4.5"], ["0"], [0],
                      ["ocean.tides=[{name: M2, amplitude_mps: 1.0}]"])


def _row(speed, towards, seed, contact=False, status="ok", clearance=3.0, coverage=0.8):
    return dict(speed_mps=str(speed), towards_deg=str(towards), seed=str(seed), status=status,
                contact=str(contact) if status == "ok" else "",
                min_clearance_m=str(clearance) if status == "ok" else "",
                coverage_multibeam=str(coverage) if status == "ok" else "")


def test_verdict_of_a_hand_made_table():
    rows = [_row(0, 0, s) for s in (0, 1)]
    for towards in (0, 90, 180, 270):
        for speed in (0.2, 0.4, 0.6):
            for seed in (0, 1):
                rows.append(_row(speed, towards, seed, clearance=2.5 - speed))
    # towards 0: seed 1 touches at 0.4; 0.6 clear again (the climb stopped at 0.4 anyway)
    rows = [r for r in rows if (r["speed_mps"], r["towards_deg"], r["seed"]) != ("0.4", "0", "1")]
    rows.append(_row(0.4, 0, 1, contact=True, clearance=0.4))
    # towards 90: a failed run at 0.6 stops the climb at 0.4
    rows = [r for r in rows if (r["speed_mps"], r["towards_deg"], r["seed"]) != ("0.6", "90", "0")]
    rows.append(_row(0.6, 90, 0, status="failed"))
    # towards 270: the 0.2 cell is missing
    rows = [r for r in rows if (r["speed_mps"], r["towards_deg"]) != ("0.2", "270")]
    verdict = envelope_verdict(rows)
    per = {p["towards_deg"]: (p["safe_mps"], p["stop_mps"], p["stop"])
           for p in verdict["directions"]}
    assert per == {0.0: (0.2, 0.4, "contact"), 90.0: (0.4, 0.6, "failed"),
                   180.0: (0.6, None, None), 270.0: (0.0, 0.2, "missing")}
    assert verdict["safe_mps"] == 0.0 and verdict["worst"] == [270.0]
    assert verdict["speeds"] == [0.0, 0.2, 0.4, 0.6] and verdict["seeds"] == [0, 1]
    cell = next(c for c in verdict["cells"] if (c["speed_mps"], c["towards_deg"]) == (0.4, 0.0))
    assert cell["contact_rate"] == 0.5 and cell["least_clearance_m"] == 0.4
    assert cell["contacts"] == 1 and cell["runs"] == 2
    still = [c for c in verdict["cells"] if c["speed_mps"] == 0.0]
    assert len(still) == 4 and all(c["runs"] == 2 for c in still)  # shared by every direction
    line = verdict_line("site", verdict)
    assert line.startswith("site: no contact in 2 seed(s) up to 0 m/s from every direction; "
                           "no runs at 0.2 m/s towards 270 deg; per direction")
    assert line.endswith("0: 0.2, 90: 0.4, 180: >= 0.6, 270: 0") and "\n" not in line
    # Without the missing cell the envelope is 0.2 m/s (towards 0); still water touching: none.
    rows += [_row(0.2, 270, s) for s in (0, 1)]
    assert envelope_verdict(rows)["safe_mps"] == 0.2
    assert "from every direction; contacts begin at 0.4 m/s towards 0 deg;" in verdict_line(
        "site", envelope_verdict(rows))
    rows.append(_row(0, 0, 2, contact=True))
    verdict = envelope_verdict(rows)
    assert verdict["safe_mps"] is None
    assert verdict_line("site", verdict).startswith(
        "site: no current is safe from every direction; contacts begin at 0 m/s")


def _csv(path) -> tuple[list[str], list[dict]]:
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


def test_cli_envelope_writes_rows_plot_and_verdict_and_reruns_nothing(tmp_path, capsys):
    out = tmp_path / "env"
    argv = ["envelope", "breakwater", "--speeds", "0:0.4:0.2", "--directions", "2",
            "--seeds", "0:1", "--set", SHORT[0], "--set", "ocean=none", "--workers", "1",
            "--quiet", "-o", str(out)]
    assert main(argv) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[0].startswith("envelope breakwater: 5 runs (0 already in envelope.csv")
    verdict = printed[1]
    assert verdict.startswith("breakwater: ") and "per direction (towards deg: m/s) 0: " in verdict
    header, rows = _csv(out / "envelope.csv")
    assert header[:6] == REQUIRED and header == list(COLUMNS)
    keys = sorted((r["speed_mps"], r["towards_deg"], r["seed"]) for r in rows)
    assert keys == [("0", "0", "0"), ("0.2", "0", "0"), ("0.2", "180", "0"), ("0.4", "0", "0"),
                    ("0.4", "180", "0")]
    assert all(r["status"] == "ok" for r in rows), rows
    moving = [r for r in rows if r["speed_mps"] != "0"]
    assert all(float(r["current_mean_mps"]) == pytest.approx(float(r["speed_mps"]), abs=1e-3)
               for r in moving)  # the water met is the grid's mean current
    assert all(r["tracking_error_p95_m"] and r["thrust_saturation_share_max"] for r in rows)
    assert (out / "envelope.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert verdict in (out / "envelope.md").read_text()
    saved = json.loads((out / "envelope.json").read_text())
    assert saved["verdict"] == verdict and saved["command"]["directions"] == 2
    assert saved["speeds"] == [0.0, 0.2, 0.4] and len(saved["cells"]) == 2 + 2 * 2
    assert main(argv) == 0  # a rerun runs nothing and writes every row once
    assert "5 runs (5 already in envelope.csv" in capsys.readouterr().out
    assert len(_csv(out / "envelope.csv")[1]) == 5


@pytest.mark.parametrize("extra, message", [
    (["--speeds", "0:0.6"], "--speeds: '0:0.6' is not A:B:STEP"),
    (["--speeds", "0:6:0.5"], "--speeds: '0:6:0.5' is out of range; allowed: A:B:STEP in m/s "
                              "with 0 <= A <= B <= 5"),
    (["--speeds", "-0.2:0.4:0.2"], "--speeds: '-0.2:0.4:0.2' is out of range"),
    (["--directions", "0"], "--directions: 0 is out of range; allowed: an integer in [1, 360]"),
    (["--directions", "100000"], "--directions: 100000 is out of range"),
    (["--seeds", "3:1"], "--seeds: '3:1' is empty or negative"),
    (["--workers", "0"], "--workers 0: this machine has"),
    (["--set", "ocean.current.towards_deg=10"], "--set ocean.current.towards_deg=10: the mean "
                                                "current is the envelope's grid"),
    (["--set", "ocean.waves.hs_m=-1"], "ocean.waves.hs_m: -1.0 is out of range"),
])
def test_cli_bad_input_one_line_exit_2_nothing_written(extra, message, tmp_path, capsys):
    args = {"--speeds": "0:0.4:0.2", "--directions": "2", "--seeds": "0:1"}
    rest = []
    for flag, value in zip(extra[::2], extra[1::2]):
        if flag in args:
            args[flag] = value
        else:
            rest += [flag, value]
    out = tmp_path / "env"
    argv = ["envelope", "breakwater", *(f"{k}={v}" for k, v in args.items()), *rest,
            "-o", str(out)]  # --speeds=-0.2:... (a value starting with '-')
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err
    assert err.startswith("drake-auv envelope: error: ")
    assert not out.exists()
