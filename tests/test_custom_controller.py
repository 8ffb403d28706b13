"""examples/custom_controller.py: the mission Diagram built from its builders with a LeafSystem
of the user's own on the survey leg, flown (with a short time cap) against the built-in one."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from drake_auv.planning.path import PlannedPath

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "custom_controller.py"
spec = importlib.util.spec_from_file_location("custom_controller", EXAMPLE)
example = importlib.util.module_from_spec(spec)
spec.loader.exec_module(example)


def seabed(x, y):
    return -30.0 + 0.1 * np.asarray(x)  # a 0.1 slope rising to +x


def follower_at(t, leg=(3.0, 100.0)):
    path = PlannedPath(np.array([[0.0, 0.0, -20.0], [10.0, 0.0, -20.0]]), 0.0, (0.0, 1.0, 0.0))
    follower = example.ConstantAltitudeFollower(path, seabed, 5.0, 0.5, legs=(3,))
    context = follower.CreateDefaultContext()
    follower.leg_input.FixValue(context, list(leg))
    context.SetTime(t)
    return (follower.GetOutputPort("reference").Eval(context),
            follower.GetOutputPort("status").Eval(context))


def test_the_follower_holds_its_altitude_along_the_track():
    reference, status = follower_at(104.0)  # 2 m along the track, up the slope
    x = 2.0 / np.hypot(1.0, 0.1)
    np.testing.assert_allclose(reference[:3], [x, 0.0, -30.0 + 0.1 * x + 5.0], atol=1e-9)
    np.testing.assert_allclose(reference[4:7], 0.5 * np.array([1.0, 0.0, 0.1]) / np.hypot(1, 0.1),
                               atol=1e-9)
    assert list(status) == [3.0, 0.0, 4.0]
    reference, status = follower_at(200.0)  # past the end: held there, the leg finished
    np.testing.assert_allclose(reference, [10.0, 0.0, -24.0, 0.0, 0, 0, 0, 0], atol=1e-9)
    assert status[:2].tolist() == [3.0, 1.0]
    _, status = follower_at(50.0, leg=(2.0, 0.0))  # not its leg
    assert status.tolist() == [-1.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="altitude"):
        example.ConstantAltitudeFollower(None, seabed, -1.0, 0.5, legs=(3,))


def test_the_example_flies_both_and_tables_them(tmp_path, capsys):
    # 120 s: the transit (about 55 s) and 65 s of the survey, each behaviour
    table = tmp_path / "table.md"
    assert example.main(["--max-time", "120", "--altitude", "7", "--markdown", str(table)]) == 0
    rows = [line.split(" | ") for line in table.read_text().splitlines()[2:]]
    assert capsys.readouterr().out.strip() == table.read_text().strip()
    assert [row[0] for row in rows] == ["| built-in: STOMP replanner",
                                        "| yours: constant altitude 7 m"]
    altitude = {row[0]: float(row[4].split()[0]) for row in rows}
    duration = [float(row[5].split()[0]) for row in rows]
    assert abs(altitude["| yours: constant altitude 7 m"] - 7.0) < 1.0
    assert abs(altitude["| built-in: STOMP replanner"] - 7.0) > 1.0
    assert all(50 < d < 75 for d in duration) and all(row[6] == "flying |" for row in rows)
