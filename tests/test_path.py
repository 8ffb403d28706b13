import numpy as np
import pytest

from drake_auv.planning import Path


def _square():
    pts = np.array([[0, 0, -5], [10, 0, -5], [10, 10, -5], [0, 10, -5.0]])
    return Path(pts, heading=[0, np.pi / 2, np.pi, -np.pi / 2], sensor_dir=[0, 0, -1],
                labels=["planar", "planar", "transit", "slice"])


def test_length_and_labels():
    path = _square()
    assert path.length == pytest.approx(30.0)
    assert path.length_by_label() == pytest.approx({"planar": 10.0, "transit": 10.0, "slice": 10.0})


def test_resample_keeps_vertices_and_spacing():
    path = _square().resample(0.7)
    assert path.length == pytest.approx(30.0)
    assert np.max(path.segment_lengths()) <= 0.7 + 1e-9
    for v in _square().points:
        assert np.min(np.linalg.norm(path.points - v, axis=1)) < 1e-9
    assert np.allclose(np.linalg.norm(path.sensor_dir, axis=1), 1.0)


def test_times_respect_speed_and_turn_rate():
    path = _square()
    t = path.times(speed=0.5, yaw_rate=np.radians(10))
    # 10 m at 0.5 m/s is 20 s; a 90 degree turn at 10 deg/s takes 9 s, so travel dominates.
    assert np.allclose(np.diff(t), 20.0)
    turn = Path([[0, 0, 0], [0.1, 0, 0]], heading=[0, np.pi], sensor_dir=[1, 0, 0])
    assert turn.times(0.5, np.radians(10))[-1] == pytest.approx(18.0)


def test_csv_round_trip(tmp_path):
    path = _square().resample(3.0)
    path.to_csv(tmp_path / "p.csv")
    back = Path.from_csv(tmp_path / "p.csv")
    assert np.allclose(back.points, path.points, atol=1e-6)
    assert np.allclose(back.heading, path.heading, atol=1e-6)
    assert list(back.labels) == list(path.labels)


def test_bad_input_is_named(tmp_path):
    with pytest.raises(ValueError, match="shape"):
        Path(np.zeros((3, 2)), 0, [0, 0, 1])
    with pytest.raises(ValueError, match="finite"):
        Path([[0, 0, np.nan]], 0, [0, 0, 1])
    with pytest.raises(ValueError, match="sensor_dir"):
        Path([[0, 0, 0]], 0, [0, 0, 0])
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        Path.from_csv(tmp_path / "nope.csv")
    (tmp_path / "bad.csv").write_text("x,y,z,heading,sensor_x,sensor_y,sensor_z,label\n1,2,a,0,0,0,1,p\n")
    with pytest.raises(ValueError, match="bad.csv:2"):
        Path.from_csv(tmp_path / "bad.csv")


def test_to_trajectory_reference():
    from pydrake.systems.primitives import TrajectorySource

    path = _square()
    traj = path.to_trajectory(speed=0.5)
    assert traj.rows() == 4
    assert traj.end_time() == pytest.approx(60.0)
    source = TrajectorySource(traj, output_derivative_order=1)
    ctx = source.CreateDefaultContext()
    ctx.SetTime(5.0)
    ref = source.get_output_port().Eval(ctx)
    assert ref.shape == (8,)
    assert np.allclose(ref[:3], [2.5, 0, -5])
    assert np.allclose(ref[4:7], [0.5, 0, 0])
