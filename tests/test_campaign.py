"""Campaigns: runs and their keys, the crash-safe results file, the summary, and real Dask:
the same seed gives the same row on either worker and alone, a worker killed mid-run loses and
duplicates nothing, a rerun runs only the missing rows, bad input gives one line."""

from __future__ import annotations

import os
import signal
import sys
import threading
import time

import pytest

from drake_auv.campaign import (ResultsFile, expand_runs, parse_seeds, parse_vary,
                                run_campaign, run_task, wilson_interval)
from drake_auv.campaign.grid import split_values
from drake_auv.campaign.task import TIMING
from drake_auv.cli import main
from drake_auv.mission.config import MissionFileError

SHORT = ["limits.max_time_s=20"]


def _metrics(row: dict) -> dict:
    return {k: v for k, v in row.items() if k not in TIMING}


def test_seeds_and_vary_parse_and_reject():
    assert parse_seeds("3:6") == [3, 4, 5] and parse_seeds("7") == [7]
    for bad in ("5:5", "a:b", "-1:2", "1:2:3"):
        with pytest.raises(ValueError, match="--seeds"):
            parse_seeds(bad)
    assert parse_vary(["site.prior_error_m=0, 2.5"]) == [("site.prior_error_m", ["0", "2.5"])]
    for bad in (["site.prior_error_m"], ["site.prior_error_m=1,,2"], ["a=1", "a=2"],
                ["seed=1,2"], ["site.prior_error_m=1,1"]):
        with pytest.raises(ValueError, match="--vary"):
            parse_vary(bad)


def test_runs_cover_every_combination_and_validate():
    runs = expand_runs("breakwater", [0, 1], parse_vary(
        ["site.prior_error_m=0,5", "steps.1.survey.replanning=true,false"]), SHORT)
    assert len(runs) == 8 and len({r.key for r in runs}) == 8
    run = next(r for r in runs if r.key == ("1", "5", "false"))
    assert run.mission["seed"] == 1 and run.mission["site"]["prior_error_m"] == 5.0
    assert run.mission["steps"][1]["survey"]["replanning"] is False
    with pytest.raises(MissionFileError, match=r"\(--vary\): site.prior_eror_m: unknown key"):
        expand_runs("breakwater", [0], parse_vary(["site.prior_eror_m=1"]))
    with pytest.raises(MissionFileError, match="prior_error_m: -1.0 is out of range"):
        expand_runs("breakwater", [0], parse_vary(["site.prior_error_m=0,-1"]))


def test_vary_reaches_every_ocean_key():
    """Every key of the `ocean:` section varies: the parts' scalars, a constituent's, a whole
    flow list (its commas inside brackets), a UTC time (YAML reads it as a datetime), a
    gridded file, and the sea itself (none or a mapping)."""
    cases = {
        "ocean.current.speed_mps=0,0.4": ("current", "speed_mps", [0.0, 0.4]),
        "ocean.current.towards_deg=0,90": ("current", "towards_deg", [0.0, 90.0]),
        "ocean.profile.seabed_depth_m=10,20": ("profile", "seabed_depth_m", [10.0, 20.0]),
        "ocean.turbulence.direction_sd_deg=0,10": ("turbulence", "direction_sd_deg",
                                                   [0.0, 10.0]),
        "ocean.waves.hs_m=0.5,1": ("waves", "hs_m", [0.5, 1.0]),
        "ocean.tides.0.amplitude_mps=0.1,0.2": ("tides", 0, [0.1, 0.2]),
        "ocean.start_utc=2024-03-01T00:00:00Z,2024-03-01T06:00:00Z":
            ("start_utc", None, ["2024-03-01T00:00:00Z", "2024-03-01T06:00:00Z"]),
        "ocean.tides=[{name: M2, amplitude_mps: 0.1}],[{name: S2, amplitude_mps: 0.2}]":
            ("tides", 0, [0.1, 0.2]),
    }
    base = ["ocean.tides=[{name: M2, amplitude_mps: 0.3}]"]
    for item, (part, key, expected) in cases.items():
        runs = expand_runs("breakwater", [0], parse_vary([item]), base)
        oceans = [r.mission["ocean"] for r in runs]
        if part == "tides":
            got = [o["tides"][key]["amplitude_mps"] for o in oceans]
        else:
            got = [o[part] if key is None else o[part][key] for o in oceans]
        assert got == expected, item
    runs = expand_runs("monterey_wall", [0], parse_vary(
        ["ocean.file=monterey_wall_current.nc,null"]))
    assert runs[0].mission["ocean"]["file"].endswith("missions/monterey_wall_current.nc")
    assert "file" not in runs[1].mission["ocean"]
    runs = expand_runs("breakwater", [0], parse_vary(["ocean=none,{current: {speed_mps: 0.2}}"]))
    assert runs[0].mission.get("ocean") is None
    assert runs[1].mission["ocean"]["current"]["speed_mps"] == 0.2
    assert split_values("1, [a, {b: 2, c: 'x,y'}], \"p,q\"") == ["1", " [a, {b: 2, c: 'x,y'}]",
                                                                 ' "p,q"']


