"""`drake-auv lawnmower` and `drake-auv simulate` write their recordings, plots and logs."""

import argparse
import base64
import re

import numpy as np
import pytest

from drake_auv.commands import lawnmower, simulate
from drake_auv.planning import PlannedPath
from drake_auv.vehicle.flight import fly_path


def parse(module, argv):
    parser = argparse.ArgumentParser()
    module.add_parser(parser.add_subparsers())
    return parser.parse_args(argv)


def test_lawnmower_writes_recording_and_error_plot(tmp_path, capsys):
    out = tmp_path / "lawnmower"
    args = parse(lawnmower, ["lawnmower", "--out", str(out), "--extent", "20", "8", "--quiet"])
    assert args.func(args) == 0
    html = (out / "mission.html").read_text()
    commands = [base64.b64decode(b64) for b64 in
                re.findall(r'data:application/octet-binary;base64,([A-Za-z0-9+/=]+)"', html)]
    animation = [c for c in commands if b"set_animation" in c]
    assert len(animation) == 1 and b"/drake_auv/vehicle" in animation[0]
    assert (out / "tracking_error.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    path = PlannedPath.from_csv(out / "path.csv")
    state = np.loadtxt(out / "state.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(state[-1, 1:4], path.points[-1], atol=0.05)
    text = capsys.readouterr().out
    rms = float(text.split("cross-track RMS ")[1].split(" m")[0])
    assert 0.0 < rms < 0.3


def test_simulate_flies_a_path_csv(tmp_path):
    path = PlannedPath(np.array([[0.0, 0, -5], [15, 0, -5], [15, 5, -5]]), [0.0, 0.0, np.pi / 2],
                (1.0, 0.0, 0.0), "slice")
    path.to_csv(tmp_path / "p.csv")
    args = parse(simulate, ["simulate", str(tmp_path / "p.csv"), "--out", str(tmp_path / "s"),
                            "--no-html", "--quiet", "--speed", "0.8"])
    assert args.func(args) == 0
    assert (tmp_path / "s" / "tracking_error.png").is_file()
    assert not (tmp_path / "s" / "mission.html").exists()
    state = np.loadtxt(tmp_path / "s" / "state.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(state[-1, 1:4], path.points[-1], atol=0.05)
    assert state[-1, 6] == pytest.approx(np.pi / 2, abs=0.02)


def test_bad_inputs_are_named(tmp_path):
    path = PlannedPath(np.array([[0.0, 0, -5], [5, 0, -5]]), 0.0, (0.0, 0.0, -1.0))
    with pytest.raises(ValueError, match="speed"):
        fly_path(path, tmp_path, speed=3.0, progress=False)
    with pytest.raises(FileNotFoundError):
        args = parse(simulate, ["simulate", str(tmp_path / "missing.csv"), "--no-html"])
        args.func(args)
    with pytest.raises(ValueError, match="extent"):
        args = parse(lawnmower, ["lawnmower", "--out", str(tmp_path), "--extent", "1", "8", "--no-html"])
        args.func(args)
    with pytest.raises(ValueError, match=r"--altitude -1 is out of range; allowed: \[0.5, 100\] m"):
        args = parse(lawnmower, ["lawnmower", "--out", str(tmp_path), "--altitude", "-1", "--no-html"])
        args.func(args)


def test_first_turn_index_finds_the_end_of_the_first_lane():
    points = [(x, 0.0, -5.0) for x in range(11)] + [(10.0, 2.0, -5.0), (9.0, 2.0, -5.0)]
    path = PlannedPath(np.array(points), 0.0, (0.0, 0.0, -1.0))
    assert lawnmower.first_turn_index(path) == 10
    straight = PlannedPath(np.array([(0.0, 0, 0), (1.0, 0.1, 0), (2.0, 0, 0)]), 0.0, (0.0, 0.0, -1.0))
    assert lawnmower.first_turn_index(straight) == 2


def test_realtime_rate_validated(tmp_path):
    path = PlannedPath(np.array([[0.0, 0, -5], [5, 0, -5]]), 0.0, (0.0, 0.0, -1.0))
    with pytest.raises(ValueError, match="realtime_rate"):
        fly_path(path, tmp_path, realtime_rate=-1.0, progress=False)
