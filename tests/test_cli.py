"""The command line's shared vocabulary: `--version` and `-o/--out` on every command."""

import json
import logging
import re

import pytest

import drake_auv
from drake_auv.cli import COMMANDS, build_parser


def test_version_prints_the_package_version(capsys):
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"drake-auv {drake_auv.__version__}"


def test_installed_and_cited_versions_are_the_package_version():
    from importlib.metadata import version
    from pathlib import Path

    assert version("drake_auv") == drake_auv.__version__  # pyproject reads it (dynamic)
    citation = (Path(__file__).resolve().parents[1] / "CITATION.cff").read_text()
    assert re.search(r"^version: (\S+)$", citation, re.M)[1] == drake_auv.__version__


@pytest.mark.parametrize("command", [c for c in COMMANDS if c != "scenarios"])
def test_every_command_writing_files_takes_o_and_out(command):
    subparser = build_parser()._subparsers._group_actions[0].choices[command]
    flags = {flag for action in subparser._actions for flag in action.option_strings
             if action.dest == "out"}
    assert {"-o", "--out"} <= flags, (command, flags)


@pytest.mark.parametrize("argv, match", [
    (["--realtime", "2"], "--realtime paces or serves the live view; allowed: with --meshcat"),
    (["--meshcat-port", "7010"], "--meshcat-port paces or serves the live view"),
    (["--meshcat", "--meshcat-port", "99999"], r"--meshcat-port must be in \[1024, 65535\]"),
    (["--meshcat", "--realtime", "-1"], "--realtime must be >= 0"),
])
def test_live_view_options_are_refused_before_any_work(tmp_path, capsys, argv, match):
    from drake_auv.cli import main

    assert main(["run", "boulder", "-o", str(tmp_path / "out"), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and re.search(match, err), err
    assert not (tmp_path / "out" / "report.json").exists()


def test_a_headless_scene_announces_no_url(caplog):
    from drake_auv.visualization import Scene

    with caplog.at_level(logging.INFO, logger="drake"):
        Scene(live=False)
    assert "Meshcat listening" not in caplog.text
    with caplog.at_level(logging.INFO, logger="drake"):
        live = Scene(live=True)
    assert live.meshcat.web_url().startswith("http://localhost:")


def test_no_reconstruction_skips_the_surface_but_keeps_the_points(tmp_path):
    from drake_auv.cli import main

    out = tmp_path / "out"
    assert main(["run", "boulder", "-o", str(out), "--no-reconstruction", "--no-html", "--quiet",
                 "--set", "limits.max_time_s=15", "--set", "ocean=none"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["config"]["outputs"]["reconstruction"] is False
    assert report["reconstruction"] == {"built": False, "reason": "switched off "
                                        "(outputs.reconstruction: false, --no-reconstruction)"}
    assert (out / "points.ply").stat().st_size > 0
    assert not (out / "reconstruction.ply").exists()