def test_wilson_interval_known_values():
    low, high = wilson_interval(0, 10)
    assert low == 0.0 and high == pytest.approx(0.2775, abs=1e-4)
    low, high = wilson_interval(5, 10)
    assert (low, high) == (pytest.approx(0.2366, abs=1e-4), pytest.approx(0.7634, abs=1e-4))
    assert wilson_interval(0, 0) == (0.0, 1.0)


def test_results_file_header_once_torn_row_dropped_other_campaign_refused(tmp_path):
    path = tmp_path / "results.csv"
    results = ResultsFile(path, ["site.prior_error_m"])
    results.append(("0", "2.5"), dict(status="ok", coverage_multibeam=0.5, contact=False))
    with open(path, "a") as f:
        f.write("1,2.5,ok,0.4")  # a crash in the middle of a row
    results = ResultsFile(path, ["site.prior_error_m"])
    assert results.done() == {("0", "2.5")}
    results.append(("1", "2.5"), dict(status="failed", error="ValueError: x"))
    text = path.read_text()
    assert text.count("seed,") == 1 and text.endswith("ValueError: x\n")
    assert [r["status"] for r in results.rows()] == ["ok", "failed"]
    with pytest.raises(ValueError, match="written by another campaign"):
        ResultsFile(path, ["replanner.R"])


def test_a_failing_run_is_a_failed_row():
    row = run_task({"name": "broken"})
    assert row["status"] == "failed"
    assert row["error"].startswith("MissionFileError: broken: site: missing (required)")
    assert "\n" not in row["error"]


@pytest.fixture(scope="module")
def client():
    from drake_auv.campaign import connect

    client, cluster = connect(workers=2)
    client.wait_for_workers(2, timeout=60)
    yield client
    client.close()
    cluster.close()


def test_same_seed_same_row_on_either_worker_and_alone(client):
    run, = expand_runs("breakwater", [3], [], ["limits.max_time_s=30"])
    alone = run_task(run.mission)
    assert alone["status"] == "ok", alone
    rows = [client.submit(run_task, run.mission, workers=[address], allow_other_workers=False,
                          pure=False).result()
            for address in client.scheduler_info()["workers"]]
    assert len(rows) == 2
    for row in rows:
        assert _metrics(row) == _metrics(alone)
    other, = expand_runs("breakwater", [4], [], ["limits.max_time_s=30"])
    assert _metrics(run_task(other.mission)) != _metrics(alone)  # the seed matters


def test_killed_worker_loses_and_duplicates_nothing_and_rerun_skips(client, tmp_path):
    runs = expand_runs("breakwater", [0, 1], parse_vary(["site.prior_error_m=0,5"]), SHORT)
    results = ResultsFile(tmp_path / "results.csv", ["site.prior_error_m"])
    first = run_campaign(runs[:1], results, client, progress=False)
    assert (first["ok"], first["skipped"]) == (1, 0)
    pids = client.run(os.getpid)
    counts = {}
    worker = threading.Thread(target=lambda: counts.update(
        run_campaign(runs, results, client, progress=False)))
    worker.start()
    killed = None
    deadline = time.monotonic() + 60
    while killed is None and time.monotonic() < deadline:
        busy = [a for a, tasks in client.processing().items() if tasks and a in pids]
        if busy:
            time.sleep(0.5)  # into the run
            killed = busy[0]
            os.kill(pids[killed], signal.SIGKILL)
        time.sleep(0.05)
    worker.join(timeout=300)
    assert killed is not None and not worker.is_alive()
    assert counts["skipped"] == 1 and counts["ok"] == 3 and counts["failed"] == 0
    rows = results.rows()
    keys = [(r["seed"], r["site.prior_error_m"]) for r in rows]
    assert sorted(keys) == sorted(r.key for r in runs) and len(set(keys)) == len(runs)
    assert all(r["status"] == "ok" for r in rows)
    again = run_campaign(runs, results, client, progress=False)
    assert (again["skipped"], again["ok"]) == (4, 0) and len(results.rows()) == 4


def test_cli_campaign_writes_results_summary_and_plots(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["campaign", "breakwater", "--seeds", "0:2", "--set", "limits.max_time_s=10",
                 "--vary", "site.prior_error_m=0,5", "--workers", "1", "--quiet",
                 "-o", str(out)])
    assert code == 0
    assert "4 runs" in capsys.readouterr().out
    for name in ("results.csv", "summary.md", "summary.json", "coverage.png", "clearance.png",
                 "variants.png", "campaign.json"):
        assert (out / name).stat().st_size > 0, name
    assert "| **all** | 4 | 0 | 0 | 0 % (0-49 %)" in (out / "summary.md").read_text()


@pytest.mark.parametrize("argv, message", [
    (["breakwater", "--seeds", "0:2", "--vary", "site.bogus=1,2"],
     "breakwater.yaml (--vary): site.bogus: unknown key"),
    (["breakwater", "--seeds", "0:2", "--vary", "site.prior_error_m=1,x"],
     "site.prior_error_m: 'x' is not a number"),
    (["no/such/mission.yaml", "--seeds", "0:2"], "mission.yaml: mission file not found"),
    (["breakwater", "--seeds", "0:2", "--scheduler", "tcp://127.0.0.1:9"],
     "cannot reach the Dask scheduler at tcp://127.0.0.1:9"),
])
def test_cli_bad_input_one_line_nonzero(argv, message, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("drake_auv.campaign.engine.CONNECT_TIMEOUT_S", 2.0)
    assert main(["campaign", *argv, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1, err


@pytest.mark.parametrize("command", [
    ["campaign", "breakwater", "--seeds", "0:2"],
    ["envelope", "breakwater", "--speeds", "0:0.2:0.1", "--directions", "2", "--seeds", "0:1"],
])
def test_without_dask_one_line_naming_the_extra_and_nothing_written(command, tmp_path, capsys,
                                                                    monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # its import raises ImportError
    out = tmp_path / "out"
    assert main([*command, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "drake_auv[campaign]" in err and len(err.splitlines()) == 1, err
    assert not out.exists()


def test_a_variant_whose_runs_all_failed_shows_dashes_not_n_a():
    from drake_auv.campaign.summary import summarise_campaign, summary_markdown

    ok = dict(status="ok", contact="False", coverage_multibeam="0.9", coverage_camera="0.5",
              min_clearance_m="2.5", real_time_factor="40", responses="")
    rows = [dict(ok, **{"site.prior_error_m": "0"}),
            dict(status="failed", error="ValueError: x", **{"site.prior_error_m": "5"})]
    text = summary_markdown(summarise_campaign(rows, ["site.prior_error_m"],
                                               dict(mission="m", seeds="0")))
    failed = next(line for line in text.splitlines() if line.startswith("| 5 |"))
    assert "n/a" not in text and failed.split(" | ")[4:] == ["-"] * 4 + ["0 (0 aborted)", "- |"]
    assert "| 90.0 [90.0-90.0] | 50.0 [50.0-50.0] | 2.50 [2.50-2.50] (2.50) |" in text
